import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.sensor_fem import sensor_modal
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

o = snakemake.output
sensor_modal(snakemake.input.mesh, o.json, o.mode, o.ritz, o.convergence_row, config)
