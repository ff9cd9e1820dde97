import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.fault_types import fault_type_voltage
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

i, o = snakemake.input, snakemake.output
harmonic = i.harmonic[0] if i.harmonic else None
fault_type_voltage(snakemake.wildcards.fault_type, i.resistance, harmonic, o.force, o.csv, o.json, config)
