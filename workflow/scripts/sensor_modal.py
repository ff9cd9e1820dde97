import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.sensor_fem import sensor_modal

sensor_modal(snakemake.input.mesh, snakemake.output.json, snakemake.output.mode, snakemake.config)
