import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.registry import declared_config
from piezobearing.stages.scorecard import assemble

config = declared_config(snakemake.params.reads, snakemake.rule)  # the run's name and conditions

assemble(snakemake.input.parts, snakemake.output.csv, snakemake.output.md, config)
