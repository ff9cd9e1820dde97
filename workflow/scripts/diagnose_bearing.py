import sys
from pathlib import Path

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.bearing_diagnosis import diagnose_bearing
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

diagnose_bearing(
    snakemake.input.record,
    Path(snakemake.output.json).parent,
    config,
    snakemake.input.influence,
    progress=lambda msg: print(f"fit: {msg}", file=sys.stderr, flush=True),
    harmonic_csv=snakemake.input.harmonic[0] if snakemake.input.harmonic else None,
)
