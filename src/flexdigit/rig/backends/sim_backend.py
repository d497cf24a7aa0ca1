"""The ``sim`` backend: the digital twin behind the :class:`~flexdigit.rig.base.Rig` interface.

Two clocks:

- ``sim`` (virtual time): :meth:`wait` advances the twin; a 10 s run takes as long as it computes. The loop's
  deadlines are kept exactly, so runs are deterministic (same seed, same numbers, on one machine). A digit other
  than the thesis rig steps with the compiled kernel (~5 x less CPU; within 1e-9 rad of numpy, not bit for bit);
  the thesis rig in numpy, whose numbers the report's are (``sim?compiled=0`` keeps numpy for any digit).
- ``sim+paced`` (wall clock): the rig clock is ``time.monotonic`` since opening; before every read and command the
  twin is advanced to the wall-clock time, and :meth:`wait` sleeps (coarse ``time.sleep`` then a short spin for the
  last ``spin_s``, so deadlines are met to tens of microseconds rather than the scheduler's ~1 ms). This is what
  the 1 kHz jitter benchmark runs, and how a controller is rehearsed in real time before meeting the hardware.
  Its twin steps with the compiled kernel (``compiled``, loaded in the background at opening: numpy steps until
  it is ready): a wall-clock run does not repeat bit for bit anyway, and the live page's twin then costs ~3 %
  of a core instead of ~15 % (``benchmarks/bench_live.py``). Opened with ``start_paced=False`` (the live page),
  it runs in virtual time until :meth:`SimRig.start_pacing`: what its start does on the twin at rest (the
  controller's tare) takes no wall time, and the seconds the start spends computing are not simulated afterwards
  at full speed to catch the twin up to the wall clock; its time carries on from where the twin is.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from flexdigit._json import fingerprint
from flexdigit._validation import check_int, check_real
from flexdigit.errors import ParameterError
from flexdigit.params import RigParams
from flexdigit.rig.base import Rig, UrlOption
from flexdigit.rig.pacing import WallPacer
from flexdigit.twin.actuator import SERVO_DRIVES, TIMER_PULSE_AFTER_TICK_S
from flexdigit.twin.twin import Twin

__all__ = ["SimRig", "from_url", "from_url_paced", "DEFAULT_TWIN_DT_S"]

#: Twin integration step used by the backend (s).
DEFAULT_TWIN_DT_S = 0.002


class SimRig(Rig):
    """The twin as a rig.

    Parameters
    ----------
    params : RigParams, optional
    paced : bool
        False: virtual time. True: paced to the wall clock.
    seed : int
        Twin noise seed.
    twin : flexdigit.twin.Twin, optional
        A ready twin (tests and studies that perturb it); built from ``params`` and ``twin_options`` otherwise.
    spin_s : float
        Paced mode: busy-wait the last ``spin_s`` of every wait.
    start_paced : bool
        Paced mode: follow the wall clock from opening (default); False runs the twin in virtual time until
        :meth:`start_pacing` (a start's waits cost no wall time, and its computing is not simulated afterwards).
    compiled : bool, optional
        Step the twin's digit with the compiled kernel (:meth:`flexdigit.twin.digit.DynamicState.use_compiled`).
        Default: in paced mode, loaded in the background (the twin steps in numpy until it is ready); in virtual
        time, :class:`~flexdigit.twin.Twin`'s default: compiled for a digit other than the thesis rig (~5 x less
        CPU), numpy for the thesis rig (its numbers then match the report's bit for bit). Either way a virtual-time
        run repeats bit for bit on one machine (same seed, same numbers); the two paths agree within 1e-9 rad, not
        bit for bit. False keeps numpy for any digit (``sim?compiled=0``). Ignored with a ready ``twin``.
    **twin_options
        Passed to :class:`flexdigit.twin.Twin` (``calibration``, ``orientation``, ``housing``, ``dt_s`` ...).
    """

    name = "sim"

    def __init__(
        self,
        params: RigParams | None = None,
        *,
        paced: bool = False,
        seed: int = 0,
        twin: Any = None,
        spin_s: float = 0.0005,
        clock=None,
        sleep=None,
        operator=None,
        compiled: bool | None = None,
        start_paced: bool = True,
        pulse_delay_ms: int | None = None,
        **twin_options: Any,
    ) -> None:
        ready = twin is not None
        self._kernel_loading = None  # the thread loading the compiled kernel (paced, until start_pacing joins it)
        if twin is None:
            # 2 ms, not the twin's 20 ms default: a loop closed every 20 ms acts on the digit's motion between
            # frames. The 30 deg step of the 20 ms design (seed 0) overshoots 2.69 % at 1 ms, 2.68 % at 2 ms,
            # 6.3 % at 5 ms and 5.5 % at 20 ms; 2 ms is the coarsest step that matches the 1 ms reference.
            twin_options.setdefault("dt_s", DEFAULT_TWIN_DT_S)
            background = compiled is None and paced  # paced: numpy steps while the kernel loads
            twin = Twin(params, seed=int(seed), compiled=False if background else compiled, **twin_options)
            if background:
                self._kernel_loading = twin.dynamics.use_compiled(background=True)
        if pulse_delay_ms is not None:
            if twin.servo.drive != "timer":
                raise ParameterError(
                    f"sim: pulse_delay_ms={pulse_delay_ms} applies to servo_drive=timer only (got servo_drive="
                    f"{twin.servo.drive})"
                )
            # the firmware image's PULSE_DELAY_MS (its banner's pulse_delay_ms): like for like with a board run
            twin.servo.pulse_after_tick_s = check_int(pulse_delay_ms, "pulse_delay_ms", "SimRig", low=1, high=19) / 1e3
        #: Whether the twin's digit steps compiled (or will, once the kernel has loaded in the background)
        self.compiled = twin.dynamics.compiled or bool(not ready and compiled is None and paced)
        self.twin = twin
        self.paced = bool(paced)
        self.spin_s = check_real(spin_s, "spin_s", "SimRig", low=0.0)
        # paced: the clock and sleep given are the wall clock's; before pacing starts, waits step the twin
        self._pacer = WallPacer(clock or time.monotonic) if self.paced else None
        if self.paced:
            self._wall_sleep = sleep or self._precise_sleep
            sleep = self._wait
        self._virtual_clock = clock if clock is not None and not self.paced else (lambda: self.twin.time_s)
        super().__init__(
            twin.params, clock=self._now, sleep=sleep or self.twin.advance, operator=operator or (lambda m: None)
        )
        if start_paced and self._pacer is not None:  # numpy steps paced while the kernel loads
            self._pacer.start(self.twin.time_s)
        self.name = "sim+paced" if self.paced else "sim"
        self._command = int(twin.servo.command)

    @property
    def _pacing(self) -> bool:
        return self._pacer is not None and self._pacer.started

    def _now(self) -> float:
        """The twin's time (virtual), or once pacing the wall clock's on the twin's time axis."""
        return self._pacer.now() if self._pacing else self._virtual_clock()

    def _wait(self, seconds: float) -> None:
        if self._pacing:
            self._wall_sleep(seconds)
        else:
            self.twin.advance(seconds)

    def start_pacing(self) -> None:
        """Paced mode: follow the wall clock from now on, carrying on from the twin's time (what ran before, in
        virtual time, took no wall time; idempotent); nothing in virtual time (``sim``).

        A held twin's compiled kernel, loading in the background since opening, is waited for first (virtual time:
        it costs no simulated seconds): numba compiling in a thread holds the interpreter, and a loop paced from
        here would find its first samples seconds late (``run``'s stall guard stopped it at a load of ~10)."""
        if self._pacer is not None and not self._pacer.started:
            if self._kernel_loading is not None:
                self._kernel_loading.join()
            self._pacer.start(self.twin.time_s)

    def _precise_sleep(self, seconds: float) -> None:
        end = self._pacer.clock() + seconds
        coarse = seconds - self.spin_s
        if coarse > 0:
            time.sleep(coarse)
        while self._pacer.clock() < end:
            pass

    def _catch_up(self) -> None:
        """Paced mode: advance the twin to the wall-clock time."""
        if self._pacing:
            behind = self._pacer.due(self.twin.time_s)
            if behind > 0:
                self.twin.advance(behind)

    def _read(self) -> tuple[np.ndarray, float]:
        self._catch_up()
        gauges, pot = self.twin.read()
        return np.asarray(gauges, dtype=float), float(pot)

    def _send(self, command: int) -> None:
        self._catch_up()
        self.twin.command(command)

    def command_pulses(self) -> int:
        """The twin's servo pulses that will carry a command sent now (2 for one serial frame in 25, else 1)."""
        self._catch_up()
        return self.twin.servo.pulses_carrying(self.twin.time_s)

    def _apply_load(self, mass_kg: float, position_from_base_m: float) -> None:
        self.twin.place_load(mass_kg, position_from_base_m)

    def _remove_loads(self) -> None:
        self.twin.clear_loads()

    def _apply_tissue(self, tissue) -> None:
        self._catch_up()
        self.twin.set_tissue(tissue)

    def _rehang(self, settle_s: float) -> None:
        self._catch_up()
        self.twin.disturb()  # same weights, same places: only the cable-guide friction settles afresh

    @property
    def deterministic(self) -> bool:  # virtual time: the same actions, the same readings
        return not self.paced

    def settings(self) -> dict[str, Any]:
        """Backend, seed, how the twin is set up, and fingerprints of its calibration and rig parameters."""
        twin = self.twin
        return (
            {
                "backend": self.name,
                "seed": int(twin.seed),
                "orientation": twin.orientation,
                "housing": bool(twin.housing),
                "cable": bool(twin.cable),
                "dt_s": float(twin.dt_s),
                "calibration_fingerprint": fingerprint(twin.calibration.to_dict()),
                "params_fingerprint": fingerprint(twin.params.to_dict()),
            }
            | ({"compiled": True} if self.compiled else {})
            | (  # only when on: older journals stay comparable
                {"servo_drive": twin.servo.drive} if twin.servo.drive != "serial" else {}
            )
            | (
                {"pulse_delay_ms": round(twin.servo.pulse_after_tick_s * 1e3)}
                if twin.servo.pulse_after_tick_s != TIMER_PULSE_AFTER_TICK_S
                else {}
            )
        )

    def tip_rotation_deg(self) -> float:
        """The twin's true tip (beam) rotation now, deg: the last link's absolute angle (not measurable on hardware)."""
        psi, _ = self.twin.state()
        return math.degrees(float(psi[-1]))

    def __repr__(self) -> str:
        state = "closed" if self.closed else "open"
        return f"SimRig(paced={self.paced}, twin={self.twin!r}, {state})"


#: What a ``sim`` / ``sim+paced`` URL may carry (:class:`~flexdigit.rig.base.UrlOption`).
URL_OPTIONS = (
    UrlOption("seed", "int", low=0, help="the seed of the twin's noise"),
    UrlOption("orientation", "choice", choices=("vertical", "horizontal", "hanging"), help="how the digit lies"),
    UrlOption("housing", "bool", help="the elastomer housing on, or the bare strip"),
    UrlOption("cable", "bool", help="the cable attached, or removed"),
    UrlOption("dt_s", "float", low=1e-5, high=0.02, help="the twin's integration step, s"),
    UrlOption("spin_s", "float", low=0.0, high=0.1, help="sim+paced: busy-wait the last spin_s of every wait, s"),
    UrlOption("compiled", "bool", help="step the digit compiled (default: yes, but numpy for the thesis rig in sim)"),
    UrlOption(
        "servo_drive",
        "choice",
        choices=SERVO_DRIVES,
        help="how commands reach the servo: the serial board (the thesis rig) or a microcontroller's timer pulse",
    ),
    UrlOption(
        "pulse_delay_ms",
        "int",
        low=1,
        high=19,
        help="servo_drive=timer: the pulse's start after the control tick, ms (a firmware image's pulse_delay_ms)",
    ),
)
#: Keyword arguments only Python passes to :class:`SimRig` (objects, not text).
PYTHON_OPTIONS = ("twin", "calibration", "cells_per_section", "command", "clock", "sleep", "operator", "start_paced")


def _no_location(location: str, scheme: str) -> None:
    if location:
        raise ParameterError(
            f"{scheme}://{location}: the twin takes no location; write '{scheme}' or '{scheme}?seed=3'"
        )


def from_url(location: str, params: RigParams | None, options: dict[str, Any]) -> SimRig:
    """``sim`` or ``sim?seed=3&orientation=horizontal`` (virtual time); options as :data:`URL_OPTIONS`."""
    _no_location(location, "sim")
    return SimRig(params, paced=False, **options)


def from_url_paced(location: str, params: RigParams | None, options: dict[str, Any]) -> SimRig:
    """``sim+paced`` (wall clock)."""
    _no_location(location, "sim+paced")
    return SimRig(params, paced=True, **options)
