import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.calibration import lowfreq
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

lowfreq(snakemake.input.resistance, snakemake.output.json, snakemake.output.csv, config)
