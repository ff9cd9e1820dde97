import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.signals import snr_study

i, o = snakemake.input, snakemake.output
snr_study({"healthy": i.healthy, "faulty": i.faulty}, i.kinematics, o.csv, o.summary, o.json, snakemake.config)
