r"""What a sensor designer compares: one stack and one measuring circuit reduced to figures of merit.

For a stack (mesh, materials) clamped on its top face and loaded by a
uniform axial force on its bottom face, with the measuring circuit (DAQ
input resistance R parallel to the cable's and the DAQ's capacitance) across
its electrodes, the SS family of :mod:`piezobearing.sensor.fem` gives:

* the first axial resonance with the electrodes shorted and open;
* the mid-band sensitivity :math:`|V/F|` at the reference frequency (the
  plateau between the RC corner and the resonance), which equals
  :math:`d_{33,\mathrm{eff}} / (C_\mathrm{FEM} + C_\mathrm{ext})`;
* the +3 dB band edge over the mid-band (root-found on the reduced model);
* the low-frequency corner :math:`f_c = 1 / (2\pi R (C_\mathrm{FEM} + C_\mathrm{ext}))`
  and the frequency from which the response stays within a tolerance
  :math:`t` of the mid-band, :math:`f_c (1-t)/\sqrt{1-(1-t)^2}` (below 1 kHz the
  FEM with the circuit is this RC high-pass to 2e-4, tests/test_sensor_fem.py);
* the stack's axial stiffness :math:`F / \bar u` (traction-weighted mean
  displacement of the loaded face, open and short circuit).

Everything is computed once per design on one mesh; the mesh level of a
study is chosen by a convergence check (docs/theory/sensor_design.md).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..signals import daq, detection
from . import fem
from .mesh import StackMesh


@dataclass(frozen=True)
class DesignSettings:
    """How the figures of merit are read.

    Parameters
    ----------
    order : int
        Lagrange order of the FEM [-].
    damping_ratio : float
        Modal damping ratio of the reduced model [-].
    n_ritz_modes : int
        Short-circuit modes of the Ritz basis [-].
    reference_frequency_Hz : float
        Mid-band reference of the sensitivity and the band edge [Hz].
    band_ratio_dB : float
        Band edge: rise over the mid-band [dB].
    linear_tolerance : float
        The response counts as linear where it is within this fraction of the mid-band [-].
    """

    order: int = 2
    damping_ratio: float = 1.0 / 160.0
    n_ritz_modes: int = 12
    reference_frequency_Hz: float = 1.0e3
    band_ratio_dB: float = 3.0
    linear_tolerance: float = 0.05


def linear_from_Hz(corner_Hz: float, tolerance: float) -> float:
    """Lowest frequency from which a first-order high-pass stays within ``tolerance`` of its plateau [Hz].

    |H| / H_inf = x / sqrt(1 + x^2), x = f / f_c, reaches 1 - t at x = (1 - t) / sqrt(1 - (1 - t)^2).
    """
    r = 1.0 - tolerance
    return float(corner_Hz * r / np.sqrt(1.0 - r * r))


def stack_stiffness_N_per_m(rs: fem.ReducedSystem) -> tuple[float, float]:
    """Axial stiffness F / u_mean of the clamped stack under its uniform load, (short, open) circuit [N/m].

    The quarter's load vector carries SECTOR_FRACTION N for 1 N on the full stack, so f . u =
    SECTOR_FRACTION x (traction-weighted mean displacement of the loaded face).
    """
    short = float(rs.f @ rs.ks_inv_f)
    opened = float(rs.f @ rs.solve_open(rs.f))
    return fem.SECTOR_FRACTION / short, fem.SECTOR_FRACTION / opened


def _first_axial(rs: fem.ReducedSystem, short: fem.Modes) -> int:
    labels = [fem.label_mode(rs, short.shapes[:, i])[0] for i in range(len(short.frequency_Hz))]
    if "axial" not in labels:
        raise RuntimeError("no axial mode among the Ritz modes; raise sensor_fem.n_ritz_modes")
    return labels.index("axial")


def design_figures(mesh: StackMesh, materials: fem.StackMaterials, circuit: fem.MeasuringCircuit,
                   settings: DesignSettings) -> dict:
    """Figures of merit of one design (see the module docstring); SI units in every key."""
    asm = fem.assemble(mesh, materials, order=settings.order, load_face="bottom")
    rs = fem.reduce(asm, fem.stack_conditions(mesh.geometry.z_interfaces_m, "SS"))
    short = fem.modes(rs, settings.n_ritz_modes, "short")
    i_ax = _first_axial(rs, short)
    f_short = float(short.frequency_Hz[i_ax])
    f_open = float(fem.modes(rs, i_ax + 2, "open").frequency_Hz[i_ax])
    model = fem.reduced_model(rs, short, settings.damping_ratio)
    ref_f = settings.reference_frequency_Hz
    s_mid = float(abs(model.voltage_per_force(ref_f, circuit)[0]))
    f_peak = fem.loaded_resonance_Hz(model, circuit, 0.97 * f_short, 1.03 * f_open)
    band_high = fem.band_edge_Hz(model, circuit, 10 ** (settings.band_ratio_dB / 20), s_mid, ref_f, f_peak)
    d_eff, c_fem = model.charge_per_force_C_per_N, model.static_capacitance_F
    c_total = c_fem + circuit.capacitance_F
    corner = 1.0 / (2 * np.pi * circuit.resistance_ohm * c_total)
    k_short, k_open = stack_stiffness_N_per_m(rs)
    return {
        "sensitivity_V_per_N": s_mid,
        "open_circuit_gain_V_per_N": d_eff / c_total,
        "effective_d33_C_per_N": d_eff,
        "stack_capacitance_F": c_fem,
        "circuit_capacitance_F": circuit.capacitance_F,
        "resistance_ohm": circuit.resistance_ohm,
        "tau_s": circuit.resistance_ohm * c_total,
        "corner_Hz": corner,
        "linear_from_Hz": linear_from_Hz(corner, settings.linear_tolerance),
        "first_resonance_short_Hz": f_short,
        "first_resonance_open_Hz": f_open,
        "coupling_factor": float(np.sqrt(max(0.0, 1 - (f_short / f_open) ** 2))),
        "loaded_resonance_Hz": f_peak,
        "band_high_Hz": band_high,
        "stack_stiffness_short_N_per_m": k_short,
        "stack_stiffness_open_N_per_m": k_open,
        "mechanical_quality_factor": 1.0 / (2.0 * settings.damping_ratio) if settings.damping_ratio > 0 else float("inf"),
        "n_dof": int(asm.n_u + asm.p_coors.shape[0]),
    }


# --------------------------------------------------------------------------- detection at absolute noise


def _detect(v: np.ndarray, dt_s: float, f0_Hz: float, noise, shapes: np.ndarray, seeds: list, es, ins) -> dict:
    """Median indicator, detection rate and clipping of record ``v`` under ``noise`` over the noise shapes."""
    ind, det, clip, thr = [], [], [], []
    for shape, rng_seed in zip(shapes, seeds, strict=True):
        acq = daq.add_noise(v, dt_s, noise, np.random.default_rng(rng_seed), shape=shape)
        r = detection.analyse(acq.voltage_V, dt_s, f0_Hz, es, ins).result
        ind.append(r["indicator"])
        det.append(r["detected"])
        thr.append(r["threshold"])
        clip.append(acq.clipped_fraction)
    return {
        "indicator": float(np.median(ind)),
        "detection_rate": float(np.mean(det)),
        "threshold": float(max(thr)),
        "clipped_fraction": float(max(clip)),
    }


#: An ADC that neither clips nor quantises at any noise the bisection tries (48 bits over +-1 MV: a 7 nV step,
#: 3.6e4 V rms of noise at the bisection's top density still inside the range).
IDEAL_ADC = {"adc_bits": 48, "range_V": 1.0e6}


def _noise_limit(v: np.ndarray, dt_s: float, f0_Hz: float, noise, shapes, seeds, es, ins,
                 required_rate: float) -> float:
    """Largest input noise density [V/sqrt(Hz)] at which ``v`` is detected in ``required_rate`` of the
    replicates: bisection on a log scale over 1 nV .. 1 kV/sqrt(Hz) (NaN if not even at 1 nV)."""
    def detected(log_density):
        n = replace(noise, noise_density_V_per_sqrtHz=10.0**log_density)
        return _detect(v, dt_s, f0_Hz, n, shapes, seeds, es, ins)["detection_rate"] >= required_rate

    lo, hi = -9.0, 3.0  # 1 nV/sqrt(Hz) .. 1 kV/sqrt(Hz)
    if not detected(lo):
        return float("nan")
    if detected(hi):
        return 10.0**hi
    for _ in range(16):  # 12 decades / 2^16: 2e-4 decade (0.004 dB)
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if detected(mid) else (lo, mid)
    return 10.0**lo


def _margin_dB(limit: float, density: float) -> float:
    return float(20 * np.log10(limit / density)) if np.isfinite(limit) else float("nan")


def detection_at_noise(voltages: dict, dt_s: float, f0_Hz: float, noise, n_seeds: int, master_seed: int,
                       es, ins, required_rate: float) -> dict:
    """Envelope fault indicator of the healthy and faulty voltages under the DAQ's absolute noise.

    ``voltages``: {"healthy": v, "faulty": v} noiseless [V] on step ``dt_s``;
    ``noise``: :class:`piezobearing.signals.daq.NoiseSettings` (absolute:
    input noise density, ADC bits over +-range_V, clipping). Replicate j of
    a case draws its noise shape from :func:`piezobearing.signals.detection.noise_rng`
    (master_seed, case, j) and keeps it at every noise level (common random
    numbers). Besides the indicator at the configured density, the largest
    density at which the faulty record is still detected in ``required_rate``
    of the replicates is found by bisection on a log scale (ADC and
    interference as configured); the margin is its ratio to the configured
    density in dB (20 log10), the headroom a design has against a noisier rig.

    Clipping: ``clipped`` is True where the configured ADC clips either record at the configured density
    (any replicate). A clipped record's margin measures the clipped waveform (the clipping's own harmonics
    and flat tops), not the design, so ``detection_margin_dB`` is NaN there and the number measured on the
    clipped record is kept apart as ``detection_margin_as_clipped_dB``. ``detection_margin_ideal_adc_dB``
    repeats the bisection with an ADC that neither clips nor quantises (:data:`IDEAL_ADC`; same noise and
    interference): comparable over every design, it scales with the gain exactly.
    ``range_needed_V`` is the noiseless records' peak |v|: the ADC range the design needs.
    """
    out = {}
    draws = {}
    for case, v in voltages.items():
        rngs = [detection.noise_rng(master_seed, case, j) for j in range(n_seeds)]
        shapes = np.array([r.standard_normal(len(v)) for r in rngs])
        seeds = [master_seed * 1000 + 17 * j + (1 if case == "faulty" else 0) for j in range(n_seeds)]
        draws[case] = (shapes, seeds)
        out[case] = _detect(v, dt_s, f0_Hz, noise, shapes, seeds, es, ins)
    shapes, seeds = draws["faulty"]
    args = (voltages["faulty"], dt_s, f0_Hz)
    limit = _noise_limit(*args, noise, shapes, seeds, es, ins, required_rate)
    limit_ideal = _noise_limit(*args, replace(noise, **IDEAL_ADC), shapes, seeds, es, ins, required_rate)
    density = noise.noise_density_V_per_sqrtHz
    clipped_fraction = max(out["faulty"]["clipped_fraction"], out["healthy"]["clipped_fraction"])
    clipped = clipped_fraction > 0
    margin = _margin_dB(limit, density)
    return {
        "indicator_faulty": out["faulty"]["indicator"],
        "indicator_healthy": out["healthy"]["indicator"],
        "threshold": max(out["faulty"]["threshold"], out["healthy"]["threshold"]),
        "detection_rate_faulty": out["faulty"]["detection_rate"],
        "detection_rate_healthy": out["healthy"]["detection_rate"],
        "clipped": bool(clipped),
        "clipped_fraction": clipped_fraction,
        "range_V": noise.range_V,
        "range_needed_V": float(max(np.abs(v).max() for v in voltages.values())),
        "noise_density_V_per_sqrtHz": density,
        "noise_std_V": float(density * np.sqrt(0.5 / dt_s)),
        "noise_limit_V_per_sqrtHz": limit,
        "detection_margin_dB": float("nan") if clipped else margin,
        "detection_margin_as_clipped_dB": margin if clipped else float("nan"),
        "noise_limit_ideal_adc_V_per_sqrtHz": limit_ideal,
        "detection_margin_ideal_adc_dB": _margin_dB(limit_ideal, density),
    }
