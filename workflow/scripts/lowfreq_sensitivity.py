import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.calibration import lowfreq

lowfreq(snakemake.input.resistance, snakemake.output.json, snakemake.output.csv, snakemake.config)
