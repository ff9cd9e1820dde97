# Config validation, shared paths and the registries of targets. No physics here.
#
# Each stage's .smk file registers what `rule all` must build by appending to
# FIGURES, SCORECARD_PARTS and TARGETS; the lists are read lazily, after every
# include, so adding a stage is adding one .smk file and its include line.
import os
import sys

from piezobearing.config import ConfigError
from piezobearing.config import results_folder
from piezobearing.config import validate as validate_config
from piezobearing.workflow.registry import (
    RECORD_RULES,
    code_hash,
    declared,
    reads_digest,
    rule_params,
    use_imports_cache,
    user_cache_dir,
)

# The jobs of the two longest chains start first: the fault classification over noise seeds (its rule the
# longest job, ~40 s on the paper config) with every job it needs, and the sensor comparison (its housing model,
# the comparison and its figure, ~35 s). The chains' rules say `priority: LONGEST_CHAINS`; the short jobs
# then fill the other core around them, and a run does not end with one long job alone on one core
# (`benchmarks/bench_command.py paper`; the docs' performance page). Rule priorities order only the jobs a run
# needs (Snakemake's `--prioritize` would add its targets to every run: one file asked for would build both
# chains). tests/test_workflow_quality.py checks that these rules are exactly the chains' jobs.
LONGEST_CHAINS = 1

# what a start computes that the next can reuse, keyed by content (registry.user_cache_dir): each package
# module's imports (the code hashes) and the diagnosis subjects' checks of their settings
CACHE = user_cache_dir()
use_imports_cache(CACHE / "imports.json")

CONFIG_FILES = [
    "config/config.yaml",
    *map(os.path.relpath, workflow.overwrite_configfiles or []),
]
# The config's one validation: the schema (JSON Schema 2020-12, as snakemake.utils.validate uses; it sets no
# defaults) and the cross-field checks, failing in one line naming the key and the fix (snakemake's validate would
# print the whole schema, and calling it too only repeated this check, parsing the schema again: 50 ms a start).
try:
    validate_config(
        config,
        source=" + ".join(CONFIG_FILES),
        schema_path=f"{workflow.basedir}/config/schema.yaml",
    )
except ConfigError as e:
    print(f"piezobearing: {e}", file=sys.stderr)
    sys.exit(1)


# Jobs find the tools of the Python that runs Snakemake (papermill; jupyter_client then starts the notebooks'
# kernel with that Python too) after those already on PATH, so `.venv/bin/snakemake` works without activating
# the venv, and a tool put first on PATH (an activated environment, the tests' stand-ins) still wins.
envvars:
    "PATH",


os.environ["PATH"] = os.pathsep.join(
    [os.environ["PATH"], os.path.dirname(sys.executable)]
)

# Every output of a run under RESULTS: results/ for the paper's case (config `run: paper`), results/<run>/ for
# any other run, so that a variant never overwrites the paper's reproduction.
RESULTS = results_folder(config)
FIGURES = []  # RESULTS/figures/*.png
SCORECARD_PARTS = []  # RESULTS/scorecard/<stage>.csv fragments
TARGETS = []  # other final outputs


def measurement_csv():
    """The calibration record every downstream stage reads: the user's file or the synthetic one."""
    user = config["calibration"]["measurement"]
    return user if user else f"{RESULTS}/calibration/measurement.csv"


def bearing_record():
    """The running-bearing record: the user's file (bearing.measurement) or the synthetic one."""
    user = config["bearing"]["measurement"]
    return user if user else f"{RESULTS}/diagnostics_bearing/synthetic_record.csv"


def sensor_harmonic():
    """The sensor FEM's response where signals.sensor_fem_correction (the one sensor model's correction), else none."""
    return (
        [f"{RESULTS}/sensor/harmonic.csv"]
        if config["signals"]["sensor_fem_correction"]
        else []
    )


def stage_params(rule, entry):
    """A rule's params, from piezobearing.workflow.registry: the config values its stage reads (``reads``, all the
    stage receives), the hash of the package code its script or notebook ``entry`` runs (``code``) and, for
    a rule reading the calibration record, the record's checksum (``record``)."""
    record = config["calibration"]["measurement"] if rule in RECORD_RULES else None
    return rule_params(rule, config, f"{workflow.basedir}/{entry}", record)


# The housing's reduced model (mesh, modes, operators) depends on the housing's config values alone
# (piezobearing.workflow.registry.READS["sensor_comparison_housing"]), not on the speed, the surroundings or the seeds:
# one file per healthy or faulty mesh, named by the digest of those values, which every comparison on that
# mesh reads (the main workflow's and the study's cases). COMPARISON_HOUSINGS maps digest to values.
COMPARISON_HOUSINGS = {}


def comparison_housings(cfg):
    """The housing model files a comparison on config ``cfg`` reads: input names housing_healthy, housing_faulty."""
    digest = reads_digest(cfg, "sensor_comparison_housing")
    COMPARISON_HOUSINGS[digest] = declared(cfg, "sensor_comparison_housing")
    return {
        f"housing_{mesh}": f"{RESULTS}/sensor_comparison/housing/{mesh}_{digest}.npz"
        for mesh in ("healthy", "faulty")
    }


def final_outputs():
    return FIGURES + TARGETS + [f"{RESULTS}/scorecard.md", f"{RESULTS}/scorecard.csv"]


def check_measurement():
    """Stop before any job runs when the configured measurement cannot be used (one line, no traceback)."""
    if not config["calibration"]["measurement"]:
        return
    # the record's readers and checks (pandas, h5py, scipy: about a second at every start), only for a user's record
    from piezobearing.io import MeasurementError
    from piezobearing.stages.calibration import check_record_once

    try:  # once per record content and settings (RESULTS/.checked/), not at every start
        check_record_once(
            config["calibration"]["measurement"], config, f"{RESULTS}/.checked"
        )
    except MeasurementError as e:
        print(f"piezobearing: {e}", file=sys.stderr)
        sys.exit(1)


check_measurement()
