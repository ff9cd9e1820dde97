"""All plotting of the project; the only package that imports matplotlib.

:func:`use_style` applies the one style file of every figure
(``piezobearing.mplstyle``). Each area has its own module with functions that
take loaded results and return a :class:`matplotlib.figure.Figure`.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

STYLE = Path(__file__).with_name("piezobearing.mplstyle")


def use_style() -> None:
    """Apply the project's matplotlib style."""
    plt.style.use(STYLE)


def save(fig, path: str | Path) -> None:
    """Save a figure as PNG, creating the folder."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path)
    plt.close(fig)
