import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.housing_model import write_housing
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # the housing's config values only
write_housing(config, snakemake.wildcards.mesh == "faulty", snakemake.output.npz)
