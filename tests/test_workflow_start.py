"""What every Snakemake start of this workflow imports at parse time: the Snakefile's package imports load no SciPy
statistics or signal processing (0.8 of a fresh `snakemake -n`'s 3 CPU s when the diagnosis engine imported them at
its top; the functions that use them import them)."""

import re
import subprocess
import sys

from conftest import REPO


def _snakefile_imports() -> list[str]:
    """The package modules the workflow's .smk files import at their top level."""
    names = set()
    for smk in sorted((REPO / "workflow/rules").glob("*.smk")):
        names.update(re.findall(r"^from (piezobearing[\w.]*) import", smk.read_text(), re.M))
    return sorted(names)


def test_the_snakefile_imports_load_no_scipy_stats_or_signal():
    modules = _snakefile_imports()
    assert "piezobearing.diagnosis.calibration.report" in modules  # the import that used to load them
    code = "import sys\n" + "".join(f"import {m}\n" for m in modules) + (
        "print(sorted(m for m in sys.modules if m in ('scipy.stats', 'scipy.signal', 'scipy.optimize')))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip() == "[]", out.stdout


def test_z99_is_scipys_normal_quantile():
    from scipy.stats import norm

    from piezobearing.diagnosis.residual_tests import Z99

    assert Z99 == float(norm.isf(0.005))
