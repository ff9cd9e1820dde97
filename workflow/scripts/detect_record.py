import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.registry import declared_config
from piezobearing.stages.detect_archive import detect_record

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares
detect_record(snakemake.input.record, snakemake.output.row, config)
