"""Which effects the record supports: rank the catalogue by evidence, add stepwise, drop stand-ins.

1. Rank: every catalogue effect not yet in the model is added to it in turn
   and refitted (warm-started from the current values and the effect's own
   starts); the evidence is the BIC drop (BIC = chi2 + k ln n with the
   measured noise) and the share of the misfit above the noise floor
   (chi2 - (n - k)) the effect explains.
2. Add: the best candidate is kept while its BIC drop exceeds
   ``min_delta_bic`` and it explains at least ``min_share`` of that misfit
   (:func:`accepted`, the same rule for every effect), at most ``max_steps`` times.
3. Drop: when structure remains after the search, an effect added on the
   way may only stand in for the missing mechanism (a catalogue effect can
   mimic the low-frequency behaviour of, say, a resonance); the selection is
   then cut at the first addition that explained less than
   ``min_share_if_unexplained`` of the misfit left at its step (:func:`cut_stand_ins`).

Identifiability: every step records its runner-up (the second-best
candidate of that step's ranking) and the BIC margin between the two, and
:func:`strength` puts a BIC difference into the words of Kass & Raftery
(1995, "Bayes factors", J. Am. Stat. Assoc. 90, 773-795, Sec. 3.2): on the
scale 2 ln B, which the BIC difference approximates, > 10 is "decisive"
(their "very strong"), 6-10 "strong", 2-6 "positive" and < 2 "weak" (not
worth more than a bare mention).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..fitting.least_squares import InfeasibleError
from .effect import Effect, StartContext
from .fit import ModelFit, fit_model
from .noise import NoiseFloor
from .record import Record
from .residual_tests import ResidualTests, residual_tests
from .settings import DiagnosticsSettings


@dataclass
class Candidate:
    """An effect added to the current model and refitted."""

    effect: Effect
    fit: ModelFit
    delta_bic: float
    excess_explained: float
    tests: ResidualTests | None = None
    param_names: tuple[str, ...] = ()
    baseline_names: tuple[str, ...] = ()

    def summary(self, current: ModelFit) -> dict:
        names = self.param_names
        v = self.fit.values
        return {
            "effect": self.effect.name,
            "title": self.effect.title,
            "delta_bic": self.delta_bic,
            "delta_chi2": current.chi2 - self.fit.chi2,
            "nrmse": self.fit.nrmse,
            "nrmse_before": current.nrmse,
            "noise_floor_nrmse": self.fit.floor_nrmse,
            "excess_explained": self.excess_explained,
            "whiteness_p": self.tests.ljung_box_p if self.tests else None,
            "white": self.tests.white if self.tests else None,
            "params": {k: v[k] for k in v if k in names},
            "stderr": {k: self.fit.result.stderr.get(k) for k in names},
            "ci95": {k: self.fit.result.ci95.get(k) for k in names},
            **{k: v[k] for k in self.baseline_names},
            "summary": self.effect.summary({k: v[k] for k in v if k in names}),
        }


def add_effect(
    current: ModelFit,
    effect: Effect,
    record: Record,
    voltage_V: np.ndarray,
    floor: NoiseFloor,
    settings: DiagnosticsSettings,
) -> ModelFit:
    """Fit current model + effect, warm-started from the current values and the effect's starts.

    An effect whose shape has a structural choice (the knot count of a spline drift) offers its
    :meth:`~piezobearing.diagnosis.effect.Effect.variants`, simplest first: they are fitted in turn and
    the one of lowest BIC kept, stopping at the first that does not lower it (a greedy search: a clean
    record costs two fits, not one per variant). Then the kept variant's
    :meth:`~piezobearing.diagnosis.effect.Effect.refinements` (a kink on the chosen spline) are fitted the
    same way, each kept while it lowers BIC.
    """
    ctx = StartContext(record, voltage_V, current.model_V, current.values)

    def fit_form(form: Effect) -> ModelFit:
        return fit_model(
            current.model.with_effect(form),
            record,
            voltage_V,
            floor,
            start=dict(current.values),
            starts=form.starts(ctx),
            max_nfev=settings.max_nfev,
            ftol=settings.ftol,
        )

    best, kept = None, effect
    for variant in effect.variants(ctx):
        f = fit_form(variant)
        if best is not None and f.bic >= best.bic:
            break
        best, kept = f, variant
    for form in kept.refinements(ctx):
        f = fit_form(form)
        if f.bic >= best.bic:
            break
        best = f
    return best


def rank(
    current: ModelFit,
    effects: list[Effect],
    record: Record,
    voltage_V: np.ndarray,
    floor: NoiseFloor,
    settings: DiagnosticsSettings,
    progress: Callable[[str], None] | None = None,
    baseline_names: tuple[str, ...] = (),
) -> list[Candidate]:
    """Every effect added to the current model in turn, best evidence (largest BIC drop) first.

    ``baseline_names`` are the baseline and nuisance parameters each candidate reports refitted.
    """
    out = []
    for e in effects:
        if progress:
            progress(f"{current.model.label} + {e.name}")
        try:
            f = add_effect(current, e, record, voltage_V, floor, settings)
        except InfeasibleError as err:  # no start of the effect has a solution of the model: not a candidate
            if progress:
                progress(f"{current.model.label} + {e.name}: left out ({err})")
            continue
        drop = current.chi2 - f.chi2
        explained = float(np.clip(drop / max(current.excess, drop, 1e-12), 0.0, 1.0))
        tests = residual_tests(f.whitened, record.input, record.dt_s, settings, filled=record.left_out)
        out.append(
            Candidate(
                e,
                f,
                current.bic - f.bic,
                explained,
                tests,
                tuple(k for k in f.values if k not in current.values),  # the chosen variant's parameters
                baseline_names,
            )
        )
    out.sort(key=lambda c: -c.delta_bic)
    out = yield_ties(out)
    # only the best can become the next step's model: the others keep their numbers, not their series
    for c in out[1:]:
        c.fit = c.fit.compact()
    return out


def yield_ties(cands: list[Candidate]) -> list[Candidate]:
    """Put an effect after the one it declares itself exactly equivalent to when they tie (margin < 2).

    Exactly equivalent effects fit a record equally well; which comes first is then decided by
    rounding in the optimiser. The declaring effect yields, so the order is reproducible, and the
    diagnosis states the equivalence (:mod:`~piezobearing.diagnosis.identifiability`).
    """
    out = list(cands)
    for i in range(len(out) - 1):
        a, b = out[i], out[i + 1]
        if b.effect.name in a.effect.equivalent_to and a.delta_bic - b.delta_bic < 2.0:
            out[i], out[i + 1] = b, a
    return out


def equivalent_in(effect: Effect, model_effects) -> bool:
    """Whether ``effect`` is exactly equivalent to an effect already in the model (adding it adds nothing)."""
    names = {e.name for e in model_effects}
    return bool(names & set(effect.equivalent_to)) or any(effect.name in e.equivalent_to for e in model_effects)


def accepted(c: Candidate, settings: DiagnosticsSettings) -> bool:
    """The evidence rule, the same for every effect."""
    return c.delta_bic > settings.min_delta_bic and c.excess_explained >= settings.min_share


def strength(delta_bic: float | None) -> str | None:
    """The plain-words strength of a BIC difference (Kass & Raftery 1995, see the module docstring)."""
    if delta_bic is None or not np.isfinite(delta_bic):
        return None
    if delta_bic > 10:
        return "decisive"
    if delta_bic > 6:
        return "strong"
    if delta_bic > 2:
        return "positive"
    return "weak"


def runner_up(cands: list[Candidate]) -> dict:
    """The second-best candidate of a ranking and the BIC margin of the best over it.

    The margin is BIC(model + runner-up) - BIC(model + best) = the difference of the two
    candidates' BIC drops: how strongly the record prefers the winner to its closest rival.
    """
    if len(cands) < 2:
        return {"runner_up": None, "runner_up_delta_bic": None, "margin_bic": None, "margin_strength": None}
    best, second = cands[0], cands[1]
    margin = float(best.delta_bic - second.delta_bic)
    return {
        "runner_up": second.effect.name,
        "runner_up_delta_bic": float(second.delta_bic),
        "margin_bic": margin,
        "margin_strength": strength(margin),
    }


def step_entry(f: ModelFit, added: str | None, c: Candidate | None, rivals: dict | None = None) -> dict:
    """One row of the error ladder: the model after a step, the evidence for the step and its runner-up."""
    return {
        "effects": f.model.names,
        "added": added,
        "nrmse": f.nrmse,
        "noise_floor_nrmse": f.floor_nrmse,
        "bic": f.bic,
        "chi2": f.chi2,
        "n_free": f.n_free,
        "delta_bic": c.delta_bic if c else None,
        "excess_explained": c.excess_explained if c else None,
        "strength": strength(c.delta_bic) if c else None,
        **(rivals or {}),
        "params": f.values,
    }


@dataclass
class Selection:
    """The stepwise search: the first ranking, each step's candidate and fit, and the ladder rows.

    ``fits[0]`` and ``steps[0]`` are the configured model (before the search).
    ``stop`` is the step that added nothing: its best candidate, BIC drop and
    strength, and its runner-up (None when the catalogue ran out or
    ``max_steps`` was reached).
    """

    ranking: list[Candidate]
    added: list[Candidate]
    steps: list[dict]
    fits: list[ModelFit]
    dropped: list[dict]
    stop: dict | None = None


def stepwise(
    configured: ModelFit,
    catalogue: list[Effect],
    record: Record,
    voltage_V: np.ndarray,
    floor: NoiseFloor,
    settings: DiagnosticsSettings,
    progress: Callable[[str], None] | None = None,
    baseline_names: tuple[str, ...] = (),
) -> Selection:
    """Rank and add effects from ``catalogue`` to the configured model while :func:`accepted` holds."""
    current = configured
    steps = [step_entry(configured, None, None)]
    fits = [configured]
    added: list[Candidate] = []
    ranking: list[Candidate] = []
    stop = None
    for step in range(settings.max_steps):
        remaining = [
            e
            for e in catalogue
            if e.name not in current.model.names and not equivalent_in(e, current.model.effects)
        ]
        if not remaining:
            break
        cands = rank(current, remaining, record, voltage_V, floor, settings, progress, baseline_names)
        if step == 0:
            ranking = cands
        best = cands[0]
        if not accepted(best, settings):
            stop = {
                "best": best.effect.name,
                "delta_bic": float(best.delta_bic),
                "strength": strength(best.delta_bic),
                "excess_explained": best.excess_explained,
                **runner_up(cands),
            }
            break
        current = best.fit
        added.append(best)
        steps.append(step_entry(current, best.effect.name, best, runner_up(cands)))
        fits.append(current)
    return Selection(ranking, added, steps, fits, [], stop)


def cut_stand_ins(sel: Selection, settings: DiagnosticsSettings) -> bool:
    """Cut ``sel`` at the first addition that explained less than ``min_share_if_unexplained`` of the
    misfit left at its step (call when structure remains); returns whether it cut."""
    weak = [i for i, c in enumerate(sel.added) if c.excess_explained < settings.min_share_if_unexplained]
    if not weak:
        return False
    cut = weak[0]
    sel.dropped = [
        {
            **sel.steps[i + 1],
            "reason": f"structure remains and this addition explained "
            f"{c.excess_explained:.0%} (< {settings.min_share_if_unexplained:.0%}) of the misfit "
            "left at its step: it may stand in for an effect outside the catalogue",
        }
        for i, c in enumerate(sel.added)
        if i >= cut
    ]
    sel.added, sel.steps, sel.fits = sel.added[:cut], sel.steps[: cut + 1], sel.fits[: cut + 1]
    return True
