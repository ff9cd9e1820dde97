# The scorecard: every paper number beside ours, gathered from the stages' fragments.


rule scorecard:
    input:
        parts=lambda wildcards: SCORECARD_PARTS,
    output:
        csv=f"{RESULTS}/scorecard.csv",
        md=f"{RESULTS}/scorecard.md",
    log:
        f"{RESULTS}/logs/scorecard.log",
    script:
        "../scripts/scorecard.py"
