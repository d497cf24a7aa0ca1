"""A tendon-driven continuum robot's description: backbone, segments and disks, tendons; TOML load + validation.

The robot is a straight elastic backbone (a Cosserat rod) clamped at its base, its frame with z along the
backbone; segments follow one another along it, each carrying equally spaced disks (the first one disk pitch
above the segment's start, the last at its end). A tendon runs parallel to the backbone through every disk at a
fixed offset and angle (measured in the disk's x-y plane from x) and is fixed to the disk it terminates at.

Conventions are those of tdcr-modeling (Rao, Peyron, Lilge, Burgner-Kahrs 2021, ``c++/main.cpp`` and
``cosseratrodmodel.cpp``), taken as they are:

- shear modulus ``G = E / (2 (1 + nu))`` with ``nu = 0.3`` (their hard-coded ``2 * 1.3``);
- stiffnesses of a solid round backbone: ``Kse = diag(GA, GA, EA)``, ``Kbt = diag(EI, EI, 2GI)``;
- tendons routed straight (constant position in the disk frame, no helix), continuously in contact with the
  backbone (their Cosserat model, Rucker & Webster 2011): the disks only mark where tendons may end;
- tendon order: segment by segment from the base, within one the angles 90, -30, 210 deg from x.

Examples
--------
>>> robot = ROBOTS["rao2021"]
>>> robot.length_m, robot.disk_count, len(robot.tendons)
(0.4, 20, 6)
>>> [t.disk for t in robot.tendons]
[10, 10, 10, 20, 20, 20]
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from numbers import Integral, Real
from pathlib import Path
from typing import Any

import numpy as np

from flexdigit._io import read_text
from flexdigit._repr import summary
from flexdigit._validation import InstanceOf, Interval, check_int, declare, validate_fields
from flexdigit.errors import ParameterError

__all__ = [
    "builtin_robots",
    "Backbone",
    "Segment",
    "Tendon",
    "Robot",
    "ROBOTS",
    "load_robot",
    "robot_from_dict",
    "get_robot",
]

# Physical ranges, wide enough for any tendon robot yet narrow enough that the rod's stiffnesses (r^4, E r^4) and
# the disk positions stay finite: a value beyond them (1e308 m, 1e-300 Pa) is a typo, and the solver would
# otherwise answer with NaN or an overflow that names no key.
_MODULUS_PA = Interval(Real, 1e3, 1e13)  # soft silicone ~1 MPa .. diamond ~1.2 TPa, with a decade each side
_RADIUS_M = Interval(Real, 1e-6, 1.0)
_LENGTH_M = Interval(Real, 1e-6, 100.0)
_OFFSET_M = Interval(Real, 0, 10.0)
_DENSITY_KG_M3 = Interval(Real, 0, 1e5)  # osmium is 22.6e3 kg/m^3


@declare
@dataclass(frozen=True)
class Backbone:
    """The elastic backbone: a solid round rod.

    Attributes
    ----------
    youngs_modulus_pa : float
        E; tdcr-modeling's example: 54 GPa (superelastic NiTi).
    poisson_ratio : float
        nu; shear modulus ``G = E / (2 (1 + nu))``. tdcr-modeling hard-codes 0.3.
    radius_m : float
        Outer radius of the backbone: 0.7 mm.
    density_kg_m3 : float
        For gravity and dynamics (tdcr-modeling has neither): 6450 kg/m^3, NiTi's handbook value (an assumption).
    """

    youngs_modulus_pa: float = 54e9
    poisson_ratio: float = 0.3
    radius_m: float = 0.7e-3
    density_kg_m3: float = 6450.0

    _parameter_constraints = {
        "youngs_modulus_pa": [_MODULUS_PA],
        "poisson_ratio": [Interval(Real, -1, 0.5, closed="right")],
        "radius_m": [_RADIUS_M],
        "density_kg_m3": [_DENSITY_KG_M3],
    }

    def __post_init__(self) -> None:
        validate_fields(self)

    @property
    def shear_modulus_pa(self) -> float:
        """``G = E / (2 (1 + nu))``."""
        return self.youngs_modulus_pa / (2.0 * (1.0 + self.poisson_ratio))

    @property
    def area_m2(self) -> float:
        return math.pi * self.radius_m**2

    @property
    def second_moment_m4(self) -> float:
        """``I = pi r^4 / 4`` (the polar moment is ``2 I``)."""
        return 0.25 * math.pi * self.radius_m**4

    @property
    def shear_extension_stiffness(self) -> np.ndarray:
        """``Kse = diag(GA, GA, EA)`` (N)."""
        a = self.area_m2
        return np.array([self.shear_modulus_pa * a, self.shear_modulus_pa * a, self.youngs_modulus_pa * a])

    @property
    def bending_torsion_stiffness(self) -> np.ndarray:
        """``Kbt = diag(EI, EI, 2 G I)`` (N m^2)."""
        i = self.second_moment_m4
        return np.array([self.youngs_modulus_pa * i, self.youngs_modulus_pa * i, 2.0 * self.shear_modulus_pa * i])

    @property
    def mass_per_length_kg_m(self) -> float:
        return self.density_kg_m3 * self.area_m2


@declare
@dataclass(frozen=True)
class Segment:
    """A segment of the backbone: its length and its equally spaced disks (the last one at its end)."""

    length_m: float = 0.2
    disk_count: int = 10

    _parameter_constraints = {
        "length_m": [_LENGTH_M],
        "disk_count": [Interval(Integral, 1, 1000)],
    }

    def __post_init__(self) -> None:
        validate_fields(self)


@declare
@dataclass(frozen=True)
class Tendon:
    """A tendon: routed at ``offset_m`` from the backbone at ``angle_deg`` from the disk's x axis, fixed to ``disk``.

    ``disk`` counts the disks from the base over all segments, 1 being the first above the base.
    """

    offset_m: float = 0.01
    angle_deg: float = 90.0
    disk: int = 10

    _parameter_constraints = {
        "offset_m": [_OFFSET_M],
        "angle_deg": [Interval(Real, -360, 360)],
        "disk": [Interval(Integral, 1, None)],
    }

    def __post_init__(self) -> None:
        validate_fields(self)

    @property
    def routing_m(self) -> np.ndarray:
        """The tendon's position in the disk frame, ``(r cos a, r sin a, 0)``."""
        a = math.radians(self.angle_deg)
        return np.array([self.offset_m * math.cos(a), self.offset_m * math.sin(a), 0.0])


@declare
@dataclass(frozen=True)
class Robot:
    """A tendon-driven continuum robot: a backbone, its segments and its tendons (see the module docstring)."""

    name: str = "robot"
    backbone: Backbone = field(default_factory=Backbone)
    segments: tuple[Segment, ...] = (Segment(),)
    tendons: tuple[Tendon, ...] = ()

    _parameter_constraints = {
        "name": [InstanceOf(str, "a string")],
        "backbone": [InstanceOf(Backbone)],
        "segments": [InstanceOf(tuple, "a tuple of Segment")],
        "tendons": [InstanceOf(tuple, "a tuple of Tendon")],
    }

    def __post_init__(self) -> None:
        validate_fields(self)
        owner = type(self).__name__
        if not self.segments or not all(isinstance(s, Segment) for s in self.segments):
            raise ParameterError(
                f"The 'segments' parameter of {owner} must be a non-empty tuple of Segment. "
                f"Got {self.segments!r} instead."
            )
        if not all(isinstance(t, Tendon) for t in self.tendons):
            raise ParameterError(
                f"The 'tendons' parameter of {owner} must be a tuple of Tendon. Got {self.tendons!r} instead."
            )
        for i, tendon in enumerate(self.tendons):
            check_int(tendon.disk, f"tendons[{i}].disk", owner, low=1, high=self.disk_count)

    @property
    def length_m(self) -> float:
        return float(sum(s.length_m for s in self.segments))

    @property
    def disk_count(self) -> int:
        return int(sum(s.disk_count for s in self.segments))

    @property
    def disk_positions_m(self) -> np.ndarray:
        """Arc length of every disk from the base (m), in order."""
        out, start = [], 0.0
        for seg in self.segments:
            out.extend(start + seg.length_m * (k + 1) / seg.disk_count for k in range(seg.disk_count))
            start += seg.length_m
        return np.array(out)

    @property
    def tendon_ends_m(self) -> np.ndarray:
        """Arc length at which each tendon terminates (m)."""
        disks = self.disk_positions_m
        return np.array([disks[t.disk - 1] for t in self.tendons])

    @property
    def routing_m(self) -> np.ndarray:
        """``(n_tendons, 3)`` tendon positions in the disk frame."""
        return np.array([t.routing_m for t in self.tendons]).reshape(-1, 3)

    def to_dict(self) -> dict[str, Any]:
        b = self.backbone
        return {
            "name": self.name,
            "backbone": {
                "youngs_modulus_pa": b.youngs_modulus_pa,
                "poisson_ratio": b.poisson_ratio,
                "radius_m": b.radius_m,
                "density_kg_m3": b.density_kg_m3,
            },
            "segments": [{"length_m": s.length_m, "disk_count": s.disk_count} for s in self.segments],
            "tendons": [{"offset_m": t.offset_m, "angle_deg": t.angle_deg, "disk": t.disk} for t in self.tendons],
        }

    def __repr__(self) -> str:
        return summary(
            self,
            name=self.name,
            length_m=sum(s.length_m for s in self.segments),
            segments=len(self.segments),
            disks=sum(s.disk_count for s in self.segments),
            tendons=len(self.tendons),
            backbone_radius_m=self.backbone.radius_m,
            youngs_modulus_pa=self.backbone.youngs_modulus_pa,
        )


def _table(value: object, where: str, source: str) -> dict:
    if not isinstance(value, dict):
        raise ParameterError(f"{source}: {where} must be a table of keys. Got {value!r} instead.")
    return value


def _build(cls, values: dict, where: str, source: str):
    allowed = [f for f in cls.__dataclass_fields__ if not f.startswith("_")]
    bad = sorted(set(values) - set(allowed))
    if bad:
        raise ParameterError(f"{source}: unknown key {bad[0]!r} in {where}; expected one of " + ", ".join(allowed))
    try:
        return cls(**values)
    except (ParameterError, TypeError, ValueError) as exc:
        raise ParameterError(f"{source}: {where} {exc}") from None


def robot_from_dict(data: object, source: str = "robot") -> Robot:
    """Build a :class:`Robot` from a nested dict (as read from TOML); bad input raises naming ``source`` and key.

    Examples
    --------
    >>> robot_from_dict({"segments": [{"length_m": 0.1, "disk_count": 5}], "tendons": [{"disk": 6}]})
    ... # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    flexdigit.errors.ParameterError: robot: The 'tendons[0].disk' parameter of Robot must be an integer inside ...
    """
    data = _table(data, "the file", source)
    unknown = sorted(set(data) - {"name", "backbone", "segments", "tendons"})
    if unknown:
        raise ParameterError(
            f"{source}: unknown key {unknown[0]!r}; expected name, [backbone], [[segments]], [[tendons]]"
        )
    name = data.get("name", Path(source).stem if source != "robot" else "robot")
    backbone = _build(Backbone, _table(data.get("backbone", {}), "[backbone]", source), "[backbone]", source)
    lists = {}
    for key, cls in (("segments", Segment), ("tendons", Tendon)):
        items = data.get(key, [])
        if not isinstance(items, list) or (key == "segments" and not items):
            raise ParameterError(
                f"{source}: {key} must be a non-empty array of tables [[{key}]]. Got {items!r} instead."
                if key == "segments"
                else f"{source}: {key} must be an array of tables [[{key}]]. Got {items!r} instead."
            )
        lists[key] = tuple(
            _build(cls, _table(item, f"[[{key}]] {i + 1}", source), f"[[{key}]] {i + 1}", source)
            for i, item in enumerate(items)
        )
    try:
        return Robot(name=name, backbone=backbone, **lists)
    except ParameterError as exc:
        raise ParameterError(f"{source}: {exc}") from None


def load_robot(path: str | Path) -> Robot:
    """Read a robot description TOML (see ``ROBOTS`` for the keys); bad input raises one line naming file and key.

    Raises
    ------
    ParameterError
        Naming the file, the key, the bad value and what was expected.
    FileNotFoundError
        If the file does not exist.
    """
    path = Path(path)
    text = read_text(path, "a robot description TOML")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError(f"{path}: not valid TOML ({exc})") from None
    return robot_from_dict(data, source=str(path))


def _rao2021() -> Robot:
    """tdcr-modeling's example robot (``c++/main.cpp``): two 200 mm segments, 3 tendons each, 10 mm off axis."""
    tendons = tuple(
        Tendon(offset_m=0.01, angle_deg=angle, disk=disk) for disk in (10, 20) for angle in (90.0, -30.0, 210.0)
    )
    return Robot(
        name="rao2021",
        backbone=Backbone(youngs_modulus_pa=54e9, poisson_ratio=0.3, radius_m=0.7e-3),
        segments=(Segment(0.2, 10), Segment(0.2, 10)),
        tendons=tendons,
    )


#: Built-in robots by name.
ROBOTS: dict[str, Robot] = {"rao2021": _rao2021()}


def builtin_robots() -> dict[str, str]:
    """The built-in robots (:data:`ROBOTS`), each with one line: segments, tendons, backbone."""
    out = {}
    for name, robot in ROBOTS.items():
        lengths = " + ".join(f"{1e3 * s.length_m:g}" for s in robot.segments)
        b = robot.backbone
        out[name] = (
            f"{len(robot.segments)} segments ({lengths} mm), {len(robot.tendons)} tendons, backbone radius "
            f"{1e3 * b.radius_m:g} mm, E {b.youngs_modulus_pa / 1e9:g} GPa"
        )
    return out


def get_robot(name_or_path: str | Path | Robot) -> Robot:
    """A built-in robot by name (``ROBOTS``), a robot TOML file, or a :class:`Robot` as it is."""
    if isinstance(name_or_path, Robot):
        return name_or_path
    if str(name_or_path) in ROBOTS:
        return ROBOTS[str(name_or_path)]
    path = Path(name_or_path)
    if path.suffix.lower() != ".toml" and not path.exists():
        raise ParameterError(
            f"unknown robot {str(name_or_path)!r}: give a built-in ({', '.join(ROBOTS)}) or a robot TOML file"
        )
    return load_robot(path)
