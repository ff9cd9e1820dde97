import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.signals import indicator

i = snakemake.input
envelopes = {c: (i[f"{c}_csv"], i[f"{c}_json"]) for c in ("healthy", "faulty")}
noisy = {c: i[f"{c}_noisy"] for c in ("healthy", "faulty")}
noisy_csvs = {c: i[f"{c}_noisy_csv"] for c in ("healthy", "faulty")}
indicator(envelopes, i.kinematics, noisy, snakemake.output.json, snakemake.config, noisy_csvs)
