# Parameter studies (config `studies`, tables in config/studies/*.tsv), built by
# the target `study_all`, not by `all`. Each case runs, in process and in
# memory, only the rules its study affects, through the functions their stages
# call (one pipeline: piezobearing.stages.studies); its only file is its
# summary.json. A summary table and figure gather the cases.
import sys

import pandas as pd
from snakemake.utils import Paramspace

from piezobearing.config import ConfigError
from piezobearing.workflow.registry import short_param
from piezobearing.config.cases import case_config, check_studies

try:  # a bad study table or case value stops before any job, in one line
    STUDY_TABLES = check_studies(config)
except ConfigError as e:
    print(f"piezobearing: {e}", file=sys.stderr)
    sys.exit(1)

STUDIES = {
    name: Paramspace(df, filename_params="*", single_wildcard="case")
    for name, df in STUDY_TABLES.items()
}
# Workflow results one case reads, by (study, case): a sensor_comparison case's housing models
# (rule sensor_comparison_housing: one file per distinct mesh).
CASE_INPUTS = (
    {
        ("sensor_comparison", case): comparison_housings(case_config(config, overrides))
        for case, overrides in zip(
            STUDIES["sensor_comparison"].instance_patterns,
            STUDY_TABLES["sensor_comparison"].to_dict("records"),
        )
    }
    if "sensor_comparison" in STUDIES
    else {}
)

# Workflow results a study kind reads that its varied keys do not affect, by kind
# (keyword arguments of its function in piezobearing.stages.studies.KINDS).
_SENSOR_INPUTS = {
    "resistance": f"{RESULTS}/calibration/resistance.json",
    **(
        {"harmonic": f"{RESULTS}/sensor/harmonic.csv"}
        if config["signals"]["sensor_fem_correction"]
        else {}
    ),
}
# the detector studies run the fault_detection chain and the classification
DETECTOR_STUDIES = ("daq_noise", "defect_position", "fault_type_speed")
STUDY_INPUTS = {
    "fault_detection": _SENSOR_INPUTS,
    **{name: _SENSOR_INPUTS for name in DETECTOR_STUDIES},
    "sensor_comparison": _SENSOR_INPUTS,
    "sensor_design": {
        "resistance": f"{RESULTS}/calibration/resistance.json",
        "force_healthy": f"{RESULTS}/bearing/sensor_force_healthy.csv",
        "force_faulty": f"{RESULTS}/bearing/sensor_force_faulty.csv",
        "kinematics": f"{RESULTS}/bearing/kinematics.json",
        "housing": f"{RESULTS}/studies/sensor_design/housing.json",
    },
}
# Each study's largest case on the paper config, peak RSS: `python benchmarks/bench_studies.py` after a
# `study_all` run (the performance page's `studies` row; calibration_circuit 0.26 GB, fault_detection 1.29 GB,
# daq_noise 2.92 GB, defect_position 1.19 GB, fault_type_speed 1.15 GB, sensor_design 0.48 GB); each bound
# about 1.4x or more above it.
STUDY_MEM_MB = {
    "calibration_circuit": 500,
    "fault_detection": 2000,
    "daq_noise": 4000,
    "defect_position": 2000,
    "fault_type_speed": 2000,
    "sensor_design": 1500,
    # measured per case: benchmarks/bench_sensor_comparison.py (results/benchmarks/sensor_comparison.json)
    "sensor_comparison": 3000,
}
STUDY_RUNTIME_MIN = {
    "calibration_circuit": 2,
    "fault_detection": 4,
    **{name: 20 for name in DETECTOR_STUDIES},
    "sensor_design": 3,
    "sensor_comparison": 60,
}
# Config sections a kind's cases depend on (as params: a changed value reruns the cases).
STUDY_SECTIONS = {
    "calibration_circuit": "seed sensor synthesis calibration lowfreq".split(),
    "fault_detection": "seed sensor sensor_fem bearing housing signals".split(),
    **{
        name: "seed sensor sensor_fem bearing housing signals".split()
        for name in DETECTOR_STUDIES
    },
    "sensor_design": "seed sensor sensor_fem lowfreq bearing housing signals".split(),
    "sensor_comparison": "seed sensor sensor_fem bearing housing signals base_motion accelerometer sensor_comparison".split(),
}


rule study_case:
    input:
        unpack(
            lambda wc: {
                **STUDY_INPUTS.get(wc.study, {}),
                **CASE_INPUTS.get((wc.study, wc.case), {}),
            }
        ),
    output:
        json=f"{RESULTS}/studies/{{study}}/{{case}}/summary.json",
    log:
        f"{RESULTS}/logs/studies/{{study}}/{{case}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/study_case_{{study}}/{{case}}.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=lambda wc: STUDY_MEM_MB.get(wc.study, 1000),
        runtime=lambda wc: STUDY_RUNTIME_MIN.get(wc.study, 10),
    params:
        code=code_hash(f"{workflow.basedir}/workflow/scripts/study_case.py"),
        overrides=lambda wc: short_param(dict(STUDIES[wc.study].instance(wc))),
        sections=lambda wc: short_param(
            {k: config[k] for k in STUDY_SECTIONS.get(wc.study, [])}
        ),
    script:
        "../scripts/study_case.py"


rule sensor_design_housing:
    output:
        json=f"{RESULTS}/studies/sensor_design/housing.json",
    log:
        f"{RESULTS}/logs/studies/sensor_design_housing.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/sensor_design_housing.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=2500,
        runtime=5,
    params:
        sections=short_param(
            {k: config[k] for k in ("sensor", "sensor_fem", "bearing", "housing")}
        ),
    script:
        "../scripts/sensor_design_housing.py"


rule study_summary:
    input:
        cases=lambda wc: expand(
            f"{RESULTS}/studies/{wc.study}/{{case}}/summary.json",
            case=STUDIES[wc.study].instance_patterns,
        ),
    output:
        csv=f"{RESULTS}/studies/{{study}}/summary.csv",
        figure=report(
            f"{RESULTS}/studies/{{study}}/summary.png",
            caption="../report/study.rst",
            category="Studies",
            subcategory="{study}",
        ),
    log:
        f"{RESULTS}/logs/studies/{{study}}_summary.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/study_summary_{{study}}.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params("study_summary", "workflow/scripts/study_summary.py"),
    script:
        "../scripts/study_summary.py"


# The sensor comparison's calibrated test, drawn from its cases' seeds: the healthy statistic's distribution
# and the ROC curves, beside its summary (piezobearing.stages.studies.calibrated_figures).
STUDY_FIGURES = {
    "sensor_comparison": [
        f"{RESULTS}/studies/sensor_comparison/healthy_statistic.png",
        f"{RESULTS}/studies/sensor_comparison/roc.png",
    ]
}


if "sensor_comparison" in STUDIES:

    rule sensor_comparison_calibrated_figures:
        input:
            cases=expand(
                f"{RESULTS}/studies/sensor_comparison/{{case}}/summary.json",
                case=STUDIES["sensor_comparison"].instance_patterns,
            ),
        output:
            healthy=report(
                f"{RESULTS}/studies/sensor_comparison/healthy_statistic.png",
                caption="../report/study.rst",
                category="Studies",
                subcategory="sensor_comparison",
            ),
            roc=report(
                f"{RESULTS}/studies/sensor_comparison/roc.png",
                caption="../report/study.rst",
                category="Studies",
                subcategory="sensor_comparison",
            ),
        log:
            f"{RESULTS}/logs/studies/sensor_comparison_calibrated_figures.log",
        benchmark:
            f"{RESULTS}/benchmarks/rules/sensor_comparison_calibrated_figures.tsv"
        conda:
            "../envs/piezobearing.yaml"
        threads: 1
        resources:
            mem_mb=500,
            runtime=2,
        params:
            **stage_params(
                "sensor_comparison_calibrated_figures",
                "workflow/scripts/sensor_comparison_calibrated_figures.py",
            ),
        script:
            "../scripts/sensor_comparison_calibrated_figures.py"


rule study_all:
    input:
        [f"{RESULTS}/studies/{name}/summary.png" for name in STUDIES],
        [f for name in STUDIES for f in STUDY_FIGURES.get(name, [])],


# One target per study: `snakemake --cores 2 study_<name>` runs that study's cases and its summary only.
for _study in STUDIES:

    rule:
        name:
            f"study_{_study}"
        input:
            f"{RESULTS}/studies/{_study}/summary.png",
            STUDY_FIGURES.get(_study, []),
        localrule: True
