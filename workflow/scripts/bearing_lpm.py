import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.registry import declared_config
from piezobearing.stages.bearing import bearing_lpm

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

o = snakemake.output
bearing_lpm(
    o.kinematics,
    {"healthy": o.npz_healthy, "faulty": o.npz_faulty},
    {"healthy": o.csv_healthy, "faulty": o.csv_faulty},
    o.json,
    config,
)
