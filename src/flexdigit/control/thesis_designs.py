"""The thesis's H-infinity designs (chapter 4), rebuilt and set beside the controllers as printed.

The problem of 4.4 weights only the tracking error (``D12 = 0``): its infimal ``gamma`` is 0 and is not
attained (for a stable minimum-phase plant ``Q = G^-1/(tau s + 1)^4`` drives ``||F S||`` to 0 as ``tau -> 0``),
so every controller MATLAB's ``hinfric`` returned belongs to some regularisation ``eps_u`` and some distance
from the optimum. :func:`fit_thesis_regularisation` finds the ``(eps_u, margin)`` whose central controller has
the printed poles: the fit is exact to 4-5 digits for both printed controllers, and then the printed
numerators are 10x ours (see :func:`printed_controller`).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import warnings

import control as ct
import numpy as np
from scipy.optimize import minimize

from flexdigit._validation import check_positive
from flexdigit.control.analysis import additive_tolerance, hinf_norm, is_stable, loop_maps, step_metrics
from flexdigit.control.generalized import filter_weight, regularise, thesis_generalized_plant
from flexdigit.control.synthesis import HinfDesign, central_controller_poles, hinf_riccati
from flexdigit.errors import ConvergenceWarning, DesignError
from flexdigit.models.plant import build_plant
from flexdigit.params import DigitDynamics
from flexdigit.reference import thesis_complex, thesis_value
from flexdigit.twin.twin import release_dynamics

__all__ = [
    "THESIS_REGULARISATION",
    "printed_controller",
    "thesis_plant",
    "thesis_design",
    "fit_thesis_regularisation",
    "sorted_poles",
    "singular_infimum_witness",
    "OPEN_LOOP_GAMMA_RTOL",
    "is_open_loop",
    "digit_plant",
    "digit_regularisation",
    "digit_hinf_design",
    "digit_hinf_summary",
]

#: ``(eps_u, margin)`` per cut-off (Hz) that reproduce the printed controller poles (tables 4.2, 4.3), as found
#: by :func:`fit_thesis_regularisation` (tests re-run the fit); other cut-offs use the 5 Hz pair.
THESIS_REGULARISATION: dict[float, tuple[float, float]] = {5.0: (1.0538e-7, 0.20912), 39.0: (8.4175e-7, 1.8405)}

#: A design whose ``gamma_opt`` is within this fraction of ``||F||_inf = 1/(2 pi f_c)`` (the cost of no controller
#: at all, ``K = 0``) is the open-loop one: the weights leave nothing to gain by feeding back, its central controller
#: is an arbitrary small stabilising one and its additive tolerance ``1/||K S||`` measures a loop that does not
#: control. 1 %: the bisection's optimum sits 8e-4 above it where K = 0 is optimal (0.00408408 against
#: 1/(2 pi 39) = 0.00408090 on every digit at 39 Hz), and a controlling design is 10-40 % below (0.020-0.025 at 5 Hz
#: against 0.0318).
OPEN_LOOP_GAMMA_RTOL = 1e-2


def is_open_loop(gamma_opt: float, filter_hz: float) -> bool:
    """Whether a design of 4.4 at cut-off ``filter_hz`` whose optimum is ``gamma_opt`` is the open-loop one:
    ``gamma_opt`` within :data:`OPEN_LOOP_GAMMA_RTOL` of ``||F||_inf = 1/(2 pi f_c)``, the cost of ``K = 0``.

    >>> is_open_loop(0.00408408, 39.0), is_open_loop(0.0240224, 5.0)
    (True, False)
    """
    return gamma_opt >= (1 - OPEN_LOOP_GAMMA_RTOL) / (2 * math.pi * filter_hz)


#: Relative pole error a fit to printed poles must reach: half a unit in table 4.3's 4th significant digit.
POLE_FIT_RTOL = 5e-4

_PRINTED = {"5hz": ("hinf.k_5hz_num", "hinf.k_5hz_den"), "39hz": ("hinf.k_39hz_num", "hinf.k_39hz_den")}


def printed_controller(which: str) -> ct.TransferFunction:
    """The controller as printed in 4.4 (``"5hz"``) or 4.7 (``"39hz"``), commands per metre.

    Examples
    --------
    >>> K = printed_controller("39hz")
    >>> float(K.num[0][0][0])
    416.5
    """
    if which not in _PRINTED:
        raise DesignError(f"The 'which' parameter must be one of {sorted(_PRINTED)}. Got {which!r} instead.")
    num, den = _PRINTED[which]
    return ct.tf(thesis_value(num), thesis_value(den))


def thesis_plant(variant: str = "printed"):
    """The plant of 4.2 from :func:`flexdigit.models.plant.build_plant` (m of gauge-1 deflection per command)."""
    return build_plant(variant).tf


def thesis_design(
    filter_hz: float,
    plant=None,
    *,
    eps_u: float | None = None,
    margin: float | None = None,
) -> HinfDesign:
    """The H-infinity design of 4.4 with the low-pass error weight ``1/(s + 2 pi filter_hz)``.

    Parameters
    ----------
    filter_hz : float
        Cut-off of ``F(s)`` in Hz (the thesis uses 0.5, 5, 39 and 50).
    plant : LTI system, optional
        Defaults to the printed plant of 4.2.
    eps_u, margin : float, optional
        Regularisation and gamma margin; default :data:`THESIS_REGULARISATION` (the 5 Hz pair for cut-offs the
        thesis prints no controller for).
    """
    fc = check_positive(filter_hz, "filter_hz", "thesis_design", error=DesignError)
    default = THESIS_REGULARISATION.get(round(fc, 6), THESIS_REGULARISATION[5.0])
    eps_u = default[0] if eps_u is None else eps_u
    margin = default[1] if margin is None else margin
    G = thesis_plant() if plant is None else plant
    P = regularise(thesis_generalized_plant(G, filter_weight(fc)), eps_u)
    return hinf_riccati(P, margin=margin)


def sorted_poles(values) -> np.ndarray:
    """Poles sorted by real part, then imaginary part (for comparing lists)."""
    v = np.asarray(values, dtype=complex)
    return v[np.lexsort((v.imag, np.round(v.real, 6)))]


def fit_thesis_regularisation(filter_hz: float, target_poles=None, plant=None) -> dict:
    """Find ``(eps_u, margin)`` whose central controller has the printed poles (table 4.2 or 4.3).

    A grid over ``log10 eps_u`` in [-9, -3] and ``margin`` in [0.01, 3], then Nelder-Mead on the relative
    squared pole error.

    Returns
    -------
    dict
        ``eps_u``, ``margin``, ``pole_error`` (largest relative pole error), ``design``, ``converged`` (the
        Nelder-Mead search met its own tolerances within 200 iterations). The fit is judged by its pole error: a
        :class:`~flexdigit.errors.ConvergenceWarning` is issued when the search stopped unconverged with an error
        above :data:`POLE_FIT_RTOL` (the 39 Hz fit stops on the iteration limit at 2e-4, within the printed digits).
    """
    fc = check_positive(filter_hz, "filter_hz", "fit_thesis_regularisation", error=DesignError)
    if target_poles is None:
        key = {5.0: "hinf.k_5hz_poles", 39.0: "hinf.k_39hz_poles"}.get(round(fc, 6))
        if key is None:
            raise DesignError(f"The thesis prints controller poles for 5 and 39 Hz only. Got {filter_hz!r}.")
        target_poles = thesis_complex(key)
    target = sorted_poles(target_poles)
    G = thesis_plant() if plant is None else plant
    P0 = thesis_generalized_plant(G, filter_weight(fc))

    def poles_for(x):
        d = hinf_riccati(regularise(P0, 10 ** x[0]), margin=x[1])
        return d, sorted_poles(np.linalg.eigvals(d.controller.A))

    gamma_opts: dict[float, float] = {}  # eps_u -> its optimum: the grid tries every eps_u at 5 margins

    def cost(x):
        if x[1] < 0 or not -12 < x[0] < 0:
            return 1e3
        try:  # the poles of poles_for(x)'s design, without building it (hundreds of evaluations)
            p = sorted_poles(central_controller_poles(P0, 10 ** x[0], x[1], gamma_opts))
        except (DesignError, ArithmeticError):
            return 1e3
        if p.size != target.size:
            return 1e3
        return float(np.sum(np.abs(p - target) ** 2 / np.abs(target) ** 2))

    grid = [(cost([le, m]), le, m) for le in np.arange(-9.0, -2.9, 0.5) for m in (0.01, 0.05, 0.2, 0.8, 3.0)]
    _, le, m = min(grid)
    res = minimize(cost, [le, m], method="Nelder-Mead", options={"xatol": 1e-4, "fatol": 1e-10, "maxiter": 200})
    design, poles = poles_for(res.x)
    err = float(np.max(np.abs(poles - target) / np.abs(target)))
    if not res.success and err > POLE_FIT_RTOL:
        warnings.warn(
            f"fit_thesis_regularisation({filter_hz:g} Hz): Nelder-Mead stopped unconverged ({res.message}) with "
            f"the largest relative pole error {err:.3g}, above the printed digits' {POLE_FIT_RTOL:g} (converged=False)",
            ConvergenceWarning,
            stacklevel=2,
        )
    return {
        "eps_u": float(10 ** res.x[0]),
        "margin": float(res.x[1]),
        "pole_error": err,
        "design": design,
        "converged": bool(res.success),
    }


def singular_infimum_witness(plant, filter_hz: float, tau: float) -> float:
    """``||F (1 - G Q)||_inf`` for ``Q = G^-1/(tau s + 1)^n``: a stabilising controller family whose cost -> 0.

    Shows that the unregularised problem of 4.4 has infimum 0 (a plant with no right-half-plane zeros or poles),
    so the thesis's gamma depends entirely on the regularisation.
    """
    G = ct.tf(plant)
    n = len(np.trim_zeros(G.den[0][0], "f")) - len(np.trim_zeros(G.num[0][0], "f"))
    lp = ct.tf([1.0], [tau, 1.0]) ** n
    S = 1 - lp  # = 1 - G Q with Q = lp / G
    F = filter_weight(filter_hz)
    return float(ct.linfnorm(ct.ss(F * S))[0]) if math.isfinite(tau) else math.nan


def digit_plant(params, calibration=None, *, orientation: str = "vertical", output: str = "deflection_sg1_m"):
    """The plant G(s) of a described digit, built the thesis's way from its components (3.5): the servo (3.2.4),
    the cable (E 3.11-3.15 with the gearing), the digit's E(s) and the gauge chain to ``output``
    (:func:`flexdigit.models.plant.build_plant` ``"consistent"``, unit-correct). E(s) is the digit's release-test
    mode from its twin (:func:`flexdigit.twin.twin.release_dynamics`; the thesis rig: table 3.2's
    values to 0.01 %), not the thesis's tables, which are its rig's alone; a file that gives ``[dynamics]``
    (identified on that digit) is taken at its word.
    """

    # the file's [dynamics] when it gives them (identified on that digit), else its twin's release mode
    given = params.dynamics != DigitDynamics()
    dynamics = params.dynamics if given else release_dynamics(params, calibration, orientation=orientation)
    if not (dynamics.wn_housing_rad_s > 0 and dynamics.zeta_housing > 0):
        raise DesignError(f"the digit's release mode is not a damped vibration ({dynamics!r}): no plant to design on")
    return build_plant("consistent", dataclasses.replace(params, dynamics=dynamics), output=output)


@functools.cache
def _thesis_rig_dc_gain() -> float:
    """``|G(0)|`` of the thesis rig's unit-correct plant (``build_plant("consistent")``), m per command."""
    return abs(build_plant("consistent").dc_gain)


def digit_regularisation(filter_hz: float, plant_dc_gain: float) -> tuple[float, float]:
    """``(eps_u, margin)`` of 4.4's design on a digit whose plant has DC gain ``plant_dc_gain`` (m per command).

    The thesis's pair (:data:`THESIS_REGULARISATION`) with ``eps_u`` scaled by ``|G(0)|`` over the thesis rig's
    (its unit-correct plant, ``design hinf --plant consistent``). The regularised problem is covariant: ``G -> c G``
    with ``eps_u -> c eps_u`` gives the same ``gamma_opt`` and ``K -> K/c``, so a digit is weighted as the thesis
    weighted its rig (control effort against its plant's gain); an absolute ``eps_u`` would weigh a digit 10x less
    stiff in gain 10x harder against control and leave it nearly open loop. The thesis rig gets its pair back.
    """
    fc = check_positive(filter_hz, "filter_hz", "digit_regularisation", error=DesignError)
    eps_u, margin = THESIS_REGULARISATION.get(round(fc, 6), THESIS_REGULARISATION[5.0])
    return eps_u * abs(plant_dc_gain) / _thesis_rig_dc_gain(), margin


def digit_hinf_design(
    filter_hz: float,
    params,
    calibration=None,
    *,
    orientation: str = "vertical",
    eps_u: float | None = None,
    margin: float | None = None,
):
    """The H-infinity design of 4.4 (:func:`thesis_design`) on a described digit's plant (:func:`digit_plant`,
    gauge-1 deflection in m per command), regularised as :func:`digit_regularisation` says unless ``eps_u`` is
    given (solved as the thesis's problem on ``c G``, ``c`` = the thesis rig's ``|G(0)|`` over the digit's, and
    ``K = c K'``: the same design, without the Riccati solver's failure at ``eps_u`` ~ 1e-8), checked: returns
    ``(design, plant)``; a controller that does not stabilise the plant is refused
    (:class:`~flexdigit.errors.DesignError`, one line)."""

    plant = digit_plant(params, calibration, orientation=orientation)
    margin = digit_regularisation(filter_hz, plant.dc_gain)[1] if margin is None else margin
    if eps_u is None:  # solved on the plant scaled to the thesis rig's |G(0)| (as well conditioned as the rig's)
        scale = _thesis_rig_dc_gain() / abs(plant.dc_gain)
        design = thesis_design(filter_hz, scale * plant.tf, margin=margin)
        design = dataclasses.replace(design, controller=scale * design.controller)
    else:
        design = thesis_design(filter_hz, plant.tf, eps_u=eps_u, margin=margin)
    maps = loop_maps(plant.tf, design.controller)
    if not is_stable(maps.T_yw):
        raise DesignError(
            f"design hinf: the {filter_hz:g} Hz central controller does not stabilise this digit's plant "
            f"(poles {np.round(plant.poles, 3).tolist()}): not a design to stand behind"
        )
    return design, plant


def digit_hinf_summary(
    filter_hz: float,
    params,
    calibration=None,
    *,
    orientation: str = "vertical",
    eps_u: float | None = None,
    margin: float | None = None,
) -> dict:
    """The H-infinity design of 4.4 on a described digit's plant and its figures, as ``flexdigit design hinf
    --params`` reports them.

    Parameters
    ----------
    filter_hz : float
        Cut-off of the error filter ``F(s) = 1/(s + 2 pi f)``, Hz.
    params : RigParams
        The digit.
    calibration : optional
        The twin's calibration for the digit's mode (default: the one the twin would get).
    orientation : str
        How the digit is mounted, for its mode.
    eps_u, margin : float, optional
        Regularisation and distance from ``gamma_opt`` (default: :func:`digit_regularisation`).

    Returns
    -------
    dict
        The plant (``plant_num``, ``plant_den``, ``plant_poles`` as ``[re, im]``, ``plant_dc_gain_m_per_command``,
        ``digit_wn_rad_s``), the design (``eps_u``, ``gamma_opt``, ``gamma``, ``margin``, ``controller_num``,
        ``controller_den``, ``controller_poles``) and its figures (``tzw_peak_db`` at ``tzw_peak_rad_s``,
        ``tpq_peak_db``, ``open_loop_gamma``, ``loop_gain_dc``, ``additive_tolerance_m_per_command``,
        ``additive_tolerance_relative_percent`` (None, ``additive_tolerance_note`` says why, for the open-loop
        design: :func:`_digit_tolerance`), ``tyw_settling_s`` over 3 s).

    Raises
    ------
    DesignError
        When the central controller does not stabilise the digit's plant (:func:`digit_hinf_design`).
    """
    d, plant = digit_hinf_design(filter_hz, params, calibration, orientation=orientation, eps_u=eps_u, margin=margin)
    K = d.controller
    maps = loop_maps(plant.tf, K)
    tzw, wzw = hinf_norm(maps.T_zw, "T_zw")
    tf = ct.tf(K)
    return {
        "filter_hz": filter_hz,
        "plant": "digit (consistent, from its components)",
        "plant_num": np.asarray(plant.poly.num).tolist(),
        "plant_den": np.asarray(plant.poly.den).tolist(),
        "plant_poles": [[float(p.real), float(p.imag)] for p in plant.poles],
        "plant_dc_gain_m_per_command": plant.dc_gain,
        "digit_wn_rad_s": plant.factors["E_digit_housing"].den[-1] ** 0.5,
        "eps_u": digit_regularisation(filter_hz, plant.dc_gain)[0] if eps_u is None else eps_u,
        "gamma_opt": d.gamma_opt,
        "gamma": d.gamma,
        "margin": d.margin,
        "controller_num": np.asarray(tf.num[0][0]).tolist(),
        "controller_den": np.asarray(tf.den[0][0]).tolist(),
        "controller_poles": [[float(p.real), float(p.imag)] for p in sorted_poles(np.linalg.eigvals(K.A))],
        "closed_loop_stable": True,
        "tzw_peak_db": 20 * np.log10(tzw),
        "tzw_peak_rad_s": wzw,
        **_digit_tolerance(filter_hz, plant, d),
        "tyw_settling_s": step_metrics(maps.T_yw, t_final=3.0)["settling_time_s"],
        "thesis_columns": "not applicable (the thesis printed its own rig's designs only)",
    }


def _digit_tolerance(filter_hz: float, plant, design: HinfDesign) -> dict:
    """The additive tolerance of a digit's design (thesis 4.6) when it measures a loop that controls.

    ``open_loop_gamma`` is ``||F||_inf = 1/(2 pi f_c)``, the cost of ``K = 0``; ``loop_gain_dc`` is ``|G(0) K(0)|``.
    A design whose ``gamma_opt`` is within :data:`OPEN_LOOP_GAMMA_RTOL` of it is the open-loop one: its tolerance
    (``1/||K S||``, millions of % of ``|G(0)|``: any plant is tolerated by a loop that barely feeds back) is refused,
    ``None`` with ``additive_tolerance_note`` saying why.
    """
    open_loop = 1 / (2 * math.pi * filter_hz)
    loop_dc = abs(plant.dc_gain * float(np.real(ct.dcgain(design.controller))))
    tol = additive_tolerance(plant.tf, design.controller)
    out = {
        "open_loop_gamma": open_loop,
        "loop_gain_dc": loop_dc,
        "tpq_peak_db": tol["tpq_db"],
        "additive_tolerance_m_per_command": tol["tolerance"],
        "additive_tolerance_relative_percent": tol["tolerance_relative_percent"],
        "additive_tolerance_note": "",
    }
    if is_open_loop(design.gamma_opt, filter_hz):
        out["additive_tolerance_note"] = (
            f"not applicable: gamma_opt {design.gamma_opt:.6g} is ||F||_inf = 1/(2 pi {filter_hz:g} Hz) = "
            f"{open_loop:.6g}, the cost of no controller: at this cut-off the weights leave nothing to gain by "
            f"feeding back (loop gain at DC {loop_dc:.3g}), so 1/||T_pq|| ({tol['tolerance']:.3g} m/command, "
            f"{tol['tolerance_relative_percent']:.3g} % of |G(0)|) is that of a loop that does not control"
        )
        out["additive_tolerance_m_per_command"] = None
        out["additive_tolerance_relative_percent"] = None
    return out
