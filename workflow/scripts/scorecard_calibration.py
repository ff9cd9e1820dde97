import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.scorecard import scorecard_calibration as scorecard
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

scorecard(
    snakemake.input.sensitivity,
    snakemake.input.resistance,
    snakemake.input.lowfreq,
    snakemake.output.csv,
    config,
)
