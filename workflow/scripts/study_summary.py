import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.studies import summarize

summarize(snakemake.wildcards.study, snakemake.input.cases, snakemake.output.csv, snakemake.output.figure)
