"""The running-bearing guide's example as a rule (``running_bearing_guide``, workflow/rules/running_bearing_guide.smk,
outside ``rule all``): one record of the dynamic LPM diagnosed without, then with the dynamic rung.

The record is the guide's (docs/guides/running_bearing.md, "When the verdict asks for the shaft's dynamics"): a
0.6 mm outer-race groove 0.35 rad (20 deg) from the sensor with 1.5 % cage slip, 2 s at 2550 Hz, 30 dB
(:data:`EXAMPLE`, the case ``outer_race_defect+cage_slip`` of validation/bearing_diagnosis.py with its default
seed), written to ``record.csv``. Each diagnosis is that of ``piezobearing diagnose-bearing RECORD`` with the
config's housing solved for its influence line and the paper sensor's response: ``diag_qs`` with
``bearing_diagnosis.dynamic_rung: off``, ``diag_dyn`` with the config's own (``auto``). The guide's figures are
their ``figures/ladder.png``, copied to the site by ``python scripts/docs_figures.py --only running_bearing``.
The rule writes into ``RESULTS/diagnostics_bearing/guide/`` (a folder of the run's diagnostics_bearing, beside the
workflow's own record's diagnosis).
"""

from __future__ import annotations

import copy
import sys
from pathlib import Path

from ..diagnosis.bearing.lpm_records import lpm_record
from ..io import write_bearing_record
from .bearing_diagnosis import diagnose_bearing, influence_from_config

#: The guide's record: hidden catalogue values, sample rate [Hz], length [s], SNR [dB] and the noise's seed.
EXAMPLE = {
    "hidden": {"outer_defect_width_m": 0.6e-3, "outer_defect_angle_rad": 0.35, "cage_slip_ratio": 0.015},
    "sample_rate_Hz": 2550.0,
    "duration_s": 2.0,
    "snr_dB": 30.0,
    "seed": 26,
}


def running_bearing_guide(out_dir: str | Path, config: dict) -> dict:
    """Write ``record.csv``, ``diag_qs/`` and ``diag_dyn/`` (each a ``diagnose-bearing`` folder) into ``out_dir``;
    returns the two diagnoses by folder name."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    influence = influence_from_config(config)
    e = EXAMPLE
    rec = lpm_record(config, influence, e["hidden"], e["sample_rate_Hz"], e["duration_s"], e["snr_dB"], e["seed"])
    record = out_dir / "record.csv"
    write_bearing_record(rec, record)
    out = {}
    for name, rung in (("diag_qs", "off"), ("diag_dyn", config["bearing_diagnosis"]["dynamic_rung"])):
        c = copy.deepcopy(config)
        c["bearing"]["measurement"] = str(record)
        c["bearing_diagnosis"]["dynamic_rung"] = rung
        out[name] = diagnose_bearing(str(record), out_dir / name, c,
                                     progress=lambda msg, n=name: print(f"{n}: {msg}", file=sys.stderr, flush=True),
                                     config_sets_speed=False)
    return out
