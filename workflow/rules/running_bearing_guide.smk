# The running-bearing guide's example (docs/guides/running_bearing.md, "When the verdict asks for the shaft's
# dynamics"): a record of the dynamic LPM diagnosed without, then with the dynamic rung, for the guide's ladder
# figures. Outside rule all: `snakemake --cores 1 running_bearing_guide --configfile docs/_data/running_bearing_guide.yaml`,
# then `python scripts/docs_figures.py --only running_bearing`.


rule running_bearing_guide:
    output:
        record=f"{RESULTS}/diagnostics_bearing/guide/record.csv",
        qs=f"{RESULTS}/diagnostics_bearing/guide/diag_qs/diagnosis.json",
        qs_ladder=f"{RESULTS}/diagnostics_bearing/guide/diag_qs/figures/ladder.png",
        dyn=f"{RESULTS}/diagnostics_bearing/guide/diag_dyn/diagnosis.json",
        dyn_ladder=f"{RESULTS}/diagnostics_bearing/guide/diag_dyn/figures/ladder.png",
    log:
        f"{RESULTS}/logs/running_bearing_guide.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/running_bearing_guide.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=1500,
        runtime=10,
    params:
        **stage_params(
            "running_bearing_guide", "workflow/scripts/running_bearing_guide.py"
        ),
    script:
        "../scripts/running_bearing_guide.py"
