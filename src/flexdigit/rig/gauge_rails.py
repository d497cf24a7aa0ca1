"""Where each gauge's chain meets its ADC's rail, and how finely it reads, over the digit's operating range.

A digit with an amplifier gain per gauge (``sensors.amplifier_gains_v_per_v``), a unipolar ADC (``adc_range_v =
[0, 3.3]``) or a coarse one (``adc_bits = 10``) may read some gauges at a rail, or a few ADC steps a degree, where
the loop needs them. :func:`gauge_rails` solves the digit's statics (the twin's chain, its default calibration,
noise-free) at every command of ``actuator.operating_commands`` and reports, per gauge, the reading at rest, the
volts and ADC steps per degree of tip rotation at rest, and the tip rotation at which the reading first reaches
an end of ``sensors.adc_range_v`` (linearly interpolated between commands), if it does inside that range.
``flexdigit params FILE`` prints one line per gauge that rails inside the operating range.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from flexdigit.errors import ConvergenceWarning, UnstableError
from flexdigit.params import RigParams
from flexdigit.rig.backends.board_link import BOARD_WINDOW_V
from flexdigit.twin.digit_calibration import twin_calibration
from flexdigit.twin.records import release_orientation
from flexdigit.twin.twin import static_gauges_v

__all__ = [
    "GaugeReach",
    "gauge_rails",
    "board_rail_lines",
    "rail_lines",
    "resolution_lines",
    "railed_readings",
    "RESOLVE_DEG",
]


@dataclass(frozen=True)
class GaugeReach:
    """One gauge over the operating range: ``gauge`` (1-based), ``rest_v`` (its reading straight, V),
    ``v_per_deg`` (at rest, V per deg of tip rotation), ``steps_per_deg`` (ADC steps a degree), ``rail_deg`` (the
    tip rotation at which it first reaches a rail, deg; None if it does not within the range), ``rail_v`` (that
    rail, V; None) and ``range_deg`` (the operating range's tip rotations, deg)."""

    gauge: int
    rest_v: float
    v_per_deg: float
    steps_per_deg: float
    rail_deg: float | None
    rail_v: float | None
    range_deg: tuple[float, float]
    span_v: tuple[float, float] = (math.nan, math.nan)


def gauge_rails(params: RigParams | None = None, calibration=None, *, orientation: str | None = None, adc_range_v=None):
    """Each gauge's reach (:class:`GaugeReach`) over the digit's operating commands (module docstring); its rails
    those of ``adc_range_v`` (V, low and high) when given (another ADC than the digit's, e.g. the board's).

    ``orientation`` is the mount (default: as ``run`` mounts the digit, tip up, or hanging for one that buckles tip
    up, :func:`~flexdigit.twin.records.release_orientation`: tip up such a digit has no straight rest, and the
    statics did not converge, trial 3's seven sections). A solve that does not converge is refused
    (:class:`~flexdigit.errors.UnstableError`), not warned about.

    Examples
    --------
    >>> [r.rail_deg for r in gauge_rails()]  # the thesis rig's gauges stay inside +-5 V
    [None, None, None]
    """
    params = params or RigParams()
    calibration = calibration or twin_calibration(params)
    a = params.actuator
    low, high = a.operating_commands
    straight = int(a.equilibrium_command)
    commands = np.unique(np.r_[np.arange(low, high + 1), straight]).astype(int)
    zeros = np.zeros(commands.size)
    orientation = orientation or release_orientation(params, calibration)
    with warnings.catch_warnings():  # said below, in one line, if it did not converge
        warnings.simplefilter("ignore", ConvergenceWarning)
        volts, sol = static_gauges_v(
            zeros,
            zeros,
            commands,
            params=params,
            calibration=calibration,
            orientation=orientation,
            adc=False,
            return_solution=True,
        )
    if not np.all(sol.converged):
        raise UnstableError(
            f"the digit's statics ({orientation}, commands {low}..{high}) did not converge: no steady rest to read"
        )
    tip = np.degrees(np.asarray(sol.psi_rad, dtype=float)[:, -1])
    rest = int(np.flatnonzero(commands == straight)[0])
    tip = tip - tip[rest]
    lo_v, hi_v = params.sensors.adc_range_v if adc_range_v is None else adc_range_v
    lsb = params.sensors.adc_lsb_v
    out = []
    for g in range(volts.shape[1]):
        v = volts[:, g]
        slope = _slope_at_rest(tip, v, rest)
        rail_deg, rail_v = None, None
        for side in (1, -1):  # away from straight, either way (a pair bends both)
            idx = range(rest, commands.size) if side == 1 else range(rest, -1, -1)
            hit = _first_rail(tip, v, list(idx), lo_v, hi_v)
            if hit is not None and (rail_deg is None or abs(hit[0]) < abs(rail_deg)):
                rail_deg, rail_v = hit
        out.append(
            GaugeReach(
                gauge=g + 1,
                rest_v=float(v[rest]),
                v_per_deg=slope,
                steps_per_deg=abs(slope) / lsb,
                rail_deg=rail_deg,
                rail_v=rail_v,
                range_deg=(float(tip.min()), float(tip.max())),
                span_v=(float(v.min()), float(v.max())),
            )
        )
    return out


def _slope_at_rest(tip: np.ndarray, v: np.ndarray, rest: int) -> float:
    """Volts per degree at rest: the chord to the neighbouring command that turns the tip more (a single cable
    is slack below straight)."""
    near = [k for k in (rest - 1, rest + 1) if 0 <= k < tip.size]
    k = max(near, key=lambda j: abs(tip[j] - tip[rest]), default=rest)
    moved = float(tip[k] - tip[rest])
    return float((v[k] - v[rest]) / moved) if abs(moved) > 1e-9 else 0.0


def _first_rail(tip, v, idx: list[int], lo_v: float, hi_v: float):
    """``(tip rotation, rail)`` where ``v`` first leaves ``[lo_v, hi_v]`` along ``idx`` (interpolated), or None."""
    for j, k in enumerate(idx):
        for rail in (lo_v, hi_v):
            out = v[k] <= rail if rail == lo_v else v[k] >= rail
            if not out:
                continue
            if j == 0:
                return float(tip[k]), rail
            p = idx[j - 1]
            frac = (rail - v[p]) / (v[k] - v[p]) if v[k] != v[p] else 0.0
            return float(tip[p] + frac * (tip[k] - tip[p])), rail
    return None


def rail_lines(reaches, params: RigParams) -> list[str]:
    """One line per gauge that reaches a rail of ``sensors.adc_range_v`` away from straight inside the operating
    range (a range that cannot read the chain at rest is :func:`flexdigit.params.adc_range_notes`'s line)."""
    s = params.sensors
    gains = s.chain(len(reaches))[2]
    key = "amplifier_gains_v_per_v" if s.amplifier_gains_v_per_v is not None else "amplifier_gain_v_per_v"
    lines = []
    for r in reaches:
        if r.rail_deg is None or math.isclose(r.rail_deg, 0.0, abs_tol=1e-9):
            continue
        lines.append(
            f"[sensors] gauge {r.gauge} reaches the ADC's {r.rail_v:g} V rail (adc_range_v) at {r.rail_deg:+.1f} deg "
            f"of tip rotation, inside the operating range {r.range_deg[0]:+.1f}..{r.range_deg[1]:+.1f} deg "
            f"([actuator] operating_commands): its readings past it are clipped ({key}: {gains[r.gauge - 1]:g})"
        )
    return lines


def board_rail_lines(params: RigParams, calibration=None, *, orientation: str | None = None) -> list[str]:
    """One line per gauge whose reading leaves the reference firmware's ADC window over the digit's operating range
    (:data:`~flexdigit.rig.backends.board_link.BOARD_WINDOW_V`: the board reads each gauge on 2.5 V into its 0..5 V
    10-bit ADC and faults "adc_rail" at count 0 or 1023), naming the gauge, its volts and the amplifier gain that
    would fit it (the chain's output scales with its gain; the window's 95 %, a margin for noise and drift).
    ``params``'s own ``adc_range_v`` is its DAQ's, not the board's: ``flexdigit params FILE`` checks that one.

    Examples
    --------
    >>> board_rail_lines(RigParams())  # the thesis rig's gauges fit the board
    []
    """
    low, high = BOARD_WINDOW_V
    s = params.sensors
    reaches = gauge_rails(params, calibration, orientation=orientation, adc_range_v=BOARD_WINDOW_V)
    gains = s.chain(len(reaches))[2]
    key = "amplifier_gains_v_per_v" if s.amplifier_gains_v_per_v is not None else "amplifier_gain_v_per_v"
    lines = []
    for r in reaches:
        v_min, v_max = r.span_v
        if low <= v_min and v_max <= high:
            continue
        fit = min(BOARD_FIT_SHARE * high / v_max if v_max > 0 else math.inf,
                  BOARD_FIT_SHARE * low / v_min if v_min < 0 else math.inf)  # fmt: skip
        gain = gains[r.gauge - 1]
        target = f"gauge {r.gauge}'s entry of {key}" if s.amplifier_gains_v_per_v is not None else key
        lines.append(
            f"[sensors] gauge {r.gauge} reads {v_min:+.2f}..{v_max:+.2f} V over the operating range "
            f"{r.range_deg[0]:+.1f}..{r.range_deg[1]:+.1f} deg ([actuator] operating_commands), outside the board's "
            f"ADC window {low:+.3f}..{high:+.3f} V (0..5 V about its 2.5 V midpoint): the board would fault "
            f"'adc_rail'; {target} <= {_round_down(gain * fit):g} fits it (now {gain:g})"
        )
    return lines


#: The share of the board's window a gauge's swing is fitted to by the gain :func:`board_rail_lines` suggests.
BOARD_FIT_SHARE = 0.95


def _round_down(x: float) -> float:
    """``x`` rounded down to 3 significant figures (a gain that fits, said as a user writes it)."""
    if not x > 0:
        return 0.0
    scale = 10 ** (math.floor(math.log10(x)) - 2)
    return math.floor(x / scale) * scale


#: The loop's figure the gauges must resolve: 2 % of a 30 deg step (issue 24's "true rotation within 2 %"), deg.
RESOLVE_DEG = 0.6


def resolution_lines(reaches, params: RigParams) -> list[str]:
    """A line when even the finest gauge reads fewer than one ADC step over :data:`RESOLVE_DEG`: the step's final
    2 % cannot be told from the readings (a 10-bit ADC over +-5 V behind a half bridge reads ~0.6 steps a degree)."""
    finest = max((r.steps_per_deg for r in reaches), default=0.0)
    if finest * RESOLVE_DEG >= 1.0:
        return []
    s = params.sensors
    return [
        f"[sensors] adc_bits = {s.adc_bits} over adc_range_v = [{s.adc_range_v[0]:g}, {s.adc_range_v[1]:g}] V: the "
        f"gauges read at most {finest:.2g} ADC steps a degree of tip rotation, {finest * RESOLVE_DEG:.2g} over 2 % "
        f"of a 30 deg step ({RESOLVE_DEG:g} deg); raise the amplifier gain or the ADC's bits"
    ]


def railed_readings(gauges_v, sensors) -> str | None:
    """``"gauge k stuck at the rail (...) in N of M readings"`` for each gauge some of whose readings sit at an end
    of ``sensors.adc_range_v`` (its lowest or highest code, the one a clipped input gives), joined by
    "; ", or None. Such a reading says only that the gauge's voltage is beyond the range, not what it is."""
    g = np.asarray(gauges_v, dtype=float)
    if g.ndim != 2 or g.shape[0] == 0:
        return None
    low, high = sensors.adc_range_v
    half = sensors.adc_lsb_v / 2
    top = low + (2**sensors.adc_bits - 1) * sensors.adc_lsb_v  # the ADC's highest code (models.bridge.adc_clipped)
    at_rail = (g <= low + half) | (g >= top - half) | ~np.isfinite(g)
    counts = at_rail.sum(axis=0)
    parts = [
        f"gauge {k + 1} stuck at the rail (sensors.adc_range_v = [{low:g}, {high:g}] V) in {int(n)} of {g.shape[0]} "
        "readings"
        for k, n in enumerate(counts)
        if n
    ]
    return "; ".join(parts) or None
