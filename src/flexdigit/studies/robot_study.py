"""Sensitivity of a tendon robot (issue 26): a study spec whose baseline is a robot, run by the studies machinery.

A robot study spec is a study spec (:mod:`flexdigit.studies.spec`: the same ``[study]``, ``[sensitivity]`` and
distribution tables) whose ``[study]`` names a robot (a built-in, or a robot TOML beside the spec) and the
tensions it holds, and whose uncertain parameters are the robot's::

    [study]
    name = "rao2021-tolerances"
    robot = "rao2021"
    tensions_n = [4, 0, 0, 0, 2, 0]
    metrics = ["tip_angle_deg", "first_frequency_hz"]

    [parameters.backbone.youngs_modulus_pa]     # a scalar field of [backbone]
    distribution = "uniform"
    relative = 0.05

    [parameters.tendons.offset_m]               # a factor on every tendon's offset
    distribution = "uniform"
    relative = 0.02

    [parameters.loads.tensions_n.0]             # one element: the first tendon's tension
    distribution = "normal"
    sd = 0.05

Sections and fields: ``backbone`` (youngs_modulus_pa, poisson_ratio, radius_m, density_kg_m3), ``segments``
(length_m), ``tendons`` (offset_m, angle_deg) and ``loads`` (tensions_n): the last three are lists, moved by one
factor or element by element (``.K``, 0-based), as a rig spec's tuple fields are. Every range is checked when the
spec is read by building the robot at its two ends (a radius of 0, a negative tension: one line naming the key).

The metrics (:data:`ROBOT_METRICS`), each of one evaluated robot (:class:`RobotCase`):

- ``tip_x_m``, ``tip_y_m``, ``tip_z_m``, ``tip_lateral_m``: the tip under the tensions (shot statics);
- ``tip_angle_deg``: the tip tangent's angle from the base's z axis (a pure tendon moment: ``T d L / EI`` rad);
- ``first_frequency_hz``: the first mode under the tensions, from a release test
  (:func:`flexdigit.tdcr.release_test`: the discrete rod, one element a disk).

They travel to the workers as the studies' user metrics (``module:function``), so :func:`run_robot_sensitivity`
is :func:`flexdigit.studies.sensitivity.run_sensitivity` as it is: Morris, Sobol (SALib) with intervals, the
N / 2N convergence check, the journal (resumable), Dask, and the same output files and figures.

Examples
--------
>>> spec = robot_spec_from_toml('''
... [study]
... robot = "rao2021"
... tensions_n = [1, 0, 0, 0, 0, 0]
... [parameters.backbone.youngs_modulus_pa]
... distribution = "uniform"
... relative = 0.1
... ''')
>>> spec.names, round(spec.parameter_set([60e9]).robot.backbone.youngs_modulus_pa / 1e9)
(['backbone.youngs_modulus_pa'], 60)
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import tomllib
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np

from flexdigit._io import read_text
from flexdigit._repr import summary
from flexdigit.errors import ParameterError
from flexdigit.studies.metrics import UserMetric
from flexdigit.studies.sensitivity import SensitivitySettings, run_sensitivity
from flexdigit.studies.spec import UncertainParameter, _table, _where, read_parameters
from flexdigit.tdcr.description import Robot, get_robot
from flexdigit.tdcr.experiments import release_test
from flexdigit.tdcr.statics import StaticSolution, solve_statics

__all__ = [
    "ROBOT_METRICS",
    "RobotCase",
    "RobotStudySpec",
    "is_robot_spec",
    "load_robot_spec",
    "robot_spec_from_toml",
    "run_robot_sensitivity",
    "SHIPPED_ROBOT_SPECS",
    "shipped_robot_specs",
]

#: Uncertain fields of a robot: section -> fields (the list-valued ones take a factor or elements).
ROBOT_FIELDS = {
    "backbone": ("youngs_modulus_pa", "poisson_ratio", "radius_m", "density_kg_m3"),
    "segments": ("length_m",),
    "tendons": ("offset_m", "angle_deg"),
    "loads": ("tensions_n",),
}


@dataclass(frozen=True)
class RobotCase:
    """One robot to evaluate: its description and the tendon tensions it holds (N)."""

    robot: Robot
    tensions_n: tuple[float, ...]


@lru_cache(maxsize=64)
def _statics(case: RobotCase) -> StaticSolution:
    """The case's statics, solved once for all its tip metrics."""
    sol = solve_statics(case.robot, case.tensions_n)
    if not sol.converged:
        raise ParameterError(f"statics of {case.robot.name!r} did not converge (residual {sol.residual:.3g})")
    return sol


def tip_x_m(case: RobotCase) -> float:
    return float(_statics(case).tip_position_m[0])


def tip_y_m(case: RobotCase) -> float:
    return float(_statics(case).tip_position_m[1])


def tip_z_m(case: RobotCase) -> float:
    return float(_statics(case).tip_position_m[2])


def tip_lateral_m(case: RobotCase) -> float:
    return float(np.hypot(*_statics(case).tip_position_m[:2]))


def tip_angle_deg(case: RobotCase) -> float:
    """The tip tangent's angle from the base's z axis (deg), by its cross product with z (exact near 0)."""
    tangent = _statics(case).tip_rotation[:, 2]
    return float(np.degrees(math.atan2(math.hypot(tangent[0], tangent[1]), tangent[2])))


def first_frequency_hz(case: RobotCase) -> float:
    test = release_test(case.robot, case.tensions_n)
    if not math.isfinite(test.first_frequency_hz):
        raise ParameterError(f"the release of {case.robot.name!r} did not converge: no first frequency")
    return test.first_frequency_hz


#: The robot metrics: name -> (unit, description).
ROBOT_METRICS: dict[str, tuple[str, str]] = {
    "tip_x_m": ("m", "tip x under the tensions (shot statics)"),
    "tip_y_m": ("m", "tip y under the tensions (shot statics)"),
    "tip_z_m": ("m", "tip z under the tensions (shot statics)"),
    "tip_lateral_m": ("m", "tip distance from the base's z axis under the tensions"),
    "tip_angle_deg": ("deg", "tip tangent's angle from the base's z axis under the tensions"),
    "first_frequency_hz": ("Hz", "first mode under the tensions, from a release test (discrete rod)"),
}
#: What a spec without ``[study] metrics`` computes.
DEFAULT_METRICS = ("tip_lateral_m", "tip_angle_deg", "first_frequency_hz")


def _user_metric(name: str, source: str) -> UserMetric:
    unit, text = ROBOT_METRICS[name]
    return UserMetric(name, f"{__name__}:{name}", unit, text, f"{source}: [study] metrics")


@dataclass(frozen=True)
class RobotStudySpec:
    """A parsed robot study spec; it reads like :class:`~flexdigit.studies.spec.StudySpec` to the studies
    machinery (``names``, ``parameter_set``, ``values_from_unit``, ``fingerprint``, ``study_metrics``)."""

    name: str
    seed: int
    parameters: tuple[UncertainParameter, ...]
    metrics: tuple[str, ...]
    settings: dict
    baseline: RobotCase
    source: str = "spec"
    user_metrics: tuple = field(default=())

    @property
    def names(self) -> list[str]:
        return [p.name for p in self.parameters]

    def __repr__(self) -> str:
        # the study at a glance (issue 23: the generated repr printed every parameter's source, 5,700 characters)
        return summary(
            self,
            name=self.name,
            seed=self.seed,
            parameters=self.names,
            metrics=self.metrics,
            settings=list(self.settings),
            source=self.source,
        )

    def study_metrics(self, default=()) -> tuple[str, ...]:
        return tuple(self.metrics)

    def fingerprint(self) -> str:
        doc = {
            "name": self.name,
            "seed": self.seed,
            "metrics": list(self.metrics),
            "settings": self.settings,
            "parameters": [dataclasses.asdict(p) for p in self.parameters],
            "robot": self.baseline.robot.to_dict(),
            "tensions_n": list(self.baseline.tensions_n),
        }
        return hashlib.sha256(json.dumps(doc, sort_keys=True, default=repr).encode()).hexdigest()[:16]

    def values_from_unit(self, u) -> np.ndarray:
        u = np.atleast_2d(np.asarray(u, dtype=float))
        return np.column_stack([p.ppf(u[:, j]) for j, p in enumerate(self.parameters)])

    def parameter_set(self, values, label: str = "sample") -> RobotCase:
        """The baseline robot with the uncertain fields set to ``values`` (a mapping name -> value, or a row)."""
        if not isinstance(values, dict):
            values = dict(zip(self.names, np.asarray(values, dtype=float).reshape(-1), strict=True))
        return _apply(self.baseline, self.parameters, values, label)


def _nominal(case: RobotCase) -> dict[str, dict]:
    robot = case.robot
    b = robot.backbone
    return {
        "backbone": {f: float(getattr(b, f)) for f in ROBOT_FIELDS["backbone"]},
        "segments": {"length_m": [float(s.length_m) for s in robot.segments]},
        "tendons": {f: [float(getattr(t, f)) for t in robot.tendons] for f in ROBOT_FIELDS["tendons"]},
        "loads": {"tensions_n": [float(v) for v in case.tensions_n]},
    }


def _apply(baseline: RobotCase, parameters, values: dict, label: str) -> RobotCase:
    current = _nominal(baseline)
    for p in parameters:
        value = float(values[p.name])
        old = current[p.section][p.field]
        if p.is_factor:
            current[p.section][p.field] = [v * value for v in old]
        elif p.element is not None:
            old[p.element] = value
        else:
            current[p.section][p.field] = value
    robot = baseline.robot
    try:
        backbone = dataclasses.replace(robot.backbone, **current["backbone"])
        segments = tuple(
            dataclasses.replace(s, length_m=v)
            for s, v in zip(robot.segments, current["segments"]["length_m"], strict=True)
        )
        tendons = tuple(
            dataclasses.replace(t, offset_m=o, angle_deg=a)
            for t, o, a in zip(robot.tendons, *(current["tendons"][f] for f in ROBOT_FIELDS["tendons"]), strict=True)
        )
        changed = dataclasses.replace(robot, backbone=backbone, segments=segments, tendons=tendons)
    except (ParameterError, TypeError) as exc:
        raise ParameterError(f"{label}: {exc}") from None
    tensions = tuple(current["loads"]["tensions_n"])
    if any(not (math.isfinite(t) and t >= 0) for t in tensions):
        raise ParameterError(f"{label}: tendon tensions must be finite and >= 0 N. Got {list(tensions)} instead.")
    return RobotCase(changed, tensions)


#: Robot study specs shipped with flexdigit (``flexdigit study sensitivity rao2021-tolerances --out DIR``).
SHIPPED_ROBOT_SPECS = ("rao2021-tolerances",)


def shipped_robot_specs() -> dict[str, str]:
    """The shipped robot study specs (:data:`SHIPPED_ROBOT_SPECS`), each with its one-line description."""
    from importlib import resources

    out = {}
    for name in SHIPPED_ROBOT_SPECS:
        text = resources.files("flexdigit.studies").joinpath("specs").joinpath(f"{name}.toml").read_text()
        out[name] = "sensitivity study: " + tomllib.loads(text)["study"].get("description", "")
    return out


def is_robot_spec(name_or_path) -> bool:
    """Whether a study spec file names a robot (``[study] robot``), or is a shipped robot spec's name; False for
    anything else (its own reader says what is wrong with it)."""
    path = Path(name_or_path)
    if not path.exists() and str(name_or_path) in SHIPPED_ROBOT_SPECS:
        return True
    try:
        return path.is_file() and "robot" in tomllib.loads(path.read_text()).get("study", {})
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError, AttributeError, RecursionError):
        return False


def load_robot_spec(path) -> RobotStudySpec:
    """Read a robot study spec file (see the module docstring); errors name the file and the key."""
    path = Path(path)
    if not path.exists() and str(path) in SHIPPED_ROBOT_SPECS:
        from importlib import resources

        ref = resources.files("flexdigit.studies").joinpath("specs").joinpath(f"{path}.toml")
        return robot_spec_from_toml(ref.read_text(), f"{path}.toml")
    if path.is_dir():
        raise IsADirectoryError(f"{path}: is a directory, not a study spec")
    return robot_spec_from_toml(read_text(path, "a robot study spec TOML"), str(path), path.parent)


def _robot(study: dict, source: str, base_dir: Path | None) -> Robot:
    value = study.get("robot")
    if not isinstance(value, str) or not value:
        raise ParameterError(f"{source}: [study] robot must be a built-in robot's name or a robot TOML file")
    path = Path(value)
    if base_dir is not None and path.suffix.lower() == ".toml" and not path.is_absolute():
        path = base_dir / path
    try:
        return get_robot(str(path) if path.suffix.lower() == ".toml" else value)
    except (ValueError, OSError) as exc:  # ParameterError, DataFileError, no such file, a NUL in the name
        raise ParameterError(f"{source}: [study] robot: {exc}".splitlines()[0]) from None


def robot_spec_from_toml(text: str, source: str = "spec", base_dir: Path | None = None) -> RobotStudySpec:
    """Parse a robot study spec from TOML text (see the module docstring)."""
    try:
        doc = tomllib.loads(text)
    except (tomllib.TOMLDecodeError, RecursionError) as exc:
        raise ParameterError(f"{source}: not valid TOML ({exc})") from None
    unknown = sorted(set(doc) - {"study", "parameters", "sensitivity"})
    if unknown:
        raise ParameterError(f"{source}: unknown table {unknown[0]!r}; expected [study], [parameters], [sensitivity]")
    study = _table(doc.get("study", {}), "[study]", source)
    keys = ("name", "seed", "metrics", "robot", "tensions_n", "description")
    bad = sorted(set(study) - set(keys))
    if bad:
        raise ParameterError(f"{source}: unknown key {bad[0]!r} in [study]; expected " + ", ".join(keys))
    robot = _robot(study, source, base_dir)
    name = study.get("name", Path(source).stem)
    if not isinstance(name, str) or not name:
        raise ParameterError(f"{source}: [study] name must be a non-empty string. Got {name!r} instead.")
    seed = study.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ParameterError(f"{source}: [study] seed must be an integer >= 0. Got {seed!r} instead.")
    tensions = study.get("tensions_n", [0.0] * len(robot.tendons))
    if (
        not isinstance(tensions, list)
        or len(tensions) != len(robot.tendons)
        or not all(isinstance(t, (int, float)) and not isinstance(t, bool) and 0 <= t < math.inf for t in tensions)
    ):
        raise ParameterError(
            f"{source}: [study] tensions_n must list one tension >= 0 N per tendon of {robot.name!r} "
            f"({len(robot.tendons)}). Got {tensions!r} instead."
        )
    metrics = study.get("metrics", list(DEFAULT_METRICS))
    if (
        not isinstance(metrics, list)
        or not metrics
        or not all(isinstance(m, str) for m in metrics)
        or len(set(metrics)) != len(metrics)
    ):
        raise ParameterError(f"{source}: [study] metrics must be a list of distinct metric names. Got {metrics!r}")
    for m in metrics:
        if m not in ROBOT_METRICS:
            raise ParameterError(
                f"{source}: [study] metrics: unknown robot metric {m!r}; expected one of " + ", ".join(ROBOT_METRICS)
            )
    baseline = RobotCase(robot, tuple(float(t) for t in tensions))
    parameters = _parameters(doc.get("parameters", {}), baseline, source)
    settings = {"sensitivity": _table(doc["sensitivity"], "[sensitivity]", source)} if "sensitivity" in doc else {}
    user = tuple(_user_metric(m, source) for m in metrics)
    return RobotStudySpec(name, seed, tuple(parameters), tuple(metrics), settings, baseline, source, user)


def _parameters(table, baseline: RobotCase, source: str) -> list[UncertainParameter]:
    """A robot spec's uncertain parameters (:func:`~flexdigit.studies.spec.read_parameters` on the robot's
    sections), each range checked by building the robot at its ends."""
    nominal = _nominal(baseline)
    parameters = read_parameters(
        table,
        tuple(ROBOT_FIELDS),
        lambda section: {name: nominal[section][name] for name in ROBOT_FIELDS[section]},
        lambda p, end: _apply(
            baseline, [p], {p.name: end}, f"{source}: {_where(p)} at {end:.6g} (the end of its range)"
        ),
        source,
    )
    if not parameters:
        raise ParameterError(f"{source}: no [parameters.SECTION.FIELD] tables: nothing is uncertain")
    return parameters


def run_robot_sensitivity(
    spec: RobotStudySpec | str | Path,
    out_dir,
    *,
    settings: SensitivitySettings | None = None,
    workers: int | None = None,
    scheduler: str | None = None,
    force: bool = False,
    progress: bool = True,
):
    """Morris and Sobol indices of a robot study (:func:`~flexdigit.studies.sensitivity.run_sensitivity` on it).

    Returns the :class:`~flexdigit.studies.sensitivity.SensitivityResult`;
    :func:`~flexdigit.studies.sensitivity.write_outputs` writes its files.
    """
    if not isinstance(spec, RobotStudySpec):
        spec = load_robot_spec(spec)
    return run_sensitivity(
        spec,
        out_dir,
        settings=settings or SensitivitySettings.from_spec(spec),
        workers=workers,
        scheduler=scheduler,
        force=force,
        progress=progress,
        rerun="rerun with a larger --n (a power of 2)",
    )
