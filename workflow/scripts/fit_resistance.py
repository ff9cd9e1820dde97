import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.registry import declared_config
from piezobearing.stages.calibration import fit_resistance

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

fit_resistance(snakemake.input.measurement, snakemake.output.json, snakemake.output.csv, config)
