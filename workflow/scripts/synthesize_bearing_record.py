import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.bearing_diagnosis import synthesize_bearing_record

synthesize_bearing_record(snakemake.input.influence, snakemake.output.csv, snakemake.config)
