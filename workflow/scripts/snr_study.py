import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.signals import snr_study
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

i, o = snakemake.input, snakemake.output
snr_study({"healthy": i.healthy, "faulty": i.faulty}, i.kinematics, o.csv, o.summary, o.json, config)
