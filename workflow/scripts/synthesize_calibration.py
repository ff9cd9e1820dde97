import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.calibration import synthesize_calibration

synthesize_calibration(snakemake.config, snakemake.output.csv)
