# The embedded sensor against a housing accelerometer on one simulated rig (docs/guides/sensor_comparison.md):
# the paper's case observed by both sensors, with the machine frame at rest and vibrating (base_motion), both
# records judged by the envelope detector; the figure of both envelope spectra.
from piezobearing.workflow.registry import short_param

FIGURES.append(f"{RESULTS}/figures/sensor_comparison.png")
TARGETS.append(f"{RESULTS}/signals/sensor_comparison.json")


# The housing's reduced model, one file per healthy or faulty mesh, which every comparison on that mesh reads
# (the main rule and the study's cases): comparison_housings in common.smk.
rule sensor_comparison_housing:
    output:
        npz=f"{RESULTS}/sensor_comparison/housing/{{mesh}}_{{digest}}.npz",
    log:
        f"{RESULTS}/logs/sensor_comparison_housing/{{mesh}}_{{digest}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/sensor_comparison_housing/{{mesh}}_{{digest}}.tsv"
    wildcard_constraints:
        mesh="healthy|faulty",
        digest="[0-9a-f]{12}",
    priority: LONGEST_CHAINS
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=3000,
        runtime=30,
    params:
        reads=lambda wc: short_param(COMPARISON_HOUSINGS[wc.digest]),
        code=code_hash(
            f"{workflow.basedir}/workflow/scripts/sensor_comparison_housing.py"
        ),
    script:
        "../scripts/sensor_comparison_housing.py"


rule sensor_comparison:
    input:
        **comparison_housings(config),
        resistance=f"{RESULTS}/calibration/resistance.json",
        # the sensor FEM's response, if signals.sensor_fem_correction (else no input)
        harmonic=(
            [f"{RESULTS}/sensor/harmonic.csv"]
            if config["signals"]["sensor_fem_correction"]
            else []
        ),
    output:
        json=f"{RESULTS}/signals/sensor_comparison.json",
        spectra=f"{RESULTS}/signals/sensor_comparison_spectra.csv",
    log:
        f"{RESULTS}/logs/sensor_comparison.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/sensor_comparison.tsv"
    priority: LONGEST_CHAINS
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=3000,
        runtime=30,
    params:
        **stage_params("sensor_comparison", "workflow/scripts/sensor_comparison.py"),
    script:
        "../scripts/sensor_comparison.py"


rule sensor_comparison_figure:
    input:
        notebook="notebooks/sensor_comparison.ipynb",
        summary=f"{RESULTS}/signals/sensor_comparison.json",
        spectra=f"{RESULTS}/signals/sensor_comparison_spectra.csv",
    output:
        figure=report(
            f"{RESULTS}/figures/sensor_comparison.png",
            caption="../report/sensor_comparison.rst",
            category="Sensor comparison",
        ),
        notebook=f"{RESULTS}/notebooks/sensor_comparison.ipynb",
    log:
        f"{RESULTS}/logs/sensor_comparison_figure.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/sensor_comparison_figure.tsv"
    priority: LONGEST_CHAINS
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params("sensor_comparison_figure", "notebooks/sensor_comparison.ipynb"),
    shell:
        "papermill {input.notebook:q} {output.notebook:q} -k python3 -r summary {input.summary:q}"
        " -r spectra {input.spectra:q} -r figure {output.figure:q} > {log:q} 2>&1"
