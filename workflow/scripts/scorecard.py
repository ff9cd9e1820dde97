import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.scorecard import assemble

assemble(snakemake.input.parts, snakemake.output.csv, snakemake.output.md)
