import logging
import sys

sys.stderr = open(snakemake.log[0], "w")
logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(message)s")  # timings go here

from piezobearing.stages.sensor_fem import sensor_modal

sensor_modal(snakemake.input.mesh, snakemake.output.json, snakemake.output.mode, snakemake.config)
