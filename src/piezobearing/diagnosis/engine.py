"""The diagnosis of one record: the engine's run, from the subject's :class:`Problem` to the verdict.

The subject (:mod:`piezobearing.diagnosis.subject`) gives the record, the
measured voltage, the baseline model, the configured effects, the catalogue,
the noise floor, the segments and its representations. :func:`diagnose`

1. fits the baseline by maximum likelihood with the measured noise floor
   (:mod:`~piezobearing.diagnosis.fit`), then the configured effects on top;
2. tests the residual whitened by the floor
   (:mod:`~piezobearing.diagnosis.residual_tests`);
3. ranks the catalogue by evidence and adds effects stepwise, dropping
   stand-ins when structure remains (:mod:`~piezobearing.diagnosis.selection`);
4. judges the subject's representations and gives the verdict
   (:mod:`~piezobearing.diagnosis.verdict`);
5. says how well the record pins the result down: each step's runner-up and
   BIC margin in plain words, the final fit's parameter correlations
   (:mod:`~piezobearing.diagnosis.identifiability`).

:meth:`Diagnosis.to_dict` is the JSON, :func:`arrays` the arrays behind the
figures. NRMSE = rms(residual) / rms(measured voltage) throughout.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from ..fitting.correlation import correlation_factors
from ..fitting.profile import honest_intervals
from .describe import describe
from .fit import ModelFit, fd_to_time, fit_model, likelihood_residual
from .identifiability import correlated_pairs, equivalences, identifiability
from .noise import NoiseFloor
from .record import Record, Segments
from .residual_tests import Z99, ResidualTests, residual_tests
from .selection import Candidate, add_effect, cut_stand_ins, stepwise
from .settings import DiagnosticsSettings
from .subject import Judgement, Problem
from .verdict import findings, verdict

#: Most parameters of the final model whose intervals are profiled (the rest keep the Jacobian's, flagged).
PROFILES = 4
#: Most forward-model evaluations the interval checks and profiles may spend in all (a count, so the
#: diagnosis stays reproducible): a bearing model of 16 parameters (roller_scatter) took over 6 CPU
#: minutes without it; a calibration diagnosis spends 2-4 (its intervals pass the cheap check).
PROFILE_EVALUATIONS = 600


@dataclass
class Diagnosis:
    """Everything the report and the figures need."""

    problem: Problem
    settings: DiagnosticsSettings
    baseline: ModelFit
    configured: ModelFit
    ranking: list[Candidate]
    steps: list[dict]
    fits: list[ModelFit]
    selected: list[str]
    final: ModelFit
    tests: dict[str, ResidualTests]
    judgements: dict[str, dict[str, Judgement]]
    verdict: str
    unexplained: list[dict]
    dropped: list[dict] = field(default_factory=list)
    identifiability: dict = field(default_factory=dict)
    outside: dict = field(default_factory=dict)

    @property
    def record(self) -> Record:
        return self.problem.record

    @property
    def voltage_V(self) -> np.ndarray:
        return self.problem.voltage_V

    @property
    def floor(self) -> NoiseFloor:
        return self.problem.floor

    @property
    def segments(self) -> Segments:
        return self.problem.segments

    def to_dict(self, answer: dict | None = None) -> dict:
        """The JSON-ready diagnosis; ``answer`` (the subject's, :meth:`Subject.answer`) follows the ranking."""
        rec = self.record
        out = {
            "n_samples": rec.n,
            "sample_rate_Hz": rec.sample_rate_Hz,
            "duration_s": float(rec.time_s[-1] - rec.time_s[0]),
            "voltage_rms_V": float(np.sqrt(np.mean(self.voltage_V**2))),
            f"n_{self.segments.name}s": len(self.segments),
            "filled_gaps": rec.filled_gaps(),
            "noise_floor": self.floor.report(),
            "noise_floor_nrmse": self.final.floor_nrmse,
            "baseline": {**self.baseline.summary(), "tests": self.tests["baseline"].summary()},
            "configured": {**self.configured.summary(), "tests": self.tests["configured"].summary()},
            "ranking": [c.summary(self.configured) for c in self.ranking],
            **(answer or {}),
            "selected": self.selected,
            "steps": self.steps,
            "dropped_steps": self.dropped,
            "final": {**self.final.summary(), "tests": self.tests["final"].summary()},
            "verdict": self.verdict,
            "unexplained": self.unexplained,
            "outside_catalogue": self.outside,
            "identifiability": self.identifiability,
            **{key: {k: j.summary for k, j in js.items()} for key, js in self.judgements.items()},
            "settings": self.settings.__dict__,
            "catalogue": self.problem.catalogue.describe(),
        }
        return out


def diagnose(
    problem: Problem,
    settings: DiagnosticsSettings | None = None,
    progress: Callable[[str], None] | None = None,
    baseline: ModelFit | None = None,
    intervals: bool = True,
) -> Diagnosis:
    """The whole diagnosis of one record (see the module docstring); ``baseline``: the baseline already fitted to
    this problem and ``settings`` (a subject's pre-pass fits it), not fitted again. ``intervals=False``: the final
    model keeps the Jacobian's intervals (``identifiability.intervals`` empty), for a run whose final model a
    subject only compares or refits (:func:`refit` gives the honest ones)."""
    settings = settings or DiagnosticsSettings()
    p = problem
    record, v, floor = p.record, np.asarray(p.voltage_V, dtype=float), p.floor
    note = progress or (lambda _msg: None)

    note("baseline")
    baseline = baseline or fit_model(p.baseline, record, v, floor, start=p.baseline_start, starts=p.baseline_starts,
                                      max_nfev=settings.max_nfev, ftol=settings.ftol)
    baseline_names = tuple(q.name for q in p.baseline.params(record))
    current = baseline
    for e in p.configured:
        note(f"configured: + {e.name}")
        current = add_effect(current, e, record, v, floor, settings)
    configured = current

    def tests_of(f: ModelFit) -> ResidualTests:
        return _tests_of(f, p, settings)

    tests = {"baseline": tests_of(baseline)}
    tests["configured"] = tests["baseline"] if configured is baseline else tests_of(configured)
    sel = stepwise(configured, list(p.catalogue.values()), record, v, floor, settings, note, baseline_names)
    tests["final"] = tests_of(sel.fits[-1])
    cut = not tests["final"].passed and cut_stand_ins(sel, settings)
    if cut:
        tests["final"] = tests_of(sel.fits[-1])
    final = sel.fits[-1]
    judgements = {
        r.key: {"baseline": r.judge(baseline, p, settings), "final": r.judge(final, p, settings)}
        for r in p.representations
    }
    if intervals:
        note("intervals of the final model")
        honest = final_intervals(final, record, v, floor, settings, p.profile_evaluations, p.interval_correlation)
    else:
        honest = {}
    found = _final_findings(tests["final"], judgements, p)
    idf = how_firm(sel, final, cut, p, honest)
    return Diagnosis(
        p,
        settings,
        baseline,
        configured,
        sel.ranking,
        sel.steps,
        sel.fits,
        [c.effect.name for c in sel.added],
        final,
        tests,
        judgements,
        verdict(found),
        found,
        sel.dropped,
        idf,
        _describe(final, tests["final"], p, v),
    )


def _tests_of(f: ModelFit, p: Problem, settings) -> ResidualTests:
    rec = p.record
    return residual_tests(f.whitened, rec.input, rec.dt_s, settings, p.segments, rec.time_s, rec.left_out)


def _final_findings(tests_final: ResidualTests, judgements: dict, p: Problem) -> list:
    """What the final model leaves: its residual tests' findings, then each representation's."""
    found = findings(tests_final, p.record.input_name, p.segments)
    for js in judgements.values():
        found += js["final"].findings
    return found


def _describe(final: ModelFit, tests_final: ResidualTests, p: Problem, v: np.ndarray):
    """The final model's residual as :func:`describe` puts it."""
    rec = p.record
    return describe(final.whitened, tests_final.window_t0_s, tests_final.window_ratio, rec.input, rec.input_name,
                    p.segments, v, rec.time_s)


def refit(d: Diagnosis, problem: Problem | None = None, progress: Callable[[str], None] | None = None) -> Diagnosis:
    """``d`` with its final model refitted on ``problem`` from its final values, and the honest intervals.

    ``problem``: the same record and voltage with the model held differently (a subject's finer integration step
    of a costly model, whose search ran at a coarser one); None: ``d``'s own, the final fit kept (a run with
    ``intervals=False`` given its intervals). The final fit's tests, judgements, findings, verdict, correlations
    and intervals are the refit's; the search (ranking, steps, the fits before the final one) stays ``d``'s.
    """
    st = d.settings
    note = progress or (lambda _msg: None)
    p = problem or d.problem
    record, v, floor = p.record, np.asarray(p.voltage_V, dtype=float), p.floor
    final = d.final
    if problem is not None:
        note("final model refitted")
        final = fit_model(d.final.model, record, v, floor, start=d.final.values, max_nfev=st.max_nfev, ftol=st.ftol)
    tests = {**d.tests, "final": _tests_of(final, p, st) if final is not d.final else d.tests["final"]}
    judgements = {r.key: {**d.judgements[r.key], "final": r.judge(final, p, st)} for r in p.representations}
    note("intervals of the final model")
    honest = final_intervals(final, record, v, floor, st, p.profile_evaluations, p.interval_correlation)
    found = _final_findings(tests["final"], judgements, p)
    corr = final.result.correlation
    idf = {**d.identifiability, "correlation": corr, "correlated_pairs": correlated_pairs(corr),
           "intervals": {k: i.report() for k, i in honest.items()}}
    fits = [final if f is d.final else f for f in d.fits]
    return Diagnosis(
        p, st, d.baseline, d.configured, d.ranking, d.steps, fits, list(d.selected), final, tests, judgements,
        verdict(found), found, d.dropped, idf, _describe(final, tests["final"], p, v),
    )


def how_firm(sel, final: ModelFit, cut: bool, p: Problem, intervals: dict) -> dict:
    """The ``identifiability`` block: margins, correlations, equivalences and the final fit's honest intervals."""
    idf = identifiability(
        sel.steps,
        sel.stop,
        final,
        cut,
        equivalences(
            p.catalogue.values(),
            {c.effect.name for c in sel.added} | {c.effect.name for c in sel.ranking[:1]},
            sel.ranking,
        ),
    )
    idf["intervals"] = {k: i.report() for k, i in intervals.items()}
    return idf


def final_intervals(final: ModelFit, record: Record, v: np.ndarray, floor: NoiseFloor, settings,
                    max_evaluations: int | None = None, correlation: bool = False) -> dict:
    """Honest 95% intervals of the final model's parameters (:func:`~piezobearing.fitting.profile.honest_intervals`).

    The Jacobian interval of each free parameter is checked along its
    quadratic profile line and profiled where it fails; the final fit's
    ``ci95`` then holds the honest interval and ``ci95_jacobian`` the Jacobian's. ``max_evaluations``: the
    budget of model evaluations (None: :data:`PROFILE_EVALUATIONS`). ``correlation``: each interval widened for
    the residual's autocorrelation (:func:`correlation_factors`, the subject's
    :attr:`~piezobearing.diagnosis.subject.Problem.interval_correlation`).
    """
    res = final.result
    params = final.model.params(record, res.values)
    out = honest_intervals(
        likelihood_residual(final.model, record, v, floor, final.scale),
        params,
        res,
        max_profiles=PROFILES,
        max_nfev=settings.max_nfev,
        ftol=settings.ftol,
        max_evaluations=PROFILE_EVALUATIONS if max_evaluations is None else max_evaluations,
        inflation=interval_factors(res, params) if correlation else None,
    )
    final.model.release()
    res.ci95_jacobian = dict(res.ci95)
    res.ci95 = {**res.ci95, **{k: i.ci for k, i in out.items()}}
    return out


def interval_factors(res, params) -> dict[str, float]:
    """Each free parameter's factor on its variance for the residual's autocorrelation
    (:func:`~piezobearing.fitting.correlation.correlation_factors`), read from the fit's residual and Jacobian in
    the likelihood's weighted DFT bins mapped back to time (:func:`~piezobearing.diagnosis.fit.fd_to_time`: the
    residual whitened by the floor, in which a correct model leaves white noise); {} without a Jacobian."""
    free = [q.name for q in params if q.vary]
    if res.jacobian is None or res.jacobian.shape[1] != len(free):
        return {}
    f = correlation_factors(fd_to_time(res.jacobian), fd_to_time(res.residual), res.n_data)
    return {n: float(x) for n, x in zip(free, f, strict=True)}


# =========================================================================== arrays for figures


def residual_psd(x: np.ndarray, dt_s: float, segment_s: float) -> tuple[np.ndarray, np.ndarray]:
    """One-sided PSD [unit^2/Hz] from non-overlapping Hann segments (the segmentation of the spectrum test)."""
    n = x.size
    seg = int(min(round(segment_s / dt_s), n))
    k = max(n // seg, 1)
    win = np.hanning(seg)
    segs = x[: k * seg].reshape(k, seg)
    segs = segs - segs.mean(axis=1, keepdims=True)
    p = np.mean(np.abs(np.fft.rfft(segs * win, axis=1)) ** 2, axis=0) / np.sum(win**2)
    return np.fft.rfftfreq(seg, dt_s), 2 * p * dt_s


#: Full-length series longer than this are stored for the figures as a min/max envelope of this many
#: points (two per bin, :func:`envelope_thin`), so diagnosis.npz stays a few MB for a record of any
#: length; the stretch the figures zoom on (:func:`zoom_window`) is kept at the full rate.
DISPLAY_POINTS = 20_000


def _display_bins(n: int, points: int) -> tuple[int, int]:
    """Samples per bin and number of bins of :func:`envelope_thin` for ``n`` samples, two points per bin."""
    size = -(-n // (points // 2))
    return size, -(-n // size)


def envelope_thin(x: np.ndarray, points: int = DISPLAY_POINTS) -> np.ndarray:
    """``x`` as at most ``points`` values: per bin of ``ceil(2 n / points)`` samples its minimum and
    maximum in the order they occur, which is what a line plot of ``x`` at that width shows. Unchanged
    if short."""
    x = np.asarray(x)
    n = x.size
    if n <= points:
        return x
    bs, bins = _display_bins(n, points)
    xp = np.concatenate([x, np.full(bins * bs - n, x[-1], dtype=x.dtype)]).reshape(bins, bs)
    i_lo, i_hi = xp.argmin(axis=1), xp.argmax(axis=1)
    rows = np.arange(bins)
    lo, hi = xp[rows, i_lo], xp[rows, i_hi]
    first = np.where(i_lo <= i_hi, lo, hi)
    second = np.where(i_lo <= i_hi, hi, lo)
    return np.stack([first, second], axis=1).ravel()


def thinned_time(time_s: np.ndarray, points: int = DISPLAY_POINTS) -> np.ndarray:
    """The time axis of :func:`envelope_thin`: each bin's two values at its first and third quarter [s]."""
    n = time_s.size
    if n <= points:
        return time_s
    bs, bins = _display_bins(n, points)
    pos = (np.arange(bins)[:, None] * bs + np.array([0.25, 0.75]) * bs).ravel()
    return np.interp(np.minimum(pos, n - 1), np.arange(n), time_s)


def zoom_window(residual_V: np.ndarray, seg: Segments, count: int) -> tuple[int, int]:
    """Sample range [start, stop) of the ``count`` consecutive segments where ``residual_V`` has the
    largest mean square (the whole record if it has no more segments than that)."""
    start, stop = np.asarray(seg.start, dtype=int), np.asarray(seg.stop, dtype=int)
    n = residual_V.size
    if start.size == 0:
        return 0, n
    if start.size <= count:
        return int(start[0]), int(min(stop[-1], n))
    c = np.concatenate([[0.0], np.cumsum(residual_V**2)])
    lo, hi = start[: start.size - count + 1], np.minimum(stop[count - 1 :], n)
    k = int(np.argmax((c[hi] - c[lo]) / np.maximum(hi - lo, 1)))
    return int(lo[k]), int(hi[k])


def arrays(d: Diagnosis, points: int = DISPLAY_POINTS) -> dict[str, np.ndarray]:
    """The arrays the figures need (saved as diagnosis.npz next to diagnosis.json).

    Full-length series (time, input, voltage, each model's voltage and residual, the quiet mask) are
    stored through :func:`envelope_thin` with ``points`` points; ``zoom_*`` holds the stretch of
    ``problem.zoom_segments`` segments where the baseline misses most at the full rate
    (``zoom_start``/``zoom_stop``: its sample range). Segment indices (``<segment>_start`` ...) refer
    to the full record: sample i is at ``t0_s + i dt_s``.
    """
    rec, st, seg = d.record, d.settings, d.segments
    series = {"time_s": rec.time_s}
    if rec.input is not None:
        series[rec.input_key] = rec.input
    series["voltage_V"] = d.voltage_V
    series["quiet_mask"] = (
        np.zeros(rec.n, np.int8) if d.floor.quiet_mask is None else d.floor.quiet_mask.astype(np.int8)
    )
    fits = (("baseline", d.baseline), ("configured", d.configured), ("final", d.final))
    for key, f in fits:
        series[f"{key}_model_V"] = f.model_V
        series[f"{key}_residual_V"] = f.residual_V
    z0, z1 = zoom_window(d.baseline.residual_V, seg, d.problem.zoom_segments)
    out = {k: thinned_time(a, points) if k == "time_s" else envelope_thin(a, points) for k, a in series.items()}
    out.update({f"zoom_{k}": a[z0:z1] for k, a in series.items() if k != "quiet_mask"})
    out.update(
        {
            "t0_s": np.array(float(rec.time_s[0])),
            "dt_s": np.array(float(rec.dt_s)),
            "zoom_start": np.array(z0),
            "zoom_stop": np.array(z1),
            f"{seg.name}_start": np.asarray(seg.start, dtype=int),
            f"{seg.name}_stop": np.asarray(seg.stop, dtype=int),
            f"{seg.name}_peak": np.asarray(seg.anchor_index, dtype=int),
        }
    )
    for key, f in fits:
        t = d.tests[key]
        freq, psd = residual_psd(f.residual_V, rec.dt_s, st.spectrum_segment_s)
        s = d.floor.spectrum(f.response)
        floor_psd = 2 * np.interp(freq, rec.freq_Hz, np.broadcast_to(s, rec.freq_Hz.shape)) * rec.dt_s
        out.update(
            {
                f"{key}_psd_freq_Hz": freq,
                f"{key}_psd_V2_per_Hz": psd,
                f"{key}_floor_psd_V2_per_Hz": floor_psd,
                f"{key}_threshold_psd_V2_per_Hz": floor_psd * t.spec_threshold,
                f"{key}_acf_lags_s": t.acf_lags_s,
                f"{key}_acf": t.acf,
                f"{key}_xcf_lags_s": t.xcf_lags_s,
                f"{key}_xcf": t.xcf,
                f"{key}_window_t0_s": t.window_t0_s,
                f"{key}_window_ratio": t.window_ratio,
            }
        )
        out[f"{key}_acf_threshold"] = np.array(t.acf_threshold)
        out[f"{key}_xcf_threshold"] = np.array(t.xcf_threshold)
        out[f"{key}_window_threshold"] = np.array(t.window_threshold)
    for rkey, js in d.judgements.items():
        for fkey, j in js.items():
            out.update({f"{rkey}_{fkey}_{name}": a for name, a in j.arrays.items()})
    out["band99"] = np.array(Z99 / np.sqrt(rec.n))
    return out
