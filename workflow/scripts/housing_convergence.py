import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.bearing import mesh_convergence
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

i, o = snakemake.input, snakemake.output
mesh_convergence(i.contact, o.json, o.csv, config, i.quasi_static)
