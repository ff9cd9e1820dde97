import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.registry import declared_config
from piezobearing.stages.calibration import lowfreq

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

lowfreq(snakemake.input.resistance, snakemake.output.json, snakemake.output.csv, config)
