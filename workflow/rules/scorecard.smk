# The scorecard: every paper number beside ours, gathered from the stages' fragments.


rule scorecard:
    input:
        parts=lambda wildcards: SCORECARD_PARTS,
    output:
        csv=f"{RESULTS}/scorecard.csv",
        md=report(
            f"{RESULTS}/scorecard.md",
            caption="../report/scorecard.rst",
            category="Scorecard",
        ),
    log:
        f"{RESULTS}/logs/scorecard.log",
    benchmark:
        f"{RESULTS}/benchmarks/rules/scorecard.tsv"
    conda:
        "../envs/piezobearing.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=2,
    params:
        **stage_params("scorecard", "workflow/scripts/scorecard.py"),
    script:
        "../scripts/scorecard.py"
