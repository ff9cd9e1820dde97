"""Copy records of the shared CWRU fan-end set into tests/data/cwru/, cropped to their first 5 s.

Run from the repository root: ``python tests/data/cwru/crop.py ../shared/data/cwru_fan_end``. Each record
keeps its layout (MATLAB v5; ``Xnnn_FE_time`` and ``Xnnn_DE_time`` columns, the 1 x 1 ``XnnnRPM``; no time
vector), and its rig file is copied beside it.
"""

import shutil
import sys
from pathlib import Path

from scipy.io import loadmat, savemat

RECORDS = ("fe37", "fe39", "fe44")
SECONDS = 5.0
RATE_HZ = 12000.0

source = Path(sys.argv[1] if len(sys.argv) > 1 else "../shared/data/cwru_fan_end")
here = Path(__file__).parent
for name in RECORDS:
    variables = loadmat(source / f"{name}.mat")
    kept = {k: v for k, v in variables.items() if not k.startswith("__") and (k.endswith("RPM") or k.endswith(("_FE_time", "_DE_time")))}
    cropped = {k: (v if k.endswith("RPM") else v[: int(SECONDS * RATE_HZ)]) for k, v in kept.items()}
    savemat(here / f"{name}.mat", cropped, format="5", do_compression=True)
    shutil.copy(source / f"{name}.yaml", here / f"{name}.yaml")
