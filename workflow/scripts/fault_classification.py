import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.signals import classification
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

i, o = snakemake.input, snakemake.output
classification({"healthy": i.healthy, "faulty": i.faulty}, i.kinematics, o.json, o.csv, o.roc, config, list(i.types))
