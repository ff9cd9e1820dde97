"""How well one record pins down the diagnosis: selection margins and parameter correlations.

- Each step of the stepwise search (:mod:`~piezobearing.diagnosis.selection`)
  with its runner-up and the BIC margin of the winner over it, in the plain
  words of Kass & Raftery (1995, J. Am. Stat. Assoc. 90, 773-795): > 10
  "decisive", 6-10 "strong", 2-6 "positive", < 2 "weak"
  (:func:`~piezobearing.diagnosis.selection.strength`). A weak margin means
  the record cannot tell the winner from its runner-up: report both.
- The step that stopped the search (the best candidate not kept, and how
  strongly the record speaks against it).
- The correlation matrix of the final fit's parameters from the Gauss-Newton
  covariance (J^T J)^-1 (in the fit's internal coordinates: log10 for
  ``log`` parameters, to first order the correlation of the relative
  errors), and every pair with |r| >= :data:`CORRELATED`: such a pair is
  determined as a combination, not one by one.
- The exact equivalences that effects of the catalogue declare
  (``Effect.equivalent_to``) between an effect selected or ranked first and
  another: the record cannot choose between them, and the statement says
  which combinations it determines.
"""

from __future__ import annotations

from .fit import ModelFit

#: |correlation| from which a pair of fitted parameters is reported as nearly confounded.
CORRELATED = 0.9


def correlated_pairs(correlation: dict[str, dict[str, float]], threshold: float = CORRELATED) -> list[dict]:
    """Every pair of parameters with |r| >= ``threshold``, largest first."""
    names = list(correlation)
    out = []
    for i, a in enumerate(names):
        for b in names[i + 1 :]:
            r = correlation[a].get(b)
            if r is not None and abs(r) >= threshold:
                out.append({"params": [a, b], "correlation": r})
    return sorted(out, key=lambda p: -abs(p["correlation"]))


def equivalences(catalogue, named: set[str], ranking: list) -> list[dict]:
    """The declared exact equivalences (``Effect.equivalent_to``) that touch an effect in ``named``.

    Each with its statement and, from the first ranking, both effects' BIC drops and fitted values.
    """
    first = {c.effect.name: c for c in ranking}
    out = []
    for e in catalogue:
        for other, text in e.equivalent_to.items():
            if not ({e.name, other} & named):
                continue
            row = {"effects": [other, e.name], "statement": text}
            for n in (other, e.name):
                if n in first:
                    row[n] = {
                        "delta_bic": float(first[n].delta_bic),
                        "summary": first[n].effect.summary(
                            {k: first[n].fit.values[k] for k in first[n].param_names}
                        ),
                    }
            out.append(row)
    return out


def identifiability(
    steps: list[dict], stop: dict | None, final: ModelFit, cut: bool, equivalent: list[dict] | None = None
) -> dict:
    """The JSON block ``identifiability`` of a diagnosis.

    ``steps`` are the kept steps (``steps[0]`` the configured model), ``stop``
    the step that added nothing (ignored when stand-ins were ``cut``: the search
    then stopped for want of a whitening effect, not for want of evidence).
    """
    keys = (
        "added",
        "delta_bic",
        "strength",
        "runner_up",
        "runner_up_delta_bic",
        "margin_bic",
        "margin_strength",
    )
    corr = final.result.correlation
    return {
        "scale": "Kass & Raftery (1995) on the BIC difference: >10 decisive, 6-10 strong, 2-6 positive, <2 weak",
        "steps": [{k: s.get(k) for k in keys} for s in steps[1:]],
        "stop": None if cut else stop,
        "correlation": corr,
        "correlated_pairs": correlated_pairs(corr),
        "correlation_threshold": CORRELATED,
        "equivalences": equivalent or [],
    }
