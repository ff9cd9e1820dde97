import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.calibration import synthesize_calibration
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

synthesize_calibration(config, snakemake.output.csv)
