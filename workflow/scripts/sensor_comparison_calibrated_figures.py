import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.studies import calibrated_figures

calibrated_figures(snakemake.input.cases, snakemake.output.healthy, snakemake.output.roc)
