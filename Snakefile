# piezobearing: rebuild every figure and number of the paper from code alone.
# Stages live in workflow/rules/*.smk; physics lives in src/piezobearing.
from snakemake.utils import min_version

min_version("9.0")


configfile: "config/config.yaml"


report: "workflow/report/workflow.rst"


include: "workflow/rules/common.smk"
include: "workflow/rules/calibration.smk"
include: "workflow/rules/sensor_fem.smk"
include: "workflow/rules/bearing.smk"
include: "workflow/rules/signals.smk"
include: "workflow/rules/sensor_comparison.smk"
include: "workflow/rules/diagnostics.smk"
include: "workflow/rules/diagnostics_bearing.smk"
include: "workflow/rules/figures.smk"
include: "workflow/rules/scorecard.smk"
include: "workflow/rules/studies.smk"
include: "workflow/rules/detect_archive.smk"
include: "workflow/rules/running_bearing_guide.smk"


rule all:
    default_target: True
    input:
        final_outputs(),
