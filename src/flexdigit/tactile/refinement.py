"""How finely ``flexdigit collect`` lays a protocol's positions on a digit: the refinement ``K`` of
:meth:`~flexdigit.tactile.protocols.Protocol.refined`, chosen from the digit's resolution (issue 24).

A network scored on held-out positions (``train --bayes-limit``) is tested between training positions two protocol
steps apart. Where the digit resolves a load's position far finer than that step (its Cramer-Rao bound a tenth of a
millimetre against thesis-6.1's 4-14 mm scaled), the network's error is that interpolation, not what the gauges
tell: the four hand-made digits over issue 24's 1.3x at K = 1 (nitinol 100 mm, thin shim, stainless eight, unequal
three; docs/guide/tactile.md) were within it at K = 4. So, before collecting, for a digit other than the thesis rig:

    K = ceil(step / (RESOLVED_STEP_BOUNDS x bound)), clamped to [1, AUTO_REFINE_MAX]

``step`` the median spacing of the protocol's positions on the digit (the evenly spaced run ``refined`` cuts),
``bound`` the median, over the protocol's loaded settings (position, load, command), of the Cramer-Rao bound of
the position with the mass unknown (:func:`~flexdigit.tactile.bounds.cramer_rao` on the twin's static gauges, their
white noise and the ADC's quantisation, :func:`~flexdigit.tactile.bounds.readings_gauge_model`: a few static solves,
no Monte Carlo). The mass unknown, because a network is not told which load hangs: the bound then separates the
digits measured (step over bound 14.8-81 on the four that needed K = 4; 13.0 at most on those within 1.3x at
K = 1); where the position and the mass are confounded (one bending gauge: the bound infinite) refining cannot
help and K is 1. A protocol of fewer than :data:`~flexdigit.tactile.protocols.HELD_OUT_MIN_POSITIONS` positions
keeps K = 1: ``train --bayes-limit`` scores its network on the readings split (test positions are training
positions), where nothing is interpolated. The thesis rig keeps K = 1 (its datasets, the report's 509 entries); a
``refine`` given wins.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from flexdigit._repr import fields_summary
from flexdigit._validation import check_int
from flexdigit.params import RigParams
from flexdigit.tactile.bounds import cramer_rao, readings_gauge_model
from flexdigit.tactile.protocols import HELD_OUT_MIN_POSITIONS, REFINE_MAX, RELAXED, Protocol
from flexdigit.twin.digit_calibration import twin_calibration

__all__ = ["AUTO_REFINE_MAX", "RESOLVED_STEP_BOUNDS", "Refinement", "position_step_m", "refinement_for"]

#: The refined step the automatic ``K`` aims at, in Cramer-Rao bounds of the position (mass unknown): the four
#: digits over 1.3x at K = 1 had steps 14.8-81 bounds (K = 4 each at 4), the digits within 1.3x 13.0 at most and
#: all but two (mixed_bridges_three 13.0: K = 4; five_unequal_bronze_full 11.3: K = 3) under 4 (K = 1)
RESOLVED_STEP_BOUNDS = 4.0
#: Most steps the automatic choice cuts one protocol step into: K = 4 was enough on the four digits measured
#: (stainless, 81 bounds a step: 0.78x); more divides thesis-6.1's 25 readings a position under 7, unmeasured
AUTO_REFINE_MAX = 4


@dataclass(frozen=True)
class Refinement:
    """The refinement a collection used and why (recorded in the dataset's settings and ``collect --json``).

    Attributes
    ----------
    factor : int
        ``K``: positions where the protocol has one step (1: the protocol as written).
    chosen : str
        ``"given"`` (``collect --refine K``), ``"thesis rig"`` (K = 1) or ``"auto"`` (the rule, module docstring).
    step_m, bound_m : float or None
        The protocol's step on the digit and the median Cramer-Rao bound of its loaded settings (m; inf where
        position and mass are confounded everywhere); None unless ``auto``.
    """

    factor: int
    chosen: str
    step_m: float | None = None
    bound_m: float | None = None

    __repr__ = fields_summary

    def to_dict(self) -> dict:
        """Plain values (a bound of inf as None), as stored in a dataset's settings and printed by ``--json``."""
        d = asdict(self)
        if d["bound_m"] is not None and not math.isfinite(d["bound_m"]):
            d["bound_m"] = None
        return d


def position_step_m(protocol: Protocol) -> float:
    """The protocol's step: the median spacing of its positions (m; 0 with fewer than two), the evenly spaced run
    :meth:`~flexdigit.tactile.protocols.Protocol.refined` cuts (an isolated position barely moves a median)."""
    tips = np.unique(np.asarray(protocol.positions_from_tip_m, dtype=float))
    return float(np.median(np.diff(tips))) if tips.size > 1 else 0.0


def _median_bound_m(protocol: Protocol, length_m: float, model) -> float:
    """The median Cramer-Rao bound (m, mass unknown) of ``model`` over the protocol's loaded settings on a digit
    ``length_m`` long (inf where more than half are confounded or invisible)."""
    commands = protocol.actuation_commands or (RELAXED,)
    grid = [(length_m - tip, load, c) for tip in protocol.positions_from_tip_m for load in protocol.loads_kg
            for c in commands]  # fmt: skip
    a, m, c = (np.array(column) for column in zip(*grid, strict=True))
    return float(np.median(cramer_rao(model, a, m, c).crlb_m))


def refinement_for(
    protocol: Protocol, params: RigParams | None = None, refine: int | None = None, *, calibration=None, model=None
) -> Refinement:
    """The refinement ``K`` to collect ``protocol`` with on the digit ``params`` (module docstring).

    Parameters
    ----------
    protocol : Protocol
        On the digit (``load_protocol(name, params)``: a built-in's positions scaled to its length), not refined.
    params : RigParams, optional
        The digit (default: the thesis rig, K = 1).
    refine : int, optional
        A ``K`` asked for (1..:data:`~flexdigit.tactile.protocols.REFINE_MAX`): it wins. None: chosen.
    calibration : Calibration or path, optional
        The twin's calibration the bound is computed on (default: the digit's derived one).
    model : gauge model, optional
        The digit's gauges and noise the bound is computed on (:mod:`~flexdigit.tactile.bounds`; default: the twin's
        as its card reads it, :func:`~flexdigit.tactile.bounds.readings_gauge_model`).

    Examples
    --------
    >>> from flexdigit.tactile.protocols import load_protocol
    >>> refinement_for(load_protocol("thesis-6.1")).factor  # the thesis rig: the protocol as written
    1
    >>> refinement_for(load_protocol("thesis-6.1"), refine=4).chosen
    'given'
    """
    if refine is not None:
        return Refinement(check_int(refine, "refine", "collect", low=1, high=REFINE_MAX), "given")
    params = params or RigParams()
    if params.is_thesis_rig():
        return Refinement(1, "thesis rig")
    step = position_step_m(protocol)
    if len(set(protocol.positions_from_tip_m)) < HELD_OUT_MIN_POSITIONS:  # scored on the readings split: K helps not
        return Refinement(1, "auto", step, None)
    if model is None and step > 0:
        model = readings_gauge_model(params, twin_calibration(params, calibration))
    bound = _median_bound_m(protocol, params.geometry.digit_length_m, model) if step > 0 else math.inf
    wanted = step / (RESOLVED_STEP_BOUNDS * bound) if math.isfinite(bound) and bound > 0 else 1.0
    # a step of exactly n x 4 bounds asks n, whatever the positions' rounding to the nanometre
    factor = int(min(AUTO_REFINE_MAX, max(1, math.ceil(wanted - 1e-9))))
    return Refinement(factor, "auto", step, bound)
