"""The Markdown report of a diagnosis, rendered from its JSON alone.

The engine gives the sections (:mod:`.sections`), each a small function of
the diagnosis dict returning lines; a subject composes its report from them
with its own wording (``Subject.report``; the calibration's is
:func:`piezobearing.diagnosis.calibration.report.render`).
"""

from __future__ import annotations

from .sections import Figures, join

__all__ = ["Figures", "join"]
