import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.scorecard import scorecard_bearing as scorecard
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

i = snakemake.input
scorecard(
    i.kinematics,
    i.lpm,
    {"healthy": i.healthy, "faulty": i.faulty},
    i.convergence,
    i.sampling,
    snakemake.output.csv,
    config,
)
