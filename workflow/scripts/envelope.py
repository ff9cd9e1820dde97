import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.signals import envelope
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

envelope(
    snakemake.input.noisy,
    snakemake.input.voltage,
    snakemake.input.kinematics,
    snakemake.output.csv,
    snakemake.output.json,
    config,
)
