"""Sensing a tendon robot's shape in 3D: strain gauges on its backbone's faces, and the shape they imply.

A gauge sits on the backbone's surface at arc length ``s`` and at angle ``a`` around it (from the cross-section's
x axis, like a tendon's angle), bonded along the backbone. It reads the axial strain of that fibre, which for the
Cosserat rod (strains ``v``, ``u`` in the body frame; ``v = (0, 0, 1)`` at rest) at the surface point
``p = r (cos a, sin a, 0)`` is ``e3 . (v + u x p) - 1``:

    eps = (v3 - 1) + r (u1 sin a - u2 cos a)

so gauges on faces at two angles 90 degrees apart see the curvature in the two bending planes, and a third face
(or the opposite ones, as a bridge does) removes the extension ``v3 - 1`` from them. Axial gauges do not see
twist, which tendons routed straight do not cause but a tip force off the bending plane does (rao2021: up to 19 mm
of tip error from 50 mN without it); a gauge tilted by ``b`` from the axis reads
``eps_axial (cos^2 b - nu sin^2 b) + gamma sin b cos b`` with the surface shear ``gamma = r u3`` (+ the rod's
shear, ~1e-6), so a +-45 deg pair (a torsion rosette) sees the twist ``u3``.

The estimate (:func:`estimate_shape`): at each station the least-squares ``(u1, u2, u3, v3 - 1)`` of its
gauges (twist and extension taken as zero where the gauges cannot tell them apart), then per segment a polynomial
in ``s`` through its stations' values (degree ``min(stations - 1, 2)``: a segment's curvature is smooth between
tendon terminations but jumps at them, so nothing is fitted across a segment's end), and the backbone integrated
from the clamped base as an unshearable rod with those strains (exact rotation on each small step).

Examples
--------
>>> from flexdigit.tdcr import ROBOTS, solve_statics
>>> robot = ROBOTS["rao2021"]
>>> gauges = gauge_layout(robot, stations_per_segment=3)
>>> twin = solve_statics(robot, [2, 0, 1, 0, 1.5, 0], nodes_per_disk=4)
>>> shape = estimate_shape(robot, gauges, gauge_strains(twin, gauges))
>>> bool(np.linalg.norm(shape.tip_position_m - twin.tip_position_m) < 2e-3)
True
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from itertools import pairwise
from pathlib import Path

import numpy as np

from flexdigit._io import read_text
from flexdigit._repr import fields_summary
from flexdigit._validation import check_array, check_int, check_real
from flexdigit.errors import DataFileError, ParameterError
from flexdigit.tdcr.description import Robot
from flexdigit.tdcr.statics import StaticSolution, solve_statics

__all__ = [
    "GaugeLayout",
    "ShapeEstimate",
    "ShapeSensing",
    "gauge_layout",
    "gauge_strains",
    "estimate_shape",
    "read_readings",
    "sense_shape",
]


@dataclass(frozen=True)
class GaugeLayout:
    """Strain gauges on a backbone.

    Attributes
    ----------
    s_m : ndarray (g,)
        Arc length of each gauge from the base (m).
    angles_deg : ndarray (g,)
        Its face: angle around the backbone from the cross-section's x axis (deg).
    radius_m : float
        Distance of the gauges from the backbone's axis (its surface: the backbone's radius).
    tilts_deg : ndarray (g,), optional
        The gauge's grid direction from the backbone's axis towards the face's tangent ``(-sin a, cos a, 0)``
        (deg): 0 (default) reads the axial strain, +-45 (a torsion rosette) the twist as well.
    poisson_ratio : float
        The backbone's, for the hoop strain a tilted gauge sees (``-nu`` times the axial strain).
    """

    s_m: np.ndarray
    angles_deg: np.ndarray
    radius_m: float
    tilts_deg: np.ndarray | None = None
    poisson_ratio: float = 0.3

    def __post_init__(self) -> None:
        s = check_array(self.s_m, "s_m", "GaugeLayout", ndim=1)
        a = check_array(self.angles_deg, "angles_deg", "GaugeLayout", shape=s.shape)
        check_real(self.radius_m, "radius_m", "GaugeLayout", low=0.0, low_open=True)
        t = np.zeros_like(s) if self.tilts_deg is None else self.tilts_deg
        t = check_array(t, "tilts_deg", "GaugeLayout", shape=s.shape)
        check_real(self.poisson_ratio, "poisson_ratio", "GaugeLayout", low=-1.0, high=0.5)
        object.__setattr__(self, "s_m", s)
        object.__setattr__(self, "angles_deg", a)
        object.__setattr__(self, "tilts_deg", t)

    def _columns(self, at) -> np.ndarray:
        """Each gauge's reading per unit ``(u1, u2, u3, v3 - 1)`` (shear ``v1, v2`` neglected: ~1e-6)."""
        a, b, r, nu = np.radians(self.angles_deg[at]), np.radians(self.tilts_deg[at]), self.radius_m, self.poisson_ratio
        axial = np.cos(b) ** 2 - nu * np.sin(b) ** 2
        return np.column_stack([r * np.sin(a) * axial, -r * np.cos(a) * axial, r * np.sin(b) * np.cos(b), axial])

    @property
    def stations_m(self) -> np.ndarray:
        """The distinct arc lengths gauges sit at, increasing."""
        return np.unique(self.s_m)

    __repr__ = fields_summary


@dataclass(frozen=True)
class ShapeEstimate:
    """A backbone shape estimated from gauge readings.

    Attributes
    ----------
    s_m : ndarray (n,)
        Arc lengths the shape is given at (every ``step_m``, and the segments' ends).
    positions_m : ndarray (n, 3)
        Backbone positions, base frame.
    rotations : ndarray (n, 3, 3)
        Backbone frames (columns: the cross-section's axes).
    curvatures : ndarray (n, 2)
        The estimated bending curvatures ``u1, u2`` (1/m), body frame.
    """

    s_m: np.ndarray
    positions_m: np.ndarray
    rotations: np.ndarray
    curvatures: np.ndarray

    @property
    def tip_position_m(self) -> np.ndarray:
        return self.positions_m[-1]

    @property
    def tip_rotation(self) -> np.ndarray:
        return self.rotations[-1]

    def at_disks(self, robot: Robot) -> ShapeEstimate:
        """The estimate at the base and the robot's disks only (each disk is on a step's end of
        :func:`estimate_shape`): the nodes a :class:`~flexdigit.tdcr.StaticSolution` has at ``nodes_per_disk=1``,
        e.g. for :func:`~flexdigit.tdcr.write_recording`."""
        s_disks = np.concatenate([[0.0], robot.disk_positions_m])
        at = np.array([int(np.argmin(np.abs(self.s_m - s))) for s in s_disks])
        if np.abs(self.s_m[at] - s_disks).max() > 1e-9 * max(robot.length_m, 1.0):
            raise ParameterError(f"at_disks: this estimate was not integrated on {robot.name!r}'s disks")
        return ShapeEstimate(s_disks, self.positions_m[at], self.rotations[at], self.curvatures[at])

    def position_at(self, s_m) -> np.ndarray:
        """Positions at arc lengths ``s_m`` (linear between the estimate's points; ``(..., 3)``)."""
        s_m = np.asarray(s_m, dtype=float)
        return np.stack([np.interp(s_m, self.s_m, self.positions_m[:, k]) for k in range(3)], axis=-1)

    __repr__ = fields_summary


def _segment_ends(robot: Robot) -> np.ndarray:
    return np.concatenate([[0.0], np.cumsum([seg.length_m for seg in robot.segments])])


def gauge_layout(
    robot: Robot, stations_per_segment: int = 2, faces_deg=(0.0, 90.0, 180.0, 270.0), *, torsion: bool = True
) -> GaugeLayout:
    """Axial gauges on every face in ``faces_deg`` at ``stations_per_segment`` stations evenly inside each segment
    (at fractions ``(k + 1/2) / stations`` of its length), and with ``torsion`` a pair at +-45 deg on the first
    face (a torsion rosette: a tip force off the bending plane twists the rod, which axial gauges cannot see)."""
    n = check_int(stations_per_segment, "stations_per_segment", "gauge_layout", low=1)
    faces = check_array(faces_deg, "faces_deg", "gauge_layout", ndim=1)
    if faces.size < 2:
        raise ParameterError(f"gauge_layout: faces_deg needs two faces or more (two planes). Got {faces.tolist()}.")
    ends = _segment_ends(robot)
    stations = np.concatenate([a + (b - a) * (np.arange(n) + 0.5) / n for a, b in pairwise(ends)])
    angles = np.concatenate([faces, [faces[0], faces[0]]]) if torsion else faces
    tilts = np.concatenate([np.zeros(faces.size), [45.0, -45.0]]) if torsion else np.zeros(faces.size)
    b = robot.backbone
    return GaugeLayout(
        np.repeat(stations, angles.size),
        np.tile(angles, stations.size),
        b.radius_m,
        np.tile(tilts, stations.size),
        b.poisson_ratio,
    )


def gauge_strains(solution, layout: GaugeLayout, *, noise_std: float = 0.0, seed: int | None = None) -> np.ndarray:
    """The gauges' readings (axial strain, dimensionless) on a solved shape (the twin's), optionally with noise.

    The rod's strains between two nodes are interpolated linearly from the strains just after the first and just
    before the second (tendon terminations make them jump at nodes). ``noise_std``: white Gaussian noise added to
    every reading (strain), drawn from ``numpy.random.default_rng(seed)``.
    """
    noise_std = check_real(noise_std, "noise_std", "gauge_strains", low=0.0)
    s_nodes = np.asarray(solution.s_m, dtype=float)
    if layout.s_m.min() < s_nodes[0] or layout.s_m.max() > s_nodes[-1]:
        raise ParameterError(
            f"gauge_strains: gauges must sit on the backbone, 0 .. {s_nodes[-1]:g} m. "
            f"Got arc lengths {layout.s_m.min():g} .. {layout.s_m.max():g} m."
        )
    i = np.clip(np.searchsorted(s_nodes, layout.s_m, side="right") - 1, 0, len(s_nodes) - 2)
    w = ((layout.s_m - s_nodes[i]) / (s_nodes[i + 1] - s_nodes[i]))[:, None]
    strains = (1 - w) * solution.strains[i] + w * solution.strains_before_jump[i + 1]
    a, b, r = np.radians(layout.angles_deg), np.radians(layout.tilts_deg), layout.radius_m
    axial = (strains[:, 2] - 1.0) + r * (strains[:, 3] * np.sin(a) - strains[:, 4] * np.cos(a))
    shear = r * strains[:, 5] - strains[:, 0] * np.sin(a) + strains[:, 1] * np.cos(a)  # engineering, z-theta
    eps = axial * (np.cos(b) ** 2 - layout.poisson_ratio * np.sin(b) ** 2) + shear * np.sin(b) * np.cos(b)
    if noise_std > 0:
        eps = eps + np.random.default_rng(seed).normal(0.0, noise_std, eps.shape)
    return eps


def _station_curvatures(layout: GaugeLayout, strains: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each station's least-squares ``(u1, u2, u3, v3 - 1)`` from its gauges: twist and extension are taken as
    zero where the gauges cannot tell them from the bending (no tilted gauge; fewer than three axial faces)."""
    stations = layout.stations_m
    out = np.zeros((stations.size, 4))
    for k, s in enumerate(stations):
        at = layout.s_m == s
        design = layout._columns(at)
        keep = [0, 1]
        for extra in (2, 3):
            if np.linalg.matrix_rank(design[:, keep + [extra]]) == len(keep) + 1:
                keep.append(extra)
        if np.linalg.matrix_rank(design[:, :2]) < 2:
            raise ParameterError(
                f"estimate_shape: the gauges at s = {s:g} m (faces {layout.angles_deg[at].tolist()} deg) do not see "
                "both bending planes; put them on two faces that are not opposite."
            )
        out[k, keep] = np.linalg.lstsq(design[:, keep], strains[at], rcond=None)[0]
    return stations, out


def _rotation(axis_angle: np.ndarray) -> np.ndarray:
    """Rodrigues: the rotation by ``|w|`` about ``w``."""
    angle = float(np.linalg.norm(axis_angle))
    if angle < 1e-12:
        return np.eye(3)
    k = axis_angle / angle
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(angle) * kx + (1 - math.cos(angle)) * kx @ kx


def estimate_shape(robot: Robot, layout: GaugeLayout, strains, *, step_m: float = 1e-3) -> ShapeEstimate:
    """The backbone's shape from gauge readings (see the module docstring for the method).

    Parameters
    ----------
    robot : Robot
        Its segments (where the curvature may jump) and length.
    layout : GaugeLayout
        Where the gauges are; every segment needs a station.
    strains : array (g,)
        The readings, in the layout's order (:func:`gauge_strains` on the twin, or measured).
    step_m : float
        Integration step (m), at most: each segment is integrated in equal steps with every disk on a step's end;
        the error it adds is ``O(step^2)`` per length, ~1e-7 m at 1 mm on rao2021.
    """
    strains = check_array(strains, "strains", "estimate_shape", shape=layout.s_m.shape)
    step_m = check_real(step_m, "step_m", "estimate_shape", low=0.0, low_open=True)
    stations, curvature = _station_curvatures(layout, strains)
    ends = _segment_ends(robot)
    s_all, u_all, r_all, p_all = [0.0], [], [np.eye(3)], [np.zeros(3)]
    for j, (a, b) in enumerate(pairwise(ends)):
        inside = (stations >= a) & (stations <= b) if j == len(ends) - 2 else (stations >= a) & (stations < b)
        if not inside.any():
            raise ParameterError(
                f"estimate_shape: segment {j + 1} ({a:g} .. {b:g} m) has no gauges; every segment needs a station."
            )
        xs, us = stations[inside], curvature[inside]
        degree = min(xs.size - 1, 2)
        mid, half = 0.5 * (a + b), 0.5 * (b - a)  # fit in a scaled coordinate: well conditioned
        coeffs = [np.polyfit((xs - mid) / half, us[:, c], degree) for c in range(4)]
        per_disk = max(int(math.ceil((b - a) / robot.segments[j].disk_count / step_m)), 1)
        steps = per_disk * robot.segments[j].disk_count  # every disk on a step's end: its frame exact, not interpolated
        h = (b - a) / steps
        for k in range(steps):
            s_mid = a + (k + 0.5) * h  # midpoint curvature, exact rotation: second order
            x = (s_mid - mid) / half
            u = np.array([np.polyval(coeffs[c], x) for c in range(3)])
            stretch = 1.0 + np.polyval(coeffs[3], x)
            rot = r_all[-1]
            step_rot = _rotation(u * h)
            # the chord of a circular arc of curvature |u|: along the mid-step tangent, length h sinc(|u| h / 2)
            half_rot = _rotation(u * h / 2)
            chord = stretch * h * np.sinc(np.linalg.norm(u) * h / (2 * np.pi))
            p_all.append(p_all[-1] + chord * (rot @ half_rot[:, 2]))
            r_all.append(rot @ step_rot)
            s_all.append(a + (k + 1) * h)
            u_all.append(u[:2])
    u_all.insert(0, u_all[0])
    return ShapeEstimate(np.array(s_all), np.array(p_all), np.array(r_all), np.array(u_all))


#: Columns of a gauge readings file (:func:`read_readings`); ``tilt_deg`` may be left out (0: axial gauges).
READINGS_COLUMNS = ("s_m", "angle_deg", "strain", "tilt_deg")
#: The most gauges a readings file may list (a robot with a gauge every millimetre on four faces of 2.5 m).
MAX_GAUGES = 10_000


def read_readings(path, robot: Robot) -> tuple[GaugeLayout, np.ndarray]:
    """A gauge readings file: a CSV with a header ``s_m,angle_deg,strain[,tilt_deg]`` and one row per gauge
    (arc length from the base in m, face angle from the cross-section's x axis in deg, the reading as a strain,
    dimensionless, and the grid's tilt from the axis in deg). The gauges sit on the backbone's surface.

    Returns the layout and the readings; a bad file raises one line naming the file, the line and the value.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from flexdigit.tdcr import ROBOTS
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "gauges.csv"
    >>> _ = path.write_text("s_m,angle_deg,strain\\n0.1,0,0\\n0.1,90,0\\n0.3,0,0\\n0.3,90,0\\n")
    >>> layout, strains = read_readings(path, ROBOTS["rao2021"])
    >>> layout.s_m.tolist(), strains.tolist()
    ([0.1, 0.1, 0.3, 0.3], [0.0, 0.0, 0.0, 0.0])
    """
    path = Path(path)
    text = read_text(path, "a gauge readings CSV (s_m,angle_deg,strain[,tilt_deg])")
    rows = [(k, row) for k, row in enumerate(csv.reader(text.splitlines()), start=1) if any(c.strip() for c in row)]
    if not rows:
        raise DataFileError(f"{path}: empty; expected a header s_m,angle_deg,strain[,tilt_deg] and a row per gauge")
    header = [c.strip() for c in rows[0][1]]
    missing = [c for c in READINGS_COLUMNS[:3] if c not in header]
    unknown = [c for c in header if c not in READINGS_COLUMNS]
    if missing or unknown or len(set(header)) != len(header):
        raise DataFileError(
            f"{path}: line {rows[0][0]}: header {','.join(header)!r}; expected the columns s_m, angle_deg, strain "
            "and optionally tilt_deg, each once"
        )
    if not 1 <= len(rows) - 1 <= MAX_GAUGES:
        raise DataFileError(f"{path}: {len(rows) - 1} gauge rows; expected 1 to {MAX_GAUGES}")
    values = np.zeros((len(rows) - 1, len(READINGS_COLUMNS)))
    for i, (line, row) in enumerate(rows[1:]):
        if len(row) != len(header):
            raise DataFileError(f"{path}: line {line}: {len(row)} cells; expected {len(header)} ({','.join(header)})")
        for name, cell in zip(header, row, strict=True):
            try:
                value = float(cell)
            except ValueError:
                value = math.nan
            if not math.isfinite(value):
                raise DataFileError(f"{path}: line {line}: {name} {cell.strip()!r} is not a finite number")
            values[i, READINGS_COLUMNS.index(name)] = value
    try:
        layout = GaugeLayout(
            values[:, 0], values[:, 1], robot.backbone.radius_m, values[:, 3], robot.backbone.poisson_ratio
        )
    except ParameterError as exc:
        raise DataFileError(f"{path}: {exc}") from None
    length = robot.length_m
    outside = np.flatnonzero((layout.s_m < 0) | (layout.s_m > length))
    if outside.size:
        i = int(outside[0])
        raise DataFileError(
            f"{path}: line {rows[i + 1][0]}: s_m {layout.s_m[i]:g} is off the backbone of {robot.name!r}; "
            f"expected 0 .. {length:g} m"
        )
    strains = values[:, 2]
    if np.abs(strains).max() > 0.1:  # 10 %: beyond any metal backbone's (NiTi's superelastic plateau ~6-8 %)
        i = int(np.argmax(np.abs(strains)))
        raise DataFileError(
            f"{path}: line {rows[i + 1][0]}: strain {strains[i]:g} is not a strain gauge's reading; expected a "
            "dimensionless strain within +-0.1 (1e-6 is a microstrain)"
        )
    return layout, strains


@dataclass(frozen=True)
class ShapeSensing:
    """What :func:`sense_shape` found: the readings, the shape they imply and, where known, the twin's.

    Attributes
    ----------
    layout : GaugeLayout
    strains : ndarray (g,)
        The readings the estimate used (the twin's, with any noise, or given).
    estimate : ShapeEstimate
    twin : StaticSolution or None
        The twin's shape under the given loads (the truth the readings came from, or the model's prediction
        beside measured readings); None when no loads were given.
    """

    layout: GaugeLayout
    strains: np.ndarray
    estimate: ShapeEstimate
    twin: StaticSolution | None

    @property
    def tip_error_m(self) -> float | None:
        """Distance between the estimated and the twin's tip (m)."""
        if self.twin is None:
            return None
        return float(np.linalg.norm(self.estimate.tip_position_m - self.twin.tip_position_m))

    @property
    def max_error_m(self) -> float | None:
        """Largest distance between the estimated and the twin's backbone, at the twin's nodes (m)."""
        if self.twin is None:
            return None
        return float(np.linalg.norm(self.estimate.position_at(self.twin.s_m) - self.twin.positions_m, axis=1).max())

    @property
    def tip_angle_error_deg(self) -> float | None:
        """Angle of the rotation between the estimated and the twin's tip frames (deg)."""
        if self.twin is None:
            return None
        # ||R1 - R2||_F = 2 sqrt(2) sin(angle / 2): exact to round-off near 0, where arccos of the trace is not
        chord = np.linalg.norm(self.estimate.tip_rotation - self.twin.tip_rotation) / (2.0 * math.sqrt(2.0))
        return float(np.degrees(2.0 * np.arcsin(min(chord, 1.0))))

    def to_dict(self, robot: Robot) -> dict:
        """Plain values: the estimate's tip pose and backbone at the base and disks (the keys and nodes of
        :meth:`StaticSolution.to_dict <flexdigit.tdcr.StaticSolution.to_dict>`), the readings, and the twin's
        shape under ``twin`` with the errors (None without a twin)."""
        disks = self.estimate.at_disks(robot)
        out = {
            "gauges": int(self.layout.s_m.size),
            "strains": self.strains.tolist(),
            **_pose_dict(disks.s_m, disks.positions_m, disks.rotations),
            "rotations": disks.rotations.tolist(),
            "twin": None,
            "tip_error_m": self.tip_error_m,
            "max_error_m": self.max_error_m,
            "tip_angle_error_deg": self.tip_angle_error_deg,
        }
        if self.twin is not None:
            keep = np.searchsorted(self.twin.s_m, disks.s_m - 1e-12)
            twin = _pose_dict(disks.s_m, self.twin.positions_m[keep], self.twin.rotations[keep])
            out["twin"] = {"converged": self.twin.converged, **twin}
        return out

    __repr__ = fields_summary


def _pose_dict(s_m, positions, rotations) -> dict:
    frame = np.eye(4)
    frame[:3, :3], frame[:3, 3] = rotations[-1], positions[-1]
    return {
        "tip_position_m": positions[-1].tolist(),
        "tip_rotation": rotations[-1].tolist(),
        "tip_frame": frame.tolist(),
        "s_m": np.asarray(s_m).tolist(),
        "backbone_m": positions.tolist(),
    }


def sense_shape(
    robot: Robot,
    strains=None,
    *,
    layout: GaugeLayout | None = None,
    tensions_n=None,
    tip_force_n=None,
    tip_moment_nm=None,
    gravity_m_s2=None,
    noise_std: float = 0.0,
    seed: int | None = None,
    stations_per_segment: int = 3,
    step_m: float = 1e-3,
) -> ShapeSensing:
    """The robot's shape from its gauges: given ``strains``, or the twin's readings under ``tensions_n`` (and
    the other loads), with ``noise_std`` of seeded white noise, beside the twin's own shape.

    Parameters
    ----------
    robot : Robot
    strains : array (g,), optional
        Measured readings in ``layout``'s order (e.g. :func:`read_readings`). None: the twin's.
    layout : GaugeLayout, optional
        Default :func:`gauge_layout` with ``stations_per_segment`` stations, four faces and a torsion rosette.
    tensions_n, tip_force_n, tip_moment_nm, gravity_m_s2 : optional
        The loads (:func:`~flexdigit.tdcr.solve_statics`); ``tensions_n`` is required without ``strains``. With
        ``strains`` they give the twin's prediction to compare with.
    noise_std, seed : float, int
        White noise on the twin's readings (strain), from ``numpy.random.default_rng(seed)``.
    step_m : float
        The estimate's integration step (:func:`estimate_shape`).

    Examples
    --------
    >>> from flexdigit.tdcr import ROBOTS
    >>> found = sense_shape(ROBOTS["rao2021"], tensions_n=[4, 0, 0, 0, 2, 0])
    >>> bool(found.tip_error_m < 1e-6)   # tendons alone: constant curvature per segment, recovered exactly
    True
    """
    owner = "sense_shape"
    layout = gauge_layout(robot, stations_per_segment) if layout is None else layout
    if not isinstance(layout, GaugeLayout):
        raise ParameterError(f"The 'layout' parameter of {owner} must be a GaugeLayout. Got {type(layout).__name__}.")
    twin = None
    if tensions_n is not None:
        twin = solve_statics(
            robot,
            tensions_n,
            tip_force_n=tip_force_n,
            tip_moment_nm=tip_moment_nm,
            gravity_m_s2=gravity_m_s2,
            nodes_per_disk=4,  # the readings interpolate strains between nodes: 4 a disk is within 1e-5 m
        )
    elif strains is None:
        raise ParameterError(f"{owner}: give the gauges' readings (strains) or the loads (tensions_n) to read them")
    if strains is None:
        strains = gauge_strains(twin, layout, noise_std=noise_std, seed=seed)
    strains = check_array(strains, "strains", owner, shape=layout.s_m.shape)
    return ShapeSensing(layout, strains, estimate_shape(robot, layout, strains, step_m=step_m), twin)
