import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.registry import declared_config
from piezobearing.bearing.reduced_housing import write_housing

config = declared_config(snakemake.params.reads, snakemake.rule)  # the housing's config values only
write_housing(config, snakemake.wildcards.mesh == "faulty", snakemake.output.npz)
