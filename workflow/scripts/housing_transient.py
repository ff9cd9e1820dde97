import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.bearing import housing_transient
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

i, o = snakemake.input, snakemake.output
housing_transient(
    snakemake.wildcards.case, i.mesh, i.contact, o.csv, o.modes, o.json, o.influence, config, o.quasi_static
)
