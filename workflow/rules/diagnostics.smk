# Model versus measurement (DESIGN.md section 4): the configured model (RC baseline
# plus model.effects) fitted to the calibration record, residual tests, effect
# ranking, stepwise selection and verdict; report in results/diagnostics/.
import sys

from piezobearing.diagnosis.effect import EffectError
from piezobearing.diagnosis.calibration.figures import FIGURES as DIAGNOSIS_FIGURES
from piezobearing.workflow.checks import check_subject_once

try:  # an unknown effect in model.effects or synthesis.hidden_effects stops before any job (once per config)
    check_subject_once(
        "piezobearing.diagnosis.calibration.subject",
        "diagnose",
        config,
        CACHE / "checked",
    )
except EffectError as e:
    print(f"piezobearing: {e}", file=sys.stderr)
    sys.exit(1)

TARGETS.extend(
    [
        f"{RESULTS}/diagnostics/diagnosis.json",
        f"{RESULTS}/diagnostics/report.md",
        f"{RESULTS}/notebooks/diagnosis.ipynb",
    ]
)


rule diagnose:
    input:
        measurement=measurement_csv(),
    output:
        json=f"{RESULTS}/diagnostics/diagnosis.json",
        arrays=f"{RESULTS}/diagnostics/diagnosis.npz",
        report=f"{RESULTS}/diagnostics/report.md",
        figures=[
            report(
                f"{RESULTS}/diagnostics/figures/{name}.png",
                caption="../report/diagnosis.rst",
                category="Model versus measurement",
            )
            for name in DIAGNOSIS_FIGURES
        ],
    log:
        f"{RESULTS}/logs/diagnose.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/diagnose.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=lambda wc, input: 500 + int(45 * input.size_mb),
        runtime=lambda wc, input: 2 + int(0.6 * input.size_mb),
    params:
        **stage_params("diagnose", "workflow/scripts/diagnose.py"),
    script:
        "../scripts/diagnose.py"


rule diagnosis_notebook:
    input:
        notebook="notebooks/diagnosis.ipynb",
        diagnosis=f"{RESULTS}/diagnostics/diagnosis.json",
        figures=[
            f"{RESULTS}/diagnostics/figures/{name}.png" for name in DIAGNOSIS_FIGURES
        ],
    output:
        figure=report(
            f"{RESULTS}/figures/diagnosis_ladder.png",
            caption="../report/diagnosis_ladder.rst",
            category="Model versus measurement",
        ),
        notebook=f"{RESULTS}/notebooks/diagnosis.ipynb",
    log:
        f"{RESULTS}/logs/diagnosis_notebook.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/diagnosis_notebook.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params("diagnosis_notebook", "notebooks/diagnosis.ipynb"),
        figures=lambda wc, input: os.path.dirname(input.figures[0]),
    shell:
        "papermill {input.notebook:q} {output.notebook:q} -k python3 -r diagnosis {input.diagnosis:q}"
        " -r figures {params.figures:q} -r figure {output.figure:q} > {log:q} 2>&1"
