import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.calibration import fit_resistance

fit_resistance(snakemake.input.measurement, snakemake.output.json, snakemake.output.csv, snakemake.config)
