import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.sensor_fem import sensor_convergence

sensor_convergence(list(snakemake.input.meshes), snakemake.output.csv, snakemake.config)
