import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.bearing import housing_transient

i, o = snakemake.input, snakemake.output
housing_transient(snakemake.wildcards.case, i.mesh, i.contact, o.csv, o.modes, o.json, o.influence, snakemake.config)
