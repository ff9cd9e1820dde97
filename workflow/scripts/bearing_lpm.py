import sys

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.bearing import bearing_lpm

o = snakemake.output
bearing_lpm(
    o.kinematics,
    {"healthy": o.npz_healthy, "faulty": o.npz_faulty},
    {"healthy": o.csv_healthy, "faulty": o.csv_faulty},
    o.json,
    snakemake.config,
)
