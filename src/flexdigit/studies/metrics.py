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
  margin broken at the plant input (a factor; the stability margin); ``time_outside_band_s`` the time the step
  spends outside the 2 % band (:func:`time_outside_band_s`: the settling time without its jumps);
- ``twin_settling_time_s``, ``twin_overshoot_percent``, ``twin_steady_state_error_deg``: the same loop *run* on
  the batched twin (:mod:`flexdigit.studies.batched_loop`): integer commands latched on the serial frame and the PWM
  pulse,
  the large-deflection digit, a setpoint step of ``context.loop`` (20 deg centred on the mid-range rotation);
  the steady-state error is what the integer command leaves (the design holds it within half a quantum);
- ``hinf_gamma``: gamma of the thesis's H-infinity design (4.4, 5 Hz error weight, the thesis's regularisation)
  on this rig's plant as the thesis assembled it (3.5, :func:`flexdigit.models.plant.build_plant` "printed");
- ``bayes_position_limit_mm``: chapter 6's localisation Bayes limit (:func:`flexdigit.tactile.bounds.protocol_limits`)
  on table 6.1's settings: the RMS position error no estimator beats on one reading, the estimator knowing the
  load hangs at one of the protocol's positions (the "settings" prior: ``flexdigit train --bayes-limit --split
  readings``'s ``bayes_limit_settings_mm``, not ``train``'s default span limit of a load anywhere on the
  stretch; both by :func:`bayes_limits_by_prior`), on the design's study calibration;
- ``blind_zone_mm``: length from the clamp where a 25 g load bends no gauge by a tenth of its noise
  (:func:`flexdigit.tactile.localisation.identifiability_map`), the zone 6.5's position 16 falls in.

Randomness: the Bayes limit's Monte Carlo draws come from the context's seed alone, the same draws for every
parameter set (common random numbers), so differences between parameter sets are the parameters' effect and not
Monte Carlo noise; the same seed gives the same numbers on any worker.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from flexdigit.control._lsim import step_output
from flexdigit.control.design20ms import closed_loop, design_20ms
from flexdigit.control.thesis_designs import thesis_design
from flexdigit.errors import ParameterError
from flexdigit.interrupts import raise_if_stopping
from flexdigit.models.plant import build_plant
from flexdigit.models.servo import servo_unit_tf
from flexdigit.params import RigParams, twin_cells
from flexdigit.studies._bayes_kernel import position_mse_m2
from flexdigit.studies.batched_loop import StepSchedule, step_figures, step_figures_batch, step_responses
from flexdigit.studies.parameter_set import ParameterSet
from flexdigit.tactile.bounds import TwinGaugeModel, noise_of, protocol_limits
from flexdigit.tactile.dataset import Dataset, dataset_columns
from flexdigit.tactile.localisation import identifiability_map, position_bayes_rmse_m
from flexdigit.tactile.protocols import RELAXED, load_protocol
from flexdigit.twin.batched import BatchedChains
from flexdigit.twin.twin import DEFAULT_CELLS_PER_SECTION, cable_shortening_m, cached_digit

__all__ = [
    "Metric",
    "MetricContext",
    "METRICS",
    "UserMetric",
    "evaluate",
    "metric_of",
    "register_metric",
    "SENSITIVITY_METRICS",
    "bayes_limits_by_prior",
]


@dataclass(frozen=True)
class UserMetric:
    """A study's own metric (a spec's ``[metrics.NAME]`` table): ``function``, ``"module:function"``, of a
    :class:`ParameterSet` returning a real number in ``unit``. It travels to the workers by name and is imported
    there, so its module must be importable where the study runs (the path of the process, or the workers').

    ``where`` names the spec key in every error (``"FILE: [metrics.NAME]"``).
    """

    name: str
    function: str
    unit: str
    description: str = ""
    where: str = ""

    def resolve(self) -> Callable:
        """The function, imported (one line naming :attr:`where` if the module or the name is missing, or if it
        is not callable)."""
        return _import_function(self.function, self.where or f"[metrics.{self.name}]")

    def __call__(self, parameter_set: ParameterSet, context: MetricContext | None = None) -> float:
        return checked_value(self.resolve()(parameter_set), self)


def checked_value(value, metric: UserMetric) -> float:
    """``value`` as a float, or one line naming the metric's spec key if it is not a real number."""
    import numbers

    if isinstance(value, bool | np.bool_) or not isinstance(value, numbers.Real):
        shown = repr(value)
        shown = shown if len(shown) <= 60 else shown[:57] + "..."
        raise ParameterError(
            f"{metric.where or f'[metrics.{metric.name}]'} function: {metric.function} returned {shown} "
            f"({type(value).__name__}); expected a real number (in {metric.unit or 'its unit'})"
        )
    return float(value)


@lru_cache(maxsize=64)
def _import_function(target: str, where: str) -> Callable:
    import importlib
    import re

    if not isinstance(target, str) or not re.fullmatch(r"[A-Za-z_][\w.]*:[A-Za-z_]\w*", target):
        raise ParameterError(
            f"{where} function: expected 'module:function' (e.g. 'my_metrics:tip_mass_g'). Got {target!r}"
        )
    module_name, _, attr = target.partition(":")
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as exc:
        if exc.name and module_name.startswith(exc.name):
            raise ParameterError(
                f"{where} function: no module {module_name!r} on the Python path (put its directory on PYTHONPATH, "
                "on the workers too)"
            ) from None
        raise ParameterError(f"{where} function: importing {module_name!r} failed: {_one_line(exc)}") from None
    except Exception as exc:  # noqa: BLE001 - whatever the user's module raises on import, said in one line
        raise ParameterError(f"{where} function: importing {module_name!r} failed: {_one_line(exc)}") from None
    func = getattr(module, attr, None)
    if func is None:
        raise ParameterError(f"{where} function: module {module_name!r} has no {attr!r}")
    if not callable(func):
        raise ParameterError(f"{where} function: {target} is a {type(func).__name__}, not a function")
    return func


def _one_line(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {exc}".splitlines()[0]


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
    user_metrics : tuple of UserMetric
        The study's own metrics (its spec's ``[metrics.NAME]`` tables), found by :func:`metric_of` beside
        :data:`METRICS`, on the workers too.
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
    user_metrics: tuple[UserMetric, ...] = ()


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


def metric_of(name: str, context: MetricContext | None = None) -> Metric:
    """The metric called ``name``: a built-in one (:data:`METRICS`) or one of the context's user metrics."""
    if name in METRICS:
        return METRICS[name]
    for user in (context or MetricContext()).user_metrics:
        if user.name == name:
            return _user_metric(user)
    raise ParameterError(f"unknown metric {name!r}; expected one of " + ", ".join(METRICS))


@lru_cache(maxsize=64)
def _user_metric(user: UserMetric) -> Metric:
    return Metric(user.name, user.unit, user.description or user.function, lambda ps, ctx: user(ps), user.where)


def evaluate(parameter_set: ParameterSet, names, context: MetricContext | None = None) -> dict[str, float]:
    """Every named metric of one parameter set (raises on the first that fails)."""
    context = context or MetricContext()
    return {name: metric_of(name, context)(parameter_set, context) for name in names}


def evaluate_many(parameter_sets, names, context: MetricContext | None = None) -> list[dict | Exception]:
    """Every named metric of many parameter sets: the metrics with a batched form run once over all of them.

    Returns, per parameter set, its metric values or the exception that stopped it (a batched metric that fails
    is retried one set at a time, so one bad set does not take the others down).
    """
    context = context or MetricContext()
    _new_block()
    out: list[dict | Exception] = [{} for _ in parameter_sets]
    names = list(names)
    batched = [n for n in names if metric_of(n, context).batched is not None]
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
                    out[i][n] = metric_of(n, context)(ps, context)
        except Exception as exc:  # noqa: BLE001 - any failure of one evaluation is that set's result
            raise_if_stopping(exc)  # (a stop is not a failure of the set)
            out[i] = exc
    return out


# ------------------------------------------------------------------------------------------------ the digit
def _chain(ps: ParameterSet, cells: int | None = None):
    # every design at one resolution, its description's (a batch of designs stacks at it too: batch_cells)
    return cached_digit(ps.params, ps.calibration, True, "vertical", cells or twin_cells(ps.params))


def _chains(parameter_sets, orientation: str = "vertical"):
    """The parameter sets' digits (housed, tip up as designed, 2.2.4) on the batched twin, with their cables."""
    rigs = ([ps.params for ps in parameter_sets], [ps.calibration for ps in parameter_sets])
    options = {"housing": True, "orientation": orientation, "cells_per_section": DEFAULT_CELLS_PER_SECTION}
    pre = [ps.pair_pretension_n for ps in parameter_sets]
    if all(p is None for p in pre):
        return BatchedChains.from_rigs(*rigs, **options)
    # a batch mixing one and two cables: a single cable is the pair with the second one never taut
    return BatchedChains.from_rigs(
        *rigs, **options, pretension_n=[0.0 if p is None else p for p in pre], antagonist=[p is not None for p in pre]
    )


def _mid_shortening_m(ps: ParameterSet) -> float:
    """Cable shortening at the middle of the operating commands (8..43 -> 25.5): where the loop works."""
    return float(cable_shortening_m(0.5 * sum(ps.params.actuator.operating_commands), ps.params))


#: The tip moment (N m) whose turn gives ``tip_stiffness_nm_per_rad``: small, the linear stiffness about the
#: mid-range shape.
PROBE_MOMENT_NM = 1e-4

#: Why a metric may have no value on a row that ran (NaN, never inf): the study refuses that metric on such rows
#: in these words (:attr:`flexdigit.studies.sensitivity.SensitivityResult.refused`), as it refuses a failed row.
_BUCKLED = "its tangent stiffness has a negative eigenvalue: the digit buckles under its weight"
UNDEFINED: dict[str, str] = {
    "release_wn_rad_s": f"the digit stands neither tip up nor hung with the cable removed ({_BUCKLED})",
    "release_zeta": f"the digit stands neither tip up nor hung with the cable removed ({_BUCKLED})",
    "actuated_wn_rad_s": f"the mid-range shape is not a stable equilibrium ({_BUCKLED} and the cable's pull)",
    "tip_stiffness_nm_per_rad": (
        f"the mid-range shape is not a stable equilibrium ({_BUCKLED} and the cable's pull), or the "
        f"{PROBE_MOMENT_NM:g} N m probe moment did not turn the tip (the static solve came back to the same angles)"
    ),
}

_BATCH_CACHE: list = [None, None]  # (the list of parameter sets, its results): the metrics share one pass


def twin_figures(parameter_sets, *, keep: bool = True) -> dict[str, np.ndarray]:
    """The twin metrics of many parameter sets at once (:class:`flexdigit.twin.batched.BatchedChains`).

    Release mode (cable removed), the actuated mode and the tip's rotational stiffness linearised mid-range, the
    rotation per command over the operating commands, and the linearised actuated digit's matrices (for
    :func:`actuated_model`).

    Tip up, as the thesis mounted the digit; a digit that buckles so under its own weight (the straight chain's
    tangent stiffness has a negative eigenvalue, e.g. tests/digits.py's 0.5 m, 5-section digit) is hung tip down,
    as :func:`flexdigit.twin.records.release_orientation` and ``run --params`` mount it. A figure about a shape
    that is not a stable equilibrium in that mount is NaN (:data:`UNDEFINED` says why).
    """
    if keep and _BATCH_CACHE[0] is parameter_sets:
        return _BATCH_CACHE[1]
    out = _mounted_figures(parameter_sets, "vertical")
    fallen = np.flatnonzero(~out.pop("_upright"))
    if fallen.size:  # those rows hung (gravity then stiffens them), the others as they stood
        hung = _mounted_figures([parameter_sets[i] for i in fallen], "hanging")
        hung.pop("_upright")
        for name, values in hung.items():
            for mine, theirs in zip(out[name], values, strict=True) if name == "_linear" else [(out[name], values)]:
                mine[fallen] = theirs
    if not keep:
        return out
    _BATCH_CACHE[:] = [parameter_sets, out]
    for i, ps in enumerate(parameter_sets):  # each row's figures, for the per-row metrics built on them
        _ROWS[ps] = {k: tuple(x[i : i + 1] for x in v) if k == "_linear" else v[i : i + 1] for k, v in out.items()}
        while len(_ROWS) > _ROWS_KEPT:
            _ROWS.pop(next(iter(_ROWS)))
    return out


def _mounted_figures(parameter_sets, orientation: str) -> dict[str, np.ndarray]:
    """:func:`twin_figures` of the digits mounted ``orientation``, and ``_upright``: whether each stands straight
    so with the cable removed."""
    chains = _chains(parameter_sets, orientation)
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
    moment = PROBE_MOMENT_NM
    turned = chains.solve_static(mid, tip_moment_nm=np.full(len(parameter_sets), moment), psi0=psi_mid)[:, -1]
    turn = turned - psi_mid[:, -1]
    linear = chains.linearised(psi_mid, mid)
    # a digit that buckles under its weight (and the cable's pull) has no stable shape there: no mode, no stiffness
    upright = _stable(chains.linearised(np.zeros_like(psi_mid), np.full(len(parameter_sets), -np.inf))[2])
    held = _stable(linear[2])
    with np.errstate(divide="ignore", invalid="ignore"):  # a row whose tip did not turn: NaN, refused (UNDEFINED)
        stiffness = np.where((turn != 0.0) & held, moment / turn, np.nan)
    out = {
        "release_wn_rad_s": np.where(upright, wn, np.nan),
        "release_zeta": np.where(upright, zeta, np.nan),
        "actuated_wn_rad_s": np.where(held, act_wn, np.nan),
        "rotation_gain_deg_per_command": np.degrees(tip_hi - tip_lo) / (commands[:, 1] - commands[:, 0]),
        "tip_stiffness_nm_per_rad": stiffness,
        "_linear": linear,
        "_mid_rotation_deg": np.degrees(psi_mid[:, -1] - tip_lo),
        "_upright": upright,
    }
    return out


def _stable(stiffness) -> np.ndarray:
    """Whether each chain's tangent stiffness (N, n, n), symmetric, is positive definite: a stable equilibrium."""
    return np.linalg.eigvalsh(stiffness)[:, 0] > 0.0


#: The twin figures of the rows of the block being evaluated (:func:`twin_figures`), by parameter set: the linear
#: loop metrics (:func:`actuated_model`) read a row's linearisation from its block's pass instead of solving it again.
_ROWS: dict = {}
_ROWS_KEPT = 4096


def _new_block() -> None:
    """Forget the last block's rows and what was built on them (:func:`evaluate_many` calls it first): a row's
    numbers then depend on its block alone (a batched pass rounds a rig's figures a little differently with other
    block-mates), never on which blocks a process evaluated before, so a study on any number of Dask workers gives
    the in-process numbers bit for bit (the blocks are the spec's chunks)."""
    _ROWS.clear()
    _BATCH_CACHE[:] = [None, None]
    _LOOP_CACHE[:] = [None, None, None]
    for cached in (actuated_model, loop_design, _loop, _single_loop):
        cached.cache_clear()


def _batched(name):
    return lambda parameter_sets, ctx: twin_figures(parameter_sets)[name]


def _single(ps: ParameterSet) -> dict[str, np.ndarray]:
    """One row's twin figures: from its block's batched pass if there was one (:data:`_ROWS`), else its own."""
    hit = _ROWS.get(ps)
    return hit if hit is not None else twin_figures([ps])


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
    # the baseline's own pass (not a block's): the same controller in every process, whatever it evaluated before
    gain = float(twin_figures([baseline], keep=False)["rotation_gain_deg_per_command"][0])
    return design_20ms(baseline.params, deg_per_command=gain)


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
    """The linear loop's figures, once per distinct loop: with the baseline's controller the loop is a function of
    the row's linearised digit (its block's pass), its servo and its pulley alone, so rows that move only the
    gauges (5 of the 18 shipped tolerances) share the figures of a row with the same digit, bit for bit."""
    if ctx.redesign:
        return _loop_figures(ps, ctx)
    a = ps.params.actuator
    key = (
        ctx,
        tuple(x.tobytes() for x in _single(ps)["_linear"]),
        a.servo_wn_rad_s,
        a.servo_zeta,
        a.rad_per_command * a.cable_m_per_servo_rad,
    )
    return _kept(_LOOPS, key, lambda: _loop_figures(ps, ctx))


def _loop_figures(ps: ParameterSet, ctx: MetricContext) -> dict:
    import control as ct

    design = loop_design(ps, ctx)
    plant_d = loop_plant(ps, design.period_s, design.delay_samples)
    loop = closed_loop(plant_d, design.controller)
    if np.max(np.abs(loop.poles())) >= 1.0:
        nothing = {"settling_time_s": math.inf, "overshoot_percent": math.inf, "time_outside_band_s": math.inf}
        return {**nothing, "gain_margin": 0.0}
    t = np.arange(0.0, 10.0, design.period_s)
    y = step_output(loop, t)  # control.step_response's numbers, its recursion compiled (~10x faster)
    figures = step_figures(t, y, target=float(y[-1]))  # settling to the last sample, as the batched loop's
    outside = time_outside_band_s(t, y, target=float(y[-1]))
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
        "time_outside_band_s": outside,
    }


def time_outside_band_s(t_s, y, *, target: float, initial: float = 0.0, band: float = 0.02) -> float:
    """How long a step response spends outside the settling band (s): the measure of the times when
    ``|y - target| > band |target - initial|``, the response linear between samples.

    The 2 % settling time is the *last* time outside the band, so it jumps when a late ripple grows through the
    band's edge: by half a ringing period (0.1 s) on the 20 ms loop, whose two modes beat; a sensitivity study
    of it needs many more samples (docs/studies.md). This is its continuous sibling: equal to it for a response
    that leaves the band once (a monotone approach), smaller by the stretches a ringing response spends back in
    the band, and a ripple that just touches the edge adds its short time outside, not a jump. Infinite if the
    response is still outside at the end of the record.
    """
    t = np.asarray(t_s, dtype=float)
    step = float(target) - float(initial)
    e = np.abs(np.asarray(y, dtype=float) - float(target)) - band * abs(step)  # > 0: outside
    if not np.all(np.isfinite(e)) or step == 0:
        return math.nan
    if e[-1] > 0:
        return math.inf
    e0, e1, dt = e[:-1], e[1:], np.diff(t)
    with np.errstate(divide="ignore", invalid="ignore"):
        share = np.where(e0 > 0, np.where(e1 > 0, 1.0, e0 / (e0 - e1)), np.where(e1 > 0, e1 / (e1 - e0), 0.0))
    return float(np.sum(dt * share))


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


@register_metric(
    "time_outside_band_s",
    "s",
    "time the 20 ms loop's step spends outside its 2 % band (linear model): the settling time without jumps",
    "5.2",
)
def time_outside_band(ps: ParameterSet, ctx: MetricContext) -> float:
    return _loop(ps, ctx)["time_outside_band_s"]


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
        pretension_n=[ps.pair_pretension_n for ps in parameter_sets],
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
    """Gamma of the design on the printed plant, once per distinct plant: the plant (a fourth-order transfer
    function of four of the shipped tolerances) costs a tenth of the design, and in a Saltelli design most rows
    move a parameter it does not read, so their plant is another row's coefficient for coefficient."""
    plant = build_plant("printed", ps.params).tf
    key = (float(ctx.hinf_filter_hz), np.asarray(plant.num[0][0]).tobytes(), np.asarray(plant.den[0][0]).tobytes())
    return _kept(_HINF, key, lambda: float(thesis_design(ctx.hinf_filter_hz, plant=plant).gamma))


#: Values kept by their exact inputs (:func:`_kept`): a row's value is then a function of its own inputs alone, the
#: same whichever rows a process evaluated before (unlike the block caches :func:`_new_block` clears).
_HINF: dict = {}
_TACTILE: dict = {}
_LOOPS: dict = {}
_KEPT_VALUES = 1024  # a Saltelli row repeats a row at most d + 2 rows back (its base sample's A)


def _forget_kept() -> None:
    """Empty the values kept by their inputs (benchmarks and tests measure a metric from scratch with it)."""
    for store in (_HINF, _TACTILE, _LOOPS):
        store.clear()


def _kept(store: dict, key, compute: Callable[[], float]) -> float:
    """``store[key]``, computed by ``compute()`` on the first call (the oldest entries dropped beyond
    :data:`_KEPT_VALUES`). Failures are not kept: they raise again for the row that asks."""
    hit = store.get(key)
    if hit is None:
        hit = store[key] = compute()
        while len(store) > _KEPT_VALUES:
            store.pop(next(iter(store)))
    return hit


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


def _bayes_settings(ps: ParameterSet, ctx: MetricContext):
    """Table 6.1's settings on this rig: positions from the base (m, rounded to the micrometre as
    :func:`flexdigit.tactile.bounds.protocol_limits` keys them), masses (kg), commands and repetitions."""
    rows = _protocol_settings(ctx.protocol)
    length = ps.params.geometry.digit_length_m
    # positions from the tip, as fractions of the thesis digit: a larger or smaller digit is probed alike
    scale = length / RigParams().geometry.digit_length_m
    a = np.where(rows[:, 1] > 0, length - rows[:, 0] * scale, 0.0)
    a = np.array([round(float(x), 6) if y > 0 else 0.0 for x, y in zip(a, rows[:, 1], strict=True)])
    m = np.array([round(float(y), 9) for y in rows[:, 1]])
    return a, m, rows[:, 2].astype(int), rows[:, 3]


def _bayes_exact(ps: ParameterSet, ctx: MetricContext) -> float:
    """The Bayes position limit by :func:`flexdigit.tactile.bounds.protocol_limits` itself (the reference the
    batched form :func:`bayes_limits` is tested against)."""
    a, m, c, w = _bayes_settings(ps, ctx)
    limits = protocol_limits(gauge_model(ps, ctx.tactile_cells), a, m, c, w, samples=ctx.bayes_samples, seed=ctx.seed)
    loaded = m > 0
    return 1e3 * float(np.sqrt(np.average(limits.position_mse_m2[loaded], weights=w[loaded])))


@lru_cache(maxsize=8)
def _bayes_draws(seed: int, samples: int, commands: tuple, gauges: int) -> np.ndarray:
    """The standard normal draws :func:`~flexdigit.tactile.bounds.protocol_limits` makes, per setting
    (settings, samples, gauges): command groups in ascending order, settings in their order within a group."""
    rng = np.random.default_rng(seed)
    c = np.asarray(commands)
    out = np.empty((c.size, samples, gauges))
    for value in np.unique(c):
        for j in np.flatnonzero(c == value):
            out[j] = rng.standard_normal((samples, gauges))
    return out


def _position_mse_m2(mean, sigma, a, m, c, w, eps) -> np.ndarray:
    """:func:`~flexdigit.tactile.bounds.protocol_limits`' position MSE of every loaded setting (NaN elsewhere): the
    same draws and the same Bayes estimate, group by group (:mod:`flexdigit.studies._bayes_kernel`)."""
    mse = np.full(a.size, np.nan)
    for value in np.unique(c):
        group = np.flatnonzero(c == value)
        loaded = m[group] > 0
        drawn = np.flatnonzero(loaded)
        if drawn.size:
            log_prior = np.log(w[group] / w[group].sum())
            args = (mean[group], sigma[group], a[group], loaded, log_prior, eps[group[drawn]], drawn)
            mse[group[drawn]] = position_mse_m2(*(np.ascontiguousarray(x) for x in args))
    return mse


def bayes_limits(parameter_sets, ctx: MetricContext) -> np.ndarray:
    """Chapter 6's Bayes position limit (mm) of many parameter sets: each rig's gauges solved on its own table 6.1
    settings, the Monte Carlo draws made once for all of them (the common random numbers, the same as
    :func:`~flexdigit.tactile.bounds.protocol_limits` draws) and scored by :func:`_position_mse_m2`. The same
    numbers as the exact form up to rounding (tested: :data:`BAYES_BATCH_RTOL`)."""
    relaxed = bool(np.all(_protocol_settings(ctx.protocol)[:, 2] == RELAXED))
    out = np.empty(len(parameter_sets))
    for i, ps in enumerate(parameter_sets):
        view = relaxed_statics(ps, ctx.baseline) if relaxed else ps
        out[i] = _kept(_TACTILE, ("bayes", view, ctx), lambda view=view: _bayes_row(view, ctx))
    return out


def _bayes_row(ps: ParameterSet, ctx: MetricContext) -> float:
    a, m, c, w = _bayes_settings(ps, ctx)
    model = gauge_model(ps, ctx.tactile_cells)
    mean = model.gauges_v(a, m, c)
    sigma = noise_of(model, a, m, c)
    eps = _bayes_draws(int(ctx.seed), int(ctx.bayes_samples), tuple(c.tolist()), mean.shape[1])
    loaded = m > 0
    mse = _position_mse_m2(mean, sigma, a, m, c, w, eps)
    return 1e3 * float(np.sqrt(np.average(mse[loaded], weights=w[loaded])))


def relaxed_statics(ps: ParameterSet, baseline: ParameterSet) -> ParameterSet:
    """``ps`` with what its relaxed statics never read set to ``baseline``'s: the actuator section, the cable's
    eccentricity, stiffness and guide friction, and the damping (``strip_beta_s``, ``housing_beta_s``).

    The tactile metrics read the digit relaxed (:data:`~flexdigit.tactile.protocols.RELAXED`), which the twin
    models with the cable detached (:class:`~flexdigit.tactile.bounds.TwinGaugeModel`), and in equilibrium, where
    no damper acts. Rows that differ only there (in a Saltelli design of the shipped tolerances, 7 of the 18
    parameters) have one value, computed once (:func:`_kept`); the test holds the view's metrics to the row's own
    (equal, not close: the fields are not read at all)."""
    base_p, base_c = baseline.params, baseline.calibration
    params = ps.params.replace(
        actuator=base_p.actuator,
        geometry=dataclasses.replace(ps.params.geometry, cable_eccentricity_m=base_p.geometry.cable_eccentricity_m),
    )
    calibration = dataclasses.replace(
        ps.calibration,
        strip_beta_s=base_c.strip_beta_s,
        housing_beta_s=base_c.housing_beta_s,
        cable_stiffness_n_m=base_c.cable_stiffness_n_m,
        cable_friction_ratio=base_c.cable_friction_ratio,
    )
    return ParameterSet(params, calibration, ps.antagonist_pretension_n)


#: How far the batched Bayes limit may stray from :func:`~flexdigit.tactile.bounds.protocol_limits` (relative): the
#: same draws and estimate, the residuals summed in another order (a few ulps of each posterior's exponent).
BAYES_BATCH_RTOL = 1e-9


def bayes_limits_by_prior(ps: ParameterSet, ctx: MetricContext) -> dict:
    """The localisation Bayes limits (mm) of ``ps`` on table 6.1's readings as ``flexdigit train --bayes-limit``
    computes them (:func:`flexdigit.tactile.localisation.position_bayes_rmse_m` on a dataset of those readings,
    every setting read its repetitions' times, the study's gauge model), by prior:

    - ``"settings"``: the load at one of the protocol's positions, what ``bayes_position_limit_mm`` is (the same
      :func:`~flexdigit.tactile.bounds.protocol_limits`; other draws) and what ``train --split readings`` compares
      its network with (``bayes_limit_settings_mm``);
    - ``"span"``: the load anywhere on the positions' stretch, what ``train --bayes-limit`` compares a network
      scored on held-out positions with (its default).

    A limit the draws do not resolve is None. The design study scores a design's twin on its own calibration
    (``[design] calibration``, by default the baseline's unscaled); the commands run an exported design's file on
    :func:`flexdigit.twin.digit_calibration.twin_calibration` (the thesis's scaled to it): pass that
    :class:`ParameterSet` to get the figures ``train`` gives on its collected readings.
    """
    a, m, c, w = _bayes_settings(ps, ctx)
    rows = np.repeat(np.arange(a.size), np.asarray(w, dtype=int))
    gauges = len(ps.params.geometry.gauge_positions_m)
    columns = {k: np.zeros(rows.size, dtype=d) for k, d in dataset_columns(gauges).items()}
    columns.update(load_kg=m[rows], position_from_base_m=a[rows], command=c[rows])
    readings = Dataset(columns, {"gauge_count": gauges})
    loaded = np.flatnonzero(readings["load_kg"] > 0)
    model = gauge_model(ps, ctx.tactile_cells)
    out = {}
    for prior in ("settings", "span"):
        try:
            limit = position_bayes_rmse_m(
                model, readings, loaded, samples=ctx.bayes_samples, seed=ctx.seed, prior=prior
            )
            out[prior] = 1e3 * limit
        except ValueError:
            out[prior] = None
    return out


@register_metric(
    "bayes_position_limit_mm",
    "mm",
    "chapter 6's localisation Bayes limit (RMS, one reading, the load at one of table 6.1's positions)",
    "6.5",
    batched=bayes_limits,
)
def bayes_position_limit_mm(ps: ParameterSet, ctx: MetricContext) -> float:
    return float(bayes_limits([ps], ctx)[0])


def _blind_zone_exact(ps: ParameterSet, ctx: MetricContext) -> float:
    """The blind zone from :func:`flexdigit.tactile.localisation.identifiability_map` itself (the Cramer-Rao bounds
    along the digit, the reference :func:`blind_zones` is tested against)."""
    length = ps.params.geometry.digit_length_m
    points = int(round(length / ctx.blind_step_m)) + 1
    zones = identifiability_map(gauge_model(ps, ctx.tactile_cells), [ctx.blind_mass_kg], [RELAXED], length, points)
    zone = zones["cases"][0]["zone"]
    seen = np.flatnonzero(zone != "no gauge bends")
    return 1e3 * float(zones["position_from_base_m"][seen[0]] if seen.size else length)


#: Grid points of the blind-zone scan solved at a time, from the clamp out: the scan stops at the first block with a
#: visible point, so a rig whose zone ends within 46 mm of the clamp (at 2 mm steps; the thesis rig's: 36 mm)
#: solves one block of the 136 points along its digit.
BLIND_BLOCK = 24


def blind_zones(parameter_sets, ctx: MetricContext) -> np.ndarray:
    """The blind zone (mm) of many parameter sets with two static solves per rig instead of the Cramer-Rao map's
    six over the whole digit: a point is blind when the load moves no gauge by a tenth of its noise
    (:func:`flexdigit.tactile.bounds.cramer_rao`'s test, on the same grid), or when no gauge's reading changes
    with the position there (checked at the first visible point only, by the bounds' own Jacobian; the exact map
    is run where it finds one). The grid is solved from the clamp out in blocks of :data:`BLIND_BLOCK` points,
    stopping at the first visible one. The same grid point as the exact form on every rig tested (a point
    within rounding of the tenth-of-the-noise threshold could move it by one grid step, ``ctx.blind_step_m``)."""
    out = np.empty(len(parameter_sets))
    for i, ps in enumerate(parameter_sets):
        view = relaxed_statics(ps, ctx.baseline)
        out[i] = _kept(_TACTILE, ("blind", view, ctx), lambda view=view: _blind_row(view, ctx))
    return out


def _blind_row(ps: ParameterSet, ctx: MetricContext) -> float:
    model = gauge_model(ps, ctx.tactile_cells)
    length = ps.params.geometry.digit_length_m
    grid = np.linspace(0.0, length, int(round(length / ctx.blind_step_m)) + 1)
    unloaded = model.gauges_v(grid[:1], 0.0, RELAXED)  # the same for every point: no load
    first = None
    for start in range(0, grid.size, BLIND_BLOCK):
        a = grid[start : start + BLIND_BLOCK]
        m = np.full(a.shape, ctx.blind_mass_kg)
        c = np.full(a.shape, RELAXED)
        moved = np.abs(model.gauges_v(a, m, c) - unloaded)
        seen = np.flatnonzero(~np.all(moved < 0.1 * noise_of(model, a, m, c), axis=1))
        if seen.size:
            first = a[seen[0]]
            break
    if first is not None and not _position_informative(model, first, ctx.blind_mass_kg):
        return _blind_zone_exact(ps, ctx)  # visible, yet no position information there: the map decides
    return 1e3 * float(length if first is None else first)


def _position_informative(model, position_m: float, mass_kg: float, step_m: float = 2e-4) -> bool:
    """Whether a visible relaxed load at ``position_m`` carries position information: the Fisher information of the
    position, :func:`~flexdigit.tactile.bounds.cramer_rao`'s ``faa``, is positive. Relaxed, the noise does not
    depend on the load, so ``faa = sum (dg/da)^2 / sigma^2`` and only ``dg/da`` is needed: the bounds' central
    difference (its step), two static solves of the six ``cramer_rao`` makes (it also differentiates by the mass
    and repeats the visibility test the scan has just made)."""
    a = np.array([position_m + step_m, position_m - step_m])
    m = np.full(2, mass_kg)
    c = np.full(2, RELAXED)
    g = model.gauges_v(a, m, c)
    sigma = noise_of(model, a[:1], m[:1], c[:1])[0]
    faa = float(np.sum(((g[0] - g[1]) / (2 * step_m)) ** 2 / sigma**2))
    return faa > 0


@register_metric(
    "blind_zone_mm", "mm", "length from the clamp where a 25 g load bends no gauge", "6.5", batched=blind_zones
)
def blind_zone_mm(ps: ParameterSet, ctx: MetricContext) -> float:
    return float(blind_zones([ps], ctx)[0])


#: The metrics a sensitivity study computes unless its spec lists others. The loop's speed is scored by
#: ``time_outside_band_s``, not ``settling_time_s``: the settling time jumps by half a ringing period where a late
#: ripple touches the band, and its Sobol indices moved by 0.09 between N = 256 and 512 where the continuous
#: figure's moved by 0.04 (same rows, same leading parameters; docs/studies.md). A spec may still list either.
SENSITIVITY_METRICS = (
    "release_wn_rad_s",
    "release_zeta",
    "actuated_wn_rad_s",
    "rotation_gain_deg_per_command",
    "time_outside_band_s",
    "overshoot_percent",
    "gain_margin",
    "hinf_gamma",
    "bayes_position_limit_mm",
    "blind_zone_mm",
)
