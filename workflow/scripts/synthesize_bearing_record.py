import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.bearing_diagnosis import synthesize_bearing_record
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

synthesize_bearing_record(
    snakemake.input.influence,
    snakemake.output.csv,
    config,
    snakemake.input.harmonic[0] if snakemake.input.harmonic else None,
)
