import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.calibration import extract_sensitivity
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

extract_sensitivity(snakemake.input.measurement, snakemake.output.json, config)
