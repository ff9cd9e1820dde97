import logging
import sys

sys.stderr = open(snakemake.log[0], "w")
logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(message)s")  # timings go here

from piezobearing.stages.sensor_fem import sensor_harmonic

i, o = snakemake.input, snakemake.output
sensor_harmonic(i.mesh, i.modal, i.resistance, i.lowfreq, o.csv, o.band, snakemake.config)
