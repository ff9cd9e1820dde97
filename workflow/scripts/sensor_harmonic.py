import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.sensor_fem import sensor_harmonic

i, o = snakemake.input, snakemake.output
sensor_harmonic(i.mesh, i.modal, i.resistance, i.lowfreq, o.csv, o.band, snakemake.config)
