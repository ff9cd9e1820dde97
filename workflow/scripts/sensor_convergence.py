import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.sensor_fem import sensor_convergence
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

sensor_convergence(list(snakemake.input.meshes), snakemake.input.modal_row, snakemake.output.csv, config)
