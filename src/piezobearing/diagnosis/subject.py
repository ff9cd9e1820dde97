"""What a diagnosis subject supplies to the engine: the interface between the two.

The engine (:mod:`piezobearing.diagnosis.engine` and the modules it uses:
``noise``, ``fit``, ``residual_tests``, ``selection``, ``verdict``,
``report``) holds a forward model against one measured record. It knows no
physics: a **subject** brings the record, the model and the catalogue. The
calibration record is the first subject (:mod:`piezobearing.diagnosis.calibration`);
the running bearing is the next. Subjects import the engine; the engine
imports no subject (``tests/test_imports.py`` checks it, and that ``src`` has
no import cycle).

A subject is a package ``piezobearing/diagnosis/<subject>/`` with

``effects/``
    its catalogue: one module per effect (physics in the docstring), each an
    :class:`~piezobearing.diagnosis.effect.Effect` subclass whose parameters
    are :class:`~piezobearing.fitting.params.Param` with a unit suffix from
    :data:`piezobearing.fitting.units.UNITS` (the declared value leaves the
    effect neutral), registered in a :class:`~piezobearing.diagnosis.effect.Catalogue`.
    The subject's own effect base class adds the hooks its forward model calls.
a forward model
    satisfying :class:`~piezobearing.diagnosis.model.Model`: baseline
    parameters and **nuisance parameters** (fitted in every model, e.g. the
    start phase and the speed within tolerance of a running bearing), both
    returned by ``Model.params`` before the effects' parameters; the engine
    grows it with ``Model.with_effect``.
a :class:`Subject`
    (below): reads and validates the record, builds the :class:`Problem` the
    engine solves, hides effects in a synthetic record, states the user's
    answer, and composes the report from the engine's sections
    (:mod:`piezobearing.diagnosis.report`).
representations
    the views the residual is judged in besides the engine's whitened time
    residual (which every subject gets: whiteness, correlation with the
    input, spectrum against the floor, energy in time windows): a list of
    :class:`Representation` in the :class:`Problem`, e.g. the error per
    impulse (calibration), or per roller passage, the synchronous average
    over the roller-passage period and the envelope spectrum with the fault
    bands (bearing). Each is evaluated on the baseline and the final fit;
    its findings on the final fit count in the verdict.

The engine's run, in order (:func:`piezobearing.diagnosis.engine.diagnose`):
fit the baseline (``Problem.baseline`` from ``Problem.baseline_start`` and
each of ``Problem.baseline_starts``), add the configured effects
(``Problem.configured``), rank the rest of ``Problem.catalogue`` by BIC and
add them stepwise (:mod:`piezobearing.diagnosis.selection`), test the
residuals, judge the representations, and give the verdict. The noise floor
(``Problem.floor``) is the subject's: measured from the record with
:mod:`piezobearing.diagnosis.noise` (quiet stretches of the input, or any
stretches the subject knows to hold noise alone).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol, Sequence, runtime_checkable

import numpy as np

from .effect import Catalogue, Effect
from .fit import ModelFit
from .model import Model
from .noise import NoiseFloor
from .record import Record, Segments
from .settings import DiagnosticsSettings


@dataclass
class Judgement:
    """A residual judged in one representation.

    Attributes
    ----------
    summary : JSON-ready value
        What the report and the JSON show (a table as a list of dicts, a dict of numbers).
    arrays : dict of ndarray
        Arrays for the figures, saved in the diagnosis NPZ as ``<key>_<fit>_<name>``.
    findings : list of dict
        Structure left, each ``{"test": <key>, "where": <one line>, ...}`` (empty: nothing left).
    """

    summary: Any
    arrays: dict[str, np.ndarray] = field(default_factory=dict)
    findings: list[dict] = field(default_factory=list)


@runtime_checkable
class Representation(Protocol):
    """A view the residual is judged in (error per segment, synchronous average, envelope spectrum)."""

    #: JSON key of its results (``per_impulse``): ``{key: {"baseline": summary, "final": summary}}``.
    key: str

    def judge(self, fit: ModelFit, problem: "Problem", settings: DiagnosticsSettings) -> Judgement:
        """Judge one fitted model's residual (``fit.residual_V``, ``fit.whitened``) in this view."""


@dataclass(frozen=True, eq=False)
class Problem:
    """One record of one subject, ready for the engine.

    Attributes
    ----------
    record : Record
        Time axis and measured input (``record.input`` may be None).
    voltage_V : ndarray
        The measured output the model predicts [V].
    baseline : Model
        The forward model without effects (baseline and nuisance parameters).
    baseline_start : dict
        Start values of the baseline fit (others: the model's defaults).
    baseline_starts : list of dict
        Each overrides some of ``baseline_start`` for one more start; the best fit is kept.
    configured : tuple of Effect
        Effects the user switched on (fitted beside the baseline before the search).
    catalogue : Catalogue
        Every effect the search may add, in the order it tries them.
    floor : NoiseFloor
        The measured noise floor.
    segments : Segments
        Stretches findings are named by (impulses, roller passages).
    representations : sequence of Representation
        Views the residual is judged in besides the whitened time residual.
    zoom_segments : int
        How many consecutive segments the figures show at the full rate (where the baseline misses
        most; :func:`piezobearing.diagnosis.engine.zoom_window`): one impulse, a dozen roller passages.
    profile_evaluations : int or None
        Most forward-model evaluations the final model's interval checks and profiles may spend (None: the
        engine's :data:`~piezobearing.diagnosis.engine.PROFILE_EVALUATIONS`); a subject lowers it for a model
        whose evaluation is costly (intervals beyond it keep the Jacobian's, flagged).
    interval_correlation : bool
        Whether the final model's intervals are widened for the residual's autocorrelation
        (:func:`~piezobearing.fitting.correlation.correlation_factors`; each interval then reports its
        ``correlation_factor``): a subject whose residual keeps model error in time sets it; False: the
        Gauss-Newton and profile intervals of white residuals.
    """

    record: Record
    voltage_V: np.ndarray
    baseline: Model
    baseline_start: dict
    baseline_starts: list[dict]
    configured: tuple[Effect, ...]
    catalogue: Catalogue
    floor: NoiseFloor
    segments: Segments
    representations: Sequence[Representation] = ()
    zoom_segments: int = 1
    profile_evaluations: int | None = None
    interval_correlation: bool = False


@runtime_checkable
class Subject(Protocol):
    """What is diagnosed: the record, its model, its catalogue, its synthesiser and the user's answer.

    Attributes
    ----------
    name : str
        Identifier (``calibration``).
    catalogue : Catalogue
        Its effects.
    figures : tuple of str
        Names of the report's figures, drawn by ``piezobearing.plotting`` (matplotlib stays there).
    """

    name: str
    catalogue: Catalogue
    figures: tuple[str, ...]

    def check_config(self, config: dict) -> None:
        """Raise a one-line EffectError for an unknown effect or parameter in the config (before any job)."""

    def read(self, path: str, config: dict) -> Any:
        """Read and validate a measured record (one-line errors naming the file and the fix)."""

    def problem(self, observation: Any, config: dict) -> Problem:
        """The engine's problem for a record read by :meth:`read` (measures its noise floor)."""

    def synthesise(self, config: dict, seed: int, hidden_effects: list[dict]) -> Any:
        """A synthetic record with catalogue effects hidden in it (``[{name, params}]``), as :meth:`read`
        returns it, so that a test can check that the engine finds them."""

    def answer(self, diagnosis: Any) -> dict:
        """The entries a user wants (for a calibration: the most likely missing effect; for a bearing:
        fault type, size and position), put into the diagnosis JSON after the ranking."""

    def report(self, d: dict, figures: dict[str, str]) -> str:
        """The Markdown report from the diagnosis JSON alone, composed of engine sections."""
