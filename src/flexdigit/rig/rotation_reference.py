"""Measured tip rotations for the rotation map: a protractor, a ruler (thesis table 3.6) or a camera.

The gauge -> rotation map (:mod:`flexdigit.rig.rotation`) is only as good as the rotations it is fitted to. On the
twin those are the twin's own; on a rig they are measured, and this module turns what a user measured into
rotations with an uncertainty:

- a tip rotation per command (protractor, camera), read with a stated resolution;
- deflections at known points along the digit per command (a ruler, as table 3.6 reads them at the gauges, 45,
  135 and 225 mm from the base, to 0.5 mm), turned into the tip rotation by :func:`rotation_from_deflections`.

The file is a small CSV (``,``, ``;`` or tab; ``#`` starts a comment line), one row per command::

    command,deflection_mm_at_45mm,deflection_mm_at_135mm,deflection_mm_at_225mm
    8,0,0,0
    12,0.5,6,14
    ...

or ``command,rotation_deg``; optional ``gauge1_v,gauge2_v,gauge3_v`` columns hold gauge readings taken at the same
time (then no sweep is needed to fit the map). Deflections are sideways, towards the cable (the way the digit
bends), in mm, at arc positions in mm from the base; rotations in degrees, positive the same way.

Why a shape model: the cable pulls with one moment ``T e`` along the whole digit (3.3), so each section's strip
bends at a constant curvature ``M / EI_k`` (its own housing stiffness), and the rigid nylon supports do not bend.
Given the deflections, :func:`rotation_from_deflections` fits one curvature per section (exact large-rotation
kinematics of arcs and straight supports, ``scipy.optimize.least_squares``) and sums them into the tip rotation;
with fewer measured points than sections it fits one scale on the sections' stiffness ratios instead. The
uncertainty follows from the reading resolution through the fit's Jacobian.
"""

from __future__ import annotations

import csv
import io
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flexdigit._io import RECORDS_LIMIT, count_lines, read_text
from flexdigit._repr import fields_summary
from flexdigit._validation import Plausible, check_array, check_param, check_real
from flexdigit.errors import DataFileError
from flexdigit.params import RigParams
from flexdigit.twin.calibration import default_calibration

__all__ = [
    "DigitShape",
    "MeasuredReference",
    "read_reference",
    "rotations_from_deflections",
    "DEFLECTION_RESOLUTION_MM",
    "ROTATION_RESOLUTION_DEG",
]

#: Table 3.6's ruler: deflections read to 0.5 mm.
DEFLECTION_RESOLUTION_MM = 0.5
#: The plausible reading resolution of a measured deflection: a micrometer's 1 um to a coarse ruler's 2 cm.
READING_RESOLUTION_MM = Plausible("mm", 1e-3, 20.0, "a reading resolution of 1 um (a micrometer) to 2 cm")
#: The sections' shares of the rotation are fitted around their compliances' (``1 / EI_k``) with this standard
#: deviation in log ratio (~30 %): readings that stop short of the tip leave the last section nearly unseen, and
#: the prior keeps the fit from trading its share against the rotation (a 0.5 mm rounding at 45/135/225 mm moved
#: an unconstrained fit by 19 %). A reading at the tip makes the prior irrelevant.
SHARE_PRIOR_SD = 0.3
#: A protractor read to 1 degree.
ROTATION_RESOLUTION_DEG = 1.0
#: The plausible reading resolution of a measured rotation: 0.001 deg (an encoder) to 10 deg.
READING_RESOLUTION_DEG = Plausible("deg", 1e-3, 10.0, "a reading resolution of 0.001 deg (an encoder) to 10 deg")
_DEFLECTION_COLUMN = re.compile(r"^deflection_mm_at_([0-9]+(?:\.[0-9]+)?)mm$")
_GAUGE_COLUMNS = ("gauge1_v", "gauge2_v", "gauge3_v")


@dataclass(frozen=True)
class DigitShape:
    """The digit's bending layout: flexible strip stretches (constant curvature each) between rigid supports.

    Built from :class:`~flexdigit.params.RigParams` (:meth:`from_params`): section ``k`` bends on
    ``[k p + h, (k+1) p - h]`` (pitch ``p`` = 90 mm, half a support ``h`` = 5 mm), the rest is rigid, as the twin's
    chain is built (:func:`flexdigit.twin.digit.build_digit`).
    """

    length_m: float
    flex_start_m: tuple[float, ...]
    flex_end_m: tuple[float, ...]

    @classmethod
    def from_params(cls, params: RigParams | None = None) -> DigitShape:
        geo = (params or RigParams()).geometry
        starts = tuple(a for a, _ in geo.section_bounds_m)  # unequal sections too
        # start + length, as ever (not the bound's end, which rounds apart by an ulp on some equal digits)
        return cls(geo.digit_length_m, starts, tuple(a + x for a, x in zip(starts, geo.section_lengths_m, strict=True)))

    @property
    def flex_length_m(self) -> np.ndarray:
        return np.asarray(self.flex_end_m) - np.asarray(self.flex_start_m)

    def deflection_m(self, curvature_1_m, s_m) -> np.ndarray:
        """Sideways deflection (m, towards the cable) at arc positions ``s_m`` for per-section curvatures (1/m).

        Exact for arcs and straight stretches at any rotation: over a stretch of length ``L`` and curvature ``k``
        starting at angle ``phi``, the sideways move is ``L sin(phi + k L / 2) sinc(k L / 2)``.
        """
        kappa = np.asarray(curvature_1_m, dtype=float)
        s = np.atleast_1d(np.asarray(s_m, dtype=float))
        # breakpoints: rigid and flexible stretches in order, each with its curvature
        edges, curv = [0.0], []
        for a, b, k in zip(self.flex_start_m, self.flex_end_m, kappa, strict=True):
            edges += [a, b]
            curv += [0.0, k]
        edges.append(self.length_m)
        curv.append(0.0)
        edges = np.asarray(edges)
        curv = np.asarray(curv)
        out = np.empty(s.size)
        for i, target in enumerate(s):
            phi, y = 0.0, 0.0
            for j, k in enumerate(curv):
                a, b = edges[j], edges[j + 1]
                if target <= a:
                    break
                length = min(target, b) - a
                half = 0.5 * k * length
                y += length * math.sin(phi + half) * np.sinc(half / math.pi)
                phi += k * length
            out[i] = y
        return out

    def tip_rotation_rad(self, curvature_1_m) -> float:
        return float(np.asarray(curvature_1_m, dtype=float) @ self.flex_length_m)


def rotations_from_deflections(
    positions_m,
    deflections_m,
    *,
    sd_m: float = DEFLECTION_RESOLUTION_MM / 1000 / math.sqrt(12),
    params: RigParams | None = None,
    stiffness=None,
) -> tuple[np.ndarray, np.ndarray, float, np.ndarray]:
    """Tip rotations (deg) of a sweep from sideways deflections at known points, jointly, with their covariance.

    The cable's moment is the same along the digit, so every command bends the sections in the same proportions
    (``kappa_k = M / EI_k``): the fit has one tip rotation per command and one set of section shares for the
    whole sweep (``n_sections - 1`` numbers). Fitting each command alone would leave the last section's curvature
    to a few millimetres of arc past the last reading (three readings, three curvatures: a 0.5 mm rounding moves the
    tip rotation by degrees); shared shares make 3 readings x N commands determine N + 2 numbers. With fewer
    readings per command than sections, the shares are fixed at the sections' compliances ``1 / EI_k``
    (``stiffness``; equal if None) and only the rotations are fitted.

    Parameters
    ----------
    positions_m : array_like, shape (P,)
        Arc positions of the readings from the base (m).
    deflections_m : array_like, shape (N, P)
        Deflections (m, towards the cable) per command and point.
    sd_m : float
        Standard uncertainty of one reading (m): 0.5 mm / sqrt(12) (a 0.5 mm ruler's rounding) by default.
    params : RigParams, optional
        The digit's layout.
    stiffness : array_like, shape (n_sections,), optional
        Section bending stiffnesses (N m^2) for the fixed shares.

    Returns
    -------
    rotation_deg : ndarray (N,)
    cov_deg2 : ndarray (N, N)
        Their covariance (deg^2): the shared shares make the errors correlated.
    rms_residual_m : float
        The fit's residual: well above ``sd_m`` means the readings do not look like a digit bent by its cable.
    shares : ndarray (n_sections,)
        The fraction of the tip rotation each section carries.

    Examples
    --------
    A digit whose sections carry 25, 35 and 40 % of the rotation, read to 0.5 mm at the gauges and the tip:

    >>> shape = DigitShape.from_params()
    >>> true = np.radians([5.0, 10, 20, 30, 40])
    >>> curv = np.outer(true, np.array([0.25, 0.35, 0.40]) / shape.flex_length_m)
    >>> points = [0.045, 0.135, 0.225, 0.27]
    >>> y = np.array([shape.deflection_m(k, points) for k in curv])
    >>> rot, cov, rms, shares = rotations_from_deflections(points, np.round(y * 2000) / 2000)
    >>> bool(np.all(np.abs(rot - np.degrees(true)) < 3 * np.sqrt(np.diag(cov)))), bool(np.sqrt(cov[-1, -1]) < 0.5)
    (True, True)
    """
    shape = DigitShape.from_params(params)
    owner = "rotations_from_deflections"
    s = check_array(
        positions_m, "positions_m", owner, ndim=1, min_length=1, low=0.0, high=shape.length_m, low_open=True
    )
    Y = check_array(deflections_m, "deflections_m", owner, shape=(None, s.size))
    sd = check_real(sd_m, "sd_m", owner, low=0.0, low_open=True)
    n_sec, n = len(shape.flex_start_m), Y.shape[0]
    lengths = shape.flex_length_m
    compliance = 1.0 / (
        np.ones(n_sec)
        if stiffness is None
        else check_array(stiffness, "stiffness", owner, shape=(n_sec,), low=0.0, low_open=True)
    )
    prior = compliance * lengths / (compliance @ lengths)  # rotation share of each section at a common moment
    seen = np.array([np.any(s > a) for a in shape.flex_start_m])
    free_shares = s.size >= n_sec and bool(seen.all()) and n >= 2
    theta, cov, rms, shares = _fit_sweep(shape, s, Y, sd, prior, free_shares)
    return np.degrees(theta), cov * math.degrees(1.0) ** 2, rms, shares


def _fit_sweep(shape: DigitShape, s, Y, sd: float, prior, free_shares: bool):
    """The joint least-squares fit of :func:`rotations_from_deflections`: tip rotations (rad), their covariance
    (rad^2), the rms residual (m) and the section shares (``prior`` unless ``free_shares``)."""
    from scipy.optimize import least_squares

    n = Y.shape[0]
    lengths = shape.flex_length_m

    def unpack(p):
        if not free_shares:
            return p, prior
        u = np.append(p[n:], 0.0)
        w = np.exp(u - u.max())
        return p[:n], w / w.sum()

    prior_u = np.log(prior[:-1] / prior[-1])

    def residual(p):
        theta, shares = unpack(p)
        curv = np.outer(theta, shares / lengths)
        misfit = (np.array([shape.deflection_m(k, s) for k in curv]) - Y).ravel() / sd
        if not free_shares:
            return misfit
        return np.concatenate([misfit, (p[n:] - prior_u) / SHARE_PRIOR_SD])

    far = int(np.argmax(s))
    theta0 = 2.0 * Y[:, far] / max(s[far], 1e-3)  # small-angle uniform arc through the farthest reading
    p0 = np.concatenate([theta0, prior_u]) if free_shares else theta0
    fit = least_squares(residual, p0, method="trf", x_scale="jac")
    J = fit.jac
    dof = Y.size - n
    rms = float(np.sqrt(np.mean((fit.fun[: Y.size] * sd) ** 2)))
    # the readings' spread: the stated resolution, or what the residuals show where that is more (a misfit)
    inflate = max(1.0, rms / sd * math.sqrt(Y.size / dof)) if dof > 0 else 1.0
    information = J.T @ J
    if np.linalg.matrix_rank(J) < J.shape[1]:
        raise DataFileError("the deflections do not determine the rotations (readings all at zero or at one place?)")
    cov = np.linalg.inv(information)[:n, :n] * inflate**2
    theta, shares = unpack(fit.x)
    return theta, cov, rms, shares


@dataclass(frozen=True)
class MeasuredReference:
    """Rotations measured on the rig at some commands (see the module docstring).

    Attributes
    ----------
    commands : ndarray of int
    rotation_deg : ndarray
        The tip rotation at each command (deg).
    rotation_cov_deg2 : ndarray (n, n)
        Their covariance (deg^2); correlated for deflections (one shape fitted to the whole sweep).
    gauges_v : ndarray (n, 3) or None
        Gauge readings taken with the measurements, if the file has them.
    kind : str
        ``"rotation"`` or ``"deflections"``.
    source : str
        The file.
    fit_residual_mm : float or None
        The shape fit's rms residual (deflections only).
    """

    commands: np.ndarray
    rotation_deg: np.ndarray
    rotation_cov_deg2: np.ndarray
    gauges_v: np.ndarray | None
    kind: str
    source: str
    fit_residual_mm: float | None = None

    def angle_source(self):
        """``angle_source(command) -> deg`` for :func:`~flexdigit.rig.rotation.calibrate_rotation`."""
        table = dict(zip(self.commands.tolist(), self.rotation_deg.tolist(), strict=True))
        return lambda command: table[int(command)]

    __repr__ = fields_summary


def read_reference(
    path,
    params: RigParams | None = None,
    *,
    resolution_mm: float = DEFLECTION_RESOLUTION_MM,
    resolution_deg: float = ROTATION_RESOLUTION_DEG,
) -> MeasuredReference:
    """Read a file of measured rotations or deflections per command (see the module docstring).

    ``resolution_mm`` / ``resolution_deg`` are the reading resolutions; each reading's standard uncertainty is
    the resolution over sqrt(12) (rounding). A bad file raises :class:`~flexdigit.errors.DataFileError` naming
    the file, line and column.
    """
    params = params or RigParams()
    path = Path(path)
    res_mm = check_param(resolution_mm, READING_RESOLUTION_MM, "resolution_mm", "read_reference")
    res_deg = check_param(resolution_deg, READING_RESOLUTION_DEG, "resolution_deg", "read_reference")
    rows = _data_rows(path)
    header, delimiter, positions = _read_header(path, rows[0], params)
    table = _read_table(path, rows[1:], header, delimiter, positions, params)
    commands = np.array(table["command"], dtype=int)
    if commands.size < 4:
        raise DataFileError(f"{path}: {commands.size} commands measured; the map needs at least 4")
    residual = None
    if "rotation_deg" in header:
        rotation = np.array(table["rotation_deg"])
        cov = np.eye(commands.size) * (res_deg / math.sqrt(12)) ** 2
        kind = "rotation"
    else:
        cols = sorted(positions, key=positions.get)
        s = np.array([positions[h] for h in cols])
        Y = np.array([table[h] for h in cols]).T / 1000
        rotation, cov, rms, _ = rotations_from_deflections(
            s, Y, sd_m=res_mm / 1000 / math.sqrt(12), params=params, stiffness=_section_stiffness(params)
        )
        residual = rms * 1000
        kind = "deflections"
    if not np.ptp(rotation) > 0:
        raise DataFileError(f"{path}: the measured rotations do not vary over the commands")
    gauges = any(h in _GAUGE_COLUMNS for h in header)
    volts = np.array([table[h] for h in _GAUGE_COLUMNS]).T if gauges else None
    return MeasuredReference(commands, rotation, cov, volts, kind, str(path), residual)


def _data_rows(path: Path) -> list[tuple[int, str]]:
    """The file's (line number, line) pairs that are neither blank nor comments; the first is the header."""
    if path.is_dir():
        raise DataFileError(f"{path}: a directory, not a file (expected a CSV of measured rotations or deflections)")
    count_lines(path, "a CSV of measured rotations or deflections")
    try:
        # a spreadsheet's byte-order mark is no part of the header; a FIFO or device is refused, never read
        text = read_text(path, "a CSV of measured rotations or deflections", RECORDS_LIMIT, encoding="utf-8-sig")
    except UnicodeDecodeError:
        raise DataFileError(f"{path}: not a text file (expected a CSV of measured rotations or deflections)") from None
    rows = [
        (n, line) for n, line in enumerate(text.splitlines(), 1) if line.strip() and not line.lstrip().startswith("#")
    ]
    if not rows:
        raise DataFileError(f"{path}: no header and no data (expected 'command,rotation_deg' or deflection columns)")
    return rows


def _read_header(path: Path, row: tuple[int, str], params: RigParams):
    """The checked column names, the delimiter and the deflection columns' positions (m from the base)."""
    header_line, header_text = row
    delimiter = max(",;\t", key=header_text.count)
    header = [h.strip() for h in next(csv.reader(io.StringIO(header_text), delimiter=delimiter))]
    where = f"{path}, line {header_line}"
    if "command" not in header:
        raise DataFileError(f"{where}: no 'command' column (got {', '.join(header)})")
    if len(set(header)) != len(header):
        raise DataFileError(f"{where}: a column name appears twice ({', '.join(header)})")
    positions = {h: float(m.group(1)) / 1000 for h in header if (m := _DEFLECTION_COLUMN.match(h))}
    has_rotation = "rotation_deg" in header
    gauges = [h for h in header if h in _GAUGE_COLUMNS]
    known = {"command", "rotation_deg", *positions, *_GAUGE_COLUMNS}
    unknown = [h for h in header if h not in known]
    if unknown:
        raise DataFileError(
            f"{where}: unknown column '{unknown[0]}'; expected command, rotation_deg or deflection_mm_at_<P>mm "
            f"columns (P in mm from the base), and optionally {', '.join(_GAUGE_COLUMNS)}"
        )
    if has_rotation == bool(positions):
        raise DataFileError(
            f"{where}: give either a rotation_deg column or deflection_mm_at_<P>mm columns (got {', '.join(header)})"
        )
    if gauges and len(gauges) != 3:
        raise DataFileError(f"{where}: gauge columns must be all three of {', '.join(_GAUGE_COLUMNS)}")
    length_mm = params.geometry.digit_length_m * 1000
    for h, p in positions.items():
        if not 0 < p * 1000 <= length_mm:
            raise DataFileError(f"{where}: column '{h}': the point must be inside (0, {length_mm:g}] mm from the base")
    return header, delimiter, positions


def _read_table(path: Path, rows, header: list[str], delimiter: str, positions: dict, params: RigParams):
    """Column name -> the checked values of the data rows, in order."""
    table: dict[str, list[float]] = {h: [] for h in header}
    seen: dict[int, int] = {}  # command -> the line it was measured on
    for number, line in rows:
        cells = [c.strip() for c in next(csv.reader(io.StringIO(line), delimiter=delimiter))]
        if len(cells) != len(header):
            raise DataFileError(f"{path}, line {number}: {len(cells)} cells for {len(header)} columns")
        for h, cell in zip(header, cells, strict=True):
            value = _read_cell(f"{path}, line {number}", h, cell, positions, params.actuator)
            if h == "command":
                if int(value) in seen:
                    raise DataFileError(
                        f"{path}, line {number}: command {int(value)} already measured on line {seen[int(value)]}; "
                        "average repeated readings into one row"
                    )
                seen[int(value)] = number
            table[h].append(value)
    return table


def _read_cell(where: str, h: str, cell: str, positions: dict, a) -> float:
    """One cell's number, checked for its column (``a``: the actuator's parameters)."""
    try:
        value = float(cell)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise DataFileError(f"{where}, column '{h}': expected a number, got {cell!r}")
    if h == "command":
        if value != int(value) or not a.command_min <= value <= a.command_max:
            raise DataFileError(
                f"{where}, column 'command': expected an integer command in "
                f"{a.command_min}..{a.command_max}, got {cell!r}"
            )
    elif h in positions and abs(value) >= positions[h] * 1000:
        raise DataFileError(
            f"{where}, column '{h}': a point {positions[h] * 1000:g} mm along the digit cannot "
            f"move {value:g} mm sideways"
        )
    elif h == "rotation_deg" and not -180 < value < 180:
        raise DataFileError(f"{where}, column 'rotation_deg': expected -180..180 deg, got {cell}")
    return value


def _section_stiffness(params: RigParams) -> np.ndarray:
    """Each section's bending stiffness (strip + the default calibration's housing), for the one-scale fit."""
    geo, mat = params.geometry, params.material
    housing = np.asarray(default_calibration().housing_ei_n_m2, dtype=float)
    strip = mat.youngs_modulus_pa * geo.second_moment_m4
    if housing.size != geo.section_count:
        return np.ones(geo.section_count)
    return strip + housing
