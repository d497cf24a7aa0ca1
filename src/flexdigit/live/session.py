"""A live session: the rig's 50 Hz loop in a thread of its own, what the page shows, and what the page may ask.

:class:`LiveSession` opens a backend (the twin in real time, the hardware, or a replay played at 1x or 10x), runs
read -> controller -> command on absolute 20 ms deadlines (the servo board's frame, 5.2), keeps the last
``history_s`` seconds of samples, estimates the shape and the contact from the latest readings
(:class:`flexdigit.shape.shape.ShapeEstimator`, and a trained network when given), records everything to MCAP
when asked (:mod:`flexdigit.rig.recording`), and takes the page's requests through :meth:`LiveSession.request`,
which validates and clamps every field (a client message is bad input like a bad file).

Why not :func:`flexdigit.rig.loop.run_loop`: a live loop has no end and takes requests while it runs; ``run_loop``
is a fixed-length run that keeps every sample in memory. The deadline rule is the same (absolute deadlines, missed
ones counted and skipped, never burst).

Safety: the loop sends the equilibrium command and closes the port whenever it ends (stop, fault, exception);
when the last page disconnects the controller lets go and the digit is relaxed (command 8) until a page asks for
a setpoint again; the recording is closed (summary, footer) by :meth:`LiveSession.stop`, and every second of it
is on the disk before that (:class:`~flexdigit.rig.recording.Recording` flushes its chunks).

Contact sources are pluggable (:class:`ContactSource`): the beam inversion of the shape estimator always, a
trained network (``--model``) when given; a palpation estimate adds itself the same way.
"""

from __future__ import annotations

import collections
import concurrent.futures
import math
import queue
import threading
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from flexdigit._validation import check_choice, check_real
from flexdigit.errors import ParameterError, RigError
from flexdigit.live.schemas import CONTACT_SCHEMA, SHAPE_SCHEMA
from flexdigit.params import RigParams, load_params
from flexdigit.rig.base import open_rig, parse_rig_url, rig_url_options
from flexdigit.rig.controllers import make_controller
from flexdigit.rig.loop import check_reading
from flexdigit.rig.recording import Recording, read_metadata, rig_metadata
from flexdigit.rig.rotation import load_rotation_map, make_rotation_map
from flexdigit.rig.step_test import reachable_rotation_deg
from flexdigit.shape.shape import ShapeEstimator
from flexdigit.tactile.model_io import load_model
from flexdigit.twin.calibration import Calibration
from flexdigit.twin.digit_calibration import twin_calibration

__all__ = [
    "LiveSession",
    "ContactSource",
    "BeamContact",
    "NetworkContact",
    "validate_request",
    "estimate_due",
    "REQUESTS",
    "SETPOINT_RANGES",
    "setpoint_range",
]

#: The page's requests and their fields: ``{type: {field: (kind, low, high)}}``; numbers are clamped to the range
#: (None: the session's own, :data:`SETPOINT_RANGES` for a setpoint, the digit's length for a position).
REQUESTS: dict[str, dict[str, tuple]] = {
    "setpoint": {"value": ("number", None, None)},
    "load": {"position_m": ("number", 0.0, None), "mass_g": ("number", 1.0, 200.0), "kind": ("choice", "weight")},
    "clear": {},
    "pause": {"paused": ("bool",)},
    "speed": {"speed": ("choice", 1, 10)},
}
#: The largest request accepted, bytes.
MAX_REQUEST_BYTES = 512
#: The setpoint slider's range per unit: beam rotation (the controller's, deg) or the servo command itself (open loop).
SETPOINT_RANGES = {"deg": (0.0, 45.0), "command": (0.0, 60.0)}


def setpoint_range(params: RigParams, unit: str) -> tuple[float, float]:
    """The slider's range on the digit ``params`` describes, in ``unit`` (:data:`SETPOINT_RANGES`'s keys).

    A beam rotation within :data:`SETPOINT_RANGES` and what the servo reaches by the cable model (E 3.15 with the
    gearing: ``(command - straight) x deg per command``); with an antagonistic pair (``cables.count = 2``) the
    digit bends both ways, so the range runs as far below zero as the servo's lowest command reaches, at most
    as far as above it. Open loop (``command``), the serial command itself (with a pair, 60 commands each side of
    the straight one).

    Examples
    --------
    >>> setpoint_range(RigParams(), "deg")
    (0.0, 45.0)
    >>> pair = RigParams.from_dict({"cables": {"count": 2, "pretension_n": 5.0}})  # straight at command 127
    >>> setpoint_range(pair, "deg"), setpoint_range(pair, "command")
    ((-45.0, 45.0), (67.0, 187.0))
    """
    low, high = SETPOINT_RANGES[unit]
    a = params.actuator
    two = params.cables.count == 2
    if unit == "command":  # a pair: as many commands each side of straight as the single cable's slider spans
        if two:
            straight = a.equilibrium_command
            return (float(max(a.command_min, straight - high)), float(min(a.command_max, straight + high)))
        return (low, min(high, float(a.command_max)))
    bottom, top = reachable_rotation_deg(params)  # run --setpoint-deg's reach (0 below for a single cable)
    return (round(max(-high if two else low, bottom), 3), round(min(high, top), 3))


def validate_request(
    message: object, digit_length_m: float = 0.27, setpoint_range: tuple[float, float] = SETPOINT_RANGES["deg"]
) -> dict[str, Any]:
    """Check a request from the page and clamp its numbers; raise :class:`ParameterError` naming what is wrong.

    A setpoint is clamped to ``setpoint_range`` (the slider's, in the session's unit), a load's position to the
    digit (0..``digit_length_m``, m) and its mass to 1..200 g.

    Examples
    --------
    >>> validate_request({"type": "setpoint", "value": 99})
    {'type': 'setpoint', 'value': 45.0}
    >>> validate_request({"type": "load", "position_m": 0.2, "mass_g": 25, "kind": "weight"})["mass_g"]
    25.0
    >>> validate_request({"type": "reboot"})
    Traceback (most recent call last):
    ...
    flexdigit.errors.ParameterError: The 'type' parameter of a request must be one of 'setpoint', 'load', 'clear', \
'pause', 'speed'. Got 'reboot' instead.
    """
    if not isinstance(message, dict):
        raise ParameterError(f"a request must be a JSON object. Got {type(message).__name__}.")
    kind = check_choice(message.get("type"), "type", tuple(REQUESTS), "a request")
    fields = REQUESTS[kind]
    extra = set(message) - set(fields) - {"type"}
    if extra:
        raise ParameterError(f"a {kind!r} request has no field {sorted(extra)[0]!r}; it takes {sorted(fields)}")
    out: dict[str, Any] = {"type": kind}
    for name, spec in fields.items():
        if name not in message:
            raise ParameterError(f"a {kind!r} request needs the field {name!r}")
        value = message[name]
        if spec[0] == "number":
            x = check_real(value, name, f"a {kind!r} request")
            if kind == "setpoint":
                low, high = setpoint_range
            else:
                low, high = spec[1], digit_length_m if spec[2] is None else spec[2]
            out[name] = float(min(max(x, low), high))
        elif spec[0] == "bool":
            if not isinstance(value, bool):
                raise ParameterError(
                    f"The '{name}' parameter of a {kind!r} request must be true or false. Got {value!r}"
                )
            out[name] = value
        else:
            if value not in spec[1:] or isinstance(value, bool):
                options = ", ".join(repr(o) for o in spec[1:])
                raise ParameterError(
                    f"The '{name}' parameter of a {kind!r} request must be one of {options}. Got {value!r}"
                )
            out[name] = value
    return out


# -- contact sources ---------------------------------------------------------------------------------------------


class ContactSource:
    """Something that says where the digit is touched: ``estimate(gauges_v, command, shape) -> dict``.

    The dict has ``source``, ``contact`` (bool), ``position_from_base_m``, ``position_sd_m`` and
    ``position_interval_m`` (None where unknown), ``force_n``, ``mass_kg``, ``located`` (its standard deviation
    below the page's threshold) and ``note`` (a sentence for the page).
    """

    name = "contact"

    def estimate(self, gauges_v: np.ndarray, command: int | None, shape) -> dict[str, Any]:  # pragma: no cover
        raise NotImplementedError


def _finite(x) -> float | None:
    try:
        value = float(x)
    except (TypeError, ValueError):
        return None
    return value if math.isfinite(value) else None


@dataclass
class BeamContact(ContactSource):
    """The shape estimator's own load (its beam inversion): position with its profile interval, force, contact."""

    located_sd_m: float = 0.005
    name: str = "beam inversion"

    def estimate(self, gauges_v, command, shape) -> dict[str, Any]:
        row = shape.row(0, every=1000)
        sd = row["load_position_sd_m"]
        contact = bool(row["contact"])
        located = contact and sd is not None and sd <= self.located_sd_m
        if not contact:
            note = "no load found"
        elif located:
            note = f"located to +- {1e3 * sd:.1f} mm"
        elif sd is None:
            note = (
                "a load, but the readings cannot place it here (its position trades off with its force or the tension)"
            )
        else:
            note = f"a load, placed only to +- {1e3 * sd:.0f} mm here"
        return {
            "source": self.name,
            "contact": contact,
            "position_from_base_m": row["load_position_from_base_m"],
            "position_sd_m": sd,
            "position_interval_m": row["load_position_interval_m"],
            "force_n": row["load_force_n"],
            "mass_kg": row["load_mass_kg"],
            "located": located,
            "consistent": row["consistent"],
            "note": note if row["consistent"] else "the readings do not fit the model (calibration?)",
        }


class NetworkContact(ContactSource):
    """A trained position network (``flexdigit train --target position``): position from the gauges (and the
    command if it was trained with it); its band is the test RMSE the model file carries. Contact comes from the
    beam inversion (a position network has no "no load" answer)."""

    def __init__(self, path, digit_length_m: float) -> None:
        self.model = load_model(path)
        if self.model.target != "position":
            raise ParameterError(f"{path}: a {self.model.target!r} model; the live page needs a 'position' model")
        self.with_command = len(self.model.inputs) == 4
        self.rmse_m = _finite(self.model.meta.get("scores", {}).get("rmse_mm"))
        self.rmse_m = None if self.rmse_m is None else self.rmse_m / 1e3
        self.length = digit_length_m
        self.name = f"network {path}"

    def estimate(self, gauges_v, command, shape) -> dict[str, Any]:
        x = list(gauges_v) + ([command if command is not None else 8] if self.with_command else [])
        from_tip = float(np.ravel(self.model.network.predict(np.array([x], dtype=float)))[0])
        position = min(max(self.length - from_tip, 0.0), self.length)
        contact = bool(shape.contact[0])
        band = None if self.rmse_m is None else [position - self.rmse_m, position + self.rmse_m]
        return {
            "source": self.name,
            "contact": contact,
            "position_from_base_m": position if contact else None,
            "position_sd_m": self.rmse_m if contact else None,
            "position_interval_m": band if contact else None,
            "force_n": None,
            "mass_kg": None,
            "located": contact,
            "consistent": True,
            "note": "trained network; band = its test RMSE" if contact else "no load found (beam inversion)",
        }


# -- the session -------------------------------------------------------------------------------------------------


def _recorded_digit(path: str):
    """The digit an MCAP recording was made on (its ``flexdigit.rig`` metadata: parameters and, of a twin, its
    calibration), so that a replay draws and estimates with the recorded gauges; ``(None, None)`` for a loop log or
    a recording without them (the thesis rig, as before). A recording that cannot be read is left to the replay
    backend to name."""
    if not str(path).lower().endswith(".mcap"):
        return None, None
    try:
        rig = read_metadata(path).get("flexdigit.rig") or {}
    except Exception:  # noqa: BLE001 - the replay backend opens it next and says what is wrong with it
        return None, None
    if not isinstance(rig.get("params"), dict):
        return None, None
    # written as dataclasses.asdict: an optional key left out is None there (RigParams.to_dict drops them too)
    recorded_params = {
        section: {k: v for k, v in values.items() if v is not None} if isinstance(values, dict) else values
        for section, values in rig["params"].items()
    }
    params = RigParams.from_dict(recorded_params, source=f"{path}: its recorded parameters")
    recorded = rig.get("twin_calibration")
    calibration = Calibration.from_dict(recorded, f"{path}: its recorded calibration") if recorded else None
    return params, calibration


def estimate_due(
    change_v: float,
    command_changed: bool,
    since_s: float,
    *,
    still_v: float,
    creep_v: float,
    window_s: float,
    max_gap_s: float,
) -> bool:
    """Whether the live loop re-estimates the shape now (it asks every other frame, the shape at up to 25 Hz).

    A digit at rest gives the same estimate again, so: when the command changed, when the averaged readings moved
    by more than ``creep_v`` (V, the largest gauge's change since the last estimate), or ``max_gap_s`` passed (the
    twin's truth moves on). Readings that moved by ``still_v``..``creep_v`` (3-6 standard deviations of a difference
    of two means) are a settling tail, a shape moving by a fraction of its own uncertainty band: re-estimated once
    ``window_s`` (the averaging window) has passed, so that each estimate averages readings the last one did not
    see, rather than every 40 ms (in the bench's stepping phase that halves the estimates of the second after each
    step, the largest share of the server's CPU).

    Examples
    --------
    >>> due = dict(still_v=3e-4, creep_v=6e-4, window_s=0.1, max_gap_s=1.0)
    >>> estimate_due(1e-3, False, 0.04, **due), estimate_due(4e-4, False, 0.04, **due)
    (True, False)
    >>> estimate_due(4e-4, False, 0.12, **due), estimate_due(1e-4, False, 0.5, **due)
    (True, False)
    """
    if command_changed or since_s >= max_gap_s or change_v > creep_v:
        return True
    return change_v > still_v and since_s >= window_s - 1e-9


@dataclass
class Sample:
    """One loop sample as the page and the recording see it."""

    k: int
    t: float
    wall_ms: float
    gauges_v: list
    pot_v: float | None
    command: int
    setpoint: float | None
    y: float | None

    def as_dict(self) -> dict[str, Any]:
        return {
            "k": self.k,
            "t": round(self.t, 4),
            "wall_ms": round(self.wall_ms, 1),
            "gauges_v": self.gauges_v,
            "pot_v": self.pot_v,
            "command": self.command,
            "setpoint": self.setpoint,
            "y": self.y,
        }


@dataclass
class _State:
    """What the page shows, guarded by the session's lock."""

    samples: collections.deque = field(default_factory=lambda: collections.deque(maxlen=600))
    shape: dict | None = None
    truth: list | None = None
    contact: list = field(default_factory=list)
    status: str = "starting"
    locatability: dict | None = None
    overruns: int = 0


class LiveSession:
    """The rig loop behind the live page (see the module docstring).

    Parameters
    ----------
    backend : str
        A rig URL (:func:`flexdigit.rig.base.open_rig`); ``sim`` runs the twin on the wall clock (``sim+paced``),
        horizontal by default (the mounting of chapters 6-7, where a hung weight bends the digit). A twin (or
        ``hil://``'s board) is paced from the loop's start: before it, the controller's tare reads it at rest in
        virtual time, and the stream's time carries on from there rather than from the session's opening.
    model : path, optional
        A trained position network for the contact panel.
    record : path, optional
        An MCAP recording of the session (refused if it exists unless ``force``).
    params : path or RigParams, optional
        The digit (``flexdigit params``): its twin on ``sim``, the rig's description on hardware; any section and
        gauge count, one cable or an antagonistic pair (then the setpoint takes both signs). The thesis rig by
        default.
    calibration : path, optional
        A calibration TOML (``flexdigit calibrate``): the twin's on ``sim``, and on every backend the channel
        gains, offsets, stiffness and noise the shape estimate uses; by default the thesis's fit, scaled to the
        digit (:func:`flexdigit.twin.digit_calibration.twin_calibration`, as ``flexdigit run --params`` does).
    rotation_map : path, optional
        A rotation map (``flexdigit run --rotation-map``) for the controller on hardware; the twin calibrates its own.
    orientation : str, optional
        How the digit is mounted, for the shape estimate on hardware (the twin knows its own).
    period_s : float
        Loop period (the servo board's 20 ms frame).
    seed : int, optional
        Twin noise seed (default: the URL's ``seed=``, else 0).
    clock, sleep : callable
        The loop's pacing: a monotonic clock (s) and a sleep, as :func:`flexdigit.rig.loop.run_loop` takes them
        (default :func:`time.monotonic` and :func:`time.sleep`); the twin (``sim``) runs on the same clock.
    """

    HISTORY_S = 10.0
    #: Requests waiting for the loop at most: more than every page's burst at once (the server's 8 pages x 40; the
    #: loop applies them every 20 ms), so only a loop that is stuck refuses them, telling the page it is behind.
    MAX_PENDING_REQUESTS = 512
    ESTIMATE_EVERY = 2  # frames: the shape at up to 25 Hz
    AVERAGE = 5  # readings averaged into each estimate (0.1 s)
    #: Re-estimate at least this often even when nothing moved (s).
    MAX_ESTIMATE_GAP_S = 1.0
    #: Readings count as moved when their 0.1 s mean changed by more than this many of its own standard deviations.
    STILL_SIGMAS = 3.0
    #: ... and as creeping (a settling tail) below this many: re-estimated once per window of fresh readings
    #: (:func:`estimate_due`).
    CREEP_SIGMAS = 6.0
    #: The locatability map is computed for commands rounded to this step (and cached).
    MAP_COMMAND_STEP = 4

    def __init__(
        self,
        backend: str = "sim",
        *,
        model=None,
        record=None,
        force: bool = False,
        params=None,
        calibration=None,
        rotation_map=None,
        orientation: str | None = None,
        period_s: float = 0.020,
        seed: int | None = None,
        clock=time.monotonic,
        sleep=time.sleep,
    ) -> None:
        # the loop's pacing clock, injected as run_loop's is (tests run it in virtual time)
        self._clock, self._sleep = clock, sleep
        given_params = params if params is None or isinstance(params, RigParams) else load_params(params)
        self.period_s = check_real(period_s, "period_s", "LiveSession", low=0.005, high=1.0)
        parsed = parse_rig_url(backend)
        self.kind = {"sim": "twin", "sim+paced": "twin", "replay": "replay"}.get(parsed.scheme, "rig")
        recorded_calibration = None
        if self.kind == "replay" and given_params is None:  # the recorded digit: its gauges, sections, cables
            given_params, recorded_calibration = _recorded_digit(parsed.location)
        if calibration is None and recorded_calibration is not None:
            self.calibration = recorded_calibration
        else:
            self.calibration = twin_calibration(given_params, calibration)
        self.backend = backend
        if self.kind == "twin":
            options = {"orientation": "horizontal", **parsed.options}
            query = "&".join(f"{k}={v}" for k, v in options.items())
            self.rig_url = f"sim+paced?{query}"
            # the URL's seed= or the seed given, never one silently over the other (issue 16)
            given = {} if seed is None else {"seed": seed}
            # the twin keeps the loop's clock (a test's virtual one steps it in virtual time), and an injected sleep
            # with it: once paced, the rig's own waits must move that clock, not spin on it
            pacing = {"clock": clock} if sleep is time.sleep else {"clock": clock, "sleep": sleep}
            # in virtual time until the loop starts (start_pacing): the tare's waits step the twin, its readings are
            # of the twin at rest, and the seconds the start computes (map, design) are not simulated afterwards
            self.rig = open_rig(
                self.rig_url, given_params, calibration=self.calibration, start_paced=False, **pacing, **given
            )
        else:
            self.rig_url = backend
            # the emulated board keeps pace with the page, as the twin does (sim -> sim+paced), from the loop's start
            paced = {"paced": True} if parsed.scheme == "hil" and "paced" not in parsed.options else {}
            held = {"start_paced": False} if parsed.scheme == "hil" else {}
            self.rig = open_rig(backend, given_params, **paced, **held)
        try:
            self._setup(model, record, force, rotation_map, orientation, seed)
        except BaseException:
            self.rig.close()
            raise
        self._lock = threading.Lock()
        # bounded: pages within their budgets cannot pile requests up behind a loop that is stuck (a rig's read
        # blocking); the relax on the last page leaving never waits for room (a flag when the queue is full)
        self._requests: queue.Queue = queue.Queue(maxsize=self.MAX_PENDING_REQUESTS)
        self._relax_due = threading.Event()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._estimator_thread: threading.Thread | None = None
        self._job = None
        self._job_ready = threading.Condition()
        self.estimate_error: str | None = None
        self.state = _State(samples=collections.deque(maxlen=int(self.HISTORY_S / self.period_s)))
        self.clients = 0
        self.paused = False
        self.speed = 1
        self.engaged = False  # the controller holds the setpoint only while a page asks for it
        #: CPU time (s) the loop spent inside the rig's read and write: on the twin, its simulation of the digit
        self.rig_cpu_s = 0.0
        self.error: str | None = None
        #: The signal that stopped the server (SIGINT, SIGTERM, SIGHUP), named in the recording's stop record.
        self.stopped_by: str | None = None

    def _setup(self, model, record, force, rotation_map, orientation, seed) -> None:
        rig = self.rig
        params = rig.params
        self.length_m = params.geometry.digit_length_m
        twin = getattr(rig, "twin", None)
        if twin is not None:
            orientation, cable, housing = twin.orientation, twin.cable, twin.housing
        else:
            orientation, cable, housing = orientation or "vertical", True, True
        self.orientation, self.cable = orientation, cable
        self.estimator, self._loc_estimator = (
            ShapeEstimator(
                params, self.calibration, orientation=orientation, housing=housing, cable=cable, n_average=self.AVERAGE
            )
            for _ in range(2)
        )
        self._loc_cache: dict = {}
        self._loc_pending: set = set()
        self._loc_worker = concurrent.futures.ThreadPoolExecutor(max_workers=1, thread_name_prefix="flexdigit-map")
        white = float(np.max(self.calibration.noise_white_v))
        self._still_v = self.STILL_SIGMAS * white * math.sqrt(2.0 / self.AVERAGE)  # a difference of two means
        self._creep_v = self._still_v * self.CREEP_SIGMAS / self.STILL_SIGMAS
        self.contacts: list[ContactSource] = [BeamContact()]
        if model is not None:
            self.contacts.insert(0, NetworkContact(model, self.length_m))
        self.controller, self.unit = None, "command"
        self.recorded_controller = None  # a replay's: the controller its recording was made under
        self.setpoint = float(params.actuator.equilibrium_command)
        if self.kind == "twin" and cable:
            # a static sweep on a twin of its own (virtual time, the twin's 20 ms step: nothing moves fast)
            _, options = rig_url_options(self.rig_url)
            options = {k: v for k, v in options.items() if k != "spin_s"}
            options["seed"] = rig.settings()["seed"] + 1
            # the thesis rig's map is the same at the twin's coarsest step, sooner; another digit's may not settle
            # at it (a 4 x 80 mm pair, horizontal, rings at 20 ms)
            if params.is_thesis_rig():
                options["dt_s"] = 0.02
            # the map run --params makes (make_rotation_map's twin source), on a twin of this digit
            estimator = make_rotation_map(rig, "twin", twin_options={"calibration": self.calibration, **options})
            self.controller = make_controller("digital20", rig, period_s=self.period_s, estimator=estimator)
            self.unit, self.setpoint = "deg", 0.0
        elif self.kind == "rig" and rotation_map is not None:
            estimator = load_rotation_map(rotation_map)
            self.controller = make_controller("digital20", rig, period_s=self.period_s, estimator=estimator)
            self.unit, self.setpoint = "deg", 0.0
        self.setpoint_range = setpoint_range(params, self.unit)
        self.recording = None
        if self.kind == "replay":
            samples = rig.samples
            self._replayed = samples
            self._replayed_t = rig.times_s - rig.times_s[0]  # an array: no float object per sample
            self._replay_length_s = float(samples[-1]["t"]) - float(samples[0]["t"])
            self.setpoint = None
            # a recording made under a controller (run, live's closed loop) has its setpoint and measured value in
            # the controller's unit, the beam rotation; one without (collect, open loop, another writer's) commands
            self.recorded_controller = (getattr(rig, "header", None) or {}).get("controller")
            self.unit = "deg" if self.recorded_controller else "command"
            self.setpoint_range = setpoint_range(params, self.unit)
        if record is not None:
            self.recording = Recording(
                record,
                header={"backend": self.backend, "controller": "digital20" if self.controller else None,
                        "period_s": self.period_s, "source": "flexdigit live",
                        "seed": self.rig.settings().get("seed")},
                metadata={
                    **rig_metadata(rig),
                    "flexdigit.calibration": {"estimator": repr(self.estimator), **self.calibration.to_dict()},
                },
                force=force,
            )  # fmt: skip
            self.recording.add_channel("/flexdigit/shape", SHAPE_SCHEMA)
            self.recording.add_channel("/flexdigit/contact", CONTACT_SCHEMA)

    # -- what the server calls -----------------------------------------------------------------------------------
    def hello(self) -> dict[str, Any]:
        """The page's set-up: the digit, what it may ask, units."""
        g = self.rig.params.geometry
        return {
            "type": "hello",
            "backend": self.backend,
            "kind": self.kind,
            "orientation": self.orientation,
            "cable": self.cable,
            "digit_length_m": self.length_m,
            "gauges_m": list(g.gauge_positions_m),
            "section_count": g.section_count,
            "supports_m": list(g.support_centres_m),
            "cables": self.rig.params.cables.count,
            "straight_command": int(self.rig.params.actuator.equilibrium_command),
            "setpoint_unit": self.unit,
            "setpoint_range": list(self.setpoint_range),
            "can_command": self.kind != "replay" and self.cable,
            "can_load": self.kind == "twin",
            "loads_g": [12.5, 25.0, 37.5, 50.0],
            "speeds": [1, 10] if self.kind == "replay" else [1],
            "period_s": self.period_s,
            "history_s": self.HISTORY_S,
            "located_sd_m": BeamContact.located_sd_m,
            "contact_sources": [c.name for c in self.contacts],
        }

    def request(self, message: object) -> dict[str, Any]:
        """Validate a page request and queue it for the loop; returns the clamped request (raises when bad)."""
        clean = validate_request(message, self.length_m, self.setpoint_range)
        kind = clean["type"]
        if kind in ("setpoint",) and not (self.kind != "replay" and self.cable):
            raise ParameterError("this backend takes no setpoint (a replay, or the cable is detached)")
        if kind in ("load", "clear") and self.kind != "twin":
            raise ParameterError("only the twin can be loaded from the page; on a rig the operator hangs weights")
        if kind == "speed" and self.kind != "replay":
            raise ParameterError("only a replay has a playback speed")
        try:
            self._requests.put_nowait(clean)
        except queue.Full:
            raise ParameterError(
                f"the rig loop is behind ({self.MAX_PENDING_REQUESTS} requests waiting); request dropped, try again"
            ) from None
        return clean

    def connected(self) -> None:
        with self._lock:
            self.clients += 1

    def disconnected(self) -> None:
        """A page went away: with none left the controller lets go and the digit is relaxed."""
        with self._lock:
            self.clients = max(self.clients - 1, 0)
            none_left = self.clients == 0
        if none_left:
            try:
                self._requests.put_nowait({"type": "relax"})
            except queue.Full:  # never lost: the loop relaxes once it has emptied the queue
                self._relax_due.set()

    def snapshot(self, since_k: int) -> dict[str, Any]:
        """Samples after ``since_k`` and the latest estimates, for one page update."""
        with self._lock:
            # the new samples are the newest: walk back to since_k rather than over all 10 s of them (30 times a
            # second per page)
            fresh = []
            for sample in reversed(self.state.samples):
                if sample.k <= since_k:
                    break
                fresh.append(sample)
            samples = [s.as_dict() for s in reversed(fresh)]
            return {
                "type": "frame",
                "samples": samples,
                "shape": self.state.shape,
                "truth": self.state.truth,
                "contact": self.state.contact,
                "state": {
                    "status": self.state.status,
                    "setpoint": self.setpoint,
                    "unit": self.unit,
                    "controller": "digital20" if self.controller else self.recorded_controller,
                    "engaged": self.engaged,
                    "paused": self.paused,
                    "speed": self.speed,
                    "loads": [[round(m, 5), round(s, 4)] for m, s in getattr(self.rig, "loads", [])],
                    "overruns": self.state.overruns,
                    "estimate_error": self.estimate_error,
                    "clients": self.clients,
                    "rig_cpu_s": round(self.rig_cpu_s, 4),
                    # a paced simulation this far behind the wall clock (a machine slower than real time)
                    "lag_s": round(float(getattr(self.rig, "lag_s", 0.0)), 4),
                    "server_ms": time.time() * 1e3,
                },
                "locatability": self.state.locatability,
            }

    # -- the loop ------------------------------------------------------------------------------------------------
    def start(self) -> None:
        """Start the loop thread and the estimator thread."""
        self._thread = threading.Thread(target=self._run, name="flexdigit-live-loop", daemon=True)
        self._estimator_thread = threading.Thread(target=self._estimates, name="flexdigit-live-shape", daemon=True)
        self._thread.start()
        self._estimator_thread.start()

    def stop(self, timeout_s: float = 5.0) -> None:
        """Stop the loop: safe command, port closed, recording closed (idempotent)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout_s)
        if self._estimator_thread is not None:
            self._estimator_thread.join(timeout_s)
        self._shutdown("stopped")

    def _shutdown(self, why: str) -> None:
        self._loc_worker.shutdown(wait=False, cancel_futures=True)
        with self._job_ready:
            self._job_ready.notify_all()
        try:
            if not self.rig.closed:
                self.rig.close()  # sends the equilibrium command, then releases the port
        finally:
            if self.recording is not None and not self.recording.closed:
                stop = {"stop": why, "message": self.error or why}
                if self.stopped_by:
                    stop["signal"] = self.stopped_by
                self.recording.close(stop)

    def _run(self) -> None:
        rig = self.rig
        adc = tuple(rig.params.sensors.adc_range_v)
        equilibrium = int(rig.params.actuator.equilibrium_command)
        if self.controller is not None:
            self.controller.reset(rig.command)
        if hasattr(rig, "start_pacing"):  # a paced twin or board: the wall clock's from here, carrying on from
            rig.start_pacing()  # the time its start (map, tare) left it at
        t0 = self._clock()
        virtual = 0.0  # replay time
        k = 0
        window: collections.deque = collections.deque(maxlen=self.AVERAGE)
        last_job = None
        try:
            with self._lock:
                self.state.status = "running"
            while not self._stop.is_set():
                deadline = t0 + k * self.period_s / (self.speed if self.kind == "replay" else 1)
                now = self._clock()
                if now < deadline:
                    self._sleep(deadline - now)
                elif now - deadline > self.period_s:
                    with self._lock:
                        self.state.overruns += 1
                    t0 = now - k * self.period_s / (self.speed if self.kind == "replay" else 1)  # resynchronise
                speed = self.speed
                self._apply_requests()
                if self.speed != speed:  # a new replay speed: new deadlines from here, not a missed one
                    t0 = self._clock() - k * self.period_s / self.speed
                if self.paused and self.kind == "replay":
                    t0 = self._clock() - k * self.period_s / self.speed
                    self._sleep(self.period_s)
                    continue
                if self.kind == "replay":
                    if virtual + self.period_s > self._replay_length_s:
                        with self._lock:
                            self.state.status = "replay finished"
                        self._stop.wait(0.2)
                        t0 = self._clock() - k * self.period_s / self.speed  # waiting is not a missed deadline
                        continue
                    rig.wait(self.period_s)
                    virtual += self.period_s
                start = time.thread_time()
                reading = rig.read()
                self.rig_cpu_s += time.thread_time() - start
                check_reading(reading, adc)
                command = self._act_and_record(k, reading, equilibrium)
                window.append(reading.gauges_v)
                if k % self.ESTIMATE_EVERY == 0 and len(window) == window.maxlen:
                    last_job = self._offer_estimate(np.mean(window, axis=0), command, reading.time_s, last_job)
                k += 1
        except (RigError, OSError) as exc:
            self.error = f"fault: {exc}"
        except Exception as exc:  # a bug must still leave the rig safe; say what it was
            self.error = f"error: {type(exc).__name__}: {exc}"
        finally:
            with self._lock:
                self.state.status = self.error or "stopped"
            self._shutdown(self.error or "stopped")

    def _act_and_record(self, k: int, reading, equilibrium: int) -> int:
        """Act on reading ``k``, record it (file and page history) and return the command sent."""
        wall_ms = time.time() * 1e3
        command, setpoint, y = self._act(reading, equilibrium)
        sample = Sample(
            k,
            reading.time_s,
            wall_ms,
            [round(float(g), 6) for g in reading.gauges_v],
            _finite(reading.pot_v),
            int(command),
            setpoint,
            y,
        )
        if self.recording is not None:
            self.recording.write_sample({kk: v for kk, v in sample.as_dict().items() if kk != "wall_ms"})
        with self._lock:
            self.state.samples.append(sample)
        return command

    def _offer_estimate(self, mean, command: int, time_s: float, last_job):
        """Hand the estimate thread a new job when the digit moved since ``last_job`` (:func:`estimate_due`);
        the job handed, else ``last_job``."""
        moved = last_job is None or estimate_due(
            float(np.max(np.abs(mean - last_job[0]))),
            command != last_job[1],
            time_s - last_job[2],
            still_v=self._still_v,
            creep_v=self._creep_v,
            window_s=self.AVERAGE * self.period_s,
            max_gap_s=self.MAX_ESTIMATE_GAP_S,
        )
        if not moved:
            return last_job
        # the estimate runs in its own thread: hand it the latest job (a slower one skips some)
        twin = getattr(self.rig, "twin", None)
        psi = None if twin is None else np.array(twin.state()[0])
        job = (mean, command, time_s, psi)
        with self._job_ready:
            self._job = job
            self._job_ready.notify()
        return job

    def _apply_requests(self) -> None:
        rig = self.rig
        while True:
            try:
                req = self._requests.get_nowait()
            except queue.Empty:
                if not self._relax_due.is_set():
                    return
                self._relax_due.clear()  # the last page left while the queue was full: after what it held
                req = {"type": "relax"}
            kind = req["type"]
            if kind == "setpoint":
                self.setpoint = req["value"]
                if self.controller is not None and not self.engaged:
                    self.controller.reset(rig.command)
                self.engaged = True
            elif kind == "relax":
                self.engaged = False
                if self.kind != "replay" and not rig.closed:
                    rig.relax()
            elif kind == "load":
                rig.clear_loads()
                rig.place_load(req["mass_g"] / 1000.0, req["position_m"])
            elif kind == "clear":
                rig.clear_loads()
            elif kind == "pause":
                self.paused = req["paused"]
            elif kind == "speed":
                self.speed = req["speed"]

    def _act(self, reading, equilibrium: int):
        """The command for this frame: the controller's while engaged, the setpoint itself open loop, else 8."""
        rig = self.rig
        if self.kind == "replay":
            # the recorded sample in force (a recording of any rate, starting at any time)
            i = max(int(np.searchsorted(self._replayed_t, reading.time_s + 1e-9, side="right")) - 1, 0)
            rec = self._replayed[i]
            return int(rec.get("command", equilibrium)), _finite(rec.get("setpoint")), _finite(rec.get("y"))
        y = None
        if self.controller is not None:
            y = _finite(self.controller.measure(reading))
            if self.engaged:
                return self._write(self.controller.step(self.setpoint, reading)), self.setpoint, y
            return rig.command, None, y
        if self.engaged and self.cable:
            return self._write(self.setpoint), self.setpoint, y
        return rig.command, None, y

    def _write(self, command) -> int:
        start = time.thread_time()
        try:
            return self.rig.write_command(command)
        finally:
            self.rig_cpu_s += time.thread_time() - start

    def _estimates(self) -> None:
        """The estimator thread: the latest job from the loop, estimated, published, recorded."""
        previous = None
        while not self._stop.is_set():
            with self._job_ready:
                while self._job is None and not self._stop.is_set():
                    self._job_ready.wait(0.2)
                job, self._job = self._job, None
            if job is None:
                continue
            try:
                previous = self._estimate(*job, previous)
            except Exception as exc:  # an estimate that fails must not take the loop (and the rig's safety) down
                self.estimate_error = f"{type(exc).__name__}: {exc}"
                previous = None

    def _estimate(self, gauges_v, command, t, psi, previous):
        est = self.estimator.estimate(gauges_v, command=command if self.cable else None, start=previous)
        row = est.row(0, every=5)
        shape = {"t": round(t, 4), **row}
        contacts = [c.estimate(gauges_v, command, est) for c in self.contacts]
        truth = None
        twin = getattr(self.rig, "twin", None)
        if twin is not None and psi is not None:
            pts = twin.chain.positions(psi, np.asarray(row["s_m"]))
            truth = np.round(pts, 6).tolist()
        locatability = self._locatability(command)
        with self._lock:
            self.state.shape, self.state.truth, self.state.contact = shape, truth, contacts
            if locatability is not None:
                self.state.locatability = locatability
        if self.recording is not None:
            self.recording.write("/flexdigit/shape", t, shape)
            self.recording.write("/flexdigit/contact", t, {"t": round(t, 4), "sources": contacts})
        return est

    def _locatability(self, command):
        """Where a 25 g load can be placed to the page's threshold at this command: computed in a worker thread
        (half a second of work must not stall the 20 ms loop), cached per command; None until something new."""
        # one map per band of MAP_COMMAND_STEP commands: a controller holding a setpoint dithers by a command or
        # two, and the map moves slowly with the command (the taut cable's friction grows with its tension: a
        # 25 g load's median sd is 22 mm at command 15, 43 mm at 25), while each map costs half a second of CPU
        key = int(self.MAP_COMMAND_STEP * round(int(command) / self.MAP_COMMAND_STEP)) if self.cable else None
        now = self._clock()  # the injected clock, as the loop's pacing
        if key != getattr(self, "_loc_seen", "unset"):
            self._loc_seen, self._loc_since = key, now
        if getattr(self, "_loc_sent", "unset") == key:
            return None
        done = self._loc_cache.get(key)
        if done is not None:
            self._loc_sent = key
            return done
        # computed only for a command held half a second: a digit on its way somewhere needs no map of each stop
        if key not in self._loc_pending and now - self._loc_since >= 0.5:
            self._loc_pending.add(key)
            self._loc_worker.submit(self._compute_locatability, key)
        return None

    def _compute_locatability(self, key) -> None:
        s = np.round(np.arange(0.005, self.length_m + 1e-9, 0.005), 4)
        try:
            sd = self._loc_estimator.locatability(s, 0.245, key)  # warns of nothing: no catch_warnings in a thread
            self._loc_cache[key] = {"command": key, "s_m": s.tolist(), "sd_m": [_finite(x) for x in sd]}
        except Exception as exc:  # the page goes without the map; it says why
            self.estimate_error = f"locatability map: {type(exc).__name__}: {exc}"
        finally:
            self._loc_pending.discard(key)
