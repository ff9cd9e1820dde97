import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.scorecard import scorecard_sensor_fem

i = snakemake.input
scorecard_sensor_fem(i.modal, i.band, i.convergence, snakemake.output.csv)
