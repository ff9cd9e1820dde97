import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.signals import noisy

noisy(snakemake.input.voltage, snakemake.wildcards.case, snakemake.output.csv, snakemake.output.json, snakemake.config)
