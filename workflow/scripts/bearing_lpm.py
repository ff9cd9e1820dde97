import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.bearing import bearing_lpm
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

o = snakemake.output
bearing_lpm(
    o.kinematics,
    {"healthy": o.npz_healthy, "faulty": o.npz_faulty},
    {"healthy": o.csv_healthy, "faulty": o.csv_faulty},
    o.json,
    config,
)
