import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.scorecard import scorecard_signals as scorecard

i = snakemake.input
scorecard(i.indicator, i.study, i.kinematics, snakemake.output.csv)
