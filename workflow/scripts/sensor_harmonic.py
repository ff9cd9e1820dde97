import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.registry import declared_config
from piezobearing.stages.sensor_fem import sensor_harmonic

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

i, o = snakemake.input, snakemake.output
sensor_harmonic(i.ritz, i.modal, i.resistance, i.lowfreq, o.csv, o.band, config)
