import sys
from pathlib import Path

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.bearing_diagnosis import diagnose_bearing

diagnose_bearing(
    snakemake.input.record,
    Path(snakemake.output.json).parent,
    snakemake.config,
    snakemake.input.influence,
    progress=lambda msg: print(f"fit: {msg}", file=sys.stderr, flush=True),
)
