"""The ``board://`` backend: the reference firmware on a real Arduino Uno, over its USB serial port (issue 25).

    board:///dev/ttyACM0?mode=host&safe=relax

The image ``make firmware`` builds (``firmware/flexdigit_board.c``; flashing and wiring: ``docs/board.md``) reads
the gauges on the Uno's ADC and drives the servo from Timer1. This backend speaks its lines
(:mod:`flexdigit.rig.backends.board_link`) over the port (pyserial ``serial_for_url``, so ``loop://`` works too),
as ``hil://`` speaks them to the same image on simavr:

- ``mode=host``: the board streams the gauges and follows ``C<command>`` lines; flexdigit's loop on the host
  closes the loop through it (``flexdigit run --backend board:///dev/ttyACM0 --rotation-map my-map.json``);
- ``mode=board``: the loop closes on the board (the exported controller in the image); the host sends the setpoint
  (:meth:`BoardRig.set_setpoint`) and watches.

Opening waits up to ``startup`` s for the board's first sample (an Uno resets when its port opens), then sends the
safe action (``safe``: relax or hold) and the mode. While the rig waits it sends a heartbeat line every 0.1 s (the
board's safe state follows 0.5 s of host silence). A fault the board reports (host silent, ADC at a rail, rotation
past its bound, command out of range) raises :class:`~flexdigit.errors.RigError` at the next read or command, as
does a board silent for ``timeout`` s: the loop's safe state. Closing puts the board in its safe state (``M0``).
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from flexdigit.errors import ParameterError, RigError
from flexdigit.params import RigParams
from flexdigit.rig.backends.board_link import (
    BAUD,
    HEARTBEAT_S,
    VOLTS_PER_COUNT,
    BoardState,
    check_board_digit,
    check_board_image,
)
from flexdigit.rig.base import Rig, RigURL, UrlOption, rig_url_options

__all__ = ["BoardRig", "from_url", "URL_OPTIONS"]

#: How often opening looks for the board's first sample, s.
POLL_S = 0.01

URL_OPTIONS = (
    UrlOption("baud", "int", low=1200, high=2_000_000, help="the firmware's baud rate (250000)"),
    UrlOption("mode", "choice", choices=("host", "board"), help="who closes the loop: the host or the board"),
    UrlOption("setpoint_deg", "float", low=-60.0, high=120.0, help="board mode: the setpoint sent at opening"),
    UrlOption("safe", "choice", choices=("relax", "hold"), help="the board's safe state: relax or hold"),
    UrlOption("startup", "float", low=0.0, high=60.0, help="s to wait for the first sample (the Uno resets)"),
    UrlOption("timeout", "float", low=0.001, high=10.0, help="s without a fresh sample before the board is silent"),
)
#: Keyword arguments only Python passes (objects, not text): an open port (tests), the clock, the operator.
PYTHON_OPTIONS = ("serial", "clock", "sleep", "operator")


class BoardRig(Rig):
    """The reference firmware on a real board (see the module docstring).

    Parameters
    ----------
    port : str
        The serial port (``/dev/ttyACM0``) or a pyserial URL.
    params : RigParams, optional
    baud : int
    mode : {"host", "board"}
    setpoint_deg : float
        Board mode: the setpoint sent when the board is put in closed loop.
    safe : {"relax", "hold"}
        What the board does on a fault.
    startup : float
        Seconds to wait for the board's first sample after opening the port.
    timeout : float
        Seconds without a fresh sample after which a read raises (the board, or its cable, is gone).
    serial : pyserial port, optional
        An open port to use instead of opening ``port`` (tests).
    clock, sleep : callable, optional
        Monotonic clock and sleep (wall clock by default; tests inject an emulator's).
    """

    name = "board"
    #: A reading's step (V): the board's 10-bit count, whatever ADC the parameters describe
    adc_lsb_v = VOLTS_PER_COUNT

    def __init__(
        self,
        port: str,
        params: RigParams | None = None,
        *,
        baud: int = BAUD,
        mode: str = "host",
        setpoint_deg: float = 0.0,
        safe: str = "relax",
        startup: float = 3.0,
        timeout: float = 0.25,
        serial: Any = None,
        clock=None,
        sleep=None,
        operator=None,
    ) -> None:
        self.port_name, self.baud, self.mode, self.safe = str(port), int(baud), mode, safe
        self.setpoint_deg, self.startup_s, self.timeout_s = float(setpoint_deg), float(startup), float(timeout)
        self._pause = sleep or time.sleep
        if params is not None:
            check_board_digit(params, f"board://{self.port_name}")
        super().__init__(params, clock=clock or time.monotonic, sleep=self._wait_alive, operator=operator)
        self.board = BoardState()
        self._last_said_s = -math.inf
        self._last_sample_s = -math.inf
        if serial is None:
            import serial as pyserial

            try:
                serial = pyserial.serial_for_url(self.port_name, baudrate=self.baud, timeout=0)
            except (pyserial.SerialException, OSError, ValueError) as exc:
                raise RigError(f"board://{self.port_name}: cannot open the port ({exc})") from None
        self._port = serial
        try:
            self._start()
        except BaseException:
            self._port.close()
            raise

    @property
    def where(self) -> str:
        return f"board://{self.port_name}"

    def _start(self) -> None:
        """Wait for the board's first sample, then send its safe action and its mode."""
        deadline = self.clock() + self.startup_s
        while self.board.latest is None:
            if self.clock() > deadline:
                raise RigError(
                    f"{self.where}: no sample from the board in {self.startup_s:g} s (the firmware flashed? the "
                    f"baud rate {self.baud}? lines seen: {self.board.info_lines[-3:]})"
                )
            self._pause(POLL_S)
            self._drain()
        check_board_image(self.board, self.params, self.where)  # its banner: the digit its image was built for
        self._say("F1" if self.safe == "hold" else "F0")
        if self.mode == "board":
            self.set_setpoint(self.setpoint_deg)
            self._say("M2")
        else:
            self._say("M1")

    # -- the port --------------------------------------------------------------------------------------------------
    def _drain(self) -> None:
        """Take what the board sent since the last look."""
        try:
            waiting = self._port.in_waiting
            data = self._port.read(waiting) if waiting else b""
        except (OSError, ValueError) as exc:  # pyserial's SerialException is an OSError
            raise RigError(f"{self.where}: the port failed ({exc})") from None
        if self.board.feed(data, self.clock()):
            self._last_sample_s = self.clock()

    def _say(self, line: str) -> None:
        try:
            self._port.write(line.encode("ascii") + b"\n")
        except (OSError, ValueError) as exc:
            raise RigError(f"{self.where}: the port failed ({exc})") from None
        self._last_said_s = self.clock()

    def _wait_alive(self, seconds: float) -> None:
        """:meth:`wait`: time passes with the host alive (a heartbeat every HEARTBEAT_S) and the port read."""
        end = self.clock() + seconds
        while (remaining := end - self.clock()) > 1e-9:
            if self.clock() - self._last_said_s >= HEARTBEAT_S:
                self._say("W")
            self._pause(min(remaining, HEARTBEAT_S / 2))
            self._drain()

    # -- the Rig contract ------------------------------------------------------------------------------------------
    def _read(self) -> tuple[np.ndarray, float]:
        self._drain()
        if self.clock() - self._last_said_s >= HEARTBEAT_S:
            self._say("W")
        self.board.raise_new_fault(self.where)
        if self.clock() - self._last_sample_s > self.timeout_s:
            raise RigError(f"{self.where}: no sample from the board for {self.timeout_s:g} s")
        return np.array(self.board.latest.gauges, dtype=float) * VOLTS_PER_COUNT, math.nan

    def _send(self, command: int) -> None:
        self._drain()
        self.board.raise_new_fault(self.where)
        self._say(f"C{int(command)}")

    def set_setpoint(self, degrees: float) -> None:
        """Board mode: the beam rotation the board's loop holds (deg)."""
        self.setpoint_deg = float(degrees)
        self._say(f"S{int(round(degrees * 1000))}")

    def set_mode(self, mode: str) -> None:
        """``"safe"``, ``"host"`` or ``"board"`` (clears a latched fault)."""
        code = {"safe": 0, "host": 1, "board": 2}[mode]
        self._say(f"M{code}")
        self.mode = mode

    def relax(self) -> int:
        """Host mode: the equilibrium command; board mode: the board's safe state."""
        if self.mode == "board" and not self._closed:
            self.set_mode("safe")
            self._command = int(self.params.actuator.equilibrium_command)
            return self._command
        return super().relax()

    def _close(self) -> None:
        try:
            self._say("M0")  # the board's safe state, whatever the mode
        except RigError:
            pass  # the port may be what failed
        finally:
            self._port.close()

    def stats(self) -> dict[str, Any]:
        return {
            "samples": len(self.board.samples),
            "faults": [{"t_s": t, "code": c, "name": n} for t, c, n in self.board.faults],
            "info_lines": list(self.board.info_lines[-10:]),
        }

    def settings(self) -> dict[str, Any]:
        return {"backend": "board", "port": self.port_name, "baud": self.baud, "mode": self.mode, "safe": self.safe}

    def __repr__(self) -> str:
        state = "closed" if self._closed else "open"
        return (
            f"BoardRig(port={self.port_name!r}, baud={self.baud}, mode={self.mode!r}, safe={self.safe!r}, "
            f"timeout={self.timeout_s:g}, {state})"
        )


def from_url(location: str, params: RigParams | None, options: dict[str, Any]) -> BoardRig:
    """``board:///dev/ttyACM0?mode=host`` (see the module docstring)."""
    if not location:
        raise ParameterError("board:// needs the board's serial port, e.g. board:///dev/ttyACM0")
    checked = rig_url_options(RigURL("board", location), **options)[1]
    return BoardRig(location, params, **checked)
