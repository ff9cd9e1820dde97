# Parameter studies (config `studies`, tables in config/studies/*.tsv), built by
# the target `study_all`, not by `all`. Each case runs only the stages its
# study affects; a summary table and figure gather the cases.
import pandas as pd
from snakemake.utils import Paramspace

from piezobearing.studies import read_table

STUDIES = {
    s["name"]: Paramspace(
        read_table(s["table"], config), filename_params="*", single_wildcard="case"
    )
    for s in config["studies"]
}


rule study_case:
    output:
        json=f"{RESULTS}/studies/{{study}}/{{case}}/summary.json",
    log:
        f"{RESULTS}/logs/studies/{{study}}/{{case}}.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/study_case_{{study}}_{{case}}.tsv"
    conda:
        "../envs/piezobearing.yaml"
    params:
        overrides=lambda wc: dict(STUDIES[wc.study].instance(wc)),
    script:
        "../scripts/study_case.py"


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
    script:
        "../scripts/study_summary.py"


rule study_all:
    input:
        [f"{RESULTS}/studies/{name}/summary.png" for name in STUDIES],
