import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.sensor_fem import sensor_mesh

sensor_mesh(list(snakemake.output.meshes), snakemake.output.json, snakemake.config)
