# From sensor force to fault detection (paper Sec. IV, Fig. 9 and 10): voltage
# through the calibrated sensor model, the DAQ's sampling and noise, envelope
# spectrum, the paper's fault indicator and the configured detector (both
# through piezobearing.signals.detectors), detection against SNR, fault-type
# classification.
from piezobearing.workflow.targets import extra_fault_types

FIGURES.extend([f"{RESULTS}/figures/{n}.png" for n in ("fig09", "fig10", "snr_study")])
SCORECARD_PARTS.append(f"{RESULTS}/scorecard/signals.csv")
TARGETS.extend(
    [
        f"{RESULTS}/signals/fault_indicator.json",
        f"{RESULTS}/signals/snr_study.csv",
        f"{RESULTS}/signals/classification.json",
    ]
)


rule sensor_voltage:
    input:
        force=f"{RESULTS}/bearing/sensor_force_{{case}}.csv",
        resistance=f"{RESULTS}/calibration/resistance.json",
        # the sensor FEM's response, if signals.sensor_fem_correction (else no input)
        harmonic=(
            [f"{RESULTS}/sensor/harmonic.csv"]
            if config["signals"]["sensor_fem_correction"]
            else []
        ),
    output:
        csv=f"{RESULTS}/signals/voltage_{{case}}.csv",
        json=f"{RESULTS}/signals/voltage_{{case}}.json",
    log:
        f"{RESULTS}/logs/sensor_voltage_{{case}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/sensor_voltage_{{case}}.tsv"
    wildcard_constraints:
        case="healthy|faulty",
    priority: LONGEST_CHAINS
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params("sensor_voltage", "workflow/scripts/sensor_voltage.py"),
    script:
        "../scripts/sensor_voltage.py"


rule noisy:
    input:
        voltage=f"{RESULTS}/signals/voltage_{{case}}.csv",
    output:
        csv=f"{RESULTS}/signals/noisy_{{case}}.csv",
        json=f"{RESULTS}/signals/noisy_{{case}}.json",
    log:
        f"{RESULTS}/logs/noisy_{{case}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/noisy_{{case}}.tsv"
    wildcard_constraints:
        case="healthy|faulty",
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params("noisy", "workflow/scripts/noisy.py"),
    script:
        "../scripts/noisy.py"


rule envelope:
    input:
        noisy=f"{RESULTS}/signals/noisy_{{case}}.csv",
        voltage=f"{RESULTS}/signals/voltage_{{case}}.csv",
        kinematics=f"{RESULTS}/bearing/kinematics.json",
    output:
        csv=f"{RESULTS}/signals/envelope_{{case}}.csv",
        json=f"{RESULTS}/signals/envelope_{{case}}.json",
    log:
        f"{RESULTS}/logs/envelope_{{case}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/envelope_{{case}}.tsv"
    wildcard_constraints:
        case="healthy|faulty",
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params("envelope", "workflow/scripts/envelope.py"),
    script:
        "../scripts/envelope.py"


rule fault_indicator:
    input:
        healthy_envelope=f"{RESULTS}/signals/envelope_healthy.json",
        faulty_envelope=f"{RESULTS}/signals/envelope_faulty.json",
        healthy_noisy=f"{RESULTS}/signals/noisy_healthy.json",
        faulty_noisy=f"{RESULTS}/signals/noisy_faulty.json",
        healthy_noisy_csv=f"{RESULTS}/signals/noisy_healthy.csv",
        faulty_noisy_csv=f"{RESULTS}/signals/noisy_faulty.csv",
        kinematics=f"{RESULTS}/bearing/kinematics.json",
    output:
        json=f"{RESULTS}/signals/fault_indicator.json",
    log:
        f"{RESULTS}/logs/fault_indicator.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/fault_indicator.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params("fault_indicator", "workflow/scripts/fault_indicator.py"),
    script:
        "../scripts/fault_indicator.py"


rule snr_study:
    input:
        healthy=f"{RESULTS}/signals/voltage_healthy.csv",
        faulty=f"{RESULTS}/signals/voltage_faulty.csv",
        kinematics=f"{RESULTS}/bearing/kinematics.json",
    output:
        csv=f"{RESULTS}/signals/snr_study.csv",
        summary=f"{RESULTS}/signals/snr_study_summary.csv",
        json=f"{RESULTS}/signals/snr_study.json",
    log:
        f"{RESULTS}/logs/snr_study.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/snr_study.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=4,
    params:
        **stage_params("snr_study", "workflow/scripts/snr_study.py"),
    script:
        "../scripts/snr_study.py"


rule snr_study_figure:
    input:
        summary=f"{RESULTS}/signals/snr_study_summary.csv",
        json=f"{RESULTS}/signals/snr_study.json",
    output:
        figure=report(
            f"{RESULTS}/figures/snr_study.png",
            caption="../report/snr_study.rst",
            category="Fault detection",
        ),
    log:
        f"{RESULTS}/logs/snr_study_figure.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/snr_study_figure.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params("snr_study_figure", "workflow/scripts/snr_study_figure.py"),
    script:
        "../scripts/snr_study_figure.py"


rule defect_events:
    input:
        healthy=f"{RESULTS}/signals/voltage_healthy.csv",
        faulty=f"{RESULTS}/signals/voltage_faulty.csv",
        kinematics=f"{RESULTS}/bearing/kinematics.json",
    output:
        csv=f"{RESULTS}/signals/defect_events.csv",
    log:
        f"{RESULTS}/logs/defect_events.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/defect_events.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params("defect_events", "workflow/scripts/defect_events.py"),
    script:
        "../scripts/defect_events.py"


rule fig09:
    input:
        notebook="notebooks/fig09_voltage.ipynb",
        healthy=f"{RESULTS}/signals/voltage_healthy.csv",
        faulty=f"{RESULTS}/signals/voltage_faulty.csv",
        events=f"{RESULTS}/signals/defect_events.csv",
        kinematics=f"{RESULTS}/bearing/kinematics.json",
    output:
        figure=report(
            f"{RESULTS}/figures/fig09.png",
            caption="../report/fig09.rst",
            category="Fault detection",
        ),
        notebook=f"{RESULTS}/notebooks/fig09_voltage.ipynb",
    log:
        f"{RESULTS}/logs/fig09.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/fig09.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params("fig09", "notebooks/fig09_voltage.ipynb"),
    shell:
        "papermill {input.notebook:q} {output.notebook:q} -k python3 -r healthy {input.healthy:q}"
        " -r faulty {input.faulty:q} -r events {input.events:q} -r kinematics {input.kinematics:q}"
        " -r figure {output.figure:q} > {log:q} 2>&1"


rule fig10:
    input:
        notebook="notebooks/fig10_envelope.ipynb",
        healthy=f"{RESULTS}/signals/envelope_healthy.csv",
        faulty=f"{RESULTS}/signals/envelope_faulty.csv",
        indicator=f"{RESULTS}/signals/fault_indicator.json",
        kinematics=f"{RESULTS}/bearing/kinematics.json",
    output:
        figure=report(
            f"{RESULTS}/figures/fig10.png",
            caption="../report/fig10.rst",
            category="Fault detection",
        ),
        notebook=f"{RESULTS}/notebooks/fig10_envelope.ipynb",
    log:
        f"{RESULTS}/logs/fig10.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/fig10.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params("fig10", "notebooks/fig10_envelope.ipynb"),
    shell:
        "papermill {input.notebook:q} {output.notebook:q} -k python3 -r healthy {input.healthy:q}"
        " -r faulty {input.faulty:q} -r indicator {input.indicator:q} -r kinematics {input.kinematics:q}"
        " -r figure {output.figure:q} > {log:q} 2>&1"


rule scorecard_signals:
    input:
        indicator=f"{RESULTS}/signals/fault_indicator.json",
        study=f"{RESULTS}/signals/snr_study.json",
        kinematics=f"{RESULTS}/bearing/kinematics.json",
    output:
        csv=f"{RESULTS}/scorecard/signals.csv",
    log:
        f"{RESULTS}/logs/scorecard_signals.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/scorecard_signals.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params("scorecard_signals", "workflow/scripts/scorecard_signals.py"),
    script:
        "../scripts/scorecard_signals.py"


rule fault_type_voltage:
    input:
        resistance=f"{RESULTS}/calibration/resistance.json",
        harmonic=(
            [f"{RESULTS}/sensor/harmonic.csv"]
            if config["signals"]["sensor_fem_correction"]
            else []
        ),
    output:
        force=f"{RESULTS}/signals/fault_types/sensor_force_{{fault_type}}.csv",
        csv=f"{RESULTS}/signals/fault_types/voltage_{{fault_type}}.csv",
        json=f"{RESULTS}/signals/fault_types/voltage_{{fault_type}}.json",
    log:
        f"{RESULTS}/logs/fault_type_voltage_{{fault_type}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/fault_type_voltage_{{fault_type}}.tsv"
    wildcard_constraints:
        fault_type="outer_race|inner_race|rolling_element",
    priority: LONGEST_CHAINS
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        # the LPM and the housing_transient rule's solve (2.3 GB) in one job
        mem_mb=2500,
        runtime=10,
    params:
        **stage_params("fault_type_voltage", "workflow/scripts/fault_type_voltage.py"),
    script:
        "../scripts/fault_type_voltage.py"


rule fault_classification:
    input:
        healthy=f"{RESULTS}/signals/voltage_healthy.csv",
        faulty=f"{RESULTS}/signals/voltage_faulty.csv",
        kinematics=f"{RESULTS}/bearing/kinematics.json",
        # one record per further fault type of signals.detector.classification_types
        types=[
            f"{RESULTS}/signals/fault_types/voltage_{t}.csv"
            for t in extra_fault_types(config)
        ],
    output:
        json=f"{RESULTS}/signals/classification.json",
        csv=f"{RESULTS}/signals/classification.csv",
        roc=f"{RESULTS}/signals/roc.csv",
    log:
        f"{RESULTS}/logs/fault_classification.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/fault_classification.tsv"
    priority: LONGEST_CHAINS
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=10,
    params:
        **stage_params(
            "fault_classification", "workflow/scripts/fault_classification.py"
        ),
    script:
        "../scripts/fault_classification.py"
