import sys
from pathlib import Path

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.diagnostics import diagnose
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares

diagnose(
    snakemake.input.measurement,
    Path(snakemake.output.json).parent,
    config,
    progress=lambda msg: print(f"fit: {msg}", file=sys.stderr, flush=True),
)
