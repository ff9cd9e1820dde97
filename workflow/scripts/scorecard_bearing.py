import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.bearing import scorecard

i = snakemake.input
scorecard(
    i.kinematics,
    i.lpm,
    {"healthy": i.healthy, "faulty": i.faulty},
    i.convergence,
    i.sampling,
    snakemake.output.csv,
    snakemake.config,
)
