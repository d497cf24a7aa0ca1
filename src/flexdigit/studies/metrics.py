"""Metrics: scalar outputs of a parameter set, each a plain function ``f(parameter_set, context) -> float``.

The registry :data:`METRICS` maps a name (unit in the name) to a :class:`Metric`; a study spec lists the names it
wants. Each metric is one call for a user::

    >>> from flexdigit.studies.metrics import METRICS, MetricContext
    >>> from flexdigit.studies.parameter_set import ParameterSet
    >>> round(METRICS["release_wn_rad_s"](ParameterSet()), 2)      # table 3.2's 13.0995 rad/s
    13.1

What each one means (thesis section in brackets):

- ``release_wn_rad_s``, ``release_zeta``: first bending mode of the housed digit with the cable removed, the
  release test of 3.1.2 (table 3.2), from the twin's chain linearised at rest;
- ``actuated_wn_rad_s``: the first mode with the cable taut, mid operating range (what the loop moves);
- ``rotation_gain_deg_per_command``: tip rotation per servo command over the operating range 8..43, from the
  twin's statics (3.4, E 3.15; 1.735 deg by the cable model);
- ``settling_time_s``, ``overshoot_percent``, ``gain_margin``: the 20 ms controller's closed loop (5.2 and
  :mod:`flexdigit.control.design20ms`), linear model: the servo (3.2.4), the pulley and this rig's digit
  linearised with the cable taut (:func:`actuated_model`), held by a zero-order hold at 20 ms with one sample
  of delay. The controller is the one
  designed for the baseline rig (a rig built to these tolerances runs the thesis rig's controller), unless the
  context says ``redesign`` (the design study designs one per candidate). ``gain_margin`` is the loop's gain
  margin broken at the plant input (a factor; the stability margin);
- ``twin_settling_time_s``, ``twin_overshoot_percent``, ``twin_steady_state_error_deg``: the same loop *run* on
  the batched twin (:mod:`flexdigit.studies.batched_loop`): integer commands latched on the serial frame and the PWM
  pulse,
  the large-deflection digit, a setpoint step of ``context.loop`` (20 deg centred on the mid-range rotation);
  the steady-state error is what the integer command leaves (the design holds it within half a quantum);
- ``hinf_gamma``: gamma of the thesis's H-infinity design (4.4, 5 Hz error weight, the thesis's regularisation)
  on this rig's plant as the thesis assembled it (3.5, :func:`flexdigit.models.plant.build_plant` "printed");
- ``bayes_position_limit_mm``: chapter 6's localisation Bayes limit (:func:`flexdigit.tactile.bounds.protocol_limits`)
  on table 6.1's settings: the RMS position error no estimator beats on one reading;
- ``blind_zone_mm``: length from the clamp where a 25 g load bends no gauge by a tenth of its noise
  (:func:`flexdigit.tactile.localisation.identifiability_map`), the zone 6.5's position 16 falls in.

Randomness: the Bayes limit's Monte Carlo draws come from the context's seed alone, the same draws for every
parameter set (common random numbers), so differences between parameter sets are the parameters' effect and not
Monte Carlo noise; the same seed gives the same numbers on any worker.
"""

from __future__ import annotations

import contextlib
import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from flexdigit.control.design20ms import closed_loop, design_20ms
from flexdigit.control.thesis_designs import thesis_design
from flexdigit.interrupts import raise_if_stopping
from flexdigit.models.plant import build_plant
from flexdigit.models.servo import servo_unit_tf
from flexdigit.params import RigParams
from flexdigit.studies.batched_loop import StepSchedule, step_figures, step_figures_batch, step_responses
from flexdigit.studies.parameter_set import ParameterSet
from flexdigit.tactile.bounds import TwinGaugeModel, protocol_limits
from flexdigit.tactile.localisation import identifiability_map
from flexdigit.tactile.protocols import RELAXED, load_protocol
from flexdigit.twin.batched import BatchedChains
from flexdigit.twin.twin import DEFAULT_CELLS_PER_SECTION, cable_shortening_m, cached_digit

__all__ = ["Metric", "MetricContext", "METRICS", "evaluate", "register_metric", "SENSITIVITY_METRICS"]


@dataclass(frozen=True)
class MetricContext:
    """What the metrics share within a study (hashable, so a worker builds its controller once).

    Attributes
    ----------
    baseline : ParameterSet
        The rig the fixed controller is designed for.
    redesign : bool
        Design the 20 ms controller for each parameter set instead (design studies).
    seed : int
        Seeds the Bayes limit's common random numbers.
    bayes_samples : int
        Monte Carlo readings per setting for the Bayes limit.
    blind_mass_kg : float
        The load whose blind zone is measured (table 6.1's 25 g).
    blind_step_m : float
        Resolution of the blind-zone scan along the digit.
    tactile_cells : int
        Springs per section of the chain behind the tactile metrics: the twin's 3 resolve a load's effect on a
        gauge to one 27 mm cell (a gauge 1 mm off its place moved the blind zone by 8 mm); 9 resolve it to 9 mm
        and agree with 15 and 27 on table 6.1's layout.
    hinf_filter_hz : float
        Cut-off of the H-infinity error weight (4.4: 5 Hz).
    protocol : str
        The tactile protocol whose settings the Bayes limit uses (table 6.1).
    loop : StepSchedule
        The setpoint step the twin-run loop metrics score (:mod:`flexdigit.studies.batched_loop`).
    """

    baseline: ParameterSet = field(default_factory=ParameterSet)
    redesign: bool = False
    seed: int = 0
    bayes_samples: int = 500
    blind_mass_kg: float = 0.025
    blind_step_m: float = 0.002
    tactile_cells: int = 9
    hinf_filter_hz: float = 5.0
    protocol: str = "thesis-6.1"
    loop: StepSchedule = field(default_factory=StepSchedule)


@dataclass(frozen=True)
class Metric:
    """A scalar output of a parameter set."""

    name: str
    unit: str
    description: str
    func: Callable[[ParameterSet, MetricContext], float]
    thesis_ref: str = ""
    batched: Callable[[list, MetricContext], np.ndarray] | None = None

    def __call__(self, parameter_set: ParameterSet, context: MetricContext | None = None) -> float:
        return float(self.func(parameter_set, context or MetricContext()))


#: The registry, in the order a report lists them.
METRICS: dict[str, Metric] = {}


def register_metric(name: str, unit: str, description: str, thesis_ref: str = "", batched=None):
    """Decorator adding a plain function ``f(parameter_set, context) -> float`` to :data:`METRICS`.

    ``batched(parameter_sets, context) -> ndarray`` optionally computes the same numbers for many parameter sets
    at once (on the batched twin); a test holds the two to each other.
    """

    def wrap(func):
        METRICS[name] = Metric(name, unit, description, func, thesis_ref, batched)
        return func

    return wrap


def evaluate(parameter_set: ParameterSet, names, context: MetricContext | None = None) -> dict[str, float]:
    """Every named metric of one parameter set (raises on the first that fails)."""
    context = context or MetricContext()
    return {name: METRICS[name](parameter_set, context) for name in names}


def evaluate_many(parameter_sets, names, context: MetricContext | None = None) -> list[dict | Exception]:
    """Every named metric of many parameter sets: the metrics with a batched form run once over all of them.

    Returns, per parameter set, its metric values or the exception that stopped it (a batched metric that fails
    is retried one set at a time, so one bad set does not take the others down).
    """
    context = context or MetricContext()
    out: list[dict | Exception] = [{} for _ in parameter_sets]
    names = list(names)
    batched = [n for n in names if METRICS[n].batched is not None]
    if batched and parameter_sets:
        try:
            columns = {n: np.asarray(METRICS[n].batched(parameter_sets, context), dtype=float) for n in batched}
            for i, values in enumerate(out):
                values.update({n: float(columns[n][i]) for n in batched})
        except Exception as exc:  # noqa: BLE001 - find the culprit one set at a time below
            raise_if_stopping(exc)  # unless a stop signal came back from a compiled kernel as this exception
    for i, ps in enumerate(parameter_sets):
        try:
            for n in names:
                if n not in out[i]:
                    out[i][n] = METRICS[n](ps, context)
        except Exception as exc:  # noqa: BLE001 - any failure of one evaluation is that set's result
            raise_if_stopping(exc)  # (a stop is not a failure of the set)
            out[i] = exc
    return out


# ------------------------------------------------------------------------------------------------ the digit
def _chain(ps: ParameterSet, cells: int | None = None):
    return cached_digit(ps.params, ps.calibration, True, "vertical", cells or DEFAULT_CELLS_PER_SECTION)


def _chains(parameter_sets):
    """The parameter sets' digits (housed, tip up as designed, 2.2.4) on the batched twin, with their cables."""
    rigs = ([ps.params for ps in parameter_sets], [ps.calibration for ps in parameter_sets])
    options = {"housing": True, "orientation": "vertical", "cells_per_section": DEFAULT_CELLS_PER_SECTION}
    pre = [ps.antagonist_pretension_n for ps in parameter_sets]
    if all(p is None for p in pre):
        return BatchedChains.from_rigs(*rigs, **options)
    # a batch mixing one and two cables: a single cable is the pair with the second one never taut
    return BatchedChains.from_rigs(
        *rigs, **options, pretension_n=[0.0 if p is None else p for p in pre], antagonist=[p is not None for p in pre]
    )


def _mid_shortening_m(ps: ParameterSet) -> float:
    """Cable shortening at the middle of the operating commands (8..43 -> 25.5): where the loop works."""
    return float(cable_shortening_m(0.5 * sum(ps.params.actuator.operating_commands), ps.params))


_BATCH_CACHE: list = [None, None]  # (the list of parameter sets, its results): the metrics share one pass


def twin_figures(parameter_sets) -> dict[str, np.ndarray]:
    """The twin metrics of many parameter sets at once (:class:`flexdigit.twin.batched.BatchedChains`).

    Release mode (cable removed), the actuated mode and the tip's rotational stiffness linearised mid-range, the
    rotation per command over the operating commands, and the linearised actuated digit's matrices (for
    :func:`actuated_model`).
    """
    if _BATCH_CACHE[0] is parameter_sets:
        return _BATCH_CACHE[1]
    chains = _chains(parameter_sets)
    wn, zeta = chains.linear_modes()
    commands = np.array([ps.params.actuator.operating_commands for ps in parameter_sets], dtype=float)
    ends = np.array(
        [cable_shortening_m(np.array(ps.params.actuator.operating_commands), ps.params) for ps in parameter_sets]
    )
    mid = np.array([_mid_shortening_m(ps) for ps in parameter_sets])
    tip_lo = chains.solve_static(ends[:, 0])[:, -1]
    tip_hi = chains.solve_static(ends[:, 1])[:, -1]
    psi_mid = chains.solve_static(mid)
    act_wn, _ = chains.linear_modes(psi_mid, mid)
    moment = 1e-4  # N m: small, the linear stiffness about the mid-range shape
    turned = chains.solve_static(mid, tip_moment_nm=np.full(len(parameter_sets), moment), psi0=psi_mid)[:, -1]
    out = {
        "release_wn_rad_s": wn,
        "release_zeta": zeta,
        "actuated_wn_rad_s": act_wn,
        "rotation_gain_deg_per_command": np.degrees(tip_hi - tip_lo) / (commands[:, 1] - commands[:, 0]),
        "tip_stiffness_nm_per_rad": moment / (turned - psi_mid[:, -1]),
        "_linear": chains.linearised(psi_mid, mid),
        "_mid_rotation_deg": np.degrees(psi_mid[:, -1] - tip_lo),
    }
    _BATCH_CACHE[:] = [parameter_sets, out]
    return out


def _batched(name):
    return lambda parameter_sets, ctx: twin_figures(parameter_sets)[name]


@lru_cache(maxsize=4096)
def _single(ps: ParameterSet) -> dict[str, np.ndarray]:
    return twin_figures([ps])


def _one(name):
    return lambda ps, ctx: float(_single(ps)[name][0])


@lru_cache(maxsize=4096)
def actuated_model(ps: ParameterSet):
    """The twin's digit linearised with the cable(s) taut, mid-range: cable shortening (m) -> tip rotation (rad).

    ``M psi'' + C psi' + K psi = b u`` about the static shape, ``M = A cos(psi_j - psi_k)``, ``K`` the tangent
    stiffness (springs, gravity, ``k_c e^2`` per taut cable), ``b = k_c e`` per taut cable on the tip link
    (:mod:`flexdigit.twin.digit`, :meth:`flexdigit.twin.batched.BatchedChains.linearised`).
    """
    import control as ct

    m, c, k, b = (x[0] for x in _single(ps)["_linear"])
    n = m.shape[0]
    a = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(m, k), -np.linalg.solve(m, c)]])
    out = np.zeros((1, 2 * n))
    out[0, n - 1] = 1.0
    return ct.ss(a, np.vstack([np.zeros((n, 1)), np.linalg.solve(m, b[:, None])]), out, np.zeros((1, 1)))


_TWIN_METRICS = (
    ("release_wn_rad_s", "rad/s", "first mode of the housed digit, cable removed", "table 3.2"),
    ("release_zeta", "", "damping ratio of that mode", "table 3.2"),
    ("actuated_wn_rad_s", "rad/s", "first mode with the cable(s) taut, mid operating range", "3.3"),
    ("rotation_gain_deg_per_command", "deg/command", "tip rotation per command over the operating commands", "E 3.15"),
    ("tip_stiffness_nm_per_rad", "N m/rad", "tip moment per tip rotation, cable(s) taut mid-range (rigidity)", "2.1"),
)
for _name, _unit, _text, _ref in _TWIN_METRICS:
    register_metric(_name, _unit, _text, _ref, batched=_batched(_name))(_one(_name))


def rotation_gain_deg_per_command(ps: ParameterSet, ctx: MetricContext | None = None) -> float:
    """Tip rotation per servo command (deg) over the operating commands (E 3.15), from the twin's statics."""
    return METRICS["rotation_gain_deg_per_command"](ps, ctx)


# -------------------------------------------------------------------------------------------------- control
@lru_cache(maxsize=8)
def _baseline_design(baseline: ParameterSet):
    return design_20ms(baseline.params, deg_per_command=rotation_gain_deg_per_command(baseline, MetricContext()))


@contextlib.contextmanager
def _quiet():
    """python-control's ss <-> tf conversions of these loops warn about tiny numerator coefficients (scipy's
    ``BadCoefficients``); the figures are checked against the poles of the state-space loop in the tests."""
    from scipy.signal import BadCoefficients

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BadCoefficients)
        yield


def loop_plant(ps: ParameterSet, period_s: float, delay_samples: int = 1):
    """The discrete plant the 20 ms loop drives (command -> tip rotation, deg): the servo (3.2.4), the pulley
    (E 3.11) and the linearised actuated digit (:func:`actuated_model`), held by a zero-order hold at ``period_s``
    with ``delay_samples`` samples of transport delay."""
    import control as ct

    a = ps.params.actuator
    metres_per_command = a.rad_per_command * a.cable_m_per_servo_rad
    with _quiet():
        plant = ct.series(ct.ss(servo_unit_tf(ps.params)), actuated_model(ps)) * (np.degrees(1.0) * metres_per_command)
        held = ct.sample_system(plant, period_s, method="zoh")
        delay = ct.ss(ct.tf([1.0], [1.0] + [0.0] * delay_samples, period_s))
        return ct.series(delay, held)


@lru_cache(maxsize=4096)
def loop_design(ps: ParameterSet, ctx: MetricContext):
    """The 20 ms design the loop metrics run on ``ps``: the baseline rig's, or its own with ``ctx.redesign``."""
    if not ctx.redesign:
        return _baseline_design(ctx.baseline)
    return design_20ms(ps.params, deg_per_command=rotation_gain_deg_per_command(ps, ctx))


@lru_cache(maxsize=4096)
def _loop(ps: ParameterSet, ctx: MetricContext) -> dict:
    import control as ct

    design = loop_design(ps, ctx)
    plant_d = loop_plant(ps, design.period_s, design.delay_samples)
    loop = closed_loop(plant_d, design.controller)
    if np.max(np.abs(loop.poles())) >= 1.0:
        return {"settling_time_s": math.inf, "overshoot_percent": math.inf, "gain_margin": 0.0}
    t = np.arange(0.0, 10.0, design.period_s)
    y = np.squeeze(ct.step_response(loop, T=t).outputs)
    figures = step_figures(t, y, target=float(y[-1]))  # settling to the last sample, as the batched loop's
    settling, overshoot = figures.settling_time_s, figures.overshoot_percent
    # the loop broken at the plant input: u = K_y y + ..., so the return ratio is -K_y P
    k = design.controller
    k_y = ct.ss(k.A, k.B[:, 1:2], k.C, k.D[:, 1:2], design.period_s)
    with _quiet():
        gm = gain_margin_frd(-k_y * plant_d)
    return {
        "settling_time_s": settling,
        "overshoot_percent": overshoot,
        "gain_margin": float(gm),
    }


def gain_margin_frd(loop) -> float:
    """Gain margin of a discrete SISO loop, python-control's ``stability_margins(loop, method="frd")[0]``.

    The same steps and the same numbers (tested equal): the loop as a transfer function, its frequency response on
    python-control's default grid below Nyquist, the interpolating spline of an ``FRD(..., smooth=True)``, the
    phase crossings found by ``brentq`` between grid points, the margin closest to 1 (in log). Hand-written
    because ``stability_margins`` also searches the phase margin and the stability margin (two thirds of its
    time, not used here) and evaluates the spline one grid point at a time; here the grid is evaluated in one
    call.
    """
    from control import frdata, freqplot, xferfcn
    from scipy.interpolate import splev
    from scipy.optimize import brentq

    sys = xferfcn._convert_to_transfer_function(loop)
    omega = freqplot._default_frequency_range(sys)
    omega = omega[omega < np.pi / sys.dt]
    tck = frdata.FRD(sys, omega, smooth=True)._ifunc[0, 0]
    omega = np.sort(omega)  # what the FRD holds

    def response(w):
        re, im = splev(w, tck, der=0)
        return re + 1.0j * im

    def arg(w):  # the phase from -180 degrees
        return np.angle(-response(w))

    widx = np.flatnonzero(np.diff(np.sign(arg(omega))))
    widx = widx[np.real(response(omega[widx])) <= 0]
    if not widx.size:
        return math.inf
    w_180 = np.array([brentq(arg, omega[i], omega[i + 1]) for i in widx])
    with np.errstate(all="ignore"):  # |L| = 0 is a margin of inf
        gm = 1.0 / np.abs(response(w_180))
        if np.isinf(gm).all():
            return math.inf
        log_gm = np.abs(np.log(gm))
    return float(gm[np.flatnonzero(log_gm == np.min(log_gm))[0]])


@register_metric("settling_time_s", "s", "2 % settling of the 20 ms loop's step (linear model)", "5.2")
def settling_time_s(ps: ParameterSet, ctx: MetricContext) -> float:
    return _loop(ps, ctx)["settling_time_s"]


@register_metric("overshoot_percent", "%", "overshoot of the 20 ms loop's step (linear model)", "5.2")
def overshoot_percent(ps: ParameterSet, ctx: MetricContext) -> float:
    return _loop(ps, ctx)["overshoot_percent"]


@register_metric("gain_margin", "factor", "gain margin of the 20 ms loop at the plant input", "5.2")
def gain_margin(ps: ParameterSet, ctx: MetricContext) -> float:
    return _loop(ps, ctx)["gain_margin"]


_LOOP_CACHE: list = [None, None, None]  # (parameter sets, context, figures): the three metrics share one run


def twin_loop_figures(parameter_sets, ctx: MetricContext) -> dict[str, np.ndarray]:
    """The 20 ms loop run on the batched twin for many parameter sets at once (:mod:`flexdigit.studies.batched_loop`):
    settling time, overshoot and steady-state error of the context's setpoint step, centred on each rig's
    mid-range rotation (where the linear metrics linearise)."""
    if _LOOP_CACHE[0] is parameter_sets and _LOOP_CACHE[1] == ctx:
        return _LOOP_CACHE[2]
    designs = [loop_design(ps, ctx) for ps in parameter_sets]
    run = step_responses(
        [ps.params for ps in parameter_sets],
        [ps.calibration for ps in parameter_sets],
        [d.runtime(ps.params) for d, ps in zip(designs, parameter_sets, strict=True)],
        twin_figures(parameter_sets)["_mid_rotation_deg"],
        ctx.loop,
        pretension_n=[ps.antagonist_pretension_n for ps in parameter_sets],
    )
    out = step_figures_batch(run)
    _LOOP_CACHE[:] = [parameter_sets, ctx, out]
    return out


@lru_cache(maxsize=4096)
def _single_loop(ps: ParameterSet, ctx: MetricContext) -> dict[str, np.ndarray]:
    return twin_loop_figures([ps], ctx)


def _loop_metric(name, unit, text):
    register_metric(
        f"twin_{name}",
        unit,
        text,
        "5.2",
        batched=lambda parameter_sets, ctx: twin_loop_figures(parameter_sets, ctx)[name],
    )(lambda ps, ctx: float(_single_loop(ps, ctx)[name][0]))


_loop_metric("settling_time_s", "s", "2 % settling of the 20 ms loop's step, run on the twin (integer command)")
_loop_metric("overshoot_percent", "%", "overshoot of the 20 ms loop's step, run on the twin")
_loop_metric("steady_state_error_deg", "deg", "the 20 ms loop's final error after its step, run on the twin")


@register_metric("hinf_gamma", "", "gamma of the thesis's H-infinity design on this rig's printed plant", "4.4")
def hinf_gamma(ps: ParameterSet, ctx: MetricContext) -> float:
    return float(thesis_design(ctx.hinf_filter_hz, plant=build_plant("printed", ps.params).tf).gamma)


# -------------------------------------------------------------------------------------------------- tactile
def gauge_model(ps: ParameterSet, cells_per_section: int | None = None):
    """The tactile gauge model of this rig (the twin's statics and its white noise plus the ADC's quantisation
    noise, ``lsb / sqrt(12)``), any number of gauges."""
    model = TwinGaugeModel(ps.params, ps.calibration, cells_per_section=cells_per_section)
    lsb = ps.params.sensors.adc_lsb_v
    model.noise_v = np.sqrt(np.asarray(model.noise_v, dtype=float) ** 2 + lsb**2 / 12.0)
    return model


@lru_cache(maxsize=4)
def _protocol_settings(name: str):
    protocol = load_protocol(name)
    commands = protocol.actuation_commands or (RELAXED,)
    rows = []
    for c in commands:
        for m in protocol.loads_kg:
            for x in protocol.positions_from_tip_m:
                rows.append((x, m, c, protocol.repetitions))
        rows.append((0.0, 0.0, c, protocol.no_load_repetitions * len(protocol.loads_kg)))
    return np.array(rows, dtype=float)


@register_metric("bayes_position_limit_mm", "mm", "chapter 6's localisation Bayes limit (RMS, one reading)", "6.5")
def bayes_position_limit_mm(ps: ParameterSet, ctx: MetricContext) -> float:
    rows = _protocol_settings(ctx.protocol)
    length = ps.params.geometry.digit_length_m
    # positions from the tip, as fractions of the thesis digit: a larger or smaller digit is probed alike
    scale = length / RigParams().geometry.digit_length_m
    a = np.where(rows[:, 1] > 0, length - rows[:, 0] * scale, 0.0)
    limits = protocol_limits(
        gauge_model(ps, ctx.tactile_cells),
        a,
        rows[:, 1],
        rows[:, 2].astype(int),
        rows[:, 3],
        samples=ctx.bayes_samples,
        seed=ctx.seed,
    )
    loaded = rows[:, 1] > 0
    return 1e3 * float(np.sqrt(np.average(limits.position_mse_m2[loaded], weights=rows[loaded, 3])))


@register_metric("blind_zone_mm", "mm", "length from the clamp where a 25 g load bends no gauge", "6.5")
def blind_zone_mm(ps: ParameterSet, ctx: MetricContext) -> float:
    length = ps.params.geometry.digit_length_m
    points = int(round(length / ctx.blind_step_m)) + 1
    zones = identifiability_map(gauge_model(ps, ctx.tactile_cells), [ctx.blind_mass_kg], [RELAXED], length, points)
    zone = zones["cases"][0]["zone"]
    seen = np.flatnonzero(zone != "no gauge bends")
    return 1e3 * float(zones["position_from_base_m"][seen[0]] if seen.size else length)


#: The metrics a sensitivity study computes unless its spec lists others.
SENSITIVITY_METRICS = (
    "release_wn_rad_s",
    "release_zeta",
    "actuated_wn_rad_s",
    "rotation_gain_deg_per_command",
    "settling_time_s",
    "overshoot_percent",
    "gain_margin",
    "hinf_gamma",
    "bayes_position_limit_mm",
    "blind_zone_mm",
)
