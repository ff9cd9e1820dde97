import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.calibration import extract_sensitivity

extract_sensitivity(snakemake.input.measurement, snakemake.output.json, snakemake.config)
