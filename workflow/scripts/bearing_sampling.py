import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.bearing import sampling_phase
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

sampling_phase(snakemake.input.contact, snakemake.input.influence, snakemake.output.json, config)
