# Config validation, shared paths and the registries of targets. No physics here.
#
# Each stage's .smk file registers what `rule all` must build by appending to
# FIGURES, SCORECARD_PARTS and TARGETS; the lists are read lazily, after every
# include, so adding a stage is adding one .smk file and its include line.
from snakemake.utils import validate


validate(config, schema="../../config/schema.yaml")

RESULTS = "results"
FIGURES = []  # results/figures/*.png
SCORECARD_PARTS = []  # results/scorecard/<stage>.csv fragments
TARGETS = []  # other final outputs


def measurement_csv():
    """The calibration record every downstream stage reads: the user's file or the synthetic one."""
    user = config["calibration"]["measurement"]
    return user if user else f"{RESULTS}/calibration/measurement.csv"


def final_outputs():
    return (
        FIGURES
        + TARGETS
        + [f"{RESULTS}/scorecard.md", f"{RESULTS}/scorecard.csv"]
    )
