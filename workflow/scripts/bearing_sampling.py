import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.registry import declared_config
from piezobearing.stages.bearing import sampling_phase

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

sampling_phase(snakemake.input.contact, snakemake.input.influence, snakemake.output.json, config)
