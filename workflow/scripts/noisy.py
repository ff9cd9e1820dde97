import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.signals import noisy
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

noisy(snakemake.input.voltage, snakemake.wildcards.case, snakemake.output.csv, snakemake.output.json, config)
