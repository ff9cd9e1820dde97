import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.signals import classification

i, o = snakemake.input, snakemake.output
classification({"healthy": i.healthy, "faulty": i.faulty}, i.kinematics, o.json, o.csv, o.roc, snakemake.config)
