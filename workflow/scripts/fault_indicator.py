import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.registry import declared_config
from piezobearing.stages.signals import indicator

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

i = snakemake.input
envelopes = {c: (i[f"{c}_csv"], i[f"{c}_json"]) for c in ("healthy", "faulty")}
noisy = {c: i[f"{c}_noisy"] for c in ("healthy", "faulty")}
noisy_csvs = {c: i[f"{c}_noisy_csv"] for c in ("healthy", "faulty")}
indicator(envelopes, i.kinematics, noisy, snakemake.output.json, config, noisy_csvs)
