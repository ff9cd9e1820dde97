import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.studies import run_case

run_case(
    snakemake.wildcards.study,
    snakemake.wildcards.case,
    snakemake.params.overrides,
    snakemake.config,
    snakemake.output.json,
    dict(snakemake.input.items()),
)
