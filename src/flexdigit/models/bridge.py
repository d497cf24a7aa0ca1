"""The sensor chain: strain gauge, Wheatstone bridge, amplifier with low-pass, 16-bit ADC (thesis 2.3.1, 2.5).

E 2.1 defines the gauge factor, ``GF = (dR/R) / strain``; E 2.2 is the bridge's output ratio::

    Vm/Vs = (R1 R3 - R2 R4) / ((R1 + R2)(R3 + R4))

With one active gauge (quarter bridge, R1 = R(1 + GF eps)) it is ``GF eps / (2 (2 + GF eps))`` ~ ``GF eps / 4``;
with two opposite gauges (half bridge, R1 = R(1 + GF eps), R2 = R(1 - GF eps), E 2.4) it is exactly
``GF/4 x 2 eps``; with four (full bridge, E 2.3) exactly ``GF eps``. The Fylde amplifier multiplies by 10,000
behind a 470 Hz low-pass (a Butterworth of ``sensors.amplifier_lowpass_order``, an assumption: the thesis gives
only the cut-off), and the PCI-DAS1602/16 card quantises +-5 V to 16 bits, clipping outside.

Everything is vectorised over numpy arrays and takes a :class:`flexdigit.params.Sensors`.

Examples
--------
>>> from flexdigit.params import Sensors
>>> round(float(bridge_ratio(1e-4, Sensors(bridge="half"))), 12)   # GF/4 * 2 eps with GF = 0.8
4e-05
>>> round(float(gauge_voltage_v(1e-4, Sensors())), 6)          # x Vs (1 V) x 10,000
0.4
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from flexdigit._validation import check_choice
from flexdigit.params import BRIDGE_TYPES, Sensors

__all__ = [
    "wheatstone_ratio",
    "gauge_resistance_ohm",
    "bridge_ratio",
    "bridge_gain_v_per_strain",
    "lowpass_tf",
    "amplifier_tf",
    "strain_to_volts_tf",
    "adc_counts",
    "counts_to_volts",
    "adc_quantise",
    "adc_clipped",
    "gauge_voltage_v",
    "strain_from_voltage",
    "gauge_noise_scale",
]

if TYPE_CHECKING:
    import control


def wheatstone_ratio(r1, r2, r3, r4):
    """``Vm/Vs = (R1 R3 - R2 R4) / ((R1 + R2)(R3 + R4))`` (E 2.2); arrays broadcast.

    Examples
    --------
    >>> float(wheatstone_ratio(120, 120, 120, 120))
    0.0
    """
    r1, r2, r3, r4 = (np.asarray(r, dtype=float) for r in (r1, r2, r3, r4))
    out = (r1 * r3 - r2 * r4) / ((r1 + r2) * (r3 + r4))
    return out if out.ndim else float(out)


def gauge_resistance_ohm(strain, sensors: Sensors | None = None):
    """Gauge resistance under strain, ``R (1 + GF eps)`` (E 2.1); vectorised."""
    s = sensors or Sensors()
    out = s.gauge_resistance_ohm * (1.0 + s.gauge_factor * np.asarray(strain, dtype=float))
    return out if out.ndim else float(out)


def bridge_ratio(strain, sensors: Sensors | None = None, *, bridge: str | None = None, linear: bool = False):
    """Bridge output over supply, ``Vm/Vs``, for the strain at the gauge(s) (E 2.2-2.4).

    Parameters
    ----------
    strain : float or array_like
        Surface strain at the gauge (dimensionless); for half and full bridges the opposite gauges see ``-strain``.
    sensors : Sensors, optional
        Gauge factor, resistance and the bridge type (default: the thesis's half bridge, GF = 0.8).
    bridge : {"quarter", "half", "full"}, optional
        Override ``sensors.bridge``.
    linear : bool
        Use the small-strain forms (``GF eps / 4``, ``GF eps / 2``, ``GF eps``) instead of E 2.2 exactly.
        Only the quarter bridge differs.

    Returns
    -------
    float or ndarray
        ``Vm/Vs`` (V/V).

    Examples
    --------
    >>> [round(float(bridge_ratio(1e-3, bridge=b)) * 1e3, 4) for b in ("quarter", "half", "full")]
    [0.1999, 0.4, 0.8]
    """
    s = sensors or Sensors()
    kind = check_choice(s.bridge if bridge is None else bridge, "bridge", BRIDGE_TYPES, "bridge_ratio")
    eps = np.asarray(strain, dtype=float)
    x = s.gauge_factor * eps  # dR/R, E 2.1
    if linear:
        out = {"quarter": x / 4.0, "half": x / 2.0, "full": x}[kind]
    else:
        r = s.gauge_resistance_ohm
        up, down = r * (1.0 + x), r * (1.0 - x)
        fixed = np.full_like(eps, r)
        if kind == "quarter":
            out = wheatstone_ratio(up, fixed, fixed, fixed)
        elif kind == "half":  # E 2.4: R3 = R4 inside the amplifier
            out = wheatstone_ratio(up, down, fixed, fixed)
        else:  # E 2.3
            out = wheatstone_ratio(up, down, up, down)
    out = np.asarray(out, dtype=float)
    return out if out.ndim else float(out)


def bridge_gain_v_per_strain(sensors: Sensors | None = None) -> float:
    """Small-strain sensitivity of bridge + excitation + amplifier, volts at the amplifier per unit strain.

    Half bridge, thesis defaults: ``0.8/2 x 1 V x 10,000 = 4000 V`` per unit strain (0.004 V per microstrain).
    """
    s = sensors or Sensors()
    per = {"quarter": 0.25, "half": 0.5, "full": 1.0}[s.bridge]
    return per * s.gauge_factor * s.excitation_v * s.amplifier_gain_v_per_v


def lowpass_tf(sensors: Sensors | None = None) -> control.TransferFunction:
    """The amplifier's low-pass as a transfer function: Butterworth, cut-off ``amplifier_lowpass_hz``, unit DC gain.

    Uses ``scipy.signal.butter(..., analog=True)``; order from ``sensors.amplifier_lowpass_order`` (assumed 2).

    Examples
    --------
    >>> lp = lowpass_tf()
    >>> round(float(abs(lp(2j * math.pi * 470.0))), 4)        # -3 dB at the cut-off
    0.7071
    """
    # imported here: python-control and scipy.signal cost 2 s of start-up to every user of the bridge (the twin)
    import control
    import scipy.signal

    s = sensors or Sensors()
    b, a = scipy.signal.butter(s.amplifier_lowpass_order, 2.0 * math.pi * s.amplifier_lowpass_hz, analog=True)
    return control.tf(b / a[0], a / a[0])


def amplifier_tf(sensors: Sensors | None = None) -> control.TransferFunction:
    """Amplifier gain times its low-pass (V/V): ``10,000 x Butterworth(470 Hz)`` by default."""
    s = sensors or Sensors()
    return s.amplifier_gain_v_per_v * lowpass_tf(s)


def strain_to_volts_tf(sensors: Sensors | None = None) -> control.TransferFunction:
    """Strain -> amplifier output volts, small-strain bridge gain times the amplifier's TF (V per unit strain)."""
    s = sensors or Sensors()
    return bridge_gain_v_per_strain(s) * lowpass_tf(s)


def adc_counts(voltage_v, sensors: Sensors | None = None):
    """ADC codes for input voltages: round to the nearest step of ``adc_lsb_v``, clip to ``[0, 2**bits - 1]``.

    Code 0 is the bottom of ``adc_range_v`` (-5 V); NaN inputs map to code 0. Returns an ``int64`` array
    (or an int for a scalar).

    Examples
    --------
    >>> adc_counts([-10.0, 0.0, 10.0]).tolist()
    [0, 32768, 65535]
    """
    s = sensors or Sensors()
    v = np.asarray(voltage_v, dtype=float)
    codes = np.rint((np.nan_to_num(v, nan=s.adc_range_v[0]) - s.adc_range_v[0]) / s.adc_lsb_v)
    out = np.clip(codes, 0, 2**s.adc_bits - 1).astype(np.int64)
    return out if out.ndim else int(out)


def counts_to_volts(counts, sensors: Sensors | None = None):
    """Voltage of ADC codes: ``range_low + code x lsb`` (V)."""
    s = sensors or Sensors()
    out = s.adc_range_v[0] + np.asarray(counts, dtype=float) * s.adc_lsb_v
    return out if out.ndim else float(out)


def adc_quantise(voltage_v, sensors: Sensors | None = None):
    """What the DAQ card reads for input voltages: quantised to 16 bits and clipped to +-5 V (V).

    Examples
    --------
    >>> [round(v, 5) for v in adc_quantise([0.0001, 7.0]).tolist()]   # one LSB is 0.153 mV
    [0.00015, 4.99985]
    """
    return counts_to_volts(adc_counts(voltage_v, sensors), sensors)


def adc_clipped(voltage_v, sensors: Sensors | None = None):
    """True where an input voltage lies outside what the ADC can represent (it reads as the end code)."""
    s = sensors or Sensors()
    v = np.asarray(voltage_v, dtype=float)
    top = s.adc_range_v[0] + (2**s.adc_bits - 1) * s.adc_lsb_v
    return (v < s.adc_range_v[0] - s.adc_lsb_v / 2) | (v > top + s.adc_lsb_v / 2)


def gauge_voltage_v(strain, sensors: Sensors | None = None, *, quantise: bool = False, linear: bool = False):
    """Static gauge-channel voltage for a surface strain: ``Vs x Vm/Vs x gain`` (V), optionally through the ADC.

    The low-pass is left out (static); use :func:`strain_to_volts_tf` for the dynamics.
    """
    s = sensors or Sensors()
    v = np.asarray(bridge_ratio(strain, s, linear=linear)) * s.excitation_v * s.amplifier_gain_v_per_v
    if quantise:
        return adc_quantise(v, s)
    return v if v.ndim else float(v)


def strain_from_voltage(voltage_v, sensors: Sensors | None = None):
    """Invert the small-strain chain: surface strain for an amplifier output voltage."""
    out = np.asarray(voltage_v, dtype=float) / bridge_gain_v_per_strain(sensors)
    return out if out.ndim else float(out)


def gauge_noise_scale(sensors: Sensors, count: int) -> np.ndarray | None:
    """Each gauge's white noise relative to the others' (the amplifier gains, ``amplifier_gains_v_per_v``) when the
    gauges have amplifiers of unequal gain, else None (equal noise): the weights of the rotation map's Gauss-Markov
    inverse (:class:`~flexdigit.rig.rotation.RotationEstimator`'s ``noise_v``; only ratios matter) and of the 20 ms
    design's model of it (:mod:`flexdigit.control.digit_model`).

    Why: a gauge's noise is its amplifier's input-referred noise amplified with its signal (the twin's default
    calibration scales ``noise_white_v`` by the gain, :mod:`flexdigit.twin.digit_calibration`). The map's
    equal-weight inverse ``theta = s' (g - a) / (s' s)`` weighs each gauge by its sensitivity in volts squared:
    amplify one gauge 12 times more than another and it takes 144 times the weight though its noise in degrees is
    the same, and the estimate becomes the most amplified gauge's alone. On the trial's stainless digit (gains
    500..6000) that was the tip gauge, which bends most in the step's transient: the estimate overshot 46 % where
    the tip overshot 12-21 %, and the loop settled in 2.4 s or never. Weighted by the gains, each gauge counts as on
    equal chains: the map does not depend on how each gauge was amplified. The gains, not the sweep's measured
    noise: a low-gain gauge's noise near one ADC step is measured in jumps of a factor 2 (the robust estimate of
    quantised readings), and its weight with it (a factor 4 between twin seeds on a mixed-gain pair).

    Examples
    --------
    >>> from flexdigit.params import Sensors
    >>> gauge_noise_scale(Sensors(), 3) is None
    True
    >>> gauge_noise_scale(Sensors(amplifier_gains_v_per_v=(500.0, 6000.0)), 2).tolist()
    [500.0, 6000.0]
    """
    gains = np.asarray(sensors.chain(count)[2], dtype=float)
    return gains if gains.size and float(gains.max()) > float(gains.min()) else None
