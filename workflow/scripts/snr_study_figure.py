import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.signals import snr_study_figure

snr_study_figure(snakemake.input.summary, snakemake.input.json, snakemake.output.figure)
