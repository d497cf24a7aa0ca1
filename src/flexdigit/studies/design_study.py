"""The design study: what the next digit should look like (thesis 2.1, 3.6 and chapter 8).

Chapter 8 asks for "feedback of all three strain gauges, and [an increased] motor step resolution"; 2.1 for "a
two cable system to ensure rigidity of the member and ultimately its stability" and a study of "the effects that
size has on ... stiffness and stability"; 2.3.1 names the quarter, half and full bridges. A design spec's
``[design]`` table lists the options (defaults in brackets):

- ``gauge_counts`` [3, 4, 5, 6] and ``layouts`` ["thesis", "equal", "d-optimal"]: where the gauges go. ``thesis``
  is table 3.5's 45/135/225 mm (3 gauges only); ``equal`` puts gauge ``k`` of ``N`` at ``(k + 1/2) L / N`` along
  the digit (for 3 gauges that is the thesis layout: midway between the supports), moved onto the strip if it
  lands on a nylon support; ``d-optimal`` maximises the expected log-determinant of the Fisher information of a
  load's (position, mass) over table 6.1's loads hung anywhere along the digit (:func:`d_optimal_positions`);
- ``bridges`` ["quarter", "half", "full"], ``adc_bits`` [12, 16];
- ``servo_deg_per_command`` [0.862, 0.431, 0.216]: the servo's step (3.6: "the range of motor motion will need to
  be increased to produce smaller steps"), its range shrinking with it (254 commands);
- ``eccentricity_m`` [0.004, 0.005715, 0.008];
- ``pretension_n`` [0, 5]: 0 is the thesis's single cable, a positive value adds the antagonistic second cable
  with that pretension (:mod:`flexdigit.twin.batched`);
- ``size`` [0.75, 1.0, 1.25]: every length along the digit scaled (sections, supports, gauges), the strip's
  cross-section and the cable's eccentricity kept;
- ``section_taper`` [1.0]: the tip section's free strip over the base section's, the sections' lengths in
  geometric progression from the base (``l_k = l_0 r^(k / (n - 1))``) with their sum, the supports and the digit's
  length kept (:func:`tapered`); 1 keeps the baseline's own sections (equal on the thesis rig). The ``thesis``
  layout's gauges keep their place within their section (midway, on the thesis rig); ``equal`` and
  ``d-optimal`` are laid on the tapered strip;
- ``calibration`` ["baseline"]: each design's twin calibration (:func:`design_calibration`): the baseline's as it
  is, or ``"scaled"``, the baseline's scaled to the design by the physics (as the commands run its exported file);
- ``samples`` [0]: 0 evaluates every combination; a positive number evaluates that many, drawn without
  replacement with the study's seed, always including the thesis design and its equal-spacing twins (the thesis
  design with 4, 5, 6 equally spaced gauges), the designs the front is read against.

Every candidate is evaluated with the 20 ms controller designed for it (:class:`MetricContext` ``redesign``):
chapter 6's localisation Bayes limit and blind zone against the closed loop's settling time, overshoot and gain
margin, the rotation per command (the quantum the integer command leaves) and the tip's stiffness. The Pareto
front (:func:`pareto_front`) is taken over ``objectives`` [["bayes_position_limit_mm", "settling_time_s"]], all
minimised, with the thesis design and the equal-spacing designs marked on it.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np

from flexdigit._io import atomic_path, atomic_write, check_output
from flexdigit._json import to_jsonable
from flexdigit._repr import fields_summary
from flexdigit.errors import ParameterError
from flexdigit.params import BRIDGE_TYPES, LENGTH_TOLERANCE_M, THESIS_SUPPORT_M, RigParams, params_template
from flexdigit.studies.execution import run_study
from flexdigit.studies.figures import _save, pareto_figure
from flexdigit.studies.metrics import METRICS, MetricContext, bayes_limits_by_prior
from flexdigit.studies.spec import ParameterSet, StudySpec, spec_from_toml
from flexdigit.tactile.protocols import load_protocol
from flexdigit.twin.digit_calibration import calibration_for, twin_calibration
from flexdigit.twin.twin import static_gauges_v

__all__ = [
    "DesignSettings",
    "Candidate",
    "DesignResult",
    "candidates",
    "design_parameter_set",
    "design_calibration",
    "equal_positions",
    "d_optimal_positions",
    "d_criterion",
    "pareto_front",
    "tapered",
    "export_design",
    "run_design",
    "write_design_outputs",
    "DESIGN_METRICS",
]

LAYOUTS = ("thesis", "equal", "d-optimal")
DESIGN_METRICS = (
    "bayes_position_limit_mm",
    "blind_zone_mm",
    "settling_time_s",
    "overshoot_percent",
    "gain_margin",
    "rotation_gain_deg_per_command",
    "tip_stiffness_nm_per_rad",
)
#: How far a gauge keeps from a nylon support (m): its grid sits on the strip (2.2.1: 10 mm supports).
SUPPORT_CLEARANCE_M = 0.002
_THESIS_DESIGN = {
    "gauge_count": 3,
    "layout": "thesis",
    "bridge": "half",
    "adc_bits": 16,
    "servo_deg_per_command": 219.0 / 254.0,
    "eccentricity_m": 5.715e-3,
    "pretension_n": 0.0,
    "size": 1.0,
    "section_taper": 1.0,
}
#: How a design's twin calibration is made (:func:`design_calibration`): ``"baseline"`` the baseline's as it is
#: (channels averaged for another gauge count; the default, the report's showcase), ``"scaled"`` the baseline's
#: scaled to each design by the physics, as the commands run its exported file.
CALIBRATIONS = ("baseline", "scaled")
#: The tapers a study may ask for (tip section over base section): past 5:1 either way a section of a 3-section
#: thesis-sized digit is shorter than the 20 mm its gauge and guide need.
TAPER_RANGE = (0.2, 5.0)


@dataclass(frozen=True)
class DesignSettings:
    """The ``[design]`` table (see the module docstring)."""

    gauge_counts: tuple[int, ...] = (3, 4, 5, 6)
    layouts: tuple[str, ...] = LAYOUTS
    bridges: tuple[str, ...] = BRIDGE_TYPES
    adc_bits: tuple[int, ...] = (12, 16)
    servo_deg_per_command: tuple[float, ...] = (219.0 / 254.0, 219.0 / 508.0, 219.0 / 1016.0)
    eccentricity_m: tuple[float, ...] = (0.004, 5.715e-3, 0.008)
    pretension_n: tuple[float, ...] = (0.0, 5.0)
    size: tuple[float, ...] = (0.75, 1.0, 1.25)
    section_taper: tuple[float, ...] = (1.0,)
    samples: int = 0
    objectives: tuple[str, ...] = ("bayes_position_limit_mm", "settling_time_s")
    chunk_size: int = 4
    bayes_samples: int = 300
    grid_step_m: float = 0.0025
    calibration: str = "baseline"

    @classmethod
    def from_spec(cls, spec: StudySpec, **overrides) -> DesignSettings:
        table = dict(spec.settings.get("design", {}))
        table.update({k: v for k, v in overrides.items() if v is not None})
        where = f"{spec.source}: [design]"
        allowed = {f.name: f for f in dataclasses.fields(cls)}
        bad = sorted(set(table) - set(allowed))
        if bad:
            raise ParameterError(f"{where}: unknown key {bad[0]!r}; expected one of " + ", ".join(allowed))
        values = {}
        for name, value in table.items():
            default = allowed[name].default
            if isinstance(default, tuple):
                if not isinstance(value, list) or not value:
                    raise ParameterError(f"{where} {name} must be a non-empty list. Got {value!r} instead.")
                kind = type(default[0])
                if kind is float and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
                    value = [float(v) for v in value]
                if not all(isinstance(v, kind) and not isinstance(v, bool) for v in value):
                    raise ParameterError(f"{where} {name} must list {kind.__name__} values. Got {value!r} instead.")
                if len(set(value)) != len(value):
                    raise ParameterError(f"{where} {name} lists a value twice: {value!r}")
                value = tuple(value)
            elif isinstance(default, int) and (isinstance(value, bool) or not isinstance(value, int)):
                raise ParameterError(f"{where} {name} must be an integer. Got {value!r} instead.")
            elif isinstance(default, float) and (isinstance(value, bool) or not isinstance(value, (int, float))):
                raise ParameterError(f"{where} {name} must be a number. Got {value!r} instead.")
            values[name] = value
        out = cls(**values)
        out._check(where)
        return out

    def _check(self, where: str) -> None:
        def bad(name, expected, got):
            raise ParameterError(f"{where} {name} must be {expected}. Got {got!r} instead.")

        if any(not 1 <= n <= 12 for n in self.gauge_counts):
            bad("gauge_counts", "gauge counts in 1..12", list(self.gauge_counts))
        if any(x not in LAYOUTS for x in self.layouts):
            bad("layouts", "a list of " + ", ".join(LAYOUTS), list(self.layouts))
        if any(x not in BRIDGE_TYPES for x in self.bridges):
            bad("bridges", "a list of " + ", ".join(BRIDGE_TYPES), list(self.bridges))
        if any(not 8 <= b <= 24 for b in self.adc_bits):  # a digit's own range (flexdigit.params.Sensors)
            bad("adc_bits", "bit counts in 8..24", list(self.adc_bits))
        if any(not 0 < d <= 360.0 / 254 for d in self.servo_deg_per_command):
            bad("servo_deg_per_command", f"steps in (0, {360 / 254:.4g}] degrees", list(self.servo_deg_per_command))
        if any(not 0 < e <= 0.02 for e in self.eccentricity_m):
            bad("eccentricity_m", "eccentricities in (0, 0.02] m", list(self.eccentricity_m))
        if any(not 0 <= p <= 100 for p in self.pretension_n):
            bad("pretension_n", "pretensions in [0, 100] N (0: one cable)", list(self.pretension_n))
        if any(not 0.25 <= s <= 4 for s in self.size):
            bad("size", "scale factors in [0.25, 4]", list(self.size))
        low, high = TAPER_RANGE
        if any(not low <= r <= high for r in self.section_taper):
            bad("section_taper", f"tip-over-base length ratios in [{low:g}, {high:g}]", list(self.section_taper))
        if self.samples < 0:
            bad("samples", "an integer >= 0 (0: every combination)", self.samples)
        if len(self.objectives) < 2 or any(o not in DESIGN_METRICS for o in self.objectives):
            bad("objectives", "two or more of " + ", ".join(DESIGN_METRICS), list(self.objectives))
        if self.calibration not in CALIBRATIONS:
            bad("calibration", " or ".join(repr(c) for c in CALIBRATIONS), self.calibration)
        if self.chunk_size < 1 or self.bayes_samples < 10 or not 0.0005 <= self.grid_step_m <= 0.02:
            bad(
                "chunk_size/bayes_samples/grid_step_m",
                ">= 1, >= 10 and in [0.0005, 0.02] m",
                (self.chunk_size, self.bayes_samples, self.grid_step_m),
            )


@dataclass(frozen=True)
class Candidate:
    """One design: every option of the study fixed."""

    gauge_count: int
    layout: str
    bridge: str
    adc_bits: int
    servo_deg_per_command: float
    eccentricity_m: float
    pretension_n: float
    size: float
    section_taper: float = 1.0

    @property
    def is_thesis(self) -> bool:
        return all(
            math.isclose(getattr(self, k), v, rel_tol=1e-3) if isinstance(v, float) else getattr(self, k) == v
            for k, v in _THESIS_DESIGN.items()
        )

    def label(self) -> str:
        cable = f"2 cables {self.pretension_n:g} N" if self.pretension_n > 0 else "1 cable"
        return (
            f"{self.gauge_count} gauges {self.layout}, {self.bridge} bridge, {self.adc_bits} bit, "
            f"{self.servo_deg_per_command:.3g} deg/cmd, e {1e3 * self.eccentricity_m:.3g} mm, {cable}, "
            f"size x{self.size:g}" + (f", taper {self.section_taper:g}" if self.section_taper != 1.0 else "")
        )


def candidates(settings: DesignSettings, seed: int) -> list[Candidate]:
    """The study's designs: every combination (``thesis`` only with 3 gauges), or a seeded sample of them that
    always contains the thesis design (when its options are in the study)."""
    combos = [
        Candidate(*c)
        for c in itertools.product(
            settings.gauge_counts,
            settings.layouts,
            settings.bridges,
            settings.adc_bits,
            settings.servo_deg_per_command,
            settings.eccentricity_m,
            settings.pretension_n,
            settings.size,
            settings.section_taper,
        )
        if c[1] != "thesis" or c[0] == 3
    ]
    if not combos:
        raise ParameterError("[design]: no candidate (the 'thesis' layout has 3 gauges: add 3 to gauge_counts)")
    if settings.samples and settings.samples < len(combos):
        rng = np.random.default_rng([seed, 17])
        # the designs the front is read against always go in: the thesis design and its equal-spacing twins
        marked = [i for i, c in enumerate(combos) if c.is_thesis or _is_equal_twin(c)]
        rest = [i for i in range(len(combos)) if i not in set(marked)]
        extra = max(0, settings.samples - len(marked))
        pick = set(marked[: settings.samples]) | set(rng.choice(rest, min(extra, len(rest)), replace=False).tolist())
        combos = [combos[i] for i in sorted(pick)]
    return combos


def _is_equal_twin(c: Candidate) -> bool:
    """An equal-spacing design that is the thesis design in every other option."""
    return c.layout == "equal" and dataclasses.replace(c, layout="thesis", gauge_count=3).is_thesis


# ----------------------------------------------------------------------------------------------------- layouts
def _strip_stretches(params: RigParams) -> list[tuple[float, float]]:
    """The flexible stretches of the strip between the nylon supports (m from the base), with a clearance."""
    return [(a + SUPPORT_CLEARANCE_M, b - SUPPORT_CLEARANCE_M) for a, b in params.geometry.section_bounds_m]


def _onto_strip(x: float, params: RigParams) -> float:
    stretches = _strip_stretches(params)
    best = min(stretches, key=lambda s: 0.0 if s[0] <= x <= s[1] else min(abs(x - s[0]), abs(x - s[1])))
    return float(min(max(x, best[0]), best[1]))


def equal_positions(count: int, params: RigParams) -> tuple[float, ...]:
    """Gauge ``k`` of ``count`` at ``(k + 1/2) L / count`` (3 gauges: table 3.5's 45/135/225 mm), on the strip.

    Examples
    --------
    >>> [round(1e3 * x, 1) for x in equal_positions(3, RigParams())]
    [45.0, 135.0, 225.0]
    """
    length = params.geometry.digit_length_m
    return tuple(_onto_strip((k + 0.5) * length / count, params) for k in range(count))


def _grid(params: RigParams, step: float) -> np.ndarray:
    pts = [np.arange(a, b + 1e-12, step) for a, b in _strip_stretches(params)]
    return np.concatenate(pts)


@lru_cache(maxsize=64)
def _information(params: RigParams, calibration, step: float, masses: tuple[float, ...]):
    """Per load case (positions along the whole digit x the protocol's masses) and grid point, the gradient of
    the gauge voltage with respect to (position / L, mass / 25 g), in units of the noise; and the grid."""
    grid = _grid(params, step)
    probe = params.replace(geometry=dataclasses.replace(params.geometry, gauge_positions_m=tuple(grid)))
    cal = calibration.replace(
        channel_gain=(float(np.mean(calibration.channel_gain)),) * grid.size,
        channel_offset_v=(0.0,) * grid.size,
        noise_white_v=(float(np.mean(calibration.noise_white_v)),) * grid.size,
        noise_drift_v_per_sqrt_s=(float(np.mean(calibration.noise_drift_v_per_sqrt_s)),) * grid.size,
    )
    length = params.geometry.digit_length_m
    a = np.linspace(0.05 * length, length, 24)
    aa, mm = (x.ravel() for x in np.meshgrid(a, masses))
    da, dm = 1e-3 * length, 0.02 * mm

    def volts(pos, mass):
        return static_gauges_v(
            mass, np.clip(pos, 0, length), None, params=probe, calibration=cal, adc=False, cells_per_section=9
        )

    ja = (volts(aa + da, mm) - volts(aa - da, mm)) / (2 * da) * length
    jm = (volts(aa, mm + dm) - volts(aa, mm - dm)) / (2 * dm)[:, None] * 0.025
    sigma = float(np.mean(calibration.noise_white_v))
    return np.stack([ja, jm], axis=-1) / sigma, grid  # (cases, grid, 2)


def d_criterion(jac: np.ndarray, chosen) -> float:
    """Expected log-determinant of the 2 x 2 Fisher information over the load cases for the gauges ``chosen``
    (indices into the grid), with a ridge of 1e-6 (one noise per ~1000 of the digit's length) so that a load no
    gauge sees costs a finite amount."""
    j = jac[:, list(chosen), :]
    f = np.einsum("cgi,cgj->cij", j, j) + 1e-6 * np.eye(2)
    sign, logdet = np.linalg.slogdet(f)
    return float(np.mean(logdet))


def d_optimal_positions(count: int, ps: ParameterSet, *, step_m: float = 0.0025, seed: int = 0, starts: int = 4):
    """D-optimal gauge positions (m from the base) on the strip: the grid points maximising :func:`d_criterion`.

    Fedorov-style coordinate exchange: each gauge in turn moves to the grid point that raises the criterion most,
    until no move does; from equal spacing and ``starts - 1`` random layouts (seeded), keeping the best.
    Returns ``(positions, criterion, criterion_of_equal_spacing)``.
    """
    masses = tuple(load_protocol("thesis-6.1").loads_kg)
    jac, grid = _information(ps.params, ps.calibration, step_m, masses)
    equal = [int(np.argmin(np.abs(grid - x))) for x in equal_positions(count, ps.params)]
    rng = np.random.default_rng([seed, count, 23])
    starts_list = [equal] + [sorted(rng.choice(grid.size, count, replace=False).tolist()) for _ in range(starts - 1)]
    best, best_value = exchange_search(jac, starts_list)
    return tuple(float(grid[g]) for g in best), best_value, d_criterion(jac, equal)


def exchange_search(jac: np.ndarray, starts) -> tuple[list[int], float]:
    """The coordinate exchange of :func:`d_optimal_positions` on any gradients ``jac`` (cases, grid, 2) from the
    layouts ``starts`` (grid indices); returns the best layout found (sorted indices) and its criterion."""
    best, best_value = None, -math.inf
    size = jac.shape[1]
    for start in starts:
        chosen = list(start)
        value = d_criterion(jac, chosen)
        improved = True
        while improved:
            improved = False
            for i in range(len(chosen)):
                others = chosen[:i] + chosen[i + 1 :]
                trial = [d_criterion(jac, others + [g]) if g not in others else -math.inf for g in range(size)]
                g = int(np.argmax(trial))
                if trial[g] > value + 1e-9:
                    chosen[i], value, improved = g, trial[g], True
        if value > best_value:
            best, best_value = sorted(chosen), value
    return best, best_value


# ----------------------------------------------------------------------------------------------------- candidates
def _scaled(params: RigParams, size: float) -> RigParams:
    g = params.geometry
    geometry = dataclasses.replace(
        g,
        section_length_m=(
            tuple(x * size for x in g.section_length_m)
            if isinstance(g.section_length_m, tuple)
            else g.section_length_m * size
        ),
        support_lengths_m=None if g.support_lengths_m is None else tuple(x * size for x in g.support_lengths_m),
        digit_length_m=g.digit_length_m * size,
        strip_length_m=g.strip_length_m * size,
        gauge_positions_m=tuple(x * size for x in g.gauge_positions_m),
    )
    return params.replace(geometry=geometry)


def tapered(params: RigParams, ratio: float) -> RigParams:
    """The digit with its sections' free strips tapered: the tip section ``ratio`` times as long as the base one,
    the lengths in geometric progression from the base (``l_k = l_0 ratio^(k / (n - 1))``), their sum (the strip),
    every support and the digit's length kept. Each gauge keeps its place within its section (a gauge on a support
    keeps its place on it): the thesis's mid-section gauges stay mid-section. ``ratio`` 1 returns ``params``
    itself (the baseline's own sections, equal or not).

    Examples
    --------
    >>> g = tapered(RigParams(), 0.5).geometry
    >>> [round(1e3 * x, 2) for x in g.section_length_m], round(1e3 * g.digit_length_m, 1)
    ([108.74, 76.89, 54.37], 270.0)
    >>> [round(1e3 * (a + b) / 2, 2) for a, b in g.section_bounds_m], [round(1e3 * x, 2) for x in g.gauge_positions_m]
    ([59.37, 162.18, 237.82], [59.37, 162.18, 237.82])
    """
    if ratio == 1.0:
        return params
    g = params.geometry
    n = g.section_count
    if n < 2:
        raise ParameterError(
            f"[design] section_taper {ratio:g}: the baseline digit has {n} section; a taper needs two or more "
            "(section_taper = [1.0] keeps it)"
        )
    weights = ratio ** (np.arange(n) / (n - 1))
    lengths = tuple(float(x) for x in g.strip_length_m * weights / weights.sum())
    new = dataclasses.replace(
        g, section_length_m=lengths, strip_length_m=math.fsum(lengths), support_lengths_m=g.supports_m
    )
    # the layout's knots (clamp, each section's ends, tip) old -> new: sections stretch, supports move whole
    old_knots = [0.0, *itertools.chain.from_iterable(g.section_bounds_m), g.digit_length_m]
    new_knots = [0.0, *itertools.chain.from_iterable(new.section_bounds_m), new.digit_length_m]
    positions = tuple(float(x) for x in np.interp(g.gauge_positions_m, old_knots, new_knots))
    return params.replace(geometry=dataclasses.replace(new, gauge_positions_m=positions))


@lru_cache(maxsize=256)
def _d_optimal_cached(count: int, base: ParameterSet, step: float, seed: int) -> tuple[float, ...]:
    return d_optimal_positions(count, base, step_m=step, seed=seed)[0]


def design_parameter_set(
    baseline: ParameterSet, c: Candidate, *, grid_step_m: float = 0.0025, seed: int = 0, calibration: str = "baseline"
):
    """The rig of a candidate design, built from the baseline (see the module docstring), with the calibration
    ``calibration`` says (:data:`CALIBRATIONS`, :func:`design_calibration`)."""
    params = tapered(_scaled(baseline.params, c.size), c.section_taper)
    geo = params.geometry
    cal = design_calibration(baseline, params, calibration)  # for the D-optimal placement
    if c.layout == "thesis":
        if c.gauge_count != 3:
            raise ParameterError(f"the 'thesis' layout has 3 gauges. Got {c.gauge_count}.")
        positions = geo.gauge_positions_m
    elif c.layout == "equal":
        positions = equal_positions(c.gauge_count, params)
    else:
        base = ParameterSet(params, cal)
        positions = _d_optimal_cached(c.gauge_count, base, grid_step_m, seed)
    n = c.gauge_count
    if calibration == "baseline" and n != len(cal.channel_gain):  # new channels: the mean gain and noise, no offset
        mean = {
            k: float(np.mean(getattr(cal, k))) for k in ("channel_gain", "noise_white_v", "noise_drift_v_per_sqrt_s")
        }
        cal = cal.replace(
            channel_gain=(mean["channel_gain"],) * n,
            channel_offset_v=(0.0,) * n,
            noise_white_v=(mean["noise_white_v"],) * n,
            noise_drift_v_per_sqrt_s=(mean["noise_drift_v_per_sqrt_s"],) * n,
        )
    act = params.actuator
    gain = c.servo_deg_per_command * act.pulley_radius_m / c.eccentricity_m  # tip deg per command (E 3.15)
    top = min(act.command_max, act.equilibrium_command + math.ceil(30.0 / gain))  # 30 deg of tip rotation (3.4.1)
    params = params.replace(
        geometry=dataclasses.replace(geo, gauge_positions_m=tuple(positions), cable_eccentricity_m=c.eccentricity_m),
        sensors=dataclasses.replace(params.sensors, bridge=c.bridge, adc_bits=c.adc_bits, adc_channels=tuple(range(n))),
        actuator=dataclasses.replace(
            act,
            angle_max_deg=act.angle_min_deg + c.servo_deg_per_command * (act.command_max - act.command_min),
            operating_commands=(act.equilibrium_command, top),
        ),
    )
    if c.pretension_n == 0 and params.cables.count == 2:  # "1 cable": a baseline's described pair is dropped, so
        params = params.replace(cables=dataclasses.replace(params.cables, count=1))  # it is not scored as a pair
    if calibration == "scaled":
        cal = design_calibration(baseline, params, calibration)
    return ParameterSet(params, cal, c.pretension_n if c.pretension_n > 0 else None)


def design_calibration(baseline: ParameterSet, params: RigParams, calibration: str = "scaled"):
    """The twin calibration a design ``params`` is scored on.

    ``"baseline"``: the baseline's as it is (the default of a study and the report's showcase; a new gauge count's
    channels are then averaged, :func:`design_parameter_set`). ``"scaled"``: the baseline's own where the design
    keeps its structure (geometry, material and amplifiers: only the bridge, ADC, servo step or cables differ, so
    the fitted values hold), else the baseline's scaled to the design by the laws of
    :func:`flexdigit.twin.digit_calibration.calibration_for` (a resized digit's supports, cable run and first mode,
    an eccentricity's housing, the channels of new gauges at their relative places): the calibration the commands
    give its exported file (:func:`flexdigit.twin.digit_calibration.twin_calibration`). The physics asks for
    ``"scaled"`` (a design is a digit nobody has measured); it is not the default because it moves the report's
    showcase front (docs/digits.md, "One default").

    Examples
    --------
    >>> from flexdigit.twin.calibration import packaged_calibration
    >>> thesis = ParameterSet()
    >>> design_calibration(thesis, RigParams()) == packaged_calibration()
    True
    >>> c = Candidate(3, "thesis", "half", 16, 219 / 254, 5.715e-3, 0.0, 1.25)
    >>> big = design_parameter_set(thesis, c, calibration="scaled")
    >>> round(big.calibration.cable_stiffness_n_m / packaged_calibration().cable_stiffness_n_m, 4)   # k = EA / l
    0.8
    """
    if calibration not in CALIBRATIONS:
        raise ParameterError(
            f"The 'calibration' parameter of design_calibration must be one of {CALIBRATIONS}. Got "
            f"{calibration!r} instead."
        )
    if calibration == "baseline":
        return baseline.calibration
    base = baseline.params
    gauges = len(params.geometry.gauge_positions_m)
    same = (
        params.geometry == base.geometry
        and params.material == base.material
        and params.sensors.chain(gauges)[2] == base.sensors.chain(gauges)[2]
    )
    return baseline.calibration if same else calibration_for(params, baseline.calibration, base)


# ----------------------------------------------------------------------------------------------------- pareto
def pareto_front(objectives: np.ndarray) -> np.ndarray:
    """Indices of the non-dominated rows of ``objectives`` (n, k), all minimised; non-finite rows never are.

    Examples
    --------
    >>> pareto_front(np.array([[1, 5], [2, 2], [3, 3], [5, 1]])).tolist()
    [0, 1, 3]
    """
    y = np.asarray(objectives, dtype=float)
    ok = np.all(np.isfinite(y), axis=1)
    front = []
    for i in np.flatnonzero(ok):
        dominated = np.all(y[ok] <= y[i], axis=1) & np.any(y[ok] < y[i], axis=1)
        if not dominated.any():
            front.append(int(i))
    return np.array(front, dtype=int)


@dataclass
class DesignResult:
    """What :func:`run_design` found."""

    spec: StudySpec
    settings: DesignSettings
    candidates: list[Candidate]
    outputs: dict[str, np.ndarray]
    errors: list[str | None]
    front: np.ndarray
    placement: list[dict] = field(default_factory=list)

    def objective_matrix(self) -> np.ndarray:
        return np.column_stack([self.outputs[o] for o in self.settings.objectives])

    def marked(self) -> dict[str, int]:
        """Rows of the thesis design and of each equal-spacing design otherwise like it."""
        marks = {}
        for i, c in enumerate(self.candidates):
            if c.is_thesis:
                marks["thesis layout"] = i
        for i, c in enumerate(self.candidates):
            if _is_equal_twin(c):
                marks[f"equal spacing, {c.gauge_count} gauges"] = i
        return marks

    def summary(self) -> dict:
        rows = []
        for i, c in enumerate(self.candidates):
            row = dataclasses.asdict(c) | {m: self.outputs[m][i] for m in self.outputs}
            row.update(row=i, on_front=bool(i in set(self.front.tolist())), error=self.errors[i], label=c.label())
            rows.append(row)
        return {
            "study": self.spec.name,
            "objectives": list(self.settings.objectives),
            "candidates": len(self.candidates),
            "pareto_front": [rows[i] for i in self.front],
            "marked": {k: rows[i] for k, i in self.marked().items()},
            "placement": self.placement,
            "failed": [r for r in rows if r["error"]],
        }

    def text(self) -> str:
        o = self.settings.objectives
        lines = [f"{self.spec.name}: {len(self.candidates)} designs, Pareto front over {', '.join(o)}:"]
        for i in self.front[np.argsort(self.outputs[o[0]][self.front])]:
            values = ", ".join(f"{m} {self.outputs[m][i]:.3g}" for m in o)
            lines.append(f"  design {i} (--export {i}): {values}: {self.candidates[i].label()}")
        for name, i in self.marked().items():
            values = ", ".join(f"{m} {self.outputs[m][i]:.3g}" for m in o)
            lines.append(f"  [{name}] {values}{' (on the front)' if i in set(self.front.tolist()) else ''}")
        for p in self.placement:
            lines.append(
                f"  D-optimal {p['gauges']} gauges: {p['positions_mm']} mm vs equal {p['equal_mm']} mm "
                f"(largest shift {p['max_shift_mm']:.1f} mm, "
                f"equal spacing's D-efficiency {p['d_efficiency_equal']:.3f})"
            )
        failed = [i for i, e in enumerate(self.errors) if e]
        if failed:
            lines.append(f"  {len(failed)} designs failed (listed in summary.json)")
        return "\n".join(lines)

    __repr__ = fields_summary


class _Builder:
    """Picklable row -> ParameterSet for the executor: a row holds a candidate's index."""

    def __init__(
        self, baseline: ParameterSet, cands: list[Candidate], step: float, seed: int, calibration: str = "baseline"
    ) -> None:
        self.baseline, self.cands, self.step, self.seed = baseline, cands, step, seed
        self.calibration = calibration

    def __call__(self, row, label):
        c = self.cands[int(row[0])]
        return design_parameter_set(
            self.baseline, c, grid_step_m=self.step, seed=self.seed, calibration=self.calibration
        )


def placement_report(ps: ParameterSet, counts, *, step_m: float, seed: int) -> list[dict]:
    """D-optimal against equal spacing for each gauge count: positions, the largest shift, the D-efficiency."""
    out = []
    for n in counts:
        positions, best, equal_value = d_optimal_positions(n, ps, step_m=step_m, seed=seed)
        equal = equal_positions(n, ps.params)
        out.append(
            {
                "gauges": n,
                "positions_mm": [round(1e3 * x, 1) for x in positions],
                "equal_mm": [round(1e3 * x, 1) for x in equal],
                "max_shift_mm": float(1e3 * np.max(np.abs(np.array(positions) - np.array(equal)))),
                # D-efficiency of equal spacing: (det F_equal / det F_opt)^(1/p), p = 2 parameters
                "d_efficiency_equal": float(math.exp((equal_value - best) / 2.0)),
            }
        )
    return out


def study_fingerprint(spec: StudySpec, settings: DesignSettings) -> str:
    """The journal's fingerprint of a design study (:mod:`flexdigit.studies.execution` resumes only its own). A
    study without tapers (``section_taper`` [1.0]) keeps the fingerprint it had before tapers existed, so its
    journals resume; so does one on the baseline's calibration (``calibration`` "baseline")."""
    import hashlib
    import json

    options = dataclasses.asdict(settings)
    if settings.section_taper == (1.0,):
        del options["section_taper"]
    if settings.calibration == "baseline":
        del options["calibration"]
    text = json.dumps([spec.fingerprint(), options], sort_keys=True, default=repr)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def run_design(
    spec: StudySpec,
    out_dir: str | Path,
    *,
    settings: DesignSettings | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    force: bool = False,
    progress: bool = True,
) -> DesignResult:
    """Run (or resume) a design study in ``out_dir`` (journal, see :mod:`flexdigit.studies.execution`)."""
    settings = settings or DesignSettings.from_spec(spec)
    cands = candidates(settings, spec.seed)
    metrics = list(dict.fromkeys([*DESIGN_METRICS, *settings.objectives, *(u.name for u in spec.user_metrics)]))
    context = MetricContext(
        baseline=spec.baseline,
        redesign=True,
        seed=spec.seed,
        bayes_samples=settings.bayes_samples,
        user_metrics=spec.user_metrics,
    )
    fingerprint = study_fingerprint(spec, settings)
    header = {"kind": "design", "study": spec.name, "fingerprint": fingerprint, "rows": len(cands)}
    build = _Builder(spec.baseline, cands, settings.grid_step_m, spec.seed, settings.calibration)
    values = np.arange(len(cands), dtype=float)[:, None]
    outputs, errors = run_study(
        build,
        values,
        metrics,
        context,
        out_dir,
        header,
        seed=spec.seed,
        chunk_size=settings.chunk_size,
        workers=workers,
        scheduler=scheduler,
        force=force,
        progress=progress,
        label=f"design {spec.name}",
    )
    result = DesignResult(spec, settings, cands, outputs, errors, np.array([], dtype=int))
    result.front = pareto_front(result.objective_matrix())
    if "d-optimal" in settings.layouts:
        result.placement = placement_report(
            spec.baseline, settings.gauge_counts, step_m=settings.grid_step_m, seed=spec.seed
        )
    return result


def write_design_outputs(result: DesignResult, out_dir: str | Path, *, force: bool = False) -> dict[str, Path]:
    """``designs.parquet`` (one row per design: options, metrics, on the front), ``summary.json``, the Pareto
    figure; returns their paths."""
    import json

    import pyarrow as pa
    import pyarrow.parquet as pq

    out_dir = Path(out_dir)
    paths = {
        "designs": out_dir / "designs.parquet",
        "summary": out_dir / "summary.json",
        "pareto": out_dir / "figures" / "pareto.png",
    }
    for path in paths.values():
        path.parent.mkdir(parents=True, exist_ok=True)
        check_output(path, force=force)
    front = set(result.front.tolist())
    columns = {f.name: [getattr(c, f.name) for c in result.candidates] for f in dataclasses.fields(Candidate)}
    columns.update({m: result.outputs[m] for m in result.outputs})
    columns["on_front"] = [i in front for i in range(len(result.candidates))]
    columns["error"] = [e or "" for e in result.errors]
    with atomic_path(paths["designs"], force=force) as tmp:
        pq.write_table(pa.table(columns), tmp)
    with atomic_write(paths["summary"], "w", force=force) as fh:
        json.dump(to_jsonable(result.summary()), fh, indent=2)
    _save(design_pareto_figure(result), paths["pareto"], force)
    return paths


def export_design(result: DesignResult, row: int, path: str | Path, *, force: bool = False) -> Path:
    """Write the rig description of design ``row`` on the Pareto front, as a parameter TOML.

    The file is the TOML of ``flexdigit params --template`` (:func:`flexdigit.params.params_template`) for the
    design's row in ``designs.parquet`` and ``summary.json``, so that ``flexdigit params`` checks it and every
    command takes it as ``--params``. The twin calibration is not
    in it: the commands scale the thesis's to the digit (:func:`flexdigit.twin.digit_calibration.calibration_for`),
    as a study with ``[design] calibration = "scaled"`` scored it (on a thesis-rig baseline the same calibration);
    the default ``"baseline"`` scored it on the baseline's unscaled, so a command's twin of a resized design is not
    exactly the study's.
    Never overwrites ``path`` without ``force``."""
    front = sorted(int(i) for i in result.front)
    if isinstance(row, bool) or not isinstance(row, int | np.integer) or int(row) not in front:
        shown = ", ".join(str(i) for i in front[:20]) + (", ..." if len(front) > 20 else "")
        raise ParameterError(
            f"--export {row!r}: design {row!r} is not on the Pareto front of {result.spec.name}; its designs are rows "
            f"{shown} (as summary.json's pareto_front lists them)"
        )
    row = int(row)
    c = result.candidates[row]
    ps = design_parameter_set(
        result.spec.baseline,
        c,
        grid_step_m=result.settings.grid_step_m,
        seed=result.spec.seed,
        calibration=result.settings.calibration,
    )
    objectives = ", ".join(f"{m} {result.outputs[m][row]:.6g}" for m in result.settings.objectives)
    exported = _with_supports(_bends_both_ways(ps.description()))
    text = params_template(exported).replace(
        "# The values are the thesis rig's. Edit them for your digit, then check with: flexdigit params FILE\n",
        f"# Design {row} on the Pareto front of study {result.spec.name!r}: {c.label()}\n# ({objectives}); check "
        f"with: flexdigit params FILE\n# Its servo step, {c.servo_deg_per_command:.4g} deg a command, is the servo's "
        "travel over the commands (angle_min_deg..angle_max_deg), as the study scored it; a geared servo of the "
        "thesis's travel (gear_ratio) gives the pulley the same step\n" + _limits_comment(result, exported),
    )
    with atomic_write(path, "w", force=force) as fh:
        fh.write(text)
    return Path(path)


def _limits_comment(result: DesignResult, exported: RigParams) -> str:
    """The export's comment lines giving the Bayes limits of the file's own twin (the calibration the commands
    derive for it, :func:`~flexdigit.twin.digit_calibration.twin_calibration`) by prior, as ``flexdigit train
    --bayes-limit`` computes them (:func:`~flexdigit.studies.metrics.bayes_limits_by_prior`): the study's
    ``bayes_position_limit_mm`` is the settings prior's on the design's study calibration (``calibration =
    "baseline"`` by default: the baseline's unscaled), so it is not what ``train`` gives on the file's readings
    (trial 2: a front design's 0.131 mm here against 1.47 mm from ``train``, 0.79 mm its settings limit)."""
    ctx = MetricContext(seed=result.spec.seed, bayes_samples=result.settings.bayes_samples)
    limits = bayes_limits_by_prior(ParameterSet(exported, twin_calibration(exported)), ctx)
    shown = {k: "not resolved" if v is None else f"{v:.3g} mm" for k, v in limits.items()}
    return (
        f"# Bayes limits of this file's twin (calibration derived by the commands; the study scored it on its "
        f"'{result.settings.calibration}' one): {shown['settings']} with the load at one of table 6.1's positions "
        f"(bayes_position_limit_mm's prior; train --bayes-limit --split readings), {shown['span']} anywhere on "
        "their stretch (train --bayes-limit on held-out positions)\n"
    )


def _with_supports(params: RigParams) -> RigParams:
    """A resized design's supports written out (``support_lengths_m``), so that its file says the supports the
    study gave it rather than deriving them from ``digit_length_m`` with a note that they are not 10 mm."""
    g = params.geometry
    if g.support_lengths_m is not None or all(abs(s - THESIS_SUPPORT_M) <= LENGTH_TOLERANCE_M for s in g.supports_m):
        return params
    supports = tuple(round(s, 12) for s in g.supports_m)
    return params.replace(geometry=dataclasses.replace(g, support_lengths_m=supports))


def _bends_both_ways(params: RigParams) -> RigParams:
    """A design with the cable pair, straight mid-range and operating as far either side as the design's 30 deg
    (its ``operating_commands`` above straight), as a pair described without a straight command is
    (:func:`flexdigit.params.load_params`): exported straight at the single cable's 8, it could never bend back
    (``run --setpoint-deg -30`` refused it). A single cable's design is returned as it is."""
    a = params.actuator
    if params.cables.count != 2:
        return params
    span = a.operating_commands[1] - a.equilibrium_command
    middle = (a.command_min + a.command_max + 1) // 2
    low, high = max(a.command_min, middle - span), min(a.command_max, middle + span)
    return params.replace(actuator=dataclasses.replace(a, equilibrium_command=middle, operating_commands=(low, high)))


def design_pareto_figure(result: DesignResult):
    """The candidates in the first two objectives, the front, the thesis and equal-spacing designs marked."""
    o = result.settings.objectives
    x, y = result.outputs[o[0]], result.outputs[o[1]]
    front = pareto_front(np.column_stack([x, y]))
    marks = {k: (x[i], y[i]) for k, i in result.marked().items()}
    return pareto_figure(
        x,
        y,
        front,
        marks,
        f"{o[0]} ({METRICS[o[0]].unit})",
        f"{o[1]} ({METRICS[o[1]].unit})",
        f"{result.spec.name}: {len(result.candidates)} designs and their Pareto front",
    )


def showcase_design(samples: int = 24, *, seed: int = 0, bayes_samples: int = 100) -> DesignResult:
    """A small design study for the report (in this process): 3, 4 and 6 gauges (thesis and equal layouts), half
    and full bridges, the S-148's step and a 4:1 gearing, one cable or the antagonistic pair, three sizes; a seeded
    sample of ``samples`` designs (the thesis design always in) and the D-optimal placement check for 3 and 6
    gauges on a 5 mm grid. ``flexdigit study design thesis-design`` runs the full space on Dask."""
    import tempfile

    spec = spec_from_toml(f"[study]\nname = 'showcase-design'\nseed = {int(seed)}\n[design]\n", source="showcase")
    settings = DesignSettings(
        gauge_counts=(3, 4, 6),
        layouts=("thesis", "equal"),
        bridges=("half", "full"),
        adc_bits=(16,),
        servo_deg_per_command=(219.0 / 254.0, 219.0 / 1016.0),
        eccentricity_m=(5.715e-3,),
        pretension_n=(0.0, 5.0),
        size=(0.75, 1.0, 1.25),
        samples=samples,
        bayes_samples=bayes_samples,
        chunk_size=10**6,
    )
    with tempfile.TemporaryDirectory() as tmp:
        result = run_design(spec, tmp, settings=settings, workers=0, progress=False)
    result.placement = placement_report(spec.baseline, (3, 6), step_m=0.005, seed=seed)
    return result
