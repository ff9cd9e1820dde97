import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.bearing import sampling_phase

sampling_phase(snakemake.input.contact, snakemake.input.influence, snakemake.output.json, snakemake.config)
