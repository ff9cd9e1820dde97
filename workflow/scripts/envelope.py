import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.signals import envelope

envelope(
    snakemake.input.noisy,
    snakemake.input.voltage,
    snakemake.input.kinematics,
    snakemake.output.csv,
    snakemake.output.json,
    snakemake.config,
)
