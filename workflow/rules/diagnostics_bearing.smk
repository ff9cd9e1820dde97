# The running bearing held against its model (docs/guides/running_bearing.md):
# the record (bearing.measurement, or a synthetic one with bearing.hidden_effects), the housing's
# influence line, the diagnosis engine with the bearing subject; report in results/diagnostics_bearing/.
import sys

from piezobearing.diagnosis.effect import EffectError
from piezobearing.diagnosis.bearing.figures import FIGURES as BEARING_FIGURES
from piezobearing.workflow.checks import check_subject_once

try:  # an unknown effect in bearing_diagnosis.effects or bearing.hidden_effects stops before any job (once per config)
    check_subject_once(
        "piezobearing.diagnosis.bearing.subject",
        "diagnose_bearing",
        config,
        CACHE / "checked",
    )
except EffectError as e:
    print(f"piezobearing: {e}", file=sys.stderr)
    sys.exit(1)

TARGETS.extend(
    [
        f"{RESULTS}/diagnostics_bearing/diagnosis.json",
        f"{RESULTS}/diagnostics_bearing/report.md",
        f"{RESULTS}/notebooks/diagnosis_bearing.ipynb",
    ]
)


rule synthesize_bearing_record:
    input:
        influence=f"{RESULTS}/bearing/influence_line_healthy.csv",
        harmonic=sensor_harmonic(),
    output:
        csv=f"{RESULTS}/diagnostics_bearing/synthetic_record.csv",
    log:
        f"{RESULTS}/logs/synthesize_bearing_record.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/synthesize_bearing_record.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params(
            "synthesize_bearing_record",
            "workflow/scripts/synthesize_bearing_record.py",
        ),
    script:
        "../scripts/synthesize_bearing_record.py"


rule diagnose_bearing:
    input:
        record=bearing_record(),
        influence=f"{RESULTS}/bearing/influence_line_healthy.csv",
        harmonic=sensor_harmonic(),
    output:
        json=f"{RESULTS}/diagnostics_bearing/diagnosis.json",
        arrays=f"{RESULTS}/diagnostics_bearing/diagnosis.npz",
        report=f"{RESULTS}/diagnostics_bearing/report.md",
        figures=[
            report(
                f"{RESULTS}/diagnostics_bearing/figures/{name}.png",
                caption="../report/diagnosis_bearing.rst",
                category="Running bearing, model versus measurement",
            )
            for name in BEARING_FIGURES
        ],
    log:
        f"{RESULTS}/logs/diagnose_bearing.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/diagnose_bearing.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=1000,
        runtime=15,
    params:
        **stage_params("diagnose_bearing", "workflow/scripts/diagnose_bearing.py"),
    script:
        "../scripts/diagnose_bearing.py"


rule diagnosis_bearing_notebook:
    input:
        notebook="notebooks/diagnosis_bearing.ipynb",
        diagnosis=f"{RESULTS}/diagnostics_bearing/diagnosis.json",
        figures=[
            f"{RESULTS}/diagnostics_bearing/figures/{name}.png"
            for name in BEARING_FIGURES
        ],
    output:
        figure=report(
            f"{RESULTS}/figures/diagnosis_bearing.png",
            caption="../report/diagnosis_bearing_envelope.rst",
            category="Running bearing, model versus measurement",
        ),
        notebook=f"{RESULTS}/notebooks/diagnosis_bearing.ipynb",
    log:
        f"{RESULTS}/logs/diagnosis_bearing_notebook.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/diagnosis_bearing_notebook.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params(
            "diagnosis_bearing_notebook", "notebooks/diagnosis_bearing.ipynb"
        ),
        figures=lambda wc, input: os.path.dirname(input.figures[0]),
    shell:
        "papermill {input.notebook:q} {output.notebook:q} -k python3 -r diagnosis {input.diagnosis:q}"
        " -r figures {params.figures:q} -r figure {output.figure:q} > {log:q} 2>&1"
