# Calibration chain (paper Sec. II, III-B/C): synthetic or measured record,
# impulse sensitivity (Fig. 5), resistance fit (Fig. 6), low-frequency
# sensitivity (Fig. 8a).

SCORECARD_PARTS.append(f"{RESULTS}/scorecard/calibration.csv")
TARGETS.extend(
    [
        f"{RESULTS}/calibration/sensitivity.json",
        f"{RESULTS}/calibration/resistance.json",
        f"{RESULTS}/sensor/lowfreq.json",
    ]
)


rule synthesize_calibration:
    output:
        csv=f"{RESULTS}/calibration/measurement.csv",
    log:
        f"{RESULTS}/logs/synthesize_calibration.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/synthesize_calibration.tsv"
    priority: LONGEST_CHAINS
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params(
            "synthesize_calibration", "workflow/scripts/synthesize_calibration.py"
        ),
    script:
        "../scripts/synthesize_calibration.py"


rule extract_sensitivity:
    input:
        measurement=measurement_csv(),
    output:
        json=f"{RESULTS}/calibration/sensitivity.json",
    log:
        f"{RESULTS}/logs/extract_sensitivity.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/extract_sensitivity.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=lambda wc, input: 500 + int(3 * input.size_mb),
        runtime=lambda wc, input: 2 + int(0.03 * input.size_mb),
    params:
        **stage_params("extract_sensitivity", "workflow/scripts/extract_sensitivity.py"),
    script:
        "../scripts/extract_sensitivity.py"


rule fit_resistance:
    input:
        measurement=measurement_csv(),
    output:
        json=f"{RESULTS}/calibration/resistance.json",
        csv=f"{RESULTS}/calibration/fit.csv",
    log:
        f"{RESULTS}/logs/fit_resistance.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/fit_resistance.tsv"
    priority: LONGEST_CHAINS
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=lambda wc, input: 500 + int(5 * input.size_mb),
        runtime=lambda wc, input: 2 + int(0.06 * input.size_mb),
    params:
        **stage_params("fit_resistance", "workflow/scripts/fit_resistance.py"),
    script:
        "../scripts/fit_resistance.py"


rule lowfreq_sensitivity:
    input:
        resistance=f"{RESULTS}/calibration/resistance.json",
    output:
        json=f"{RESULTS}/sensor/lowfreq.json",
        csv=f"{RESULTS}/sensor/lowfreq.csv",
    log:
        f"{RESULTS}/logs/lowfreq_sensitivity.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/lowfreq_sensitivity.tsv"
    priority: LONGEST_CHAINS
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params("lowfreq_sensitivity", "workflow/scripts/lowfreq_sensitivity.py"),
    script:
        "../scripts/lowfreq_sensitivity.py"


rule scorecard_calibration:
    input:
        sensitivity=f"{RESULTS}/calibration/sensitivity.json",
        resistance=f"{RESULTS}/calibration/resistance.json",
        lowfreq=f"{RESULTS}/sensor/lowfreq.json",
    output:
        csv=f"{RESULTS}/scorecard/calibration.csv",
    log:
        f"{RESULTS}/logs/scorecard_calibration.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/scorecard_calibration.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params(
            "scorecard_calibration", "workflow/scripts/scorecard_calibration.py"
        ),
    script:
        "../scripts/scorecard_calibration.py"
