"""A described digit's design model: the twin's chain linearised with its cable(s) taut, its modes truncated.

The thesis's G(s) (3.5) is servo x cable x one digit mode. A digit nobody has identified has more than one mode
that matters: a 0.5 m digit's first mode is 1.5 Hz with zeta 0.02, within the servo's bandwidth, and its gauges,
spread along the strip, see the higher modes the tip hardly shows. Here the model is built from the same chain the
twin integrates (:mod:`flexdigit.twin.digit`), linearised about the static shape half-way to the step:

``M psi'' + C psi' + K psi = b s``, ``M = A cos(psi_j - psi_k)``, ``K`` the tangent stiffness (springs, gravity,
``k_c e^2`` per taut cable), ``b = k_c e`` per taut cable on the tip link (E 3.11), ``s`` the cable shortening
(the pulley's metres per command times the servo's angle, 3.2.4 and E 3.11).

Two outputs, both in degrees:

- the **tip rotation** ``psi_n`` (what the loop is asked to hold, and scored on);
- the **rotation the loop measures**: the gauges' curvature ``kappa = D psi`` through each channel's volts per
  curvature (:meth:`flexdigit.twin.sensors.SensorChain.volts_per_curvature`) and the static map the calibration
  sweep fits (:class:`flexdigit.rig.rotation.RotationEstimator`, equal weights: its weights are the gauges'
  sensitivities along the static shape over their sum of squares). Statically the two agree; while the digit
  vibrates they do not, and the design knows by how much.

**Modal truncation.** Of the chain's ``n`` modes (one a cell, :func:`flexdigit.twin.digit.default_cells`) the
model keeps the lowest :data:`MAX_MODES` (vibrating, or the real poles of overdamped cells), whatever their
frequency against the loop's Nyquist frequency; the others' static share is kept (the residual is matched at
DC, python-control's ``modred(..., "matchdc")``), so the model's rotation per command is the chain's. A mode
above Nyquist is not negligible because the command cannot excite it at its own frequency: matched at DC it
answers the servo at once, while a stiffness-damped mode lags it by ``2 zeta / wn``. Where such a mode carries a
large static share of the gauges the model's measured rotation leads and outswings the twin's:
``random_digit(23)`` (one 0.475 m section, hung, at 3 cells a section), its 200 rad/s third mode (zeta 0.93)
dropped, read 32.9 deg where the twin's gauges read 13.7, 40 ms into a step (kept: 13.7 against 13.8), and the
design chosen on it overshot 21 % on the twin. Sampled with the hold (``sample_system(..., "zoh")``) a kept mode
above Nyquist is exact at the samples: it aliases in the model as it does on the rig. The noise of the measured
rotation is the gauges' white noise through the map's weights.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import control as ct
import numpy as np

from flexdigit.errors import DesignError
from flexdigit.models.bridge import gauge_noise_scale
from flexdigit.models.cable import tip_rotation_per_command_deg
from flexdigit.models.servo import servo_unit_tf
from flexdigit.params import RigParams, twin_cells
from flexdigit.twin.digit_calibration import twin_calibration
from flexdigit.twin.sensors import SensorChain
from flexdigit.twin.twin import cable_shortening_m, cached_digit

__all__ = ["DigitModel", "digit_model", "MAX_MODES"]

#: The most chain modes a design model keeps (lowest first; module docstring): with the servo, the delay and the
#: disturbance an observer of at most 2 + 2 x 6 + 2 states.
MAX_MODES = 6


@dataclass(frozen=True)
class DigitModel:
    """The design model of one digit (module docstring).

    Attributes
    ----------
    plant : control.StateSpace
        Continuous, command deviation -> ``[tip rotation, measured rotation]`` (deg).
    deg_per_command : float
        Its DC gain (both outputs).
    modes_wn_rad_s, modes_zeta : ndarray
        The chain's modes kept (cable(s) taut, about the operating shape).
    truncated_wn_rad_s : ndarray
        The modes left out (past the lowest :data:`MAX_MODES`).
    measurement_sd_deg : float
        Standard deviation of one reading of the measured rotation from the gauges' white noise and the ADC's
        rounding (:func:`reading_variance_v2`), deg.
    operating_deg : float
        The tip rotation the chain was linearised about, deg.
    measured_deg_per_rad : ndarray or None
        The measured rotation as a row of the chain's angles (deg per rad of each link's angle): what the plant's
        second output reads of a state of the chain (its static map at the operating shape).
    """

    plant: ct.StateSpace
    deg_per_command: float
    modes_wn_rad_s: np.ndarray
    modes_zeta: np.ndarray
    truncated_wn_rad_s: np.ndarray
    measurement_sd_deg: float
    operating_deg: float
    measured_deg_per_rad: np.ndarray | None = None


def _operating_shape(chain, params: RigParams, at_deg: float):
    """The chain's static solution at the command nearest ``at_deg`` of tip rotation (cable model, E 3.15)."""
    a = params.actuator
    command = a.equilibrium_command + round(at_deg / tip_rotation_per_command_deg(params))
    command = min(max(command, a.command_min), a.command_max)
    shortening = float(cable_shortening_m(command, params))
    solution = chain.solve_static(cable_shortening_m=np.array([shortening]))
    if not bool(np.all(solution.converged)):
        raise DesignError(f"design: the digit's static shape at command {command} did not converge")
    return solution, shortening


def digit_model(
    params: RigParams,
    calibration=None,
    *,
    orientation: str = "vertical",
    at_deg: float = 15.0,
    cells_per_section: int | None = None,
) -> DigitModel:
    """The design model of a described digit (module docstring), linearised at ``at_deg`` of tip rotation.

    Parameters
    ----------
    params : RigParams
    calibration : Calibration, optional
        The twin's (default: the one the twin gets for the digit).
    orientation : str
        How the digit is mounted (gravity on the chain).
    at_deg : float
        The operating tip rotation, deg (half the 30 deg step).

    Returns
    -------
    DigitModel

    Examples
    --------
    >>> m = digit_model(RigParams())
    >>> m.plant.noutputs, round(m.deg_per_command, 1), bool(m.modes_wn_rad_s[0] < 157)
    (2, 1.7, True)
    """

    cal = calibration if calibration is not None else twin_calibration(params)
    cells = cells_per_section or twin_cells(params)  # the description's resolution, not a derived twin's finer one
    chain = cached_digit(params, cal, True, orientation, cells)
    solution, shortening = _operating_shape(chain, params, at_deg)
    psi = np.asarray(solution.psi_rad[0], dtype=float)
    _, _, taut1, taut2 = chain.cable_tensions(psi[-1], shortening)
    taut = float(bool(taut1)) + float(bool(taut2))
    if taut == 0:
        raise DesignError(f"design: the digit's cable is slack at {at_deg:g} deg; no command reaches the tip")
    n = chain.n
    m = chain.a_mass * np.cos(psi[:, None] - psi[None, :])
    k = chain.tangent_stiffness(psi, chain.g_gravity, taut)
    b = np.zeros(n)
    b[-1] = chain.cable_stiffness * chain.eccentricity * taut
    c_measured, sd_deg = _measured_rotation(chain, params, cal, solution, np.linalg.solve(k, b))
    # modal form of the chain, the lowest modes kept, the rest matched at DC
    minv = np.linalg.inv(m)
    a_chain = np.block([[np.zeros((n, n)), np.eye(n)], [-minv @ k, -minv @ chain.c_psi]])
    b_chain = np.concatenate([np.zeros(n), minv @ b])[:, None]
    c_chain = np.zeros((2, 2 * n))
    c_chain[0, n - 1] = 1.0
    c_chain[1, :n] = c_measured
    reduced, dropped, kept = _truncated(a_chain, b_chain, np.degrees(c_chain))
    metres_per_command = params.actuator.rad_per_command * params.actuator.cable_m_per_servo_rad
    plant = _balanced(ct.series(ct.ss(servo_unit_tf(params)), reduced) * metres_per_command)
    dc = np.real(np.asarray(ct.dcgain(plant))).reshape(-1)
    lam_kept = np.linalg.eigvals(np.asarray(reduced.A))
    lam_kept = lam_kept[lam_kept.imag > 0]
    order = np.argsort(np.abs(lam_kept))
    return DigitModel(
        plant=plant,
        deg_per_command=float(dc[0]),
        modes_wn_rad_s=np.abs(lam_kept[order]),
        modes_zeta=-lam_kept[order].real / np.abs(lam_kept[order]),
        truncated_wn_rad_s=dropped,
        measurement_sd_deg=sd_deg,
        operating_deg=math.degrees(float(psi[-1])),
        measured_deg_per_rad=np.degrees(c_measured),
    )


def _measured_rotation(chain, params: RigParams, calibration, solution, static: np.ndarray):
    """The rotation the gauges measure as a row of the chain's angles (rad per rad), and one reading's standard
    deviation from their white noise (deg): curvature at the gauges (linear in the angles), each channel's volts
    per curvature at the operating shape, and the weights the sweep's equal-weight map gives them (each gauge's
    sensitivity along the static shape ``static`` over their sum of squares, :class:`RotationEstimator`); each
    reading's variance is its white noise's and the ADC's rounding's (:func:`reading_variance_v2`)."""
    d = np.asarray(chain._psi_to_gauge_curvature, dtype=float)  # (G, n)
    sensors = SensorChain(params, calibration, np.random.default_rng(0))
    vpc = sensors.volts_per_curvature(solution.curvature_1_m[0], solution.axial_force_n[0])
    sens_v_per_rad = vpc * (d @ static) / static[-1]  # each gauge's volts per radian of tip rotation
    information = float(sens_v_per_rad @ sens_v_per_rad)
    if not information > 0:
        raise DesignError("design: the digit's gauges do not see the cable's bending (no gauge on a bent strip)")
    weights = _map_weights(sens_v_per_rad, gauge_noise_scale(params.sensors, sens_v_per_rad.size))
    sd_deg = math.degrees(float(np.sqrt(np.sum(weights**2 * reading_variance_v2(params, sensors.white)))))
    return (weights * vpc) @ d, sd_deg


def reading_variance_v2(params: RigParams, white_v) -> np.ndarray:
    """Each gauge's reading variance (V^2): its white noise and the ADC's rounding, ``lsb^2 / 12`` (the uniform
    rounding error of a step ``lsb``; Widrow and Kollar, *Quantization Noise*, 2008, ch. 4). A coarse ADC's steps
    are most of what a reading scatters by: heavy_supports_10bit_bipolar's 10 bits over 5 V step 4.9 mV (1.41 mV
    sd) beside 0.1 mV of white noise, so a design that saw the white noise alone (0.02 deg of measured rotation,
    0.29 with the rounding) chose an observer that turned each step of the reading into several commands (the
    command swung 15..34 about 26 and the tip left the band by 13.5 %)."""
    white = np.asarray(white_v, dtype=float)
    return white**2 + float(params.sensors.adc_lsb_v) ** 2 / 12.0


def _map_weights(sens_v_per_rad: np.ndarray, noise) -> np.ndarray:
    """The weights (rad per volt) the sweep's map gives the gauges (:class:`~flexdigit.rig.rotation.RotationEstimator`
    as :func:`~flexdigit.rig.rotation.calibrate_rotation` fits it): each gauge's sensitivity over their sum of
    squares, or, with an amplifier gain per gauge (``noise``, :func:`~flexdigit.models.bridge.gauge_noise_scale`),
    the Gauss-Markov weights ``W s / (s' W s)``, ``W = 1 / noise^2``."""
    w = np.ones_like(sens_v_per_rad) if noise is None else 1.0 / np.asarray(noise, dtype=float) ** 2
    information = float(sens_v_per_rad @ (w * sens_v_per_rad))
    return w * sens_v_per_rad / information


def _truncated(a: np.ndarray, b: np.ndarray, c: np.ndarray):
    """Modal truncation of ``(a, b, c)`` keeping its lowest :data:`MAX_MODES` modes (a conjugate pair or a real
    pole each, by ``|lambda|``), the others' static share kept as a feedthrough (matched at DC).

    The kept modes' invariant subspace is spanned by the real and imaginary parts of their eigenvectors; ``P``, the
    spectral projector onto it (real: conjugate pairs are kept together), gives the reduced system
    ``(W a V, W b, c V)`` with ``W = V^+ P``, and the rest's DC share ``-c a^-1 (I - P) b``. Returns
    ``(system, the dropped modes' wn (rad/s), the kept modes' wn)``.
    """
    lam, vectors = np.linalg.eig(a)
    left = np.linalg.inv(vectors)
    upper = lam.imag >= 0
    # the lowest modes, vibrating or real (an overdamped cell mode's branches), whatever the loop's Nyquist frequency
    # (module docstring: a mode above it matched at DC answers the servo too early)
    ranked = np.sort(np.abs(lam[upper]))[:MAX_MODES]
    cutoff = ranked[-1] if ranked.size else 0.0
    keep = np.abs(lam) <= cutoff * (1 + 1e-9)
    projector = np.real(vectors[:, keep] @ left[keep, :])
    basis = np.hstack([vectors[:, keep & upper].real, vectors[:, keep & upper & (lam.imag > 0)].imag])
    w = np.linalg.pinv(basis) @ projector
    rest = np.eye(a.shape[0]) - projector
    feedthrough = -c @ np.linalg.solve(a, rest @ b)
    system = ct.ss(w @ a @ basis, w @ b, c @ basis, feedthrough)
    return system, np.sort(np.abs(lam[upper & ~keep])), ranked


def _balanced(system: ct.StateSpace) -> ct.StateSpace:
    """The same system with its states scaled (LAPACK's balancing of ``[[A, B], [C, 0]]``): the series of the
    servo (radians) and the chain (per metre of cable) spans nine decades between ``B`` and ``C``, which the
    Riccati solvers of the design refuse ("spectrum too close to the boundary")."""
    import scipy.linalg

    a, b, c, d = (np.asarray(x, dtype=float) for x in (system.A, system.B, system.C, system.D))
    n = a.shape[0]
    whole = np.zeros((n + 1, n + 1))
    whole[:n, :n], whole[:n, n:], whole[n:, :n] = a, b, c[-1:]
    _, (scale, _) = scipy.linalg.matrix_balance(whole, permute=False, separate=True)
    t = scale[:n] / scale[n]
    return ct.ss(a * t[None, :] / t[:, None], b / t[:, None], c * t[None, :], d)
