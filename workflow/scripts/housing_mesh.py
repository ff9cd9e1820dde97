import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.bearing import housing_mesh

o = snakemake.output
housing_mesh(snakemake.wildcards.case, o.npz, o.vtk, o.json, snakemake.config)
