"""How far the twin's statics are from the elastica at a resolution, estimated from the twin itself (issue 24).

The chain (:mod:`flexdigit.twin.digit`) lumps each cell's curvature at its mid-point: its static deflection
converges to the inextensible elastica of the same digit as ``h^2`` (``h`` the cell length). Two chains, at the
resolution asked for and at :data:`REFINEMENT` times as many cells a section, give the error of the first by
Richardson extrapolation, ``e(h) = (t_h - t_{h/3}) / (1 - 1/9)`` (Richardson 1911; the ``h^2`` law is the
mid-point rule's). Checked against an independent ``scipy.integrate.solve_bvp`` elastica of the same geometry on
three digits (``tests/twin/test_twin_resolution.py``): the estimate is the measured error within 0.05 % of itself
(0.3674 % for 0.3674 % on the thesis rig's tip load), so ``flexdigit params FILE`` prints it for any description
without a boundary-value solve.

The two load cases are the issue's: a tip load of ``alpha^2 = P L^2 / EI = 1`` (``EI`` the strip's plus the
softest section's housing) and the cable shortened as a rigid cable would turn the tip 30 deg, the digit hanging
(stable for any digit: a long one buckles tip up), with its own weight and its supports'. The error is the tip's
distance from the converged tip over the tip's deflection.

An a-priori law ``e ~ C (h/L)^2`` would need ``C`` per digit: on the thesis rig, the one-section digit and the
campaign's seed 2 ``C`` spans 0.38-0.53 (tip load) and a wider range under the cable, whose error comes from
the sections near the clamp; the extrapolation needs no constant and costs two static solves.

Examples
--------
>>> from flexdigit.params import RigParams
>>> e = static_error(RigParams())
>>> e.cells, round(100 * e.tip_load, 2), round(100 * e.cable, 2)     # the default's 3 cells a section, in %
((3, 3, 3), 0.37, 0.1)
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from flexdigit._repr import fields_summary
from flexdigit.errors import ConvergenceWarning
from flexdigit.params import (
    MAX_CELL_LENGTH_M,
    MAX_TWIN_CELLS,
    RigParams,
    TwinResolution,
    cells_no_longer_than,
    twin_cells,
)
from flexdigit.twin.digit import build_digit, section_cells
from flexdigit.twin.digit_calibration import is_derived, twin_calibration

__all__ = [
    "TIP_LOAD_ALPHA2",
    "CABLE_TIP_DEG",
    "REFINEMENT",
    "STATIC_RTOL",
    "StaticError",
    "static_error",
    "resolution_for",
    "ResolutionAdvice",
    "resolution_advice",
    "DERIVED_RTOL",
    "twin_default_cells",
]

#: The tip load as ``alpha^2 = P L^2 / EI``: 1 bends a cantilever's tip through ~28 deg (large deflection).
TIP_LOAD_ALPHA2 = 1.0
#: The cable shortened as a rigid cable turning the tip this far (deg).
CABLE_TIP_DEG = 30.0
#: The finer chain's cells a section, a multiple of the asked-for: 3 keeps odd counts odd and every spring's
#: cell a union of three fine ones.
REFINEMENT = 3
#: The issue's tolerance on the static deflection against the elastica: 0.1 % of the deflection.
STATIC_RTOL = 1e-3
#: What the estimate must meet for a digit on its derived calibration (:func:`twin_default_cells`): 0.07 %, a
#: margin under :data:`STATIC_RTOL` for the estimate's own error (its h^4 term) and the solve_bvp reference's.
DERIVED_RTOL = 7e-4


@dataclass(frozen=True)
class StaticError:
    """The estimated static error of a twin resolution (relative to the tip's deflection).

    Attributes
    ----------
    cells : tuple of int
        Springs per section.
    tip_load, cable : float
        Under the tip load and under the cable (:data:`TIP_LOAD_ALPHA2`, :data:`CABLE_TIP_DEG`); NaN where a
        static solve did not converge.
    """

    cells: tuple[int, ...]
    tip_load: float
    cable: float

    __repr__ = fields_summary

    @property
    def worst(self) -> float:
        """The larger of the two (NaN if either is)."""
        return max(self.tip_load, self.cable) if not math.isnan(self.tip_load + self.cable) else math.nan


def _tips(params: RigParams, calibration, cells) -> np.ndarray | None:
    """Tip positions (2, 2) under the tip load and the cable, hanging; None where the Newton did not converge."""
    chain = build_digit(params, calibration, orientation="hanging", cells_per_section=cells)
    length = params.geometry.digit_length_m
    ei = params.bending_stiffness_n_m2 + min(calibration.housing_ei_n_m2)
    force = TIP_LOAD_ALPHA2 * ei / length**2
    shortening = params.geometry.cable_eccentricity_m * math.radians(CABLE_TIP_DEG)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ConvergenceWarning)
        try:
            load = chain.solve_static(tip_force_n=[[0.0, force]])
            cable = chain.solve_static(cable_shortening_m=[shortening])
        except ConvergenceWarning:
            return None
    return np.array([load.tip_m[0], cable.tip_m[0]])


def static_error(params: RigParams, calibration=None, cells=None) -> StaticError:
    """The static error of the twin of ``params`` at ``cells`` (None: its own, :func:`flexdigit.params.twin_cells`)
    under the tip load and the cable, by Richardson extrapolation (module docstring).

    Parameters
    ----------
    params : RigParams
    calibration : Calibration, optional
        Default :func:`~flexdigit.twin.digit_calibration.twin_calibration` (the twin's own).
    cells : int, sequence of int or None
        Springs per section (one count or one per section); None: the twin's own, :func:`twin_default_cells`.
    """
    cal = twin_calibration(params) if calibration is None else calibration
    cells = twin_default_cells(params, cal) if cells is None else section_cells(params.geometry, cells, "static_error")
    coarse = _tips(params, cal, cells)
    fine = _tips(params, cal, tuple(REFINEMENT * n for n in cells))
    if coarse is None or fine is None:
        return StaticError(tuple(cells), math.nan, math.nan)
    limit = fine + (fine - coarse) / (REFINEMENT**2 - 1)  # the h -> 0 tip, h^2 extrapolated
    deflection = np.linalg.norm(limit - [params.geometry.digit_length_m, 0.0], axis=1)
    error = np.linalg.norm(coarse - limit, axis=1) / deflection
    return StaticError(tuple(int(n) for n in cells), float(error[0]), float(error[1]))


def resolution_for(params: RigParams, rtol: float = STATIC_RTOL, calibration=None) -> tuple[float, StaticError]:
    """The longest cell (m, to 0.5 mm) whose twin of ``params`` is within ``rtol`` of the elastica under both load
    cases (:func:`static_error`), and that twin's error: the ``[twin] max_cell_length_m`` to set. Starts from
    the ``h^2`` law on the default's error and shortens the cell until the estimate meets ``rtol``.

    >>> h, e = resolution_for(RigParams())
    >>> h, e.cells
    (0.014, (7, 7, 7))
    """
    cal = twin_calibration(params) if calibration is None else calibration
    base = params.digit_only()
    error = static_error(base, cal, twin_cells(base))  # the 27 mm default a [twin] table replaces
    h = MAX_CELL_LENGTH_M
    for _ in range(20):
        if not error.worst > rtol:  # met (a NaN: no estimate; the default kept)
            return h, error
        h = max(1e-3, math.floor(2000 * h * min(0.9, math.sqrt(rtol / error.worst))) / 2000)
        finer = base.replace(twin=TwinResolution(max_cell_length_m=h))
        error = static_error(finer, cal, twin_cells(finer))
        if h <= 1e-3:
            break
    return h, error


@dataclass(frozen=True)
class ResolutionAdvice:
    """Whether a description's twin meets the static tolerance, and the ``[twin]`` setting that would
    (:func:`resolution_advice`).

    Attributes
    ----------
    error : StaticError
        The description's own twin's (its ``[twin]`` or the default).
    rtol : float
        The tolerance (relative to the tip's deflection).
    max_cell_length_m : float or None
        The ``[twin] max_cell_length_m`` whose twin meets ``rtol`` within :data:`~flexdigit.params.MAX_TWIN_CELLS`
        springs; None when the own twin meets it, its error is not determined, or no setting a twin takes meets it.
    suggested_error : StaticError or None
        The twin of that setting's (the finest tried when none meets); None when none was looked for.
    """

    error: StaticError
    rtol: float
    max_cell_length_m: float | None
    suggested_error: StaticError | None

    __repr__ = fields_summary

    @property
    def determined(self) -> bool:
        """Whether both static solves converged (else no figure rather than a wrong one)."""
        return not math.isnan(self.error.worst)

    @property
    def acceptable(self) -> bool:
        """Whether the description's own twin is within ``rtol`` under both load cases."""
        return self.error.worst <= self.rtol


def resolution_advice(params: RigParams, rtol: float = STATIC_RTOL, calibration=None) -> ResolutionAdvice:
    """The static error of ``params``'s own twin (:func:`static_error`) and, when it misses ``rtol``, the
    ``[twin] max_cell_length_m`` that meets it (:func:`resolution_for`) if a twin of at most
    :data:`~flexdigit.params.MAX_TWIN_CELLS` springs does: what ``flexdigit params FILE`` reports.

    >>> a = resolution_advice(RigParams())
    >>> a.acceptable, a.max_cell_length_m, a.suggested_error.cells
    (False, 0.014, (7, 7, 7))
    """
    error = static_error(params, calibration)
    if not error.worst > rtol:  # met, or not determined (NaN): nothing to suggest
        return ResolutionAdvice(error, rtol, None, None)
    h, finer = resolution_for(params, rtol, calibration)
    met = finer.worst <= rtol and sum(finer.cells) <= MAX_TWIN_CELLS
    return ResolutionAdvice(error, rtol, h if met else None, finer)


def twin_default_cells(params: RigParams, calibration) -> tuple[int, ...]:
    """Springs per section of the twin of ``params`` on ``calibration`` when no cells are asked for (what
    :func:`flexdigit.twin.twin.cached_digit`, so :class:`~flexdigit.twin.twin.Twin`, builds).

    - a ``[twin]`` table: its cells (:func:`flexdigit.params.twin_cells`);
    - the digit's derived default calibration (:func:`~flexdigit.twin.digit_calibration.is_derived`, a digit
      nobody measured): the fewest odd cells, the longest section's count setting every section's cell length,
      whose estimated static error (:func:`static_error`, both load cases) is within :data:`DERIVED_RTOL`,
      found once per digit (cached);
    - any other calibration (the packaged thesis fit, a ``calibrate`` result, a design study's): the default
      27 mm cells it was fitted or derived at, so the thesis rig keeps 3 cells a section and its report.

    >>> from flexdigit.twin.calibration import packaged_calibration
    >>> twin_default_cells(RigParams(), packaged_calibration())
    (3, 3, 3)
    """
    if not params.twin.is_default or not is_derived(params, calibration):
        return twin_cells(params)
    return _derived_cells(params.digit_only(), calibration)


@lru_cache(maxsize=64)
def _derived_cells(params: RigParams, calibration) -> tuple[int, ...]:
    """:func:`twin_default_cells` on a derived calibration: from the default, the ``h^2`` law's count for the
    longest section (Richardson's estimate says how far), then two more cells until the estimate meets
    :data:`DERIVED_RTOL`; the default kept where a static solve fails, the finest tried at :data:`MAX_TWIN_CELLS`."""
    geo = params.geometry
    longest = max(end - start for start, end in geo.section_bounds_m)
    cells = twin_cells(params)
    error = static_error(params, calibration, cells)
    while error.worst > DERIVED_RTOL:  # False for a NaN: no estimate, the cells kept
        count = max(max(cells) + 2, math.ceil(max(cells) * math.sqrt(error.worst / DERIVED_RTOL)))
        finer = cells_no_longer_than(geo, longest / count)
        if sum(finer) > MAX_TWIN_CELLS:
            break
        cells, error = finer, static_error(params, calibration, finer)
    return cells
