import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.bearing import housing_mesh
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

o = snakemake.output
housing_mesh(snakemake.wildcards.case, o.npz, o.vtk, o.json, config)
