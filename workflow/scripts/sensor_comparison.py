import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.sensor_comparison import sensor_comparison
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

i, o = snakemake.input, snakemake.output
sensor_comparison(i.resistance, i.harmonic[0] if i.harmonic else None, i.housing_healthy, i.housing_faulty,
                  o.json, o.spectra, config)
