import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.signals import defect_events

i = snakemake.input
defect_events(i.healthy, i.faulty, i.kinematics, snakemake.output.csv)
