r"""A healthy bearing that is not silent: surface roughness, waviness and the shaft's unbalance.

A real healthy bearing has a vibration floor of its own. Three of its sources enter the LPM
(:mod:`piezobearing.bearing.lpm`) here, each off at zero (the paper's case) and each drawn anew per
realisation from the config's seed:

**Roughness.** Each raceway and each roller carries a random profile h(s) along its circumference in the
rolling direction (arc length s [m]): Gaussian, stationary, with the exponential autocorrelation that
describes ground surfaces (Whitehouse & Archard, Proc. R. Soc. Lond. A 316 (1970) 97-121),

.. math::
    R(x) = \sigma^2 e^{-|x| / \beta}, \qquad
    S(f) = \frac{2 \sigma^2 \beta}{1 + (2 \pi f \beta)^2}

(S the two-sided spectral density per unit spatial frequency f [cycles/m]; sigma the RMS ``roughness_rms_m``,
beta the correlation length ``roughness_correlation_length_m``). The RMS is assumed: a bearing superfinishing
guide gives raceways Ra 0.1 um ground and Ra <= 0.02 um superfinished (Rq about 1.25 Ra for a Gaussian profile),
and 0.05-0.3 um is the range quoted with the lubricant film parameter Lambda (Harris & Kotzalas, Essential
Concepts of Bearing Technology, 5th ed., CRC 2007; not checked against its text): docs/theory/bearing_housing.md
gives the sources. Correlation lengths of ground surfaces are micrometres to tens of micrometres (Whitehouse &
Archard).
The profile is drawn on a periodic grid of the surface's circumference with exactly that covariance (a
circulant embedding of R: its DFT is the discrete spectrum, :func:`discrete_spectrum`), so its variance is
sigma^2 and its expected periodogram the discrete spectrum.

A line contact does not feel wavelengths shorter than its width: the contact sees the profile averaged over
the Hertzian contact width 2b (a box filter, H(f) = sinc(2 b f)), with b of the most loaded roller
(:func:`contact_half_width_m`, Johnson, Contact Mechanics, 1985, Eq. 4.43). Left out: the averaging along the
roller's length (a profile across the lay would lower the excitation further) and the asperities' own
compliance; the roughness's excitation here is therefore an upper estimate for a given RMS, and the comparison
reports how far the RMS moves its answer.

**Waviness.** Each raceway's radius deviates by sum_n A_n cos(n theta + phi_n) over the orders n
(``waviness_orders``, ``waviness_amplitudes_m``), with phases drawn per realisation and per raceway: the outer
race's at the roller's angle, the inner race's at its angle on the turning ring.

Every height h (roughness and waviness, both raceways and the roller's two contacts) adds to the roller's
overlap: the LPM's contact offset loses h (:meth:`piezobearing.bearing.lpm.LPMParameters.contact_offsets`).

**Unbalance.** A mass eccentricity U = m e [kg m] (``unbalance_kg_m``) on the shaft turns with it: the shaft
feels F(t) = U omega(t)^2 n(theta(t) + phi) along the outward normal n(psi) = (sin psi, -cos psi) at the
shaft's angle theta plus a phase drawn per realisation (omega = 2 pi f(t); the tangential U d omega/dt of a
speed ramp is left out). ISO 21940-11 grade G 6.3 (e omega = 6.3 mm/s at the largest service speed, general
machinery) at 3000 rpm gives e = 20 um: U = 2.0e-5 kg m for the 1 kg shaft.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

#: Young's modulus and Poisson's ratio of through-hardened bearing steel (AISI 52100 / 100Cr6; Harris &
#: Kotzalas, Essential Concepts of Bearing Technology, 2007) [Pa, -]: both bodies of every contact.
STEEL_YOUNG_PA = 208.0e9
STEEL_POISSON = 0.3
#: Stream index of the surfaces' draws: default_rng([seed, SURFACE_STREAM, faulty, realisation, surface]).
SURFACE_STREAM = 40
#: Largest grid of one surface's profile [points].
MAX_GRID = 2**20


def contact_modulus_Pa() -> float:
    """E* of two steel bodies, 1 / E* = 2 (1 - nu^2) / E [Pa]."""
    return STEEL_YOUNG_PA / (2.0 * (1.0 - STEEL_POISSON**2))


def contact_half_width_m(load_N: float, relative_radius_m: float, length_m: float) -> float:
    """Hertzian half-width b of a line contact, b = sqrt(4 Q R / (pi l E*)) [m] (Johnson 1985, Eq. 4.43).

    Parameters
    ----------
    load_N : float
        Roller load Q [N].
    relative_radius_m : float
        Relative radius R of the two surfaces [m].
    length_m : float
        Contact length l [m].
    """
    return float(np.sqrt(4.0 * max(load_N, 0.0) * relative_radius_m / (np.pi * length_m * contact_modulus_Pa())))


def discrete_spectrum(n: int, dx_m: float, rms_m: float, correlation_length_m: float) -> np.ndarray:
    """The discrete spectrum P_k of the periodic exponential autocorrelation on n points of spacing dx [m^2].

    P_k = sum_m R(d_m) exp(-2 pi i k m / n), d_m = dx min(m, n - m): the eigenvalues of the profile's
    circulant covariance (real, positive); (1/n) sum_k P_k = R(0) = sigma^2. For n dx >> beta and
    k / (n dx) << 1 / dx, P_k dx tends to S(f_k) (module docstring).
    """
    m = np.arange(n)
    d = dx_m * np.minimum(m, n - m)
    r = rms_m**2 * np.exp(-d / correlation_length_m)
    return np.maximum(np.fft.fft(r).real, 0.0)


def grid_points(circumference_m: float, correlation_length_m: float, half_width_m: float) -> int:
    """Points of a surface's profile grid: spacing at most beta / 4 and b / 4 (an even number, at most MAX_GRID)."""
    dx = min(correlation_length_m, half_width_m if half_width_m > 0 else correlation_length_m) / 4.0
    n = int(np.ceil(circumference_m / dx))
    return int(min(MAX_GRID, n + (n % 2)))


def rough_profile(n: int, dx_m: float, rms_m: float, correlation_length_m: float,
                  rng: np.random.Generator) -> np.ndarray:
    """One periodic Gaussian profile with the exponential autocorrelation, n points of spacing dx [m]."""
    p = discrete_spectrum(n, dx_m, rms_m, correlation_length_m)
    w = np.fft.fft(rng.standard_normal(n))
    return np.fft.ifft(w * np.sqrt(p)).real


def contact_filtered(profile_m: np.ndarray, dx_m: float, half_width_m: float) -> np.ndarray:
    """The profile averaged over a contact of width 2b (box filter sinc(2 b f) on its Fourier series) [m]."""
    n = profile_m.size
    f = np.fft.rfftfreq(n, dx_m)
    return np.fft.irfft(np.fft.rfft(profile_m) * np.sinc(2.0 * half_width_m * f), n)


@dataclass(frozen=True)
class Track:
    """One surface's height as a contact sees it: a periodic profile on a grid, plus waviness.

    Attributes
    ----------
    circumference_m : float
        Length of the surface's circumference [m] (the profile's period).
    profile_m : ndarray (n,)
        Contact-filtered roughness on the grid s_i = i circumference / n [m] (empty: none).
    orders : ndarray (k,)
        Waviness orders [-].
    amplitudes_m : ndarray (k,)
        Their amplitudes [m].
    phases_rad : ndarray (k,)
        Their phases [rad].
    """

    circumference_m: float
    profile_m: np.ndarray
    orders: np.ndarray
    amplitudes_m: np.ndarray
    phases_rad: np.ndarray

    def height_m(self, angle_rad: np.ndarray) -> np.ndarray:
        """Height at the surface angle theta [rad] (the arc s = theta circumference / (2 pi)) [m]."""
        theta = np.asarray(angle_rad, dtype=float)
        # compiled, one pass over the angles: np.interp(period=) sorts and pads the grid at every call, and
        # array expressions form a dozen arrays of the record's size (benchmarks/bench_comparison_kernels.py)
        closed = np.append(self.profile_m, self.profile_m[:1]) if self.profile_m.size else self.profile_m
        return _track_heights(np.ascontiguousarray(theta).ravel(), closed, np.asarray(self.orders, dtype=float),
                              np.asarray(self.amplitudes_m, dtype=float),
                              np.asarray(self.phases_rad, dtype=float)).reshape(theta.shape)


@njit(cache=True)
def _track_heights(theta, closed, orders, amplitudes, phases):  # pragma: no cover - compiled
    """A track's height at the angles ``theta`` [rad] (any turn): the roughness profile on the uniform grid of one
    turn, ``closed`` its n points and the first again (n + 1,; empty: none), interpolated linearly, plus each
    waviness order's A cos(n theta + phi)."""
    n = closed.size - 1
    scale = n / (2 * np.pi) if n > 0 else 0.0
    out = np.zeros(theta.size)
    for k in range(theta.size):
        h = 0.0
        if n > 0:
            u = theta[k] * scale
            cell = np.floor(u)
            i = int(cell) % n
            h = closed[i] + (u - cell) * (closed[i + 1] - closed[i])
        for m in range(orders.size):
            h += amplitudes[m] * np.cos(orders[m] * theta[k] + phases[m])
        out[k] = h
    return out


@dataclass(frozen=True)
class SurfaceSettings:
    """The healthy bearing's floor (config ``bearing``): roughness, waviness, unbalance; zero for each is off.

    Parameters
    ----------
    roughness_rms_m : float
        RMS sigma of every raceway's and roller's roughness profile [m].
    roughness_correlation_length_m : float
        Correlation length beta of the exponential autocorrelation [m].
    waviness_orders : tuple of int
        Waviness orders of both raceways [-].
    waviness_amplitudes_m : tuple of float
        Their amplitudes [m].
    unbalance_kg_m : float
        The shaft's unbalance U = m e [kg m].
    """

    roughness_rms_m: float = 0.0
    roughness_correlation_length_m: float = 10.0e-6
    waviness_orders: tuple[int, ...] = ()
    waviness_amplitudes_m: tuple[float, ...] = ()
    unbalance_kg_m: float = 0.0

    def __post_init__(self):
        if len(self.waviness_orders) != len(self.waviness_amplitudes_m):
            raise ValueError("config bearing: waviness_orders and waviness_amplitudes_m need the same length "
                             f"(got {len(self.waviness_orders)} and {len(self.waviness_amplitudes_m)})")

    @classmethod
    def from_config(cls, bearing: dict) -> SurfaceSettings:
        """From the ``bearing`` section."""
        return cls(float(bearing["roughness_rms_m"]), float(bearing["roughness_correlation_length_m"]),
                   tuple(int(n) for n in bearing["waviness_orders"]),
                   tuple(float(a) for a in bearing["waviness_amplitudes_m"]), float(bearing["unbalance_kg_m"]))

    @property
    def tracks_on(self) -> bool:
        """Whether any surface carries roughness or waviness."""
        return self.roughness_rms_m > 0 or any(a != 0 for a in self.waviness_amplitudes_m)

    @property
    def active(self) -> bool:
        """Whether any source is on (each realisation then differs)."""
        return self.tracks_on or self.unbalance_kg_m > 0


@dataclass(frozen=True)
class Surfaces:
    """One realisation of the bearing's surfaces and unbalance phase.

    Attributes
    ----------
    outer, inner : Track
        The raceways (the outer at the roller's angle psi, the inner at psi minus the shaft's angle).
    roller_outer, roller_inner : tuple of Track
        Each roller's surface as its outer-race and its inner-race contact see it (the same profile, each
        contact's filter; the inner contact half a spin after the outer).
    unbalance_kg_m : float
        U [kg m].
    unbalance_phase_rad : float
        Angle of the unbalance on the shaft at t = 0 from the load direction [rad].
    """

    outer: Track
    inner: Track
    roller_outer: tuple[Track, ...]
    roller_inner: tuple[Track, ...]
    unbalance_kg_m: float
    unbalance_phase_rad: float

    def heights_m(self, psi_rad: np.ndarray, shaft_angle_rad: np.ndarray, spin_rad: np.ndarray) -> np.ndarray:
        """The surfaces' heights at each roller's two contacts, summed (n_t, Z) [m].

        ``psi_rad`` (n_t, Z) the roller angles, ``shaft_angle_rad`` (n_t,), ``spin_rad`` (n_t,) the roller
        spin relative to the cage (the same for all rollers).
        """
        h = self.outer.height_m(psi_rad) + self.inner.height_m(psi_rad - shaft_angle_rad[:, None])
        for j, (ro, ri) in enumerate(zip(self.roller_outer, self.roller_inner, strict=True)):
            h[:, j] += ro.height_m(spin_rad) + ri.height_m(spin_rad + np.pi)
        return h


def _track(circumference_m: float, settings: SurfaceSettings, half_width_m: float, waviness: bool,
           rng: np.random.Generator) -> tuple[Track, np.ndarray, float]:
    """A surface's raw profile drawn and filtered for one contact; returns the track, the raw profile and dx."""
    raw, dx = np.zeros(0), 0.0
    prof = np.zeros(0)
    if settings.roughness_rms_m > 0:
        n = grid_points(circumference_m, settings.roughness_correlation_length_m, half_width_m)
        dx = circumference_m / n
        raw = rough_profile(n, dx, settings.roughness_rms_m, settings.roughness_correlation_length_m, rng)
        prof = contact_filtered(raw, dx, half_width_m)
    k = len(settings.waviness_orders) if waviness else 0
    orders = np.asarray(settings.waviness_orders[:k], dtype=float)
    amps = np.asarray(settings.waviness_amplitudes_m[:k], dtype=float)
    phases = rng.uniform(0.0, 2 * np.pi, k)
    return Track(circumference_m, prof, orders, amps, phases), raw, dx


def draw(settings: SurfaceSettings, geometry, half_widths_m: dict[str, float], seed: int, faulty: bool,
         realisation: int) -> Surfaces | None:
    """One realisation of the surfaces (None when every source is off).

    ``geometry``: the bearing's :class:`~piezobearing.bearing.lpm.BearingGeometry`; ``half_widths_m``: the
    contact half-width b at the outer and the inner race (keys ``outer``, ``inner``) [m]. Each surface draws
    from its own stream, default_rng([seed, SURFACE_STREAM, faulty, realisation, surface]).
    """
    if not settings.active:
        return None

    def rng(surface: int) -> np.random.Generator:
        return np.random.default_rng([int(seed), SURFACE_STREAM, int(faulty), int(realisation), surface])

    outer = _track(2 * np.pi * geometry.outer_raceway_radius_m, settings, half_widths_m["outer"], True, rng(0))[0]
    inner = _track(2 * np.pi * geometry.inner_raceway_radius_m, settings, half_widths_m["inner"], True, rng(1))[0]
    circ = np.pi * geometry.roller_diameter_m
    r_out, r_in = [], []
    for j in range(geometry.n_rollers):
        t_out, raw, dx = _track(circ, settings, half_widths_m["outer"], False, rng(2 + j))
        r_out.append(t_out)
        prof = contact_filtered(raw, dx, half_widths_m["inner"]) if raw.size else raw
        r_in.append(Track(circ, prof, t_out.orders, t_out.amplitudes_m, t_out.phases_rad))
    phase = float(rng(2 + geometry.n_rollers).uniform(0.0, 2 * np.pi))
    return Surfaces(outer, inner, tuple(r_out), tuple(r_in), settings.unbalance_kg_m, phase)


def unbalance_force_N(unbalance_kg_m: float, phase_rad: float, shaft_angle_rad: np.ndarray,
                      shaft_speed_Hz: np.ndarray) -> np.ndarray:
    """The unbalance's force on the shaft (n, 2) (y, z) [N]: U omega^2 n(theta + phi), n(psi) = (sin, -cos)."""
    w2 = (2 * np.pi * np.asarray(shaft_speed_Hz, dtype=float)) ** 2
    a = np.asarray(shaft_angle_rad, dtype=float) + phase_rad
    f = unbalance_kg_m * w2 * np.ones_like(a)
    return np.stack([f * np.sin(a), -f * np.cos(a)], axis=1)
