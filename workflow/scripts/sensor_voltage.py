import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.signals import sensor_voltage
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

sensor_voltage(
    snakemake.input.force,
    snakemake.input.resistance,
    snakemake.input.harmonic[0] if snakemake.input.harmonic else None,
    snakemake.output.csv,
    snakemake.output.json,
    config,
)
