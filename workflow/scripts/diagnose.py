import sys
from pathlib import Path

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.diagnostics import diagnose

diagnose(
    snakemake.input.measurement,
    Path(snakemake.output.json).parent,
    snakemake.config,
    progress=lambda msg: print(f"fit: {msg}", file=sys.stderr, flush=True),
)
