"""Settings of the diagnosis engine (config section ``diagnostics``), the same for every subject."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class DiagnosticsSettings:
    """Settings of the diagnosis (config section ``diagnostics``).

    Parameters
    ----------
    max_steps : int
        Most effects the stepwise selection adds [-].
    min_delta_bic : float
        BIC drop an addition needs (10: "very strong" evidence) [-].
    min_share : float
        Share of the current misfit above the noise floor (chi2 - (n - k)) an addition must explain [-].
    min_share_if_unexplained : float
        When structure remains after the search, the share each kept addition must have explained [-].
    significance : float
        Family-wise false-alarm probability of the four residual tests of the verdict [-].
    max_lag_s : float
        Largest lag of the auto- and cross-correlation tests [s].
    spectrum_segment_s : float
        Segment length of the residual spectrum (its resolution is 1/segment) [s].
    window_s : float
        Length of the windows of the residual-energy test in time [s].
    quiet_settle_s : float
        Time after the force settles before a stretch counts as quiet [s].
    max_nfev : int
        Most model evaluations per fit [-].
    ftol : float
        Relative change of chi2 at which a fit stops (1e-6 of chi2 ~ n is far below any BIC step) [-].
    """

    max_steps: int = 4
    min_delta_bic: float = 10.0
    min_share: float = 0.2
    min_share_if_unexplained: float = 0.5
    significance: float = 0.01
    max_lag_s: float = 0.1
    spectrum_segment_s: float = 2.0
    window_s: float = 0.1
    quiet_settle_s: float = 0.1
    max_nfev: int = 400
    ftol: float = 1e-6

    @classmethod
    def from_config(cls, section: dict | None) -> "DiagnosticsSettings":
        return cls(**(section or {}))

    @property
    def test_alpha(self) -> float:
        """Significance of each of the four residual tests (Bonferroni) [-]."""
        return self.significance / 4
