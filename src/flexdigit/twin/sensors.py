"""The sensor chain: gauge strain -> Wheatstone bridge -> amplifier and low-pass -> 16-bit ADC, with noise (2.3, 2.5).

Each gauge pair sits on the two faces of the strip, ``t/2`` from the neutral axis: the face away from the cable
stretches by ``+kappa t/2 + eps_axial`` and the cable-side face by ``-kappa t/2 + eps_axial`` (``eps_axial`` is
the axial force over ``E A``: the cable's compression and the hanging weights' pull). The bridge ratio is E 2.2
evaluated with the actual resistances (``R (1 + GF eps)``), not its small-strain forms, so the quarter bridge sees
the axial strain and the half bridge (E 2.4) cancels it:

- quarter: R1 = tension-face gauge, R2 = R3 = R4 = R;
- half (the rig): R1 = tension face, R2 = compression face, R3 = R4 = R (completion resistors in the amplifier);
- full: R1 = R3 = tension faces, R2 = R4 = compression faces (E 2.3).

The amplifier multiplies by ``amplifier_gain_v_per_v`` (10,000) times a per-channel calibration factor (E 3.20-3.22
differ by channel: gauge placement, bonding and the unknown excitation ``excitation_v``, an assumption) and adds a
per-channel offset (bridge imbalance). Its Butterworth low-pass (470 Hz) is applied as its group delay
``tau = a1/a0`` of the filter's denominator: the digit's signals are below 20 Hz, where the filter's gain differs
from 1 by less than 1e-4 and its phase is ``-omega tau`` to the same order (checked against ``scipy.signal.lsim`` in
the tests). Noise is added at the ADC input: white (per sample) plus a slow random-walk drift per channel, from a
seeded generator. The ADC clips to its range and rounds to its 16-bit step.

Cable-guide friction (taut cable only)
--------------------------------------
The cable slides through the nylon guides whenever its tension changes (a weight hung, the servo hunting within
its deadband); static friction at each guide then holds a tension difference of up to ``mu phi T`` (capstan,
``phi`` the cable's wrap at the guide), whose sign and size depend on how the cable last slid. So each gauge's
section carries, besides ``e T`` from the cable's anchor at the tip, an extra moment ``e dT_k`` with
``dT_k = ratio * T * xi_k``, ``xi_k`` standard normal, independent per gauge section
(``Calibration.cable_friction_ratio``). The state ``xi`` is held until something jolts the cable in its guides:
hanging, lifting or re-hanging a weight by hand draws it afresh (:meth:`flexdigit.twin.Twin.disturb`); the servo
pulling the cable slides it one way only, a repeatable state that the calibration absorbs, so a loop with no
weights hung (chapter 5) sees none of it. It enters as curvature through the section's local compliance
(:attr:`flexdigit.twin.digit.Chain.gauge_curvature_per_moment`), not through the chain's equilibrium: a
first-order model of a redistribution that the stiff cable (which pins the tip angle) keeps local. It is zero with
a slack or detached cable (the non-actuated digit of chapter 6) and grows with the tension. Its draws come from a
generator of their own (seeded from the twin's seed), so the white noise and drift are the same numbers with or
without it. The thesis repeats "the procedure" 25 times at each setting (6.4, 7.1): every reading follows its own
hang, so its own friction state (the tactile protocols re-hang before every repetition, ``rehang``); readings
taken one after another after a single hang would share one state, which, split at random between training and
test, leaves corr2 untouched (the report shows both).
"""

from __future__ import annotations

import dataclasses
import math
from functools import lru_cache

import numpy as np

from flexdigit.errors import ParameterError
from flexdigit.models.bridge import adc_quantise, gauge_resistance_ohm, wheatstone_ratio
from flexdigit.params import Sensors

__all__ = ["bridge_ratio", "lowpass_group_delay_s", "adc", "CHANNEL_FIELDS", "check_channels", "SensorChain"]


def bridge_ratio(eps_tension_face, eps_compression_face, sensors: Sensors):
    """Bridge output over excitation, ``Vm/Vs`` (E 2.2), for the two face strains of a gauge pair.

    :func:`flexdigit.models.bridge.bridge_ratio` assumes the opposite gauge sees exactly ``-strain``; on the digit
    the faces also share an axial strain (cable compression, hanging weights), which only the quarter bridge sees,
    so the resistances are built here and E 2.2 is :func:`flexdigit.models.bridge.wheatstone_ratio`.

    Parameters
    ----------
    eps_tension_face, eps_compression_face : array_like
        Strain (dimensionless) of the gauge on the face away from the cable and on the cable side.
    sensors : Sensors
        Gauge factor, resistance and bridge type.

    Examples
    --------
    >>> from flexdigit.params import Sensors
    >>> round(float(bridge_ratio(1e-4, -1e-4, Sensors(bridge="half"))) / (0.8 / 4 * 2e-4), 6)   # E 2.4
    1.0
    >>> round(float(bridge_ratio(1e-4, -1e-4, Sensors(bridge="full"))) / (0.8 * 1e-4), 6)        # E 2.3
    1.0
    >>> float(bridge_ratio(5e-5, 5e-5, Sensors(bridge="half")))     # pure axial strain cancels
    0.0
    """
    r1 = gauge_resistance_ohm(eps_tension_face, sensors)
    r2 = gauge_resistance_ohm(eps_compression_face, sensors)
    r = np.full_like(np.asarray(r1, dtype=float), sensors.gauge_resistance_ohm)
    if sensors.bridge == "quarter":
        return np.asarray(wheatstone_ratio(r1, r, r, r))
    if sensors.bridge == "half":  # R3 = R4 inside the amplifier (E 2.4)
        return np.asarray(wheatstone_ratio(r1, r2, r, r))
    return np.asarray(wheatstone_ratio(r1, r2, r1, r2))  # E 2.3


@lru_cache(maxsize=16)
def lowpass_group_delay_s(cutoff_hz: float, order: int) -> float:
    """DC group delay of an analog Butterworth low-pass, ``a1 / a0`` of its denominator (s)."""
    from scipy.signal import butter

    _, den = butter(order, 2.0 * np.pi * cutoff_hz, btype="low", analog=True)
    return float(den[-2] / den[-1])


def adc(voltage_v, sensors: Sensors) -> np.ndarray:
    """What the card reads: clipped to its range and rounded to its 16-bit step (2.5.2); see
    :func:`flexdigit.models.bridge.adc_quantise`."""
    return np.asarray(adc_quantise(voltage_v, sensors), dtype=float)


#: The calibration's fields that hold one value per gauge channel.
CHANNEL_FIELDS = ("channel_gain", "channel_offset_v", "noise_white_v", "noise_drift_v_per_sqrt_s")


def check_channels(params, calibration) -> None:
    """Refuse rig parameters and a calibration that disagree on the number of gauges, naming both.

    A rig TOML with two gauge positions met the packaged three-channel calibration in a numpy broadcast (issue 16);
    studies of other gauge counts give a calibration with one value per gauge (:mod:`flexdigit.studies.design_study`).
    """
    gauges = len(params.geometry.gauge_positions_m)
    for name in CHANNEL_FIELDS:
        channels = len(getattr(calibration, name))
        if channels != gauges:
            raise ParameterError(
                f"The rig parameters place {gauges} gauge(s) (geometry.gauge_positions_m) but the twin's calibration "
                f"has {channels} value(s) of '{name}': give one calibration value per gauge (the thesis rig and its "
                "packaged calibration have 3)"
            )


@lru_cache(maxsize=16)
def _gauge_chains(sensors: Sensors, count: int) -> tuple[Sensors, ...]:
    """Each gauge's own :class:`~flexdigit.params.Sensors` (its bridge and gauge factor), kept per description:
    a :class:`SensorChain` is built per static solve (``static_gauges_v``), and validating ``count`` replaced
    ``Sensors`` there cost a per-gauge digit's tactile chapters seconds."""
    bridges, factors, _ = sensors.chain(count)
    return tuple(dataclasses.replace(sensors, bridge=b, gauge_factor=f) for b, f in zip(bridges, factors, strict=True))


class SensorChain:
    """Strain at the gauges to ADC volts, with per-channel gain/offset and seeded noise (module docstring).

    Parameters
    ----------
    params : RigParams
    calibration : Calibration
        ``channel_gain``, ``channel_offset_v``, ``noise_white_v``, ``noise_drift_v_per_sqrt_s``, ``pot_noise_v``.
    rng : numpy.random.Generator
    """

    def __init__(self, params, calibration, rng: np.random.Generator):
        check_channels(params, calibration)
        s = params.sensors
        self.params = params
        count = len(params.geometry.gauge_positions_m)
        amplifier = s.chain(count)[2]
        # a chain per gauge (issue 24): each gauge's bridge and gauge factor; the shared chain keeps its fast path
        self._chains = _gauge_chains(s, count) if s.per_gauge else None
        amp = np.asarray(amplifier, dtype=float) if s.amplifier_gains_v_per_v is not None else s.amplifier_gain_v_per_v
        self.gain = amp * s.excitation_v * np.asarray(calibration.channel_gain, dtype=float)
        self.offset = np.asarray(calibration.channel_offset_v, dtype=float)
        self.white = np.asarray(calibration.noise_white_v, dtype=float)
        self.drift_rate = np.asarray(calibration.noise_drift_v_per_sqrt_s, dtype=float)
        self.pot_noise = float(calibration.pot_noise_v)
        self.friction_ratio = float(calibration.cable_friction_ratio)
        self._eccentricity = float(params.geometry.cable_eccentricity_m)
        self.delay_s = lowpass_group_delay_s(s.amplifier_lowpass_hz, s.amplifier_lowpass_order)
        self.rng = rng
        self.drift = np.zeros(self.gain.size)
        self._last_t = None
        half_t = 0.5 * params.geometry.strip_thickness_m
        self._half_t = half_t
        self._ea = params.material.youngs_modulus_pa * params.geometry.cross_section_m2
        self._half_bridge = s.bridge == "half"
        self._gf = float(s.gauge_factor)
        self._adc_lo = float(s.adc_range_v[0])
        self._lsb = float(s.adc_lsb_v)
        self._top = float(2**s.adc_bits - 1)

    def clean_v(self, curvature_1_m, axial_force_n) -> np.ndarray:
        """Noise-free amplifier output (V) for curvature (1/m) and axial force (N) at the gauges; vectorised."""
        kappa = np.asarray(curvature_1_m, dtype=float)
        eps_axial = np.asarray(axial_force_n, dtype=float) / self._ea
        bend = kappa * self._half_t
        if self._chains is not None:
            ratio = np.stack(
                [
                    bridge_ratio(bend[..., i] + eps_axial[..., i], -bend[..., i] + eps_axial[..., i], chain)
                    for i, chain in enumerate(self._chains)
                ],
                axis=-1,
            )
        elif self._half_bridge:
            # E 2.2 for the half bridge, (R1 - R2) / (2 (R1 + R2)) with R = 1 + GF eps, inlined: the general
            # bridge_ratio costs ~15 us a read in conversions (tests check the two agree)
            gf = self._gf
            ratio = (gf * (2.0 * bend)) / (2.0 * (2.0 + (2.0 * gf) * eps_axial))
        else:
            ratio = bridge_ratio(bend + eps_axial, -bend + eps_axial, self.params.sensors)
        return self.gain * ratio + self.offset

    def friction_curvature_sd_1_m(self, tension_n, curvature_per_moment) -> np.ndarray:
        """Standard deviation (1/m) of the cable-guide friction's curvature at each gauge (module docstring).

        ``tension_n`` (...) the cable tension (N; 0 or less: slack, no friction); ``curvature_per_moment`` (3,)
        the sections' local compliance (1/(N m^2)). Returns (..., 3).
        """
        tension = np.maximum(np.asarray(tension_n, dtype=float), 0.0)
        c = np.asarray(curvature_per_moment, dtype=float)
        return (self.friction_ratio * self._eccentricity) * tension[..., None] * c

    def volts_per_curvature(self, curvature_1_m, axial_force_n, step_1_m: float = 1e-4) -> np.ndarray:
        """``dV/dkappa`` (V m) of each channel at a state (central difference of :meth:`clean_v`)."""
        kappa = np.asarray(curvature_1_m, dtype=float)
        return (self.clean_v(kappa + step_1_m, axial_force_n) - self.clean_v(kappa - step_1_m, axial_force_n)) / (
            2.0 * step_1_m
        )

    def friction_sd_v(self, curvature_1_m, axial_force_n, tension_n, curvature_per_moment) -> np.ndarray:
        """Standard deviation (V) of the friction's share of a reading, per gauge (linearised; exact for the
        half bridge to a part in 1e4)."""
        sd = self.friction_curvature_sd_1_m(tension_n, curvature_per_moment)
        return np.abs(self.volts_per_curvature(curvature_1_m, axial_force_n)) * sd

    def friction_draw(self, curvature_1_m, tension_n, curvature_per_moment, rng: np.random.Generator):
        """Curvature with one draw of the friction added; draws nothing (same stream) when it is zero."""
        kappa = np.asarray(curvature_1_m, dtype=float)
        sd = self.friction_curvature_sd_1_m(tension_n, curvature_per_moment)
        if not np.any(sd > 0):
            return kappa
        return kappa + sd * rng.standard_normal(sd.shape)

    def sample(self, clean_v: np.ndarray, time_s: float) -> np.ndarray:
        """One ADC sample of the gauge channels at ``time_s``: drift advanced since the last sample, white noise."""
        if self._last_t is not None and time_s > self._last_t:
            step = math.sqrt(time_s - self._last_t)
            self.drift += (self.drift_rate * step) * self.rng.standard_normal(self.drift.size)
        self._last_t = time_s
        noisy = clean_v + self.drift + self.white * self.rng.standard_normal(self.drift.size)
        return self._quantise(noisy)

    def sample_series(self, clean_v: np.ndarray, times_s: np.ndarray, pot_v: np.ndarray):
        """:meth:`sample` then :meth:`sample_pot` at each of ``times_s`` (N,), non-decreasing, in one go: the same
        draws in the same order, the same operations, so the same numbers. ``clean_v`` (N, C), ``pot_v`` (N,).

        Returns the gauge samples (N, C) and the pot samples (N,).
        """
        n, c = clean_v.shape
        prev = np.empty(n)
        prev[1:] = times_s[:-1]
        prev[0] = math.inf if self._last_t is None else self._last_t
        moves = times_s > prev  # the drift advances (and draws) only when time has passed
        # each read draws c (drift, when it moves), then c (white noise), then 1 (pot): one draw, spread in order
        taken = np.ones((n, 2 * c + 1), dtype=bool)
        taken[:, :c] = moves[:, None]
        z = np.zeros(taken.shape)
        z[taken] = self.rng.standard_normal(int(taken.sum()))
        with np.errstate(invalid="ignore"):
            step = np.sqrt(np.where(moves, times_s - prev, 0.0))
        steps = (self.drift_rate * step[:, None]) * z[:, :c]
        drift = np.cumsum(np.concatenate([self.drift[None], steps]), axis=0)[1:]  # sequential, as += per read
        noisy = clean_v + drift + self.white * z[:, c : 2 * c]
        self.drift = drift[-1].copy()
        self._last_t = float(times_s[-1])
        return self._quantise(noisy), self._quantise(pot_v + self.pot_noise * z[:, 2 * c])

    def _quantise(self, volts):
        # models.bridge.adc_quantise, inlined: it costs ~40 us a call in NaN handling and conversions, more than the
        # rest of a read; tests/twin/test_sensors.py checks the two agree.
        lo = self._adc_lo
        return lo + np.clip(np.rint((volts - lo) / self._lsb), 0.0, self._top) * self._lsb

    def sample_pot(self, pot_v: float) -> float:
        """One ADC sample of the potentiometer channel (V)."""
        noisy = pot_v + self.pot_noise * self.rng.standard_normal()
        return float(self._quantise(noisy))
