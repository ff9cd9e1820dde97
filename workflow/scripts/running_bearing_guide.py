import sys
from pathlib import Path

sys.stderr = open(snakemake.log[0], "w")

from piezobearing.stages.running_bearing_guide import running_bearing_guide
from piezobearing.workflow.registry import declared_config

config = declared_config(snakemake.params.reads, snakemake.rule)  # only what the rule declares
running_bearing_guide(Path(snakemake.output.record).parent, config)
