import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.bearing import mesh_convergence

mesh_convergence(snakemake.input.contact, snakemake.output.json, snakemake.output.csv, snakemake.config)
