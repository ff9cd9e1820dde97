import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.detect_archive import detect_record
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares
detect_record(snakemake.input.record, snakemake.output.row, config)
