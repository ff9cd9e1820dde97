import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.signals import indicator
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

i = snakemake.input
cases = ("healthy", "faulty")
envelopes = {c: i[f"{c}_envelope"] for c in cases}
noisy_csvs = {c: i[f"{c}_noisy_csv"] for c in cases}
noisy_jsons = {c: i[f"{c}_noisy"] for c in cases}
indicator(envelopes, i.kinematics, noisy_csvs, noisy_jsons, snakemake.output.json, config)
