import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.signals import scorecard

i = snakemake.input
scorecard(i.indicator, i.study, i.kinematics, snakemake.output.csv)
