import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.registry import declared_config
from piezobearing.stages.sensor_fem import sensor_convergence

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

sensor_convergence(list(snakemake.input.meshes), snakemake.input.modal_row, snakemake.output.csv, config)
