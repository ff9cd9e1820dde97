import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.calibration import scorecard

scorecard(
    snakemake.input.sensitivity,
    snakemake.input.resistance,
    snakemake.input.lowfreq,
    snakemake.output.csv,
    snakemake.config,
)
