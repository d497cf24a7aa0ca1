"""Palpation: press the digit into tissue through a command sweep, read the gauges, say how stiff the tissue is.

Beyond the thesis (chapter 8: "identify variability in tissue stiffness"). The protocol drives the servo through
a staircase of commands on the real-time loop (:func:`flexdigit.rig.loop.run_loop`, 20 ms frames): a tare
plateau at the equilibrium command (the digit straight, clear of the tissue), one plateau per command of the sweep,
and the tare again, holding each ``settle_s`` and averaging its last ``readings`` samples. Every sample is kept
(:class:`SweepRecord`).

The tissue is the twin's model of it (:class:`flexdigit.twin.contact.Tissue`: a unilateral Winkler foundation,
or Hunt-Crossley ``q = k delta^n``): where it lies along the digit is what the experimenter knows (it is placed
there); how far its surface is (``gap_m``) and how stiff it is (``modulus_n_m2``, and ``exponent``) are estimated
by maximum likelihood on the plateaus' gauges through the digit's static contact model
(:class:`flexdigit.palpation.contact_estimation.ContactGaugeModel`), with each gauge's offset and linear drift over
the sweep
as nuisance parameters profiled out (the two tares pin them). The standard deviations come from the fit's
Jacobian; the Cramer-Rao bound of the same sweep is :func:`stiffness_bound`.

Beside the fit, the force-indentation curve: at each plateau the contact force from the gauges alone
(:class:`flexdigit.palpation.contact_estimation.ContactEstimator`, no tissue model) against the indentation (the deepest
penetration of the fitted model), and its least-squares slope, the lumped contact stiffness (N/m).

:func:`scan` repeats the palpation with the tissue moved along the digit and fits one inclusion (centre, stiffness
ratio) to the whole scan. :func:`hold_force` closes the 20 ms loop on the contact-force estimate.

Units: m, N, N/m (lumped), N/m^2 (the foundation's modulus: N/m for every m of digit pressed in; ``k / 100`` is
the N/m of one centimetre).
"""

from __future__ import annotations

import copy
import math
import warnings
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from flexdigit._repr import fields_summary
from flexdigit._validation import check_choice, check_int, check_real, check_values
from flexdigit.errors import DesignWarning, ParameterError, RigError
from flexdigit.models.cable import tip_rotation_per_command_deg
from flexdigit.palpation.contact_estimation import ContactEstimator, ContactGaugeModel
from flexdigit.params import RigParams
from flexdigit.rig.base import Reading
from flexdigit.rig.loop import run_loop
from flexdigit.twin.calibration import packaged_calibration
from flexdigit.twin.contact import Inclusion, Tissue, TissueContact
from flexdigit.twin.digit_calibration import twin_calibration
from flexdigit.twin.twin import Twin

__all__ = [
    "MODELS",
    "PalpationProtocol",
    "THESIS_STRAIGHT",
    "command_scale",
    "towards",
    "digit_command",
    "digit_protocol",
    "tissue_scale",
    "digit_tissue",
    "digit_scan",
    "TISSUE_REACH_M",
    "check_tissue_reach",
    "check_sweep_commands",
    "ring_time_s",
    "SweepRecord",
    "RAIL_MARGIN",
    "run_sweep",
    "QUANTISATION_TERMS",
    "quantisation_bias_v",
    "plateau_sigma_v",
    "TissueFit",
    "fit_tissue",
    "stiffness_bound",
    "PalpationResult",
    "analyse",
    "palpate",
    "simulate_sweep",
    "ScanResult",
    "scan",
    "ForceController",
    "ForceHold",
    "hold_force",
    "check_tare_rails",
    "TARE_RAIL_SIGMAS",
    "rig_contact_model",
    "THESIS_FORCE_GAIN",
    "THESIS_APPROACH_RATE",
    "force_per_command",
    "force_gains",
    "lone_step_ring",
    "lone_step_response",
    "quantiser_band",
    "hold_coarseness",
    "COARSE_SEARCH_STEPS",
    "RING_BAND",
    "INTEGER_FORCE_SHARE",
    "RING_RECORD_S",
    "RING_STEP_S",
    "force_region",
    "twin_step_s",
    "SWEEP_STEPS_S",
    "STEP_AGREEMENT",
    "servo_lag_force",
    "SERVO_LAG_FORCE",
    "free_motion_chi2",
    "motion_detect_chi2",
    "FREE_MOTION_S",
    "CONTACT_FRACTION",
    "DETECT_SIGMAS",
    "FORCE_PLACE_SPREAD",
    "PLACE_WANDER_CHI2",
    "FORCE_TOLD",
    "COMMAND_TOLD",
    "PLACE_READINGS",
    "HELD_SD_SHARE",
]

MODELS = ("linear", "hunt-crossley")


@dataclass(frozen=True)
class PalpationProtocol:
    """A palpation sweep.

    Attributes
    ----------
    commands : tuple of int
        The staircase, in order (servo commands, 0..254).
    settle_s : float
        Time each plateau is held before it is read (s). The housed digit rings for seconds after each command
        step (zeta 0.068, table 3.2): on the twin 1 s leaves chi^2/dof ~ 10 in the fit, 3 s ~ 0.9.
    readings : int
        Samples averaged at the end of each plateau (one per loop period).
    tare_command : int
        Command of the tare plateaus before and after the sweep (the digit clear of the tissue).
    period_s : float
        Loop period (s): 0.020, the servo board's frame (5.2).
    model : {"linear", "hunt-crossley"}
        The tissue model fitted: Winkler (``q = k delta``) or Hunt-Crossley (``q = k delta^n``, ``n`` fitted).
    return_settle_s : float
        Extra settling of the closing tare (s): the step back from the last command is the whole sweep, not one
        command (:func:`digit_protocol` sets it on a digit whose gauges see that step ring longer than the thesis
        rig's; 0 on it).
    """

    commands: tuple[int, ...] = tuple(range(8, 31))
    settle_s: float = 2.5
    readings: int = 20
    tare_command: int = 8
    period_s: float = 0.020
    model: str = "linear"
    return_settle_s: float = 0.0

    def __post_init__(self) -> None:
        owner = "PalpationProtocol"
        cmds = check_values(self.commands, "commands", owner, low=0, high=254, integer=True)
        if cmds.ndim != 1 or cmds.size < 3:
            raise ParameterError(
                f"The 'commands' parameter of {owner} must list at least 3 commands. Got {np.ravel(cmds).tolist()!r}."
            )
        object.__setattr__(self, "commands", tuple(int(c) for c in cmds))
        object.__setattr__(self, "period_s", check_real(self.period_s, "period_s", owner, low=1e-3, high=1.0))
        object.__setattr__(self, "settle_s", check_real(self.settle_s, "settle_s", owner, low=0.0, high=600.0))
        object.__setattr__(
            self, "return_settle_s", check_real(self.return_settle_s, "return_settle_s", owner, low=0.0, high=600.0)
        )
        object.__setattr__(self, "readings", check_int(self.readings, "readings", owner, low=1, high=100_000))
        object.__setattr__(self, "tare_command", check_int(self.tare_command, "tare_command", owner, low=0, high=254))
        check_choice(self.model, "model", MODELS, owner)

    @property
    def plateau_s(self) -> float:
        """Duration of one plateau (s): the settling and the readings."""
        return self.settle_s + self.readings * self.period_s

    @property
    def duration_s(self) -> float:
        """The whole sweep, tares included (s)."""
        return (len(self.commands) + 2) * self.plateau_s + self.return_settle_s

    def reading_times_s(self) -> np.ndarray:
        """Mid-time (s from the start) of each plateau's readings, the tares included."""
        times = self.plateau_s * (np.arange(len(self.commands) + 2) + 1.0) - 0.5 * self.readings * self.period_s
        times[-1] += self.return_settle_s
        return times


#: The thesis rig's straight command: the built-in protocols count their commands from it.
THESIS_STRAIGHT = 8


def command_scale(params) -> float:
    """Commands of ``params``'s digit per command of the thesis rig for the same tip rotation: the thesis's cable-model
    1.735 deg a command over the digit's (:func:`flexdigit.models.cable.tip_rotation_per_command_deg`: its servo
    step, gearing, pulley radius and cable eccentricity). 1 on the thesis rig, the gear ratio on a geared copy of it
    (3 on a 3:1), 5.6 on a servo of 0.216 deg a command (the design study's front design 30: 0.31 deg of tip)."""
    # to 12 figures: a 3:1 copy of the thesis rig scales by 3, not 2.9999999999999996
    return float(f"{tip_rotation_per_command_deg(RigParams()) / tip_rotation_per_command_deg(params):.12g}")


def towards(params, side: str = "cable") -> int:
    """+1 if the digit's commands above its straight one bend it towards a body on ``side``, -1 if those below do
    (an antagonistic pair, ``side`` "opposite"). A single cable bends the digit towards its cable side only: a body
    on the other side is refused in one line (:class:`~flexdigit.errors.ParameterError`)."""
    check_choice(side, "side", ("cable", "opposite"), "towards")
    if side == "cable":
        return 1
    if params.cables.count == 2:
        return -1
    raise ParameterError(
        "tissue side 'opposite': this digit's single cable bends it towards its cable side only, never into a body on "
        "the other side; place the tissue on side 'cable' (or describe an antagonistic pair, [cables] count = 2)"
    )


def digit_command(params, thesis_command: float, side: str = "cable") -> int:
    """The command of ``params``'s digit as far past its straight command, towards ``side``, in tip rotation as
    ``thesis_command`` is past the thesis rig's straight 8 (:func:`command_scale`), within the servo's range."""
    a = params.actuator
    past = (float(thesis_command) - THESIS_STRAIGHT) * command_scale(params)
    command = int(a.equilibrium_command) + towards(params, side) * int(round(past))
    return int(min(int(a.command_max), max(int(a.command_min), command)))


def ring_time_s(model) -> float:
    """The slowest time constant ``1 / (zeta wn)`` (s) of ``model``'s digit (its chain's linear modes, housed, as
    mounted): the thesis rig's 1.12 s (13.1 rad/s, zeta 0.068); a 0.5 m one-section digit's 4.9 s."""
    wn, zeta = model.chain.linear_modes()
    return float(np.max(1.0 / (np.asarray(zeta) * np.asarray(wn))))


@lru_cache(maxsize=1)
def _thesis_ring_time_s() -> float:
    return ring_time_s(ContactGaugeModel(RigParams(), packaged_calibration()))


def _return_swing(model, tare: int, last: int, readings: int) -> float:
    """The closing tare's step, ``last`` back to ``tare``, on the gauges, in plateau-mean noise sds (the largest)."""
    v = model.free_v([tare, last])
    return float(np.max(np.abs(v[1] - v[0]) / (np.asarray(model.noise_v, dtype=float) / math.sqrt(readings))))


@lru_cache(maxsize=1)
def _thesis_return_swing() -> float:
    p = PalpationProtocol()
    return _return_swing(ContactGaugeModel(RigParams(), packaged_calibration()), p.tare_command, p.commands[-1], 20)


def digit_protocol(
    protocol: PalpationProtocol,
    params,
    side: str = "cable",
    *,
    laid_out=("commands", "tare_command"),
    model=None,
):
    """A protocol written for the thesis rig (commands counted from its straight 8) laid out on ``params``'s digit:
    each command the same tip rotation past the digit's straight command (:func:`digit_command`), towards the tissue
    (above it on the cable side; below it for an antagonistic pair's other side), the tare at its straight command.

    ``laid_out`` names which of ``commands``, ``tare_command`` and ``settle_s`` are the thesis's (a protocol file's
    own values are the user's, kept, and checked by :func:`check_sweep_commands`). Commands that fall on one after
    rounding (a coarser step than the thesis's) are taken once; fewer than 3 left is refused. Before, the built-in
    sweep ran 8..30 and tared at 8 on every digit: 119 commands below an antagonistic pair's straight 127 (a runaway
    at -124 deg), or 22 fine steps of a 0.31 deg servo that never reached the tissue.

    ``settle_s`` (with ``model``, the digit's gauge model as mounted): the thesis's settling times the digit's
    slowest ring (:func:`ring_time_s`) over the thesis rig's, never shorter: the thesis's 2.5 s is 2.2 of its 1.12 s
    time constants; the 0.5 m one-section digit (4.9 s) rang through its 2.5 s plateaus, chi2/dof 948. The closing
    tare steps back the whole sweep: where the gauges see that step ``S`` times larger (in their noise) than the
    thesis rig's (587 sd), it settles ``ring ln S`` longer (``return_settle_s``; the one-section digit's 3x: 5.4 s;
    its closing tare was 28 sd off at 10.8 s)."""
    commands = protocol.commands
    if "commands" in laid_out:
        commands = tuple(dict.fromkeys(digit_command(params, c, side) for c in protocol.commands))
    tare = digit_command(params, protocol.tare_command, side) if "tare_command" in laid_out else protocol.tare_command
    if len(commands) < 3:
        raise ParameterError(
            f"the sweep's commands laid out on this digit ({tare} straight, {command_scale(params):.3g} of its "
            f"commands a thesis command) are {list(commands)}: fewer than 3 distinct commands; give 'commands' for it"
        )
    settle, back = protocol.settle_s, protocol.return_settle_s
    if "settle_s" in laid_out and model is not None:
        ring = ring_time_s(model)
        settle = max(settle, round(settle * ring / _thesis_ring_time_s(), 1))
        swing = _return_swing(model, tare, commands[-1], protocol.readings)
        back = max(back, round(ring * math.log(max(1.0, swing / _thesis_return_swing())), 1))
    return PalpationProtocol(
        commands=commands,
        settle_s=settle,
        return_settle_s=back,
        readings=protocol.readings,
        tare_command=tare,
        period_s=protocol.period_s,
        model=protocol.model,
    )


def tissue_scale(params) -> float:
    """How much a built-in tissue (and the built-in scan's offsets) are scaled beside ``params``'s digit: its length
    over the thesis rig's 0.27 m (1 on the thesis rig; :func:`digit_tissue`)."""
    return params.geometry.digit_length_m / RigParams().geometry.digit_length_m


def digit_tissue(tissue: Tissue, params) -> Tissue:
    """A built-in tissue (written beside the thesis rig's 0.27 m digit) laid out beside ``params``'s digit: where it
    lies along the digit (start, end, its inclusions' centres and widths) and its surface's gap, all scaled by the
    digit's length over the thesis rig's. A digit of the thesis rig's shape, only longer or shorter, bent to the same
    tip rotation (as :func:`digit_protocol` lays out the sweep) then meets the tissue where the thesis rig does, at
    the same fraction of its length; the thesis rig's tissue is unchanged. The modulus, exponent and damping (the
    tissue's material) are kept: the answer palpation must give back. Before, the built-in soft-block started at
    150 mm on every digit: at the tip of a 0.15 m digit, whose sweep then touched nothing (modulus 30 +- inf)."""
    scale = tissue_scale(params)
    if scale == 1.0:
        return tissue

    def at(x: float) -> float:  # to 0.1 mm: a place a user can read back and write in a file
        return round(scale * x, 4)

    inclusions = tuple(Inclusion(at(i.centre_m), at(i.width_m), i.ratio) for i in tissue.inclusions)
    return tissue.replace(
        start_m=at(tissue.start_m), end_m=at(tissue.end_m), gap_m=at(tissue.gap_m), inclusions=inclusions
    )


def digit_scan(scan: dict, params) -> dict:
    """A built-in scan (``offsets_m``, ``inclusion_width_m``, m; written beside the thesis rig) laid out beside
    ``params``'s digit as :func:`digit_tissue` lays out its tissue: both scaled by :func:`tissue_scale`, to 0.1 mm,
    so the nodule passes along the digit as along the thesis rig's (+-40 mm beside its 0.27 m; +-22.2 mm beside a
    0.15 m digit). The thesis rig's scan is returned unchanged."""
    scale = tissue_scale(params)
    if scale == 1.0:
        return scan
    return {
        **scan,
        "offsets_m": tuple(round(scale * d, 4) for d in scan["offsets_m"]),
        "inclusion_width_m": round(scale * scan["inclusion_width_m"], 4),
    }


#: The least stretch of the digit a tissue must lie beside to be pressed: two of the contact estimator's 1 mm grid
#: steps (the force hold's bound before the sweep shared it).
TISSUE_REACH_M = 2e-3


def check_tissue_reach(tissue: Tissue, params) -> None:
    """Refuse (one line, :class:`~flexdigit.errors.ParameterError`) a tissue that starts at or past ``params``'s
    digit's tip (less than :data:`TISSUE_REACH_M` of it left beside the tissue): no command presses it, and a sweep
    would fit a modulus to nothing (30 +- inf on a 0.15 m digit beside the thesis's 150 mm soft-block)."""
    length = params.geometry.digit_length_m
    if tissue.start_m > length - TISSUE_REACH_M:
        raise ParameterError(
            f"the tissue starts at {1000 * tissue.start_m:g} mm, at or past the digit's {1000 * length:g} mm tip, "
            "where no command presses it; place it along the digit"
        )


def check_sweep_commands(protocol: PalpationProtocol, params, side: str = "cable") -> None:
    """Refuse, in one line, a sweep (or tare) command that bends ``params``'s digit away from a body on ``side`` past
    its straight command: an antagonistic pair bends both ways, and the thesis's 8..30 are 119 commands the wrong way
    of a pair's straight 127. (Below a single cable's straight command its cable is slack: harmless, allowed.)"""
    if params.cables.count != 2:
        towards(params, side)
        return
    straight = int(params.actuator.equilibrium_command)
    sign = towards(params, side)
    away = [c for c in (protocol.tare_command, *protocol.commands) if sign * (c - straight) < 0]
    if away:
        direction = "above" if sign > 0 else "below"
        raise ParameterError(
            f"the sweep's command {away[0]} bends this digit away from the {side}-side tissue: its straight command "
            f"is {straight} and it presses the tissue {direction} it; give 'commands' and 'tare_command' from "
            f"{straight} {direction} (or leave them out: the built-in sweep laid out on the digit)"
        )


@dataclass
class SweepRecord:
    """What a sweep read: every sample, and the plateaus' means.

    Attributes
    ----------
    command : ndarray (m,)
        The command of each plateau (the first and last are the tares).
    time_s : ndarray (m,)
        Mid-time of each plateau's readings (s from the start of the sweep).
    gauges_v : ndarray (m, 3)
        Mean gauge voltages of each plateau's readings.
    tare : ndarray of bool (m,)
        Which plateaus are tares.
    readings : int
        Samples averaged per plateau.
    samples : dict
        Every loop sample: ``time_s``, ``gauges_v``, ``command`` (and ``true_force_n`` on the twin).
    status : str
        The loop's stop status (``completed``, ``fault``, ``interrupted``).
    """

    command: np.ndarray
    time_s: np.ndarray
    gauges_v: np.ndarray
    tare: np.ndarray
    readings: int
    samples: dict = field(default_factory=dict)
    status: str = "completed"
    message: str = ""
    #: why the staircase stopped climbing short of the protocol's top command, in one line ("" when it did not):
    #: a gauge read within :data:`RAIL_MARGIN` of an ADC rail (:class:`_Staircase`)
    capped: str = ""

    __repr__ = fields_summary


#: How near an ADC rail (a fraction of the ADC's span) a gauge may read before a sweep stops climbing: a tenth
#: (1 V of +-5 V) leaves room for the next plateau's ringing; the loop faults a gauge within 1 mV of a rail.
RAIL_MARGIN = 0.10


class _Staircase:
    """A loop controller that sends a scheduled command: the sweep's open-loop staircase. Given ``adc_range_v``
    it reads the gauges too, and stops climbing once one reads within :data:`RAIL_MARGIN` of a rail: the remaining
    climbing plateaus hold that plateau's command (each a repeated reading of it), the closing tare as planned.
    ``sent`` is the command each plateau held, ``capped`` says why it stopped. Before, a digit with one gauge at
    gain 6000 clipped it at +5 V at t = 68 s of its sweep, and the loop's fault ended the palpation."""

    def __init__(self, commands, plateau_s: float, adc_range_v=None) -> None:
        self.commands = list(commands)
        self.sent = list(commands)
        self.plateau_s = plateau_s
        self._t = 0.0
        self._k = 0
        self._range = None if adc_range_v is None else (float(adc_range_v[0]), float(adc_range_v[1]))
        self.cap: int | None = None  # the plateau whose command the climb stopped at
        self.capped = ""

    def reset(self, command: int) -> None:
        self._k = 0

    def step(self, setpoint: float, reading) -> float:
        index = min(int(setpoint // self.plateau_s), len(self.commands) - 1)
        last = len(self.commands) - 1  # the closing tare: always sent
        if self.cap is None and self._range is not None and 0 < index < last:
            self._watch(index, reading)
        if self.cap is not None and self.cap < index < last:
            self.sent[index] = self.sent[self.cap]
        return self.sent[index]

    def _watch(self, index: int, reading) -> None:
        low, high = self._range
        margin = RAIL_MARGIN * (high - low)
        volts = np.asarray(getattr(reading, "gauges_v", ()), dtype=float)
        near = np.flatnonzero((volts >= high - margin) | (volts <= low + margin))
        if near.size:
            g = int(near[0])
            self.cap = index
            self.capped = (
                f"stopped climbing at command {self.sent[index]}: gauge {g + 1} read {volts[g]:+.3f} V, within "
                f"{RAIL_MARGIN:.0%} of the ADC's {low:+g}..{high:+g} V range; the remaining plateaus held it"
            )


def run_sweep(rig, protocol: PalpationProtocol, *, log_path=None, truth=None, log_mode: str = "new") -> SweepRecord:
    """Drive ``rig`` through the protocol's staircase on the real-time loop and average each plateau.

    ``truth`` (the twin): a callable returning the true contact force (N) now, logged beside every sample so a
    study can score the estimate. The rig is left open (at the equilibrium command) for the next sweep.
    ``log_mode``: what to do with an existing ``log_path`` (:func:`~flexdigit.rig.loop.run_loop`: refuse it,
    ``"replace"`` it, ``"append"`` to it).
    """
    sequence = [protocol.tare_command, *protocol.commands, protocol.tare_command]
    stairs = _Staircase(sequence, protocol.plateau_s, adc_range_v=rig.params.sensors.adc_range_v)
    true_force = []
    on_sample = (lambda k, t, y, c: true_force.append(truth())) if truth is not None else None
    result = run_loop(
        rig,
        stairs,
        setpoint=lambda t: t,  # the staircase reads its schedule from the loop time
        duration_s=protocol.duration_s,
        period_s=protocol.period_s,
        log_path=log_path,
        log_mode=log_mode,
        on_sample=on_sample,
        close_rig=False,
        header={"palpation": {"commands": list(protocol.commands), "plateau_s": protocol.plateau_s}},
    )
    result.raise_if_interrupted()  # a stop (Ctrl-C, SIGTERM) ends the sweep and the command, not a rig fault
    if not result.ok:
        raise_from = result.message
        raise RigError(f"palpation sweep stopped: {raise_from}")
    sequence = stairs.sent  # the commands the plateaus held (repeated where the climb stopped short of a rail)
    t = result.time_s
    plateau = np.minimum((t // protocol.plateau_s).astype(int), len(sequence) - 1)
    means, times = [], []
    for j in range(len(sequence)):
        rows = np.flatnonzero(plateau == j)[-protocol.readings :]
        means.append(result.gauges_v[rows].mean(axis=0))
        times.append(float(np.mean(t[rows])))
    samples = {"time_s": t, "gauges_v": result.gauges_v, "command": result.command}
    if truth is not None:
        samples["true_force_n"] = np.array(true_force)
    tare = np.zeros(len(sequence), dtype=bool)
    tare[[0, -1]] = True
    return SweepRecord(
        np.array(sequence), np.array(times), np.array(means), tare, protocol.readings, samples, capped=stairs.capped
    )


# --------------------------------------------------------------------------------------------- the tissue fit
@dataclass
class TissueFit:
    """Maximum-likelihood tissue parameters of one sweep (or scan), with standard deviations (inf: not seen).

    ``offset_v`` / ``drift_v_per_s`` are the nuisance gauge offsets and drifts; ``chi2`` the weighted residual sum
    of squares over ``dof`` degrees of freedom (about ``dof`` when the model explains the readings to their noise);
    ``covariance`` that of the fitted ``(gap_m, ln modulus[, exponent])``, widened as the sds are (None: not fitted).
    """

    tissue: object
    gap_m: float
    gap_sd_m: float
    modulus_n_m2: float
    modulus_sd_n_m2: float
    exponent: float
    exponent_sd: float
    chi2: float
    dof: int
    converged: bool
    offset_v: np.ndarray
    drift_v_per_s: np.ndarray
    extra: dict = field(default_factory=dict)
    covariance: np.ndarray | None = None

    @property
    def stiffness_n_m_per_cm(self) -> float:
        """The modulus as the N/m of one centimetre of digit pressed in."""
        return 0.01 * self.modulus_n_m2

    __repr__ = fields_summary


class _TissueLikelihood:
    """Weighted residuals of the plateaus' gauges under a tissue hypothesis, nuisance offsets and drifts profiled
    out (variable projection: for a given tissue they are a linear least-squares fit per gauge).

    ``walk_v_per_sqrt_s`` (per gauge): the gauges' random-walk drift, whose wander about the fitted line is
    correlated from plateau to plateau: the residuals are then whitened by each gauge's covariance (white noise plus
    ``walk^2 min(t_i, t_j)`` from the first plateau) and the nuisance fitted by generalised least squares. Without it
    (white noise only) a 75 s sweep's walk read as stiffness: the 2 x 65 mm pair's twin sweeps fitted 1155, 970 and
    1111 N/m^2 for 1000 (seeds 0-2), each "+- 29" (5 sd); with the walk's drift off the twin, 1015 +- 19."""

    def __init__(self, model, commands, times, gauges, sigma, tissue_of, nuisance: bool = True, walk_v_per_sqrt_s=None):
        self.model = model
        self.commands = np.asarray(commands, dtype=int)
        self.gauges = np.asarray(gauges, dtype=float)
        self.sigma = np.asarray(sigma, dtype=float)
        t = np.asarray(times, dtype=float)
        span = max(float(np.ptp(t)), 1e-9)
        self.design = np.column_stack([np.ones_like(t), (t - t.mean()) / span]) if nuisance else None
        self._span, self._t0 = span, float(t.mean())
        self.tissue_of = tissue_of
        self.evaluations = 0
        self._shapes: dict[int, np.ndarray] = {}
        self.whiten = None  # per gauge: W with W C W^T = I
        if walk_v_per_sqrt_s is not None and self.design is not None:
            walk = np.broadcast_to(np.asarray(walk_v_per_sqrt_s, dtype=float), (self.gauges.shape[1],))
            sigma = np.broadcast_to(self.sigma, (self.gauges.shape[1],))
            since = t - t.min()
            shared = np.minimum.outer(since, since)
            self.whiten = [
                np.linalg.inv(np.linalg.cholesky(np.diag(np.full(t.size, sd**2)) + rate**2 * shared))
                for sd, rate in zip(sigma, walk, strict=True)
            ]

    def _gls(self, r):
        """Per gauge: the whitened residual after the GLS nuisance fit, and the nuisance's coefficients."""
        out, coefs = np.empty_like(r), []
        for g, w in enumerate(self.whiten):
            design, rw = w @ self.design, w @ r[:, g]
            coef, *_ = np.linalg.lstsq(design, rw, rcond=None)
            out[:, g] = rw - design @ coef
            coefs.append(coef)
        return out, np.array(coefs).T

    def predict(self, theta):
        self.evaluations += 1
        tissues = self.tissue_of(theta)
        blocks = [(slice(None), tissues)] if not isinstance(tissues, list) else tissues  # a scan: one per offset
        out = np.empty_like(self.gauges)
        for i, (rows, tissue) in enumerate(blocks):
            # each evaluation starts from the last one's shapes: the fit's steps and differences move them little
            sol, out[rows] = self.model.tissue_solution(tissue, self.commands[rows], psi0=self._shapes.get(i))
            if sol.static.converged:
                self._shapes[i] = sol.static.psi_rad
        return out

    def residuals(self, theta):
        r = self.gauges - self.predict(theta)
        if self.whiten is not None:
            return self._gls(r)[0].ravel()
        if self.design is not None:
            coef, *_ = np.linalg.lstsq(self.design, r, rcond=None)
            r = r - self.design @ coef
        return (r / self.sigma).ravel()

    def nuisance(self, theta):
        r = self.gauges - self.predict(theta)
        if self.design is None:
            return np.zeros(3), np.zeros(3)
        if self.whiten is not None:
            coef = self._gls(r)[1]
        else:
            coef, *_ = np.linalg.lstsq(self.design, r, rcond=None)
        return coef[0] - coef[1] * self._t0 / self._span, coef[1] / self._span


def _least_squares(likelihood, x0, lower, upper, scale):
    from scipy.optimize import least_squares

    sol = least_squares(
        likelihood.residuals, x0, bounds=(lower, upper), x_scale=scale, diff_step=1e-4, xtol=1e-10, ftol=1e-12
    )
    cov = _covariance(sol.jac)
    return sol, np.sqrt(np.where(np.diag(cov) > 0, np.diag(cov), np.inf))


def _covariance(jac) -> np.ndarray:
    """The Gauss-Newton covariance ``(J^T J)^-1`` of whitened residuals' Jacobian ``jac``; inf where singular."""
    with np.errstate(divide="ignore", invalid="ignore"):
        try:
            return np.linalg.inv(jac.T @ jac)
        except np.linalg.LinAlgError:
            return np.full((jac.shape[1], jac.shape[1]), np.inf)


#: Terms of the quantisation bias's Fourier series summed (:func:`quantisation_bias_v`): those left out weigh under
#: 1e-3 of the sum at no noise (sum over k > 1000 of 1/k^2 against pi^2/6), less with noise.
QUANTISATION_TERMS = 1000


def quantisation_bias_v(noise_v, step_v: float) -> np.ndarray:
    """The rms (V) of the part of an ADC's quantisation error that averaging readings does not remove: the mean of
    many readings of a level ``x`` with Gaussian noise ``noise_v`` before a quantiser of step ``step_v`` is off by
    ``b(x) = sum_k (step / (pi k)) (-1)^k exp(-2 pi^2 k^2 sigma^2 / step^2) sin(2 pi k x / step)`` (Widrow and
    Kollar, *Quantization Noise*, Cambridge 2008, ch. 19: the Fourier series of the rounding error smoothed by the
    noise); its rms over levels is ``sqrt(sum_k step^2 / (2 pi^2 k^2) exp(-4 pi^2 k^2 sigma^2 / step^2))``.
    ``step / sqrt(12)`` with no noise (every reading rounds alike), nothing once the noise spans a step: 0 to
    machine precision on the thesis rig (2 mV of noise, 0.15 mV steps), 1.4 mV on a 10-bit +-2.5 V ADC whose 0.1 mV
    of noise never dithers its 4.9 mV steps."""
    sigma = np.asarray(noise_v, dtype=float)
    k = np.arange(1, QUANTISATION_TERMS + 1)[:, None]
    terms = step_v**2 / (2 * math.pi**2 * k**2) * np.exp(-4 * math.pi**2 * k**2 * sigma[None, :] ** 2 / step_v**2)
    return np.sqrt(terms.sum(axis=0))


def plateau_sigma_v(model, readings: int) -> np.ndarray:
    """The standard deviation (V, per gauge) of one plateau's mean of ``readings`` readings: the gauges' white noise
    averaged down, and the ADC's quantisation bias that no averaging removes (:func:`quantisation_bias_v`; without
    it a 10-bit digit's sweep, 0.1 mV of noise on 4.9 mV steps, fitted chi2/dof 1500). The thesis rig's: its noise
    over sqrt(readings), unchanged to the last bit (np.hypot with 0)."""
    averaged = np.asarray(model.noise_v, dtype=float) / math.sqrt(readings)
    return np.hypot(averaged, quantisation_bias_v(model.noise_v, model.params.sensors.adc_lsb_v))


def fit_tissue(
    record: SweepRecord,
    model,
    placed,
    *,
    fit_exponent: bool = False,
    sigma_v=None,
    start=None,
    drift: bool = False,
) -> TissueFit:
    """Fit a tissue's gap and modulus (and Hunt-Crossley exponent) to a sweep's plateaus (module docstring).

    The standard deviations are the fit's (Gauss-Newton) widened by ``sqrt(chi2 / dof)`` when the readings scatter
    about the model more than their noise says.

    Parameters
    ----------
    record : SweepRecord
    model : ContactGaugeModel
        The digit's static model (the twin's, or a real rig's calibrated one).
    placed : Tissue
        Where the tissue lies (``start_m``, ``end_m``, ``side``, inclusions known as ratios): its ``gap_m`` and
        ``modulus_n_m2`` are only used to name the answer's type, never as a starting point.
    fit_exponent : bool
        Fit Hunt-Crossley's ``n`` too (the "hunt-crossley" model).
    sigma_v : array_like, optional
        Noise of one plateau mean per gauge (V); default the model's white noise over ``record.readings``.
    start : TissueFit, optional
        Start from this fit's gap and modulus (a neighbouring sweep's) instead of a coarse grid search.
    drift : bool
        Weigh the gauges' random-walk drift (the calibration's ``noise_drift_v_per_sqrt_s``) in the likelihood
        (:class:`_TissueLikelihood`): the modulus and its sd honest over a long sweep (``flexdigit palpate``). Off,
        white noise only, as the report's studies have always fitted.
    """
    sigma = plateau_sigma_v(model, record.readings) if sigma_v is None else sigma_v
    like = _TissueLikelihood(
        model,
        record.command,
        record.time_s,
        record.gauges_v,
        sigma,
        lambda th: placed.replace(gap_m=th[0], modulus_n_m2=math.exp(th[1]), exponent=th[2] if fit_exponent else 1.0),
        walk_v_per_sqrt_s=_walk(model) if drift else None,
    )
    if start is None:
        x0 = _start(like, model, placed, record.command, fit_exponent)
    else:
        x0 = np.array([start.gap_m, math.log(start.modulus_n_m2)] + ([start.exponent] if fit_exponent else []))
    lower = [-0.05, math.log(1.0)] + ([1.0] if fit_exponent else [])
    upper = [0.3, math.log(1e7)] + ([3.0] if fit_exponent else [])
    sol, sd = _least_squares(like, x0, lower, upper, [1e-3, 0.1] + ([0.1] if fit_exponent else []))
    gap, k = float(sol.x[0]), math.exp(float(sol.x[1]))
    n = float(sol.x[2]) if fit_exponent else 1.0
    # the offsets and drifts reported (and taken off the force-indentation curve): the straight line through the
    # plateaus' residuals that the two tares pin, as without the walk (its GLS line left the thesis rig's first
    # contact plateaus 4-5 mN off the twin's force)
    like.whiten = None
    offset, drift = like.nuisance(sol.x)
    # an offset and a drift per gauge (G of them: it counted 3 on every digit)
    nuisances = like.design.shape[1] * like.gauges.shape[1] if like.design is not None else 0
    dof = like.gauges.size - sol.x.size - nuisances
    # readings the model explains worse than their noise (ringing, drift, a model error) widen the uncertainty
    widen = max(1.0, 2 * sol.cost / max(dof, 1))
    sd = sd * math.sqrt(widen)
    return TissueFit(
        tissue=placed.replace(gap_m=gap, modulus_n_m2=k, exponent=n),
        gap_m=gap,
        gap_sd_m=float(sd[0]),
        modulus_n_m2=k,
        modulus_sd_n_m2=float(k * sd[1]),
        exponent=n,
        exponent_sd=float(sd[2]) if fit_exponent else 0.0,
        chi2=float(2 * sol.cost),
        dof=int(dof),
        converged=bool(sol.success),
        offset_v=offset,
        drift_v_per_s=drift,
        extra={"evaluations": like.evaluations},
        covariance=_covariance(sol.jac) * widen,
    )


def _walk(model) -> np.ndarray:
    """The gauges' random-walk drift (V / sqrt(s)) of ``model``'s calibration."""
    return np.asarray(model.calibration.noise_drift_v_per_sqrt_s, dtype=float)


def _start(like, model, placed, commands, fit_exponent):
    """A starting point from a coarse grid: gaps where the free digit's deepest point in the tissue's stretch
    would meet it at each plateau, moduli log-spaced 30..3e5 N/m^2."""
    free = model.tissue_solution(Tissue(placed.start_m, placed.end_m, 1.0, 0.0, side=placed.side), commands)[0]
    chain = model.chain
    s = np.linspace(0.0, chain.length_m, 55)
    pos = chain.positions(free.static.psi_rad, s)  # (m, 55, 2)
    inside = (pos[..., 0] >= placed.start_m) & (pos[..., 0] <= placed.end_m)
    reach = np.where(inside, placed.sign * pos[..., 1], -np.inf).max(axis=1)
    gaps = np.unique(np.round(reach[np.isfinite(reach)], 5))
    if gaps.size == 0:
        raise ParameterError(
            f"The tissue from {placed.start_m:g} to {placed.end_m:g} m is nowhere beside the digit during the sweep: "
            "check 'start_mm' and 'end_mm'."
        )
    gaps = np.quantile(gaps, np.linspace(0.05, 0.95, 7))
    best, x0 = np.inf, None
    for g in gaps:
        for logk in np.log([30.0, 300.0, 3000.0, 3e4, 3e5]):
            th = np.array([g, logk] + ([1.0] if fit_exponent else []))
            cost = float(np.sum(like.residuals(th) ** 2))
            if cost < best:
                best, x0 = cost, th
    return x0


def stiffness_bound(
    model, tissue, protocol: PalpationProtocol, *, fit_exponent: bool = False, drift: bool = False
) -> dict:
    """Cramer-Rao standard deviations of the gap (m), modulus (N/m^2) and exponent from one sweep of
    ``protocol`` on ``tissue``, with the gauges' white noise over ``readings`` and the nuisance offsets and drifts
    estimated as the fit does."""
    commands = [protocol.tare_command, *protocol.commands, protocol.tare_command]
    times = protocol.plateau_s * (np.arange(len(commands)) + 0.5)
    times[-1] += protocol.return_settle_s
    sigma = plateau_sigma_v(model, protocol.readings)
    clean = model.tissue_solution(tissue, commands)[1]
    like = _TissueLikelihood(
        model,
        commands,
        times,
        clean,
        sigma,
        lambda th: tissue.replace(gap_m=th[0], modulus_n_m2=math.exp(th[1]), exponent=th[2] if fit_exponent else 1.0),
        walk_v_per_sqrt_s=_walk(model) if drift else None,
    )
    theta = np.array([tissue.gap_m, math.log(tissue.modulus_n_m2)] + ([tissue.exponent] if fit_exponent else []))
    steps = np.array([1e-5, 1e-3] + ([1e-3] if fit_exponent else []))
    jac = np.stack(
        [
            (like.residuals(theta + d) - like.residuals(theta - d)) / (2 * h)
            for d, h in zip(np.diag(steps), steps, strict=True)
        ],
        axis=1,
    )
    sd = np.sqrt(np.diag(np.linalg.inv(jac.T @ jac)))
    out = {"gap_m": float(sd[0]), "modulus_n_m2": float(sd[1] * tissue.modulus_n_m2)}
    if fit_exponent:
        out["exponent"] = float(sd[2])
    return out


# -------------------------------------------------------------------------------------------------- palpate
@dataclass
class PalpationResult:
    """One palpation: the fit, the force-indentation curve, the lumped stiffness.

    ``curve`` holds per sweep plateau (tares excluded): ``command``, ``force_n`` and ``force_sd_n`` (from the
    gauges alone, the contact force pressing the digit back, > 0; NaN where no force is read), ``force_read``
    (bool: a contact seen, its sd finite and under the force), ``indentation_m`` (deepest penetration of the
    fitted tissue), ``model_force_n`` (the fitted tissue's force) and, on the twin, ``true_force_n``.
    """

    protocol: PalpationProtocol
    placed: object
    fit: TissueFit
    curve: dict
    lumped_stiffness_n_m: float
    lumped_stiffness_sd_n_m: float
    record: SweepRecord

    def summary(self) -> dict:
        f = self.fit
        return {
            "model": self.protocol.model,
            "gap_mm": 1000 * f.gap_m,
            "gap_sd_mm": 1000 * f.gap_sd_m,
            "modulus_n_m2": f.modulus_n_m2,
            "modulus_sd_n_m2": f.modulus_sd_n_m2,
            "stiffness_n_m_per_cm": f.stiffness_n_m_per_cm,
            "exponent": f.exponent,
            "exponent_sd": f.exponent_sd,
            "lumped_stiffness_n_m": self.lumped_stiffness_n_m,
            "lumped_stiffness_sd_n_m": self.lumped_stiffness_sd_n_m,
            "chi2_per_dof": f.chi2 / max(f.dof, 1),
            "converged": f.converged,
        }

    __repr__ = fields_summary


def analyse(
    record: SweepRecord, placed, protocol: PalpationProtocol, model, estimator=None, *, drift: bool = False
) -> PalpationResult:
    """Turn a sweep into a palpation result: the tissue fit, the force-indentation curve and its slope.

    The curve's ``force_n`` is NaN ("no force read", ``force_read`` False) where the gauges read no force: the
    estimator saw no contact, or its standard deviation is infinite or over the value (:func:`_force_read`). The
    lumped slope's sd carries the fit's (:func:`_lumped_fit_sd`); with ``drift``, each force's sd the gauges' walk
    about the fitted line (:func:`_walk_widening`).
    """
    fit = fit_tissue(record, model, placed, fit_exponent=protocol.model == "hunt-crossley", drift=drift)
    sweep = ~record.tare
    cmds = record.command[sweep]
    if estimator is None:
        estimator = ContactEstimator(
            model, classify=False, n_readings=record.readings, side=placed.side, region_m=_tissue_region(model, placed)
        ).fit()
    # the fit's offsets and drifts at each plateau's time, taken off before the force is estimated
    nuisance = fit.offset_v + np.outer(record.time_s, fit.drift_v_per_s)
    est = estimator.predict(record.gauges_v[sweep] - nuisance[sweep], cmds)
    sol, _ = model.tissue_solution(fit.tissue, cmds)
    depth = _deepest(model, fit.tissue, sol.static.psi_rad)
    read = _force_read(est)
    # one gauge reads one number, the force times its lever: no force from the gauges alone (its Cramer-Rao sd is
    # infinite at every plateau; it read 0.95 N where the twin pressed 0.22 N)
    told = np.full(cmds.size, len(model.params.geometry.gauge_positions_m) > 1)
    read &= told
    force = np.where(read, -placed.sign * est.point_force_n, np.nan)  # the tissue pushes back: a positive force
    curve = {
        "command": cmds,
        "force_n": force,
        "force_sd_n": np.where(read, est.force_sd_n, np.nan),
        "force_read": read,
        "indentation_m": depth,
        "model_force_n": -placed.sign * sol.contact_force_n,
    }
    if "true_force_n" in record.samples:
        curve["true_force_n"] = _plateau_truth(record, protocol)[sweep]
    if not np.all(told):
        curve["force_refused"] = (
            "one gauge reads one number, the contact's force times its lever (infinite Cramer-Rao sd): no force "
            "from the gauges alone (model_force_n is the fitted tissue's, its place known)"
        )
    touching = (depth > 0) & read
    slope, slope_sd = _lumped_slope(depth, force, curve["force_sd_n"], touching)
    slope_sd = math.hypot(slope_sd, _lumped_fit_sd(model, fit, cmds, curve["force_sd_n"], touching))
    if drift:  # each force also carries the gauges' walk about the fitted line (the slope weighs by white noise)
        white = np.asarray(model.noise_v, dtype=float) / math.sqrt(record.readings)
        curve["force_sd_n"] = curve["force_sd_n"] * _walk_widening(record.time_s, _walk(model), white)[sweep]
    return PalpationResult(protocol, placed, fit, curve, slope, slope_sd, record)


def _walk_widening(times, walk, white) -> np.ndarray:
    """Per plateau, how much the gauges' random walk (``walk``, V / sqrt(s) per gauge) widens one plateau's white
    noise (``white``, V per gauge) once the fitted straight line (an offset and a drift per gauge, least squares
    through every plateau) is taken off: ``sqrt(1 + mean_g (walk_g / white_g)^2 [P M P]_ii)``, ``M_ij = min(t_i, t_j)``
    from the first plateau, ``P`` the line's residual projector. Exact for a force read from gauges whose walk and
    white noise are in one ratio (a digit's default calibration); their mean ratio otherwise."""
    t = np.asarray(times, dtype=float)
    since = t - t.min()
    design = np.column_stack([np.ones_like(t), t - t.mean()])
    residual = np.eye(t.size) - design @ np.linalg.pinv(design)
    shared = np.diag(residual @ np.minimum.outer(since, since) @ residual)
    ratio = float(np.mean((np.asarray(walk, dtype=float) / np.asarray(white, dtype=float)) ** 2))
    return np.sqrt(1.0 + ratio * shared)


def _tissue_region(model, placed) -> tuple[float, float]:
    """Arc positions (m) where the tissue can touch the digit: from where it starts (a bent digit's arc position
    is past its point's distance along the tissue) to the tip. The whole digit let a few millivolts of mismatch
    read as a large force near the clamp, where the gauges barely see one (0.57 N at no contact, 4-gauge digit)."""
    step = 2e-3  # two of the estimator's default grid steps: the least region it takes
    return min(max(float(placed.start_m), 0.0), model.length_m - step), model.length_m


def _force_read(est) -> np.ndarray:
    """Plateaus where the gauges read a force: a contact seen (its likelihood ratio over the estimator's
    threshold) and a finite standard deviation no larger than the force. Elsewhere the point estimate is the
    profile's clip (``max_force_n``, 1 N, where the gauges are blind to a force) or noise: no force read."""
    force, sd = np.abs(est.point_force_n), est.force_sd_n
    with np.errstate(invalid="ignore"):
        return est.contact & np.isfinite(sd) & np.isfinite(force) & (sd <= force)


def _lumped_slope(depth, force, force_sd, touching) -> tuple[float, float]:
    """Weighted least-squares slope through the origin of force against indentation (N/m) and its sd, on the
    plateaus ``touching`` (NaN, inf with fewer than two)."""
    w = 1.0 / np.maximum(force_sd[touching], 1e-12) ** 2
    x, y = depth[touching], force[touching]
    information = float(np.sum(w * x * x))
    if np.count_nonzero(touching) >= 2 and information > 0:
        return float(np.sum(w * x * y) / information), float(1.0 / math.sqrt(information))
    return math.nan, math.inf


#: Central-difference steps of the fitted (gap (m), ln modulus, exponent) for the lumped slope's sensitivity: the
#: stiffness bound's steps (:func:`stiffness_bound`).
LUMPED_STEPS = (1e-5, 1e-3, 1e-3)


def _lumped_fit_sd(model, fit: TissueFit, commands, force_sd, touching) -> float:
    """The lumped slope's sd (N/m) from the fit's uncertain gap and modulus (delta method: the fitted tissue's own
    force-against-depth slope, with the measured slope's plateaus and weights, differentiated in the fitted
    parameters, through their covariance). Every plateau's depth comes from the fitted gap and its force from the
    gauges less the fitted drift: one error shared by all, which the forces' scatter alone leaves out (it claimed
    0.02 N/m where two_sections_half's seeds 0-9 scattered 0.35; the modulus sd honest there)."""
    if np.count_nonzero(touching) < 2:
        return math.inf
    cov = fit.covariance
    if cov is None or not np.all(np.isfinite(cov)):
        return math.inf
    weights = 1.0 / np.maximum(force_sd[touching], 1e-12) ** 2
    theta = np.array([fit.gap_m, math.log(fit.modulus_n_m2), fit.exponent][: cov.shape[0]])

    def slope(th) -> float:
        tissue = fit.tissue.replace(gap_m=th[0], modulus_n_m2=math.exp(th[1]), exponent=th[2] if th.size > 2 else 1.0)
        sol, _ = model.tissue_solution(tissue, commands)
        depth = _deepest(model, tissue, sol.static.psi_rad)[touching]
        force = -tissue.sign * sol.contact_force_n[touching]
        return float(np.sum(weights * depth * force) / max(float(np.sum(weights * depth**2)), 1e-300))

    steps = np.array(LUMPED_STEPS[: theta.size])
    pairs = zip(np.diag(steps), steps, strict=True)
    grad = np.array([(slope(theta + d) - slope(theta - d)) / (2 * h) for d, h in pairs])
    variance = float(grad @ cov @ grad)
    return math.sqrt(variance) if variance >= 0 else math.inf


def _deepest(model, tissue, psi) -> np.ndarray:
    """Deepest penetration (m) of the digit into the tissue at each state (0 when clear)."""
    _, _, delta, _, _ = TissueContact(model.chain, tissue).points(psi)
    return delta.max(axis=1, initial=0.0) if delta.size else np.zeros(psi.shape[0])


def _plateau_truth(record: SweepRecord, protocol: PalpationProtocol) -> np.ndarray:
    t = record.samples["time_s"]
    plateau = np.minimum((t // protocol.plateau_s).astype(int), len(record.command) - 1)
    truth = record.samples["true_force_n"]
    return np.array(
        [truth[np.flatnonzero(plateau == j)[-record.readings :]].mean() for j in range(len(record.command))]
    )


def palpate(
    rig,
    placed,
    protocol: PalpationProtocol | None = None,
    *,
    model=None,
    log_path=None,
    log_mode: str = "new",
    drift: bool = False,
) -> PalpationResult:
    """Run a palpation on ``rig`` with the tissue ``placed`` beside the digit (:func:`run_sweep`, :func:`analyse`).

    On the twin the tissue is put there (``rig.place_tissue``) and the true contact force is logged beside each
    sample; on hardware the operator is asked to place it. ``drift``: weigh the gauges' random-walk drift in the fit
    (:func:`fit_tissue`).
    """
    protocol = protocol or PalpationProtocol()
    model = model or rig_contact_model(rig)
    rig.place_tissue(placed)
    truth = _truth_of(rig)
    record = run_sweep(rig, protocol, log_path=log_path, truth=truth, log_mode=log_mode)
    return analyse(record, placed, protocol, model, drift=drift)


#: The twin's steps a sweep or scan on a digit tries, coarsest first (divisors of the loop's 20 ms period).
SWEEP_STEPS_S = (0.005, 0.0025, 0.00125)
#: How far (a share of one plateau mean's white noise, 20 readings) the resting gauges may read apart at a step and
#: at half of it before :func:`twin_step_s` takes the finer one.
STEP_AGREEMENT = 0.1


def twin_step_s(kind: str, params=None, calibration=None, orientation: str = "vertical") -> float:
    """The twin's integration step (s) for a palpation on the sim backend: ``kind`` "force" (a hold: the loop acts
    between frames) 5 ms; "sweep" or "scan" (quasi-static plateaus) 10 ms on the thesis rig (the fit's chi^2 the same
    at 2 ms); on any other digit the coarsest of :data:`SWEEP_STEPS_S` at which its twin rests as at half that step
    (:func:`_resting_step`). At 10 ms the 2 x 0.10 m four-gauge example digit's barely taut cable chatters at the
    first command past straight (a 33 Hz limit cycle: 1.6-4 mV on the gauges read as a 3 mN contact where nothing
    touches); at 5 ms the 0.11 m one-section nitinol digit's chatters back at straight (12 mV, the sweep's tares
    180 sd apart: chi2/dof 1975), at 2.5 ms it rests. ``calibration`` (default the digit's) and ``orientation``: the
    twin's, as the sim backend builds it."""
    if kind == "force":
        return 0.005
    if params is None or params.is_thesis_rig():
        return 0.01
    return _resting_step(params, calibration or twin_calibration(params), orientation)


@lru_cache(maxsize=8)
def _resting_step(params, calibration, orientation: str) -> float:
    """The coarsest of :data:`SWEEP_STEPS_S` whose noise-free twin, stepped one command past straight and back, reads
    the means of a plateau's last 20 readings (each end) within :data:`STEP_AGREEMENT` of a plateau's noise of those
    at half the step: the twin's own step-size error, the one a palpation's plateaus would read as contact."""
    quiet = (0.0,) * len(calibration.noise_white_v)
    calibration_quiet = calibration.replace(noise_white_v=quiet, noise_drift_v_per_sqrt_s=quiet)
    tolerance = STEP_AGREEMENT * np.asarray(calibration.noise_white_v, dtype=float) / math.sqrt(20)
    for step in SWEEP_STEPS_S:
        coarse, fine = (_rest_means(params, calibration_quiet, orientation, h) for h in (step, step / 2))
        if np.all(np.abs(coarse - fine) <= tolerance):
            return step
    return SWEEP_STEPS_S[-1] / 2


def _rest_means(params, calibration, orientation: str, step_s: float) -> np.ndarray:
    """Means (V, (2, G)) of the last 20 of 20 ms clean readings of the twin at step ``step_s``, 2.5 s (the thesis's
    settling) at one command past straight, then 2.5 s back at straight."""
    twin = Twin(params, calibration, orientation=orientation, dt_s=step_s)
    straight = int(params.actuator.equilibrium_command)
    means = []
    for command in (min(straight + 1, int(params.actuator.command_max)), straight):
        twin.command(command)
        twin.advance(2.1)
        readings = []
        for _ in range(20):
            twin.advance(0.02)
            readings.append(twin.clean_read()[0])
        means.append(np.mean(readings, axis=0))
    return np.array(means)


#: The thesis rig's force loop (:func:`hold_force`): integral gain (commands / s / N) and approach rate
#: (commands / s), and what they were chosen on: the soft block (1000 N/m^2) 30 mm beside 0.15-0.35 m, 0.1 N.
THESIS_FORCE_GAIN = 30.0
THESIS_APPROACH_RATE = 4.0
_THESIS_FORCE_TISSUE = (0.15, 0.35, 0.03, 1000.0)


def force_per_command(model, tissue: Tissue, setpoint_n: float) -> float:
    """The contact force a command adds where the statics of ``model`` first press ``setpoint_n`` (N) into
    ``tissue`` (N per command, the loop's plant gain at its setpoint), from the digit's straight command up its
    thesis range (:func:`_press_commands`); NaN if it never presses that hard there."""
    commands = _press_commands(model.params)
    force = np.abs(model.tissue_solution(tissue, commands)[0].contact_force_n)
    reached = np.flatnonzero(force >= setpoint_n)
    if not reached.size or reached[0] == 0:
        return math.nan
    k = int(reached[0])
    return float(force[k] - force[k - 1])


def _press_commands(params) -> np.ndarray:
    """The commands force control may press with: the thesis rig's 8..60 laid out on the digit, from its straight
    command up as far in tip rotation (:func:`digit_command`: 52 commands x its gearing on a copy of the thesis
    rig; before, 52 x the gearing on any digit, 11 deg of tip on a 0.31 deg servo that never reached the tissue)."""
    eq = int(params.actuator.equilibrium_command)
    return np.arange(eq, digit_command(params, THESIS_STRAIGHT + 52) + 1)


@lru_cache(maxsize=1)
def _thesis_force_per_command() -> float:
    # the thesis rig's own description and packaged calibration, not the defaults: inside `reproduce --params` the
    # default calibration is the user's digit's (another section count), and this value is cached once
    thesis = ContactGaugeModel(RigParams(), packaged_calibration())
    return force_per_command(thesis, Tissue(*_THESIS_FORCE_TISSUE), 0.1)


def force_gains(model, setpoint_n: float = 0.1, *, region_m=None, side: str = "cable") -> dict:
    """The force loop's gains derived from the digit of ``model``: ``{"gain", "approach_rate", "force_per_command_n"}``.

    The thesis rig's integral gain (:data:`THESIS_FORCE_GAIN`) put the loop's crossover, gain x the force a command
    presses, at ~0.8 rad/s, well below the digit's lightly damped mode. A digit whose command presses less (a long
    or geared digit: its 0.5 m five-section one 0.011 N a command against the thesis rig's 0.027; a 4:1 gearing
    0.0068) was held by that gain 4 times slower, still pressing 23 % short after 8 s. The gain here keeps the
    thesis's crossover: ``30 x k_thesis / k_digit``, to three figures (30 on the thesis rig), ``k`` the force per
    command where the statics first press ``setpoint_n`` into the thesis's soft block laid out beside the digit's
    ``region_m`` as beside the thesis rig's (from its start to 80 mm past its end, 30 mm x L / 0.27 m away; the
    digit's outer 45 % without a region; a real tissue's stiffness is as unknown to the loop on the thesis rig).
    The approach rate turns the tip as fast as the thesis's 4 commands per second (x :func:`command_scale`: the
    gearing on a geared copy of the thesis rig).
    """
    k = force_per_command(model, _reference_tissue(model, region_m, side), setpoint_n)
    if not k > 0:  # never presses the setpoint there: the thesis rig's rates per turn of the pulley
        k = _thesis_force_per_command() / command_scale(model.params)
    gain = float(f"{THESIS_FORCE_GAIN * _thesis_force_per_command() / k:.3g}")
    return {
        "gain": gain,
        "approach_rate": THESIS_APPROACH_RATE * command_scale(model.params),
        "force_per_command_n": k,
    }


def _reference_tissue(model, region_m=None, side: str = "cable") -> Tissue:
    """The thesis's soft block laid out beside ``region_m`` as beside the thesis rig's (from its start to 80 mm past
    its end, 30 mm x L / 0.27 m away; the digit's outer 45 % without a region): the body the loop's design presses
    (:func:`force_gains`, :func:`lone_step_ring`), a real tissue's stiffness being unknown to it."""
    length = float(model.params.geometry.digit_length_m)
    start, end = (0.55 * length, length) if region_m is None else (float(region_m[0]), float(region_m[1]))
    return Tissue(start, end + 0.08, 0.03 * length / 0.27, _THESIS_FORCE_TISSUE[3], side=side)


#: How long (s) :func:`lone_step_ring` records the contact force after its one-frame step: 1.5 of the thesis rig's
#: first-mode time constants (1.12 s), the slow hand-made digits' ring (cfrp_strip_four's 6.8 Hz in contact) peaking
#: within 0.2 s.
RING_RECORD_S = 1.5
#: The twin's step (s) for :func:`lone_step_ring`: a hold's (:func:`twin_step_s`).
RING_STEP_S = 0.005


def lone_step_response(model, setpoint_n: float = 0.1, *, region_m=None, side: str = "cable") -> np.ndarray:
    """The contact force's departure (N, per :data:`RING_STEP_S`, over :data:`RING_RECORD_S`) after one lone
    one-frame command step of ``model``'s digit pressing ``setpoint_n`` into the reference body
    (:func:`_reference_tissue`), on its twin (noise-free, the serial drive); empty where it never presses that hard,
    or where the twin does not rest there within :data:`RING_BAND` of the statics' force (seven_sections_450mm: its
    twin's statics unconverged, the contact bouncing 0-0.95 N, read before as a 1.08 N ring).

    The twin rests pressing at the first command whose statics press ``setpoint_n`` (:func:`_press_commands`), is
    sent the next command for one loop period and that command again. What the force loop's sigma-delta sends where
    the command the force needs sits near an integer: that integer with such a step every few frames."""
    tissue = _reference_tissue(model, region_m, side)
    commands = _press_commands(model.params)
    force = np.abs(model.tissue_solution(tissue, commands)[0].contact_force_n)
    reached = np.flatnonzero(force >= setpoint_n)
    if not reached.size or int(commands[reached[0]]) >= int(model.params.actuator.command_max):
        return np.zeros(0)
    command = int(commands[reached[0]])
    twin = Twin(model.params, model.calibration, orientation=model.orientation, housing=model.housing,
                dt_s=RING_STEP_S, command=command)  # fmt: skip
    twin.set_tissue(tissue, settle=True)
    rest = twin.contact_state()[0]
    if not abs(abs(rest) - force[reached[0]]) <= RING_BAND * setpoint_n:  # its statics unconverged: no rest to ring
        return np.zeros(0)
    period = float(model.params.actuator.serial_period_s)
    twin.command(command + 1)
    twin.advance(period)
    twin.command(command)
    ring = []
    for _ in range(round(RING_RECORD_S / RING_STEP_S)):
        twin.advance(RING_STEP_S)
        ring.append(abs(twin.contact_state()[0]) - abs(rest))
    return np.array(ring)


#: A hold whose lone one-frame step rings the contact force more than this share of its setpoint (the issue's 10 %
#: band) sends the integer near the command it needs (:func:`quantiser_band`).
RING_BAND = 0.10
#: The force error (share of the setpoint) a hold accepts from sending an integer command instead of toggling: half
#: the 10 % band, the other half left to the noise and the ring of the steps it still makes.
INTEGER_FORCE_SHARE = 0.05


def quantiser_band(model, setpoint_n: float = 0.1, *, region_m=None, side: str = "cable") -> dict:
    """How the force loop rounds its command on ``model``'s digit: ``{"lone_step_ring_n", "integer_band"}``.

    ``integer_band`` (commands, :class:`ForceController`): where one lone one-frame command step rings the contact
    force by more than :data:`RING_BAND` of the setpoint (:func:`lone_step_ring`, on the twin), the loop sends the
    integer within ``INTEGER_FORCE_SHARE x setpoint / k`` of its continuous command (``k`` the force a command presses,
    :func:`force_per_command`: that integer's force within half the band), never more than 0.5; 0 elsewhere. The
    sigma-delta sends such a step every ``1 / (u - n)`` frames where the command sits near an integer
    (cfrp_strip_four: 19, a 20 one frame in 25, its hold 26.5 % over). The thesis rig keeps its sigma-delta and its
    report's entries (``integer_band`` 0, its ring not measured): its step rings 16 mN at 0.1 N too, but its command
    sits where the sigma-delta toggles at a duty of ~0.75 and its hold overshoots 2.4-4.6 %.
    """
    if model.params.digit_only() == RigParams():
        return {"lone_step_ring_n": math.nan, "integer_band": 0.0}
    ring = lone_step_ring(model, setpoint_n, region_m=region_m, side=side)
    k = force_per_command(model, _reference_tissue(model, region_m, side), setpoint_n)
    band = min(0.5, INTEGER_FORCE_SHARE * setpoint_n / k) if ring > RING_BAND * setpoint_n and k > 0 else 0.0
    return {"lone_step_ring_n": ring, "integer_band": float(band)}


def lone_step_ring(model, setpoint_n: float = 0.1, *, region_m=None, side: str = "cable") -> float:
    """How far (N) one lone one-frame command step rings the contact force (:func:`lone_step_response`'s largest
    departure; NaN where the digit never presses ``setpoint_n``). The thesis rig: 16 mN at 0.1 N; cfrp_strip_four:
    24 mN (its hold's 26.5 % overshoot under the sigma-delta); coarse_step_big_pulley 47 mN."""
    response = lone_step_response(model, setpoint_n, region_m=region_m, side=side)
    return float(np.max(np.abs(response))) if response.size else math.nan


#: :func:`hold_coarseness` looks for the least setpoint it holds within the band over at most this many presses.
COARSE_SEARCH_STEPS = 6


def hold_coarseness(model, setpoint_n: float = 0.1, *, region_m=None, side: str = "cable") -> dict:
    """Whether ``model``'s digit's command is too coarse to hold ``setpoint_n`` (N) within the 10 % band, before it
    presses: ``{"lone_step_ring_n", "force_per_command_n", "past_setpoint_n", "coarse", "least_setpoint_n",
    "note"}``.

    Where the command the force needs sits between two integers, the sigma-delta sends the integer under it with a
    lone one-frame step up every ``1 / e`` frames (``e`` its fraction), each ringing the contact force by
    :func:`lone_step_ring` above that integer's force, ``e x k`` under the setpoint (``k``,
    :func:`force_per_command`). Past half a command the steps turn into a toggle, no longer lone: so wherever the
    command sits (the tissue unknown before the press), a lone step rings the force past the setpoint by at least
    ``past_setpoint_n = ring - k / 2``. ``coarse`` where that exceeds :data:`RING_BAND` of the setpoint: no tissue
    lets the hold stay within 10 %. ``least_setpoint_n`` (2 figures, rounded up): the least setpoint whose
    ``past_setpoint_n`` is within the band (the measure again at each setpoint tried, at most
    :data:`COARSE_SEARCH_STEPS`; NaN where it is never met below the digit's last command); ``setpoint_n`` itself
    where not ``coarse``. ``note``: the warning in one line ("" where not coarse). NaN figures where the ring is not
    measured (the digit never presses ``setpoint_n``, or its twin does not rest on the reference body).

    A bound, not a forecast: where the command sits nearer an integer than half a command the ring passes the
    setpoint further (cfrp_strip_four: ``e`` 0.02, its hold 26.5 % over), but where that is depends on the tissue.
    The thesis rig: ring 16 mN, ``k`` 26.6 mN, 2.7 mN past 0.1 N (its holds 2.4-4.6 % over): not coarse.
    """
    setpoint = check_real(setpoint_n, "setpoint_n", "hold_coarseness", low=0, low_open=True)

    def past(f):
        ring = lone_step_ring(model, f, region_m=region_m, side=side)
        k = force_per_command(model, _reference_tissue(model, region_m, side), f)
        return ring, k, ring - 0.5 * k

    ring, k, over = past(setpoint)
    out = {"lone_step_ring_n": ring, "force_per_command_n": k, "past_setpoint_n": over, "coarse": False,
           "least_setpoint_n": setpoint if math.isfinite(over) else math.nan, "note": ""}  # fmt: skip
    if not over > RING_BAND * setpoint:
        return out
    least, f = math.nan, setpoint
    for _ in range(COARSE_SEARCH_STEPS):
        f = max(1.05 * f, over / RING_BAND)  # the ring and k grow slowly with the force pressed
        over = past(f)[2]
        if not math.isfinite(over):
            break
        if over <= RING_BAND * f:
            least = _round_up(f)
            break
    held = f"it holds {least:g} N or more within 10 %" if math.isfinite(least) else "no setpoint it presses holds"
    note = (
        f"hold: the command is too coarse for {setpoint:g} N: one command presses {1000 * k:.0f} mN and a lone "
        f"one-frame step rings the force {1000 * ring:.0f} mN, at least {1000 * out['past_setpoint_n']:.0f} mN "
        f"({100 * out['past_setpoint_n'] / setpoint:.0f} %) past the setpoint wherever the command sits, over the "
        f"{100 * RING_BAND:g} % band; {held} (the protocol's [force] setpoint_n)"
    )
    return {**out, "coarse": True, "least_setpoint_n": least, "note": note}


def _round_up(f: float) -> float:
    """``f`` rounded up to 2 significant figures."""
    scale = 10 ** (math.floor(math.log10(f)) - 1)
    return float(f"{math.ceil(f / scale - 1e-9) * scale:.2g}")


#: How far (relative) the force of a one-reading point-contact estimate may move as its place wanders within that
#: reading's noise (:data:`PLACE_WANDER_CHI2`) before force control narrows where it looks (:func:`force_region`):
#: the issue's 10 % (the thesis rig's 4.4 %, its loop -4.1 %; the short digit's 35 %, its loop -31 %).
FORCE_PLACE_SPREAD = 0.10
#: chi^2 above the best place that one reading's noise lets the place estimate wander to (2 sd of one parameter).
PLACE_WANDER_CHI2 = 4.0
#: Where the search is narrowed to: the places whose profiled force reads the reference press within this (a fifth
#: of the issue's 10 %).
FORCE_TOLD = 0.02
#: How far (relative) one reading's point force may read apart at the two commands around the servo's position
#: before the loop moves the reading to each command's free shape (:class:`ForceController`'s ``free_step``): a
#: tenth of the issue's 10 % (the thesis rig's 0.6 %, as before; ``random_digit(10)``'s 44 %, the one-gauge digit's
#: 139 %).
COMMAND_TOLD = 0.01
#: Readings (2 s of the loop) whose mean tells the contact's place the loop reads its force at (where it reads
#: each command at its own free shape, ``free_step``, and the gauges tell the place): one reading's place sd over 10
#: (``ForceController``'s ``place_readings``).
PLACE_READINGS = 100
#: A hold whose force read is uncertain (1 sd, :func:`_held_force_sd`) by more than this share of its setpoint is
#: refused (:meth:`ForceHold.unreached`): the issue's 10 % at 2 sd. The one-gauge digit (12 mN at 0.1 N) and the
#: drawn one- and two-gauge digits ``random_digit(7, 16, 21, 28)`` (5.3-8.0 mN) at 0.1 N; none of the others.
HELD_SD_SHARE = 0.05
#: Readings the force loop tares on at the straight command (nothing touching) before it presses (at least).
TARE_READINGS = 10
#: The tare's force error (1 sd) a hold allows, relative to its setpoint: a third of the issue's 10 % (more readings
#: where one reading's force is noisier, :func:`_tare_readings`).
TARE_SHARE = 0.10 / 3
#: At most this many readings in a tare (10 s of the loop's 20 ms readings) ...
MAX_TARE_READINGS = 500
#: ... and in an estimate's mean (0.5 s: at the loop's ~0.8 rad/s crossover a 0.25 s delay, 0.2 rad of phase).
MAX_AVERAGE_READINGS = 25


def force_region(model, setpoint_n: float = 0.1, *, region_m=None, side: str = "cable", window_s: float = 3.0) -> dict:
    """Where force control looks for the contact, and whether its gauges can tell the place: a dict with
    ``region_m`` (searched, m from the base: ``region_m`` itself, or narrowed), ``narrowed`` (bool),
    ``spread`` (relative), ``place_told`` (bool), ``place_sd_m`` and ``reason`` (one line).

    The reference press is :func:`force_gains`'s: the thesis's soft block laid out beside ``region_m`` as beside the
    thesis rig, at the first command that presses ``setpoint_n``. For that noise-free reading the point-force
    hypothesis is profiled along the region (:meth:`ContactEstimator.force_profile`): where its chi^2 stays within
    :data:`PLACE_WANDER_CHI2` of the best, one reading's noise can put the estimate. If the force read over those
    places moves by more than :data:`FORCE_PLACE_SPREAD` of the reference's (the loop then holds a biased average:
    the short digit's 2 gauges read 35 % high 20 mm short of its contact), the search is narrowed to the stretch
    around the reference contact's centroid where the profiled force reads it within :data:`FORCE_TOLD` (on a digit
    of two or more gauges the stretch past its outermost gauge, where the shear between the gauges is the force
    whatever the place; on a digit of one gauge the place is assumed there: the tissue's expected contact).

    ``place_told``: the Cramer-Rao standard deviation of the contact's place over ``window_s`` of 20 ms readings
    (its point-force Fisher information at the reference press) is finite and within the searched region; a single
    gauge reads one number, ``F`` times a lever, and never tells the place (``reason`` says so).
    """
    length = float(model.params.geometry.digit_length_m)
    start, end = (0.55 * length, length) if region_m is None else (float(region_m[0]), float(region_m[1]))
    tissue = Tissue(start, end + 0.08, 0.03 * length / 0.27, _THESIS_FORCE_TISSUE[3], side=side)
    commands = _press_commands(model.params)
    sol, volts = model.tissue_solution(tissue, commands)
    force = np.abs(sol.contact_force_n)
    reached = np.flatnonzero(force >= setpoint_n)
    out = {"region_m": region_m, "narrowed": False, "spread": math.nan, "place_told": False, "place_sd_m": math.inf,
           "force_sd_n": math.nan, "point_error": math.nan, "classify": False, "command_error": math.nan,
           "free_step": False}  # fmt: skip
    if not reached.size:
        return {**out, "reason": "the digit never presses the reference body that hard: place not checked"}
    k = int(reached[0])
    truth, centroid, command = float(force[k]), float(sol.contact_centroid_m[k]), int(commands[k])
    estimator = ContactEstimator(model, classify=False, side=side, region_m=region_m).fit()
    s, profiled, chi2 = estimator.force_profile(volts[k], command)
    profiled, chi2 = np.abs(profiled[0]), chi2[0]
    wander = chi2 < PLACE_WANDER_CHI2
    spread = float(np.max(np.abs(profiled[wander] - truth)) / truth)
    searched = region_m
    if spread > FORCE_PLACE_SPREAD:
        told = np.abs(profiled - truth) <= FORCE_TOLD * truth
        i = int(np.argmin(np.abs(s - centroid)))
        if not told[i]:
            i = int(np.flatnonzero(told)[np.argmin(np.abs(s[told] - centroid))]) if np.any(told) else i
        lo = hi = i
        while lo > 0 and told[lo - 1]:
            lo -= 1
        while hi < s.size - 1 and told[hi + 1]:
            hi += 1
        lo, hi = max(0, min(lo, i - 1)), min(s.size - 1, max(hi, i + 1))  # at least two grid steps
        if hi - lo < 3:  # the centroid the region's end (the 0.49 m section, soft-block: 349-350 mm, refused by
            lo, hi = max(0, hi - 3), min(s.size - 1, max(0, hi - 3) + 3)  # ContactEstimator; 348-350 a float short)
        searched = (float(s[lo]), float(s[hi]))
    place_sd, force_sd = _contact_sd(model, centroid, truth, command, side)
    place_sd /= math.sqrt(max(1.0, window_s / 0.020))  # over the window's 20 ms readings
    # the reference press is a stretch of contact: where the point hypothesis misreads its total by > FORCE_TOLD (a
    # gauge inside it), the loop weighs line loads too (classify; random_digit(0..30) within 2 %, the thesis 0.006 %)
    point_error, command_error = _reference_errors(model, searched, side, volts[k], command, truth)
    width = (searched[1] - searched[0]) if searched is not None else length
    gauges = len(model.params.geometry.gauge_positions_m)
    place_told = gauges > 1 and place_sd <= width
    if place_told:
        reason = f"the gauges tell the place (Cramer-Rao {1000 * place_sd:.2g} mm over {window_s:g} s)"
    elif gauges == 1:
        reason = "one gauge reads one number, the force times its lever: it cannot tell the contact's place"
    else:
        reason = (
            f"the gauges cannot tell the contact's place here (Cramer-Rao {1000 * place_sd:.3g} mm over "
            f"{window_s:g} s, wider than the {1000 * width:.3g} mm searched)"
        )
    if searched != region_m:
        reason = (
            f"searched {1000 * searched[0]:.1f}-{1000 * searched[1]:.1f} mm, where the gauges read the force within "
            f"{FORCE_TOLD:.0%} whatever the place (over the whole region one reading's noise moves it "
            f"{spread:.0%}); " + reason
        )
    return {**out, "region_m": searched, "narrowed": searched != region_m, "spread": spread,
            "place_told": bool(place_told), "place_sd_m": float(place_sd), "force_sd_n": force_sd,
            "point_error": point_error, "classify": point_error > FORCE_TOLD, "command_error": command_error,
            "free_step": command_error > COMMAND_TOLD, "reason": reason}  # fmt: skip


def _reference_errors(model, searched, side: str, reading, command: int, truth: float) -> tuple[float, float]:
    """How the point estimate over ``searched`` misreads the reference press's ``reading`` (relative): at its own
    ``command``, and at the next one (the loop's servo sits between two: :class:`ForceController`'s ``free_step``)
    against its own command's."""
    searching = ContactEstimator(model, classify=False, side=side, region_m=searched).fit()
    best = searching.predict(reading, command)
    point_error = float(abs(abs(best.point_force_n[0]) - truth) / truth)
    beside = command + 1 if command < int(model.params.actuator.command_max) else command - 1
    command_error = float(abs(searching.predict(reading, beside).point_force_n[0] / best.point_force_n[0] - 1))
    return point_error, command_error


def _contact_sd(model, place_m: float, force_n: float, command: int, side: str) -> tuple[float, float]:
    """Cramer-Rao standard deviations of one reading: a point contact's place (m; place and force unknown; inf where
    the Fisher information is singular, one gauge) and its force with the place known (N), by central differences
    of the model's gauges (1 mm, 1 mN)."""
    sign = -1.0 if side == "cable" else 1.0
    s0 = min(max(place_m, 1e-3), model.length_m - 1e-3)
    h, f = 1e-3, sign * force_n
    ds = model.point_v([s0 + h], [f], command) - model.point_v([s0 - h], [f], command)
    df = model.point_v([s0], [f + sign * h], command) - model.point_v([s0], [f - sign * h], command)
    jac = np.stack([ds[0] / (2 * h), df[0] / (2 * h)], axis=1)
    information = jac.T @ (jac / np.asarray(model.noise_v, dtype=float)[:, None] ** 2)
    force_sd = 1.0 / math.sqrt(information[1, 1]) if information[1, 1] > 0 else math.inf
    if np.linalg.matrix_rank(information, tol=1e-12 * np.max(np.abs(information))) < 2:
        return math.inf, force_sd
    variance = np.linalg.inv(information)[0, 0]
    return (float(math.sqrt(variance)) if variance > 0 else math.inf), float(force_sd)


def rig_contact_model(rig) -> ContactGaugeModel:
    """The gauge model of the digit ``rig`` carries: its parameters, its twin's calibration and mount on the twin
    (``sim?orientation=hanging`` included), else the digit's default calibration
    (:func:`~flexdigit.twin.digit_calibration.twin_calibration`) mounted tip up. Before, a rig of another digit
    was read through the thesis rig's calibration, tip up, whatever its own: another digit's channel gains."""
    twin = getattr(rig, "twin", None)
    calibration = getattr(twin, "calibration", None) or twin_calibration(rig.params)
    return ContactGaugeModel(rig.params, calibration, orientation=getattr(twin, "orientation", None) or "vertical")


def _truth_of(rig):
    twin = getattr(rig, "twin", None)
    if twin is None or not hasattr(twin, "contact_state"):
        return None
    return lambda: -twin.tissue.sign * twin.contact_state()[0] if twin.tissue is not None else 0.0


def _place_of(rig):
    """The twin's contact centroid now (m of arc from the base; NaN clear of the body), or None off the twin."""
    twin = getattr(rig, "twin", None)
    if twin is None or not hasattr(twin, "contact_state"):
        return None
    return lambda: twin.contact_state()[1] if twin.tissue is not None else math.nan


def simulate_sweep(model, tissue, protocol: PalpationProtocol, *, seed=0, drift_v_per_sqrt_s=None) -> SweepRecord:
    """A sweep's plateaus from the twin's statics and its sensor noise, without the dynamics: each plateau's mean is
    the static contact's gauges plus white noise over ``readings`` samples and the random-walk drift accumulated
    since the start (the calibration's rates). For studies: the loop-driven sweep on the dynamic twin
    (:func:`palpate`) agrees with it once the plateaus settle (tests)."""
    rng = np.random.default_rng(seed)
    sequence = np.array([protocol.tare_command, *protocol.commands, protocol.tare_command])
    times = protocol.reading_times_s()
    sol, clean = model.tissue_solution(tissue, sequence)
    rate = (
        np.asarray(model.calibration.noise_drift_v_per_sqrt_s, dtype=float)
        if drift_v_per_sqrt_s is None
        else np.asarray(drift_v_per_sqrt_s, dtype=float)
    )
    shape = (sequence.size, clean.shape[1])  # the digit's G gauges
    steps = np.sqrt(np.diff(np.concatenate([[0.0], times])))[:, None] * rate * rng.standard_normal(shape)
    white = model.noise_v / math.sqrt(protocol.readings) * rng.standard_normal(shape)
    gauges = clean + np.cumsum(steps, axis=0) + white
    tare = np.zeros(sequence.size, dtype=bool)
    tare[[0, -1]] = True
    truth = -tissue.sign * sol.contact_force_n
    samples = {"time_s": times, "gauges_v": gauges, "command": sequence, "true_force_n": truth, "plateau_means": True}
    return SweepRecord(sequence, times, gauges, tare, protocol.readings, samples)


# ------------------------------------------------------------------------------------------------------ scan
@dataclass
class ScanResult:
    """A scan: the tissue at each offset along the digit, the local stiffness map and the fitted inclusion.

    ``offsets_m`` (j,); ``local`` the per-offset uniform fits (:class:`TissueFit`); ``map_position_m`` where on
    the tissue each local fit looked (its contact centroid, in the tissue's own coordinate: m from where its start
    was at offset 0); ``inclusion`` the joint fit of one inclusion to every sweep (dict: ``centre_m`` in the
    tissue's coordinate at offset 0, ``ratio``, ``modulus_n_m2``, ``gap_m`` and their standard deviations).
    """

    offsets_m: np.ndarray
    local: list
    map_position_m: np.ndarray
    map_modulus_n_m2: np.ndarray
    map_modulus_sd_n_m2: np.ndarray
    inclusion: dict
    records: list

    __repr__ = fields_summary


def scan(
    records_or_rig,
    placed,
    offsets_m,
    protocol: PalpationProtocol | None = None,
    *,
    model=None,
    inclusion_width_m: float = 0.01,
    log_paths=None,
    log_mode: str = "new",
) -> ScanResult:
    """Palpate with the tissue moved along the digit by each offset, map the stiffness and find an inclusion.

    ``records_or_rig``: a rig (the tissue is placed at each offset, :meth:`flexdigit.rig.base.Rig.place_tissue`,
    and swept) or a list of :class:`SweepRecord`, one per offset (e.g. :func:`simulate_sweep`). ``placed`` is the
    tissue at offset 0 (where it lies; its modulus and gap are not used). ``inclusion_width_m`` is the size of the
    nodule looked for: its ratio is fitted for that width (a narrower, stiffer one presses back alike). On a rig,
    ``log_paths`` (one per offset, or None) and ``log_mode`` log each sweep (:func:`run_sweep`).
    """
    protocol = protocol or PalpationProtocol()
    offsets = check_values(offsets_m, "offsets_m", "scan", unit="m").reshape(-1)
    if offsets.size < 3:
        raise ParameterError(f"The 'offsets_m' parameter of scan needs at least 3 offsets. Got {offsets.tolist()!r}.")
    if isinstance(records_or_rig, list):
        records = records_or_rig
        model = model or ContactGaugeModel()
    else:
        rig = records_or_rig
        model = model or rig_contact_model(rig)
        records = []
        for d, log in zip(offsets, log_paths or [None] * offsets.size, strict=True):
            rig.place_tissue(placed.moved(float(d)))
            records.append(run_sweep(rig, protocol, log_path=log, truth=_truth_of(rig), log_mode=log_mode))
    uniform = placed.replace(inclusions=())
    local, where = [], []
    for d, rec in zip(offsets, records, strict=True):
        fit = fit_tissue(rec, model, uniform.moved(float(d)), start=local[-1] if local else None)
        local.append(fit)
        sol, _ = model.tissue_solution(fit.tissue, rec.command[~rec.tare][-1:])
        where.append(float(sol.static.tip_m[0, 0] if np.isnan(sol.contact_centroid_m[0]) else _centroid_a(model, sol)))
    map_k = np.array([f.modulus_n_m2 for f in local])
    map_sd = np.array([f.modulus_sd_n_m2 for f in local])
    position = np.array(where) - offsets - placed.start_m
    inclusion = _fit_inclusion(records, model, uniform, offsets, local, position, map_k, inclusion_width_m)
    return ScanResult(offsets, local, position, map_k, map_sd, inclusion, records)


def _centroid_a(model, sol) -> float:
    """Where along the digit's axis (world ``a``, m from the clamp) the contact's centroid is."""
    return float(model.chain.positions(sol.static.psi_rad, [sol.contact_centroid_m[0]])[0, 0, 0])


def _fit_inclusion(records, model, uniform, offsets, local, position, map_k, width):
    """One inclusion fitted to every sweep of the scan: gap, base modulus, centre and ratio (width given)."""
    gauges = np.concatenate([r.gauges_v for r in records])
    commands = np.concatenate([r.command for r in records])
    times = np.concatenate([r.time_s + 1e4 * j for j, r in enumerate(records)])  # (drift fitted per sweep below)
    sigma = np.asarray(model.noise_v, dtype=float) / math.sqrt(records[0].readings)
    blocks = []
    start = 0
    for r in records:
        blocks.append(slice(start, start + r.command.size))
        start += r.command.size

    def tissues(th):
        gap, logk, centre, logratio = th
        body = uniform.replace(gap_m=gap, modulus_n_m2=math.exp(logk))
        body = body.replace(inclusions=(Inclusion(uniform.start_m + centre, width, math.exp(logratio)),))
        return [(rows, body.moved(float(d))) for rows, d in zip(blocks, offsets, strict=True)]

    like = _ScanLikelihood(model, commands, times, gauges, sigma, tissues, blocks)
    base = float(np.median(map_k))
    peak = int(np.argmax(map_k))
    gap0 = float(np.median([f.gap_m for f in local]))
    x0 = np.array([gap0, math.log(base), position[peak], math.log(max(map_k[peak] / base, 1.05))])
    span = float(np.ptp(position)) + width
    lower = [-0.05, math.log(1.0), float(position.min()) - width, math.log(0.05)]
    upper = [0.3, math.log(1e7), float(position.max()) + width, math.log(50.0)]
    x0 = np.clip(x0, np.array(lower) + 1e-9, np.array(upper) - 1e-9)
    sol, sd = _least_squares(like, x0, lower, upper, [1e-3, 0.1, 0.2 * span / max(len(offsets), 1), 0.1])
    dof = gauges.size - 4 - 6 * len(records)
    sd = sd * math.sqrt(max(1.0, 2 * sol.cost / max(dof, 1)))
    ratio = math.exp(sol.x[3])
    return {
        "centre_m": float(sol.x[2]),
        "centre_sd_m": float(sd[2]),
        "ratio": ratio,
        "ratio_sd": float(ratio * sd[3]),
        "modulus_n_m2": math.exp(sol.x[1]),
        "modulus_sd_n_m2": float(math.exp(sol.x[1]) * sd[1]),
        "gap_m": float(sol.x[0]),
        "width_m": width,
        "chi2_per_dof": float(2 * sol.cost / max(dof, 1)),
        "converged": bool(sol.success),
    }


class _ScanLikelihood(_TissueLikelihood):
    """The scan's residuals: offsets and drifts profiled out per sweep (each has its own tares)."""

    def __init__(self, model, commands, times, gauges, sigma, tissue_of, blocks):
        super().__init__(model, commands, times, gauges, sigma, tissue_of, nuisance=False)
        self.blocks = blocks
        self.times = np.asarray(times, dtype=float)

    def residuals(self, theta):
        r = self.gauges - self.predict(theta)
        for rows in self.blocks:
            t = self.times[rows]
            design = np.column_stack([np.ones_like(t), t - t.mean()])
            coef, *_ = np.linalg.lstsq(design, r[rows], rcond=None)
            r[rows] = r[rows] - design @ coef
        return (r / self.sigma).ravel()


# ------------------------------------------------------------------------------------------------ force control
class ForceController:
    """Hold a set contact force with the 20 ms loop, from the gauges' force estimate (integral control).

    Each sample the contact is estimated from the reading
    (:class:`flexdigit.palpation.contact_estimation.ContactEstimator`) at the servo's position, which is taken as the
    controller's own continuous command (the servo low-passes what it is sent): the estimate at the two integer
    commands around it, interpolated. **The force follows the contact
    decision** (:meth:`estimate`): nothing touching reads 0 N, a point contact its point force, a line load (a
    classifying estimator) its total; before, every reading was converted as a point force at the guessed place, so
    noise with nothing touching read as a force (clipped at zero: +11 mN on the one-gauge digit). The command
    integrates the force error (``gain`` commands per second per N, clamped to ``low..high``: no wind-up), and is
    rounded with error feedback (a first-order sigma-delta): the integer commands sent average to the continuous
    one, a resolution the servo (20 rad/s) and the digit (13 rad/s) filter the 25 Hz toggling out of, finer than the
    ~0.03 N a whole command step presses. Integral action alone has no overshoot while the crossover (``gain`` x
    ~0.03 N per command) stays well below the digit's lightly damped mode.

    Parameters
    ----------
    estimator : ContactEstimator
        Fitted; its ``n_readings`` should be ``average_readings`` (the noise its decision weighs).
    offset_v : array_like (G,)
        Subtracted from every reading first (the tare: readings at rest minus the model's).
    gain : float
        Integral gain (commands / s / N).
    approach_rate : float
        Commands per second while nothing touches yet (until the force passes ``contact_fraction`` of the
        setpoint): the integral would creep up on the body at ``gain x setpoint``, letting the gauges drift since
        the tare.
    period_s : float
    low, high : int
        Command range the controller may use.
    sign : float
        -1 when the body is on the cable side (its force on the digit is negative): the force held is
        ``sign * estimate``, positive.
    detect_readings : int
        The contact shows when the mean of the last this many estimates passes ``contact_fraction`` of the
        setpoint (1: each estimate).
    average_readings : int
        Each estimate is made on the mean of the last this many tared readings, at their mean servo position (1: each
        reading alone, the thesis rig). A noisy gauge's single reading cannot decide a contact at the setpoint (the
        one-gauge digit: 36 mN a reading against a 30 mN threshold); their mean can, and its estimate is not
        clipped at zero force as a mean of one-reading estimates is.
    free_step : bool
        Read the two commands around the servo's position each at its own free shape: the reading (taken at the
        continuous position) is moved by the free digit's gauges' step to each command before that command's
        estimate (:func:`force_region`'s ``command_error``). Off, the same reading is estimated at both: to each
        command's model it is a digit bent a fraction of a command more or less than its own, which the point fit
        reads as contact somewhere else (``random_digit(10)``: a reading at one command read at the next as 0.146 N
        for 0.101 N, 70 mm inward), and the two estimates interpolated do not cancel: 0.1 N between two commands
        read up to 9.4 % high (a third of a command past one), where the loop stopped pressing (its hold -18 % on
        seed 2). Off on the thesis rig (its two estimates agree within 0.6 %, its report's entries unchanged).
    place_readings : int
        Once a contact shows, read its force at one place: the point estimate's place from the mean of the last
        this many tared readings (at their mean servo position), the force of each estimate profiled there
        (:meth:`ContactEstimator.force_profile`), where a still body's contact stays. 0: each estimate's own place
        (the thesis rig). A point force's place from one reading wanders with its noise and drift, and the force
        read with it (``random_digit(12)``: 150 mm for its contact's 160, where a reading means more force: the
        hold 10 % short); at one place the force is linear in the reading, its noise averaging out.
    detect_chi2 : float, optional
        The contact decision's threshold on the likelihood ratio against nothing (None: the estimator's): raised
        where the digit's own free motion reads as contact (:func:`motion_detect_chi2`).
    integer_band : float
        Within this many commands of an integer, send that integer (the residue cleared) instead of the sigma-delta's
        integer with a lone one-frame step every ``1 / (u - n)`` frames: 0 (the thesis rig) always the sigma-delta.
        ``hold_force(integer_band=True)`` sets it where one such step rings the contact force more than the 10 %
        band (:func:`quantiser_band`).
    servo : (float, float), optional
        The servo's natural frequency (rad/s) and damping ratio: the force is then estimated at the position the
        servo's second-order model reaches from the commands sent (zero-order hold over ``period_s``), not at the
        continuous command. The servo lags a ramp by ``2 zeta / wn`` (55 ms on the thesis rig's): where a digit's
        gauges read that lag as force (:func:`servo_lag_force`), the estimate led the true force by it.

    Per sample it keeps the force held (``forces``, N, > 0 pressing), its standard deviation (``force_sds``, N, the
    estimator's at its decision), the decision (``kinds``: "none", "point", "distributed") and the point estimate's
    place (``places``, m from the base).
    """

    def __init__(
        self,
        estimator,
        offset_v,
        *,
        gain=30.0,
        period_s=0.020,
        low=8,
        high=60,
        sign=-1.0,
        approach_rate=4.0,
        contact_fraction=0.3,
        servo=None,
        detect_readings=1,
        average_readings=1,
        free_step=False,
        place_readings=0,
        integer_band=0.0,
        detect_chi2=None,
    ) -> None:
        self.detect_chi2 = (
            None if detect_chi2 is None else check_real(detect_chi2, "detect_chi2", "ForceController", low=0)
        )
        self.chi2 = math.nan
        self.free_step = bool(free_step)
        self.place_readings = check_int(place_readings, "place_readings", "ForceController", low=0)
        self._free_steps: dict[int, np.ndarray] = {}
        self.detect_readings = check_int(detect_readings, "detect_readings", "ForceController", low=1)
        self.average_readings = check_int(average_readings, "average_readings", "ForceController", low=1)
        self.approach_rate = check_real(approach_rate, "approach_rate", "ForceController", low=0, low_open=True)
        self.contact_fraction = check_real(contact_fraction, "contact_fraction", "ForceController", low=0, high=1)
        self.estimator = estimator
        self.offset_v = np.asarray(offset_v, dtype=float)
        self.gain = check_real(gain, "gain", "ForceController", low=0, low_open=True)
        self.period_s = period_s
        self.low, self.high = int(low), int(high)
        self.sign = sign
        self.forces: list[float] = []
        self.force_sds: list[float] = []
        self.kinds: list[str] = []
        self.places: list[float] = []  # the point estimate's place (m from the base) per sample
        self.place_m = math.nan
        self.servo = servo
        self._servo = None if servo is None else _servo_step(float(servo[0]), float(servo[1]), float(period_s))
        self.integer_band = check_real(integer_band, "integer_band", "ForceController", low=0, high=0.5)

    def reset(self, command: int) -> None:
        self.u = float(command)
        self.residue = 0.0
        self.forces, self.force_sds, self.kinds, self.places = [], [], [], []
        self._readings: list[np.ndarray] = []
        self._positions: list[float] = []
        self.touching = False
        self._servo_state = np.array([float(command), 0.0])
        self._held = None
        self._contact_v: list[np.ndarray] = []  # tared readings and positions since the contact showed
        self._contact_at: list[float] = []

    def estimate(self, gauges_v, position: float) -> tuple[float, float, str]:
        """``(force (N, > 0 pressing), its sd (N), decision)`` from one (mean) reading with the servo at the
        (continuous) ``position``: the estimator's decided force (0 for no contact, the point force, or a line
        load's total) at the two commands around it, interpolated; the decision and sd of the nearer command.
        Also sets :attr:`place_m` (the point estimate's place)."""
        # the two commands around it within the servo's range (a digit pressing up to its last command, 254)
        top = int(self.estimator.model.params.actuator.command_max)
        lo = min(int(math.floor(position)), top - 1)
        frac = position - lo
        v = np.asarray(gauges_v, dtype=float) - self.offset_v
        rows = np.vstack([v, v])
        if self.free_step:  # each command's estimate of the reading moved to that command's free shape
            step = self._free_step(lo)
            rows = np.vstack([v - frac * step, v + (1.0 - frac) * step])
        est = self.estimator.predict(rows, np.array([lo, lo + 1]))
        near = int(frac >= 0.5)
        self.place_m = float((1 - frac) * est.point_position_m[0] + frac * est.point_position_m[1])
        # one decision for the reading: its likelihood ratio against nothing, interpolated as the force is
        self.chi2 = float((1 - frac) * est.chi2_contact[0] + frac * est.chi2_contact[1])
        if self.chi2 <= (self.estimator.detect_chi2 if self.detect_chi2 is None else self.detect_chi2):
            return 0.0, float(est.force_sd_n[near]), "none"
        kind = "distributed" if est.kind[near] == "distributed" else "point"
        f = self.sign * (est.line_total_n if kind == "distributed" else est.point_force_n)
        if kind == "point" and self._held is not None:  # the force at the contact's held place
            s, profiled, _ = self.estimator.force_profile(rows[0], lo)
            _, above, _ = self.estimator.force_profile(rows[1], lo + 1)
            f = self.sign * np.array([np.interp(self._held, s, profiled[0]), np.interp(self._held, s, above[0])])
            self.place_m = self._held
        return float((1 - frac) * f[0] + frac * f[1]), float(est.force_sd_n[near]), kind

    _held = None  # the contact's held place (m), when the controller holds one (place_readings)

    def _hold_place(self, position: float) -> None:
        """The held place from the mean of the readings kept since the contact showed (place_readings)."""
        self._held = None
        mean_v, at = np.mean(self._contact_v, axis=0), float(np.mean(self._contact_at))
        self.estimate(mean_v, at)
        self._held = self.place_m

    def _free_step(self, command: int) -> np.ndarray:
        """The free digit's gauges from ``command`` to the next (V), kept per command."""
        if command not in self._free_steps:
            free = self.estimator.model.free_v([command, command + 1])
            self._free_steps[command] = free[1] - free[0]
        return self._free_steps[command]

    def force(self, gauges_v, position: float) -> float:
        """Contact force (N, > 0 pressing) from one reading with the servo at the (continuous) ``position``, as
        the contact decision says (:meth:`estimate`)."""
        return self.estimate(gauges_v, position)[0]

    def step(self, setpoint: float, reading) -> float:
        # where the servo is: the continuous command, or the servo's model driven by the commands sent
        n = self.average_readings
        self._readings = [*self._readings, np.asarray(reading.gauges_v, dtype=float)][-n:]
        self._positions = [*self._positions, self.u if self._servo is None else self._servo_state[0]][-n:]
        if self.average_readings == 1:  # (the thesis rig: its estimates to the last bit as before)
            mean_v, position = self._readings[-1], self._positions[-1]
        else:
            mean_v, position = np.mean(self._readings, axis=0), float(np.mean(self._positions))
        if self.place_readings and self.touching:
            self._contact_v = [*self._contact_v, self._readings[-1]][-self.place_readings :]
            self._contact_at = [*self._contact_at, self._positions[-1]][-self.place_readings :]
            self._hold_place(position)
        f, sd, kind = self.estimate(mean_v, position)
        self.forces.append(f)
        self.force_sds.append(sd)
        self.kinds.append(kind)
        self.places.append(self.place_m)
        if not self.touching and np.mean(self.forces[-self.detect_readings :]) > self.contact_fraction * setpoint:
            self.touching = True
        # approach at a steady rate until the contact shows, then integrate the force error
        rate = self.approach_rate if not self.touching else self.gain * (setpoint - f)
        self.u = min(max(self.u + self.period_s * rate, self.low), self.high)
        sent = self._quantise(self.u)
        if self._servo is not None:
            a, b = self._servo
            self._servo_state = a @ self._servo_state + b * sent
        return sent

    def _quantise(self, u: float) -> int:
        """The integer command sent for the continuous ``u``: rounded with error feedback (a first-order sigma-delta:
        the residue ``u - sent`` carried to the next sample), or, within :attr:`integer_band` of an integer, that
        integer with the residue cleared (no lone one-frame steps where the integer's force is near enough)."""
        if self.integer_band > 0.0 and abs(u - round(u)) <= self.integer_band:
            self.residue = 0.0
            return int(round(u))
        wanted = u + self.residue
        sent = int(round(wanted))
        self.residue = wanted - sent
        return sent


def _servo_step(wn: float, zeta: float, period_s: float) -> tuple[np.ndarray, np.ndarray]:
    """The servo's second-order model ``x'' + 2 zeta wn x' + wn^2 x = wn^2 u`` over one period with ``u`` held:
    ``(A, b)`` of ``[x, x'] <- A [x, x'] + b u`` (exact, by the matrix exponential)."""
    from scipy.linalg import expm

    system = np.array([[0.0, 1.0, 0.0], [-(wn**2), -2.0 * zeta * wn, wn**2], [0.0, 0.0, 0.0]])
    step = expm(system * period_s)
    return step[:2, :2], step[:2, 2]


#: The force loop declares the contact at this fraction of the setpoint (:class:`ForceController`).
CONTACT_FRACTION = 0.3
#: Standard deviations of the averaged estimate's noise below the contact threshold (:func:`hold_force`): one
#: reading's noise passes 3 sd once in 700 readings, 14 s of the loop.
DETECT_SIGMAS = 3.0
#: The force (relative to the setpoint) the servo's lag behind the approach ramp may read as before the force loop
#: models the servo (:func:`servo_lag_force`): the contact threshold over DETECT_SIGMAS, as for the noise (the
#: thesis rig's 1.7 %; the one-gauge digit's 31 %, which declared a contact before any and led the true force).
SERVO_LAG_FORCE = CONTACT_FRACTION / DETECT_SIGMAS


def _held_force_sd(model, force_sd_n: float, duration_s: float, tare_readings: int = TARE_READINGS) -> float:
    """How uncertain (1 sd, N) the force a hold reads is, its noise averaged out: the tare's ``tare_readings``
    readings and the gauges' random-walk drift over the hold (its wait and duration), in force through one reading's
    force sd with the place known (the drift's share of a reading's noise, root-mean-square over the gauges)."""
    cal = model.calibration
    ratio = float(np.sqrt(np.mean((np.asarray(cal.noise_drift_v_per_sqrt_s) / np.asarray(model.noise_v)) ** 2)))
    return float(force_sd_n * math.sqrt(1.0 / tare_readings + ratio**2 * (1.0 + duration_s)))


def _detect_readings(force_sd_n: float, threshold_n: float) -> int:
    """Readings to average so that their mean's noise is :data:`DETECT_SIGMAS` below ``threshold_n`` (at least 1)."""
    if not math.isfinite(force_sd_n):
        return 1
    return max(1, math.ceil((DETECT_SIGMAS * force_sd_n / threshold_n) ** 2))


def servo_lag_force(model, estimator, approach_rate: float, command: int) -> float:
    """The force (N) the servo's lag behind a ramp of ``approach_rate`` commands per second reads as at ``command``:
    the estimate from the gauges the statics give ``approach_rate x 2 zeta / wn`` commands short of it, against the
    model's at it (both signs of the lag, the estimate being clipped to one side)."""
    act = model.params.actuator
    lag = approach_rate * 2.0 * act.servo_zeta / act.servo_wn_rad_s
    free = model.free_v([command - 1, command, command + 1])
    slope = (free[2] - free[0]) / 2.0
    readings = np.vstack([free[1] - lag * slope, free[1] + lag * slope])
    return float(np.max(np.abs(estimator.predict(readings, command).point_force_n)))


#: Seconds of the free approach :func:`free_motion_chi2` simulates: the ramp's start and a dozen rings of the
#: stiffest test digit's 35 rad/s mode, at the loop's approach rate.
FREE_MOTION_S = 3.0


def free_motion_chi2(controller, model, command: int, duration_s: float = FREE_MOTION_S) -> float:
    """The largest contact chi^2 (the likelihood ratio against nothing touching) ``controller`` reads on its digit
    moving with nothing touching: ``model``'s digit on its twin (noise-free, the serial drive, the hold's 5 ms step)
    driven from rest at ``command`` by the controller's own approach for ``duration_s``, each reading estimated as
    the loop estimates it (its servo model, its free steps). The statics read the moving digit's shape (its modes
    ringing at every command step the sigma-delta sends, the servo's pulse phase) as a contact where they differ from
    a shape at rest: thick_stiff_strong_servo's approach read chi^2 up to 350 (8-36 mN of "point" contact), the
    thesis rig's 4.3 (under :data:`~flexdigit.palpation.contact_estimation.DETECT_CHI2`, 13.8)."""
    free = copy.copy(controller)  # its settings and estimator; its own state and tare
    twin = Twin(model.params, model.calibration, orientation=model.orientation, housing=model.housing,
                dt_s=twin_step_s("force"), command=command)  # fmt: skip
    free.offset_v = np.asarray(twin.clean_read()[0]) - model.free_v([command])[0]
    free.reset(command)
    period = float(model.params.actuator.serial_period_s)
    chi2 = [0.0]
    for _ in range(round(duration_s / period)):
        gauges_v, pot_v = twin.clean_read()
        reading = Reading(twin.time_s, gauges_v, pot_v, command)
        command = free.step(math.inf, reading)  # an unreachable setpoint: approach only
        chi2.append(free.chi2)
        twin.command(command)
        twin.advance(period)
    return float(np.nanmax(chi2))


def motion_detect_chi2(detect_chi2: float, motion_chi2: float) -> float:
    """The force loop's contact threshold on a digit whose free motion reads ``motion_chi2``
    (:func:`free_motion_chi2`): ``detect_chi2`` where that motion stays under it (nothing changes: the thesis rig),
    else ``(sqrt(motion_chi2) + sqrt(detect_chi2))^2``. The decision's chi^2 is the squared weighted norm of the
    reading's part the contact explains, a projection, so its root is sub-additive: a reading of motion no worse
    than the free approach's worst plus noise passes this threshold no more often than the noise alone passes
    ``detect_chi2`` (0.1 %). A contact pressing ``f`` reads about ``(f / sd)^2`` (``sd`` one reading's force sd):
    on thick_stiff_strong_servo 350 -> 503, declared from ~43 mN of contact instead of 7 mN (the 30 mN threshold
    of the setpoint's share is then met a few frames later)."""
    if not motion_chi2 > detect_chi2:
        return float(detect_chi2)
    return float((math.sqrt(motion_chi2) + math.sqrt(detect_chi2)) ** 2)


@dataclass
class ForceHold:
    """A force-control run: per sample ``time_s``, ``command``, ``force_n`` (estimated, as the contact decision
    says: ``kind``, ``force_sd_n``) and, on the twin, ``true_force_n``; the figures over the last ``window_s``: mean
    true (or estimated) force and its error, and the overshoot (largest force over the setpoint, relative)."""

    setpoint_n: float
    time_s: np.ndarray
    command: np.ndarray
    force_n: np.ndarray
    true_force_n: np.ndarray | None
    steady_force_n: float
    steady_error: float
    steady_ripple_n: float
    overshoot: float
    settling_s: float
    status: str
    gain: float = math.nan  # the loop's integral gain (commands / s / N) and approach rate (commands / s)
    approach_rate: float = math.nan
    #: where the contact was looked for and what the gauges can say of its place (:func:`force_region`)
    region: dict = field(default_factory=dict)
    place_m: np.ndarray | None = None  # the estimate's place per sample (m from the base)
    true_place_m: np.ndarray | None = None  # the twin's contact centroid per sample (NaN clear of the body)
    window_s: float = 3.0  # the figures' window (s)

    #: the place estimated from the window's mean reading (NaN where the gauges cannot tell it: ``region``)
    steady_place_m: float = math.nan
    #: per sample: the estimate's standard deviation (N) and the contact decision it follows ("none", "point",
    #: "distributed"; :meth:`ForceController.estimate`)
    force_sd_n: np.ndarray | None = None
    kind: np.ndarray | None = None
    #: whether the loop read a contact (its estimate passed CONTACT_FRACTION of the setpoint), and the last command
    #: it may press with (:func:`_press_commands`)
    touched: bool = True
    high_command: int = 254

    def unreached(self) -> str:
        """Why the hold never held its setpoint, in one line ("" when it did): no contact read up to its last
        command; or pressing at its last command over the figures' window and reading under 90 % of the setpoint;
        or a force read uncertain by more than :data:`HELD_SD_SHARE` of the setpoint (1 sd, ``held_force_sd_n``:
        the 10 % not held at 2 sd; the one-gauge digit's 12 mN at 0.1 N: its twin held -25, -27, -22 % on seeds 1,
        2 and 4, its estimate on the setpoint, one gauge drifting); or, on the twin, a true force under half the
        setpoint over the window (the gauges misread a contact).
        Before, a hold that never touched reported "completed" with a steady force of 0 N (error -100 %)."""
        window = self._window()
        if not self.touched:
            ran = float(self.time_s[-1]) if self.time_s.size else 0.0  # no sample: a fault before the first
            top = int(np.max(self.command, initial=0))
            return (
                f"never reached {self.setpoint_n:g} N: no contact read in {ran:.1f} s, pressing up to "
                f"command {top} of its last {self.high_command} (the tissue out of reach?)"
            )
        estimated = float(np.mean(self.force_n[window])) if np.any(window) else 0.0
        if np.all(self.command[window] >= self.high_command) and estimated < 0.9 * self.setpoint_n:
            return (
                f"never reached {self.setpoint_n:g} N: pressing at its last command {self.high_command}, the gauges "
                f"read {estimated:.3g} N over the last {self.window_s:g} s"
            )
        region = self.region
        uncertain = _uncertain_hold(
            self.setpoint_n, float(region.get("held_force_sd_n", math.nan)), region.get("least_held_n", math.nan)
        )
        if uncertain:
            return uncertain
        if self.true_force_n is not None and self.steady_force_n < 0.5 * self.setpoint_n:
            return (
                f"never reached {self.setpoint_n:g} N: the twin's true contact force was {self.steady_force_n:.3g} N "
                f"over the last {self.window_s:g} s while the gauges read {estimated:.3g} N"
            )
        return ""

    def over_band(self) -> str:
        """The overshoot past the 10 % band, in one line ("" within it): a hold's figures are never printed as a
        success over it. Where the command was too coarse for the setpoint (``region["coarse_command"]``,
        :func:`hold_coarseness`) the line says so and the least setpoint held."""
        if not self.overshoot > RING_BAND:
            return ""
        coarse = self.region.get("coarse_command", {})
        why = (
            f": the command is too coarse for it (holds {coarse['least_setpoint_n']:g} N or more within 10 %)"
            if coarse.get("coarse")
            else ": the sigma-delta's lone one-frame steps ring the contact where its command sits near an integer"
        )
        return (
            f"overshoot {100 * self.overshoot:.1f} % of {self.setpoint_n:g} N, over the {100 * RING_BAND:g} % band{why}"
        )

    def limit_reached(self) -> bool:
        """Whether the hold ended short of its setpoint (more than 10 %, on the scored force) with the loop at the
        highest command it may send (``region["command_range"]``: the thesis rig's 8..60 in tip rotation): the
        digit cannot press that hard there, which no gain would change."""
        top = self.region.get("command_range", (None, None))[1]
        window = self._window()
        if top is None or not np.any(window) or not self.steady_error < -0.1:
            return False
        return bool(np.max(self.command[window]) >= top)

    def settled(self) -> bool:
        """Whether the scored force stayed within 10 % of the setpoint over the whole figures' window (its last
        ``window_s``): only then are the steady figures a steady state. ``settling_s`` is the last time outside 10 %;
        one inside the window means the steady mean is over a force still rising (thick_stiff_strong_servo: within
        10 % from 8.98 s of 10, its last 3 s's mean -14.9 %: said "within 10 % after 8.98 s" before) or ringing
        past the band late in the hold."""
        if not self.time_s.size:
            return False
        return bool(self.settling_s <= self.time_s[-1] - self.window_s)

    def settle_note(self) -> str:
        """Why the steady figures are not a steady state, in one line ("" when :meth:`settled`)."""
        if self.settled():
            return ""
        end = float(self.time_s[-1]) if self.time_s.size else 0.0
        within = (
            "never within 10 % of the setpoint at the end"
            if not math.isfinite(self.settling_s)
            else f"within 10 % only from {self.settling_s:.2f} s"
        )
        return (
            f"not settled: {within}, after the figures' window began ({end - self.window_s:.2f} s of {end:.2f} s): "
            f"the steady {100 * self.steady_error:+.1f} % is a mean over a force still rising or ringing past 10 %"
        )

    def decisions(self) -> dict:
        """How many samples of the figures' window each contact decision took (``{"none": n, "point": n, ...}``)."""
        if self.kind is None:
            return {}
        kinds = self.kind[self._window()]
        return {k: int(np.count_nonzero(kinds == k)) for k in ("none", "point", "distributed")}

    @property
    def true_steady_place_m(self) -> float:
        """The twin's median contact centroid over the figures' window (NaN on hardware or clear of the body)."""
        if self.true_place_m is None or not np.any(np.isfinite(self.true_place_m[self._window()])):
            return math.nan
        return float(np.nanmedian(self.true_place_m[self._window()]))

    def _window(self) -> np.ndarray:
        t = self.time_s
        return t >= t[-1] - self.window_s if t.size else np.zeros(0, dtype=bool)

    __repr__ = fields_summary


def hold_force(
    rig,
    setpoint_n: float,
    *,
    duration_s: float = 10.0,
    model=None,
    estimator=None,
    gain: float | None = None,
    window_s: float = 3.0,
    side: str = "cable",
    region_m=None,
    approach_rate: float | None = None,
    log_path=None,
    log_mode: str = "new",
    refuse_uncertain: bool = False,
    integer_band: bool = False,
) -> ForceHold:
    """Press the digit against whatever is beside it and hold ``setpoint_n`` (N) of contact force on the 20 ms loop.

    Tares at the equilibrium command first (nothing must touch the digit there; :data:`TARE_READINGS` readings, more
    where one reading's force is noisy: ``region["tare_readings"]``), then runs :class:`ForceController`, whose force
    follows the contact decision, each estimate on the mean of ``region["average_readings"]`` readings (1 unless one
    reading's noise would pass the contact threshold, :data:`DETECT_SIGMAS`). ``region_m`` (m from the base): where
    the contact can be (where the tissue lies), which steadies the estimate when nothing touches yet;
    :func:`force_region` narrows it where the force read hangs on the place, and ``ForceHold.region`` says what was
    decided. On the twin the true contact force is logged beside the estimate; the figures (steady force and error
    over the last ``window_s``, overshoot, 10 % settling time) use it there, and the estimate on hardware.

    ``gain`` and ``approach_rate`` default to the digit's own (:func:`force_gains`): the thesis rig's 30 commands per
    second per N and 4 commands per second, scaled so that the loop's crossover and approach speed are the thesis's.

    ``refuse_uncertain``: refuse in one line, before the rig moves, a hold whose force read would be uncertain by
    more than :data:`HELD_SD_SHARE` of the setpoint (``flexdigit palpate``; a study keeps its figures, and
    :meth:`ForceHold.unreached` says the same). ``integer_band``: round the command by :func:`quantiser_band`
    (off by default: over the 44 test digits it traded two holds over 10 % for two others, docs/guide/palpation.md).
    A command too coarse for the setpoint warns before the rig moves (:func:`_warn_if_coarse`)."""
    setpoint = check_real(setpoint_n, "setpoint_n", "hold_force", low=0, low_open=True)
    model = model or rig_contact_model(rig)
    _check_presses(model, side)
    if gain is None or approach_rate is None:
        derived = force_gains(model, setpoint, region_m=region_m, side=side)
        gain = derived["gain"] if gain is None else gain
        approach_rate = derived["approach_rate"] if approach_rate is None else approach_rate
    # where the contact is looked for (force_region: narrowed where noise moves the force read > 10 %); quantiser_band
    region = {**force_region(model, setpoint, region_m=region_m, side=side, window_s=window_s),
              **(quantiser_band(model, setpoint, region_m=region_m, side=side) if integer_band else {}),
              "coarse_command": _warn_if_coarse(model, setpoint, region_m, side)}  # fmt: skip
    estimator = estimator or _hold_estimator(model, region, setpoint, side)
    least = _least_held(model, region.get("force_sd_n", math.nan), duration_s)
    if refuse_uncertain:  # before the rig moves: the tare's readings and the drift over the hold are known now
        _refuse_uncertain(model, region.get("force_sd_n", math.nan), setpoint, duration_s, least)
    controller, region = _force_controller(rig, model, estimator, region, setpoint, gain, approach_rate, side)
    region["held_force_sd_n"] = _held_force_sd(
        model, region.get("force_sd_n", math.nan), duration_s, region["tare_readings"]
    )
    region["least_held_n"] = least
    truth, place = _truth_of(rig), _place_of(rig)
    true_force, true_place = [], []

    def on_sample(k, t, y, c):
        true_force.append(truth())
        true_place.append(place())

    result = run_loop(
        rig, controller, setpoint, duration_s, log_path=log_path, log_mode=log_mode,
        on_sample=on_sample if truth else None, close_rig=False,
    )  # fmt: skip
    _raise_if_stopped(result)
    t = result.time_s
    est = np.array(controller.forces[: t.size])
    figures = _hold_figures(t, np.array(true_force) if truth else est, setpoint, window_s)
    true = np.array(true_force) if truth else None
    steady_place = _steady_place(controller, result, window_s) if region.get("place_told", False) else math.nan
    return ForceHold(
        setpoint, t, result.command, est, true, *figures, result.status, float(gain), float(approach_rate),
        region=region, place_m=np.array(controller.places[: t.size]),
        true_place_m=np.array(true_place) if truth else None, window_s=float(window_s), steady_place_m=steady_place,
        force_sd_n=np.array(controller.force_sds[: t.size]), kind=np.array(controller.kinds[: t.size], dtype=str),
        touched=bool(getattr(controller, "touching", True)), high_command=int(controller.high),
    )  # fmt: skip


def _warn_if_coarse(model, setpoint: float, region_m, side: str) -> dict:
    """:func:`hold_coarseness` of the hold, warned (:class:`~flexdigit.errors.DesignWarning`, its one line) where
    the command is too coarse for the setpoint: the hold still runs (its steady force is held), its overshoot
    flagged after (:meth:`ForceHold.over_band`)."""
    coarseness = hold_coarseness(model, setpoint, region_m=region_m, side=side)
    if coarseness["coarse"]:
        warnings.warn(coarseness["note"], DesignWarning, stacklevel=3)
    return coarseness


def _hold_estimator(model, region: dict, setpoint: float, side: str) -> ContactEstimator:
    """The hold's contact estimator over ``region``: each estimate on the mean of enough readings for its noise to
    stay DETECT_SIGMAS below the contact threshold (1 on the thesis rig: 3.3 mN a reading against 30 mN; 14 on the
    one-gauge digit, 36 mN a reading)."""
    needed = _detect_readings(region.get("force_sd_n", math.nan), CONTACT_FRACTION * setpoint)
    average = min(MAX_AVERAGE_READINGS, needed)
    return ContactEstimator(
        model, classify=region.get("classify", False), side=side, region_m=region["region_m"], n_readings=average
    ).fit()


#: How near (in a reading's noise sds, plus one ADC step) an ADC rail a gauge may read at the hold's tare before the
#: hold is refused (:func:`check_tare_rails`): at 3 sd one reading in 700 clips, and the loop faults on it.
TARE_RAIL_SIGMAS = 3.0


def check_tare_rails(model) -> None:
    """Refuse (one line, :class:`~flexdigit.errors.ParameterError`, before the rig moves) a hold whose tare would
    read a gauge at an ADC rail: straight, with nothing touching, each gauge's model reading must lie more than
    :data:`TARE_RAIL_SIGMAS` noise sds and one ADC step inside ``[sensors] adc_range_v``. A microcontroller's
    0..3.3 V ADC without an offset reads a balanced bridge's 0 V straight on its rail (heavy_supports_10bit: all
    three gauges; before, the loop faulted at its first tare reading, "gauge 1 clipped at +0.000 V"). Taring
    bent instead would leave the gauges a fraction of an ADC step a degree above the rail where the contact
    unbends the digit, and ``flexdigit params`` already says such a range cannot read the chain: refused, naming
    the gauges, not worked round."""
    s = model.params.sensors
    low, high = (float(v) for v in s.adc_range_v)
    eq = int(model.params.actuator.equilibrium_command)
    rest = model.free_v([eq])[0]
    margin = TARE_RAIL_SIGMAS * np.asarray(model.noise_v, dtype=float) + s.adc_lsb_v
    near = [g for g in range(rest.size) if not low + margin[g] < rest[g] < high - margin[g]]
    if not near:
        return
    named = ", ".join(f"gauge {g + 1} {rest[g]:+.3f} V" for g in near)
    raise ParameterError(
        f"hold: the tare at the straight command {eq} (nothing touching) would read {named}, on or within "
        f"{TARE_RAIL_SIGMAS:g} noise sds of an ADC rail ([sensors] adc_range_v = [{low:g}, {high:g}]): the tare "
        "cannot read it; give a range around the gauges' rest or offset their amplifier; the digit was not moved"
    )


def _raise_if_stopped(result) -> None:
    """A hold's loop stopped: a stop (Ctrl-C, SIGTERM) raised again, a rig or sensor fault raised as
    :class:`~flexdigit.errors.RigError` in one line (run_loop sent the safe command and its message says so), as the
    sweep does. Before, a fault at the first reading left an empty hold and an IndexError ("internal error")."""
    result.raise_if_interrupted()
    if result.status == "fault":
        raise RigError(f"force hold stopped: {result.message}")


def _check_presses(model, side: str) -> None:
    """Refuse (one line) a body force control cannot press: on a single cable's other side (:func:`towards`), or on
    an antagonistic pair's other side (the loop presses with commands above straight only); and a tare that would
    read a gauge at an ADC rail (:func:`check_tare_rails`)."""
    check_tare_rails(model)
    if towards(model.params, side) < 0:
        raise ParameterError(
            "force control presses the digit towards its cable side (commands above straight): an antagonistic "
            "pair's 'opposite'-side tissue is not held yet; place it on side 'cable'"
        )


def _force_controller(rig, model, estimator, region, setpoint, gain, approach_rate, side):
    """Tare the rig at its straight command and build the hold's :class:`ForceController`; ``region`` (a copy) gains
    what was decided: whether the servo is modelled, the readings the contact shows on."""
    eq = int(rig.params.actuator.equilibrium_command)
    rig.write_command(eq)
    rig.wait(1.0)
    tare = _tare_readings(region.get("force_sd_n", math.nan), setpoint)
    offset = _tare(rig, tare) - model.free_v([eq])[0]
    sign = -1.0 if side == "cable" else 1.0
    # the thesis rig's 8..60, laid out on the digit (_press_commands)
    act = rig.params.actuator
    high = int(_press_commands(rig.params)[-1])
    # the servo's lag behind the approach read as force: modelled where it would read as more than 10 % of the
    # setpoint (not on the thesis rig: 1.7 mN at 0.1 N)
    lag_force = servo_lag_force(model, estimator, approach_rate, min(eq + 2, high))
    servo = (act.servo_wn_rad_s, act.servo_zeta) if lag_force > SERVO_LAG_FORCE * setpoint else None
    # each estimate (and the contact's decision) on the mean of the estimator's readings (hold_force: enough for
    # their noise to stay DETECT_SIGMAS below the threshold)
    average = int(getattr(estimator, "n_readings", 1))
    region = {**region, "servo_lag_force_n": lag_force, "servo_modelled": servo is not None,
              "average_readings": average, "tare_readings": tare, "classify": bool(estimator.classify),
              "command_range": (eq, high)}  # fmt: skip
    controller = ForceController(
        estimator, offset, gain=gain, low=eq, high=high, sign=sign, approach_rate=approach_rate, servo=servo,
        contact_fraction=CONTACT_FRACTION, average_readings=average, free_step=bool(region.get("free_step", False)),
        place_readings=PLACE_READINGS if region.get("free_step", False) and region.get("place_told", False) else 0,
        integer_band=float(region.get("integer_band", 0.0)),
    )  # fmt: skip
    # the digit's own motion read as contact (the moving shape through the statics), on its twin at the tare
    motion = free_motion_chi2(controller, model, eq)
    controller.detect_chi2 = motion_detect_chi2(estimator.detect_chi2, motion)
    region.update(free_motion_chi2=motion, detect_chi2=controller.detect_chi2)
    return controller, region


def _refuse_uncertain(model, force_sd_n: float, setpoint_n: float, duration_s: float, least_n: float) -> None:
    """Refuse, in one line, a hold whose force read would be uncertain by more than :data:`HELD_SD_SHARE` of its
    setpoint (:func:`_uncertain_hold`; its tare and the drift over ``duration_s``, :func:`_held_force_sd`)."""
    held_sd = _held_force_sd(model, force_sd_n, duration_s, _tare_readings(force_sd_n, setpoint_n))
    uncertain = _uncertain_hold(setpoint_n, held_sd, least_n)
    if uncertain:
        raise ParameterError(f"hold: {uncertain}; the digit was not moved")


def _uncertain_hold(setpoint_n: float, held_sd_n: float, least_n: float) -> str:
    """Why a hold of ``setpoint_n`` cannot be said to hold it within 10 %, in one line ("" when it can): its force
    read uncertain (1 sd, ``held_sd_n``) by more than :data:`HELD_SD_SHARE` of it; ``least_n`` the least force the
    digit holds within it (:func:`_least_held`)."""
    if not held_sd_n > HELD_SD_SHARE * setpoint_n:
        return ""
    return (
        f"cannot hold {setpoint_n:g} N within 10 %: the force its gauges read is uncertain by {1000 * held_sd_n:.0f} "
        f"mN (1 sd: the tare's noise and their drift over the hold, read as force), more than "
        f"{100 * HELD_SD_SHARE:g} % of it; it holds {least_n:g} N or more within 10 %"
    )


def _least_held(model, force_sd_n: float, duration_s: float) -> float:
    """The least setpoint (N, 2 figures, rounded up) whose hold's force read is uncertain by at most
    :data:`HELD_SD_SHARE` of it (:func:`_held_force_sd`; its tare on the readings that setpoint takes, fewer for a
    larger force: :func:`_tare_readings`), ``force_sd_n`` one reading's force sd (taken as the same at any force)."""
    if not math.isfinite(force_sd_n):
        return math.nan

    def held(f):
        return _held_force_sd(model, force_sd_n, duration_s, _tare_readings(force_sd_n, f))

    f = held(1.0) / HELD_SD_SHARE  # the drift's share alone, the tare's least
    if not f > 0:  # a noiseless twin's gauges: any force
        return 0.0
    while held(f) > HELD_SD_SHARE * f:
        f *= 1.02
    scale = 10 ** (math.floor(math.log10(f)) - 1)
    return float(f"{math.ceil(f / scale - 1e-9) * scale:.2g}")


def _tare_readings(force_sd_n: float, setpoint_n: float) -> int:
    """Readings the hold tares on: :data:`TARE_READINGS`, or enough for the tare's force error (one reading's force
    sd over their root) to stay within :data:`TARE_SHARE` of the setpoint (the one-gauge digit: 36 mN a reading,
    118 readings, 2.4 s; the thesis rig 3.3 mN, its 10)."""
    if not math.isfinite(force_sd_n):
        return TARE_READINGS
    return min(MAX_TARE_READINGS, max(TARE_READINGS, math.ceil((force_sd_n / (TARE_SHARE * setpoint_n)) ** 2)))


def _tare(rig, readings: int) -> np.ndarray:
    """The mean of ``readings`` gauge readings at rest: :data:`TARE_READINGS` read at once (the thesis rig's tare, as
    it was), more read one loop period (20 ms) apart, as the loop reads them."""
    if readings <= TARE_READINGS:
        return np.array([rig.read().gauges_v for _ in range(readings)]).mean(axis=0)
    rest = []
    for _ in range(readings):
        rest.append(rig.read().gauges_v)
        rig.wait(0.020)
    return np.array(rest).mean(axis=0)


def _steady_place(controller, result, window_s: float) -> float:
    """The place from the window's mean reading at the mean command sent (what the Cramer-Rao sd over the window is
    for: a median of one-reading estimates is biased where the region ends at the tip, 37 mm on the thesis rig)."""
    t = result.time_s
    window = t >= t[-1] - window_s if t.size else np.zeros(0, dtype=bool)
    if not np.any(window):
        return math.nan
    controller.force(result.gauges_v[window].mean(axis=0), float(np.mean(result.command[window])))
    return controller.place_m


def _hold_figures(t, scored, setpoint: float, window_s: float) -> tuple:
    """A hold's figures from its scored force: steady force and error and ripple over the last ``window_s``,
    overshoot, and the settling time (the last time outside 10 % of the setpoint)."""
    last = t >= t[-1] - window_s if t.size else np.zeros(0, dtype=bool)
    steady = float(np.mean(scored[last])) if np.any(last) else math.nan
    outside = np.flatnonzero(np.abs(scored - setpoint) > 0.1 * setpoint)
    settling = (
        float(t[outside[-1] + 1])
        if outside.size and outside[-1] + 1 < t.size
        else (0.0 if not outside.size else math.inf)
    )
    return (
        steady,
        (steady - setpoint) / setpoint,
        float(np.std(scored[last])) if np.any(last) else math.nan,
        float(max(0.0, (np.max(scored) - setpoint) / setpoint)) if scored.size else math.nan,
        settling,
    )
