import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.detect_archive import archive_table
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares
archive_table(list(snakemake.input.rows), snakemake.output.csv, config)
