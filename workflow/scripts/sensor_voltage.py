import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.signals import sensor_voltage

sensor_voltage(
    snakemake.input.force,
    snakemake.input.resistance,
    snakemake.input.harmonic[0] if snakemake.input.harmonic else None,
    snakemake.output.csv,
    snakemake.output.json,
    snakemake.config,
)
