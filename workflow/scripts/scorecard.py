import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.scorecard import assemble
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # the run's name and conditions

assemble(snakemake.input.parts, snakemake.output.csv, snakemake.output.md, config)
