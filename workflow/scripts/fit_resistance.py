import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.calibration import fit_resistance
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

fit_resistance(snakemake.input.measurement, snakemake.output.json, snakemake.output.csv, config)
