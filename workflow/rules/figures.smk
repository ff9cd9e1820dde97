# Paper figures of the calibration chain: one papermill notebook each; the
# executed notebook is kept under results/notebooks/.

FIGURES.extend([f"{RESULTS}/figures/{n}.png" for n in ("fig05", "fig06", "fig08a")])


rule fig05:
    input:
        notebook="notebooks/fig05_calibration_impulses.ipynb",
        measurement=measurement_csv(),
        sensitivity=f"{RESULTS}/calibration/sensitivity.json",
    output:
        figure=report(
            f"{RESULTS}/figures/fig05.png",
            caption="../report/fig05.rst",
            category="Calibration",
        ),
        notebook=f"{RESULTS}/notebooks/fig05_calibration_impulses.ipynb",
    log:
        f"{RESULTS}/logs/fig05.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/fig05.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=lambda wc, input: 500 + int(5 * input.size_mb),
        runtime=lambda wc, input: 2 + int(0.03 * input.size_mb),
    params:
        **stage_params("fig05", "notebooks/fig05_calibration_impulses.ipynb"),
    shell:
        "papermill {input.notebook:q} {output.notebook:q} -k python3 -r measurement {input.measurement:q}"
        " -r sensitivity {input.sensitivity:q} -r figure {output.figure:q} > {log:q} 2>&1"


rule fig06:
    input:
        notebook="notebooks/fig06_resistance_fit.ipynb",
        fit=f"{RESULTS}/calibration/fit.csv",
        resistance=f"{RESULTS}/calibration/resistance.json",
    output:
        figure=report(
            f"{RESULTS}/figures/fig06.png",
            caption="../report/fig06.rst",
            category="Calibration",
        ),
        notebook=f"{RESULTS}/notebooks/fig06_resistance_fit.ipynb",
    log:
        f"{RESULTS}/logs/fig06.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/fig06.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=lambda wc, input: 500 + int(5 * input.size_mb),
        runtime=lambda wc, input: 2 + int(0.03 * input.size_mb),
    params:
        **stage_params("fig06", "notebooks/fig06_resistance_fit.ipynb"),
    shell:
        "papermill {input.notebook:q} {output.notebook:q} -k python3 -r fit {input.fit:q}"
        " -r resistance {input.resistance:q} -r figure {output.figure:q} > {log:q} 2>&1"


rule fig08a:
    input:
        notebook="notebooks/fig08a_lowfreq_sensitivity.ipynb",
        curve=f"{RESULTS}/sensor/lowfreq.csv",
        lowfreq=f"{RESULTS}/sensor/lowfreq.json",
    output:
        figure=report(
            f"{RESULTS}/figures/fig08a.png",
            caption="../report/fig08a.rst",
            category="Calibration",
        ),
        notebook=f"{RESULTS}/notebooks/fig08a_lowfreq_sensitivity.ipynb",
    log:
        f"{RESULTS}/logs/fig08a.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/fig08a.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params("fig08a", "notebooks/fig08a_lowfreq_sensitivity.ipynb"),
    shell:
        "papermill {input.notebook:q} {output.notebook:q} -k python3 -r curve {input.curve:q}"
        " -r lowfreq {input.lowfreq:q} -r figure {output.figure:q} > {log:q} 2>&1"
