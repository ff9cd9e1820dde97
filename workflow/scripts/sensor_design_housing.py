import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.studies import sensor_design_housing

sensor_design_housing(snakemake.output.json, snakemake.config)
