import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.sensor_fem import sensor_harmonic
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

i, o = snakemake.input, snakemake.output
sensor_harmonic(i.ritz, i.modal, i.resistance, i.lowfreq, o.csv, o.band, config)
