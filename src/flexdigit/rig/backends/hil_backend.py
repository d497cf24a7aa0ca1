"""The ``hil://`` backend: the reference firmware on an emulated ATmega328P (simavr), joined to the twin (issue 25).

    hil://firmware/build/flexdigit_board.elf?seed=0&mode=host

The firmware image (``make firmware``) runs unchanged on simavr's ATmega328P in a small harness
(``firmware/hil/flexdigit_hil.c``, against libsimavr) that this backend drives over a pipe, in *simulated* time:
every ``step_s`` (0.5 ms) of AVR time it

1. sets the voltages on the AVR's ADC pins from the twin's G gauges (gauge k on ADCk, ``2.5 V + gauge volts``: the
   level shift of the board's front end, the AVR's ADC reading 0..5 V), to a tenth of a millivolt; the harness makes
   simavr's ADC convert as the ATmega328P's datasheet says (``vin x 1024 / 5 V``, not simavr's ``x 1023``), so
   the board's readings, its rest reading (which it tares its map on) among them, are a real Uno's;
2. runs the AVR for ``step_s`` and collects what its UART sent (stream-protocol lines) and the servo pulse its
   Timer1 generates (OCR1A latched at the pulse's start, as the hardware double-buffers it);
3. turns the pulse width into the servo's command (1..2 ms over 0..254, unrounded: Timer1's 0.5 us resolution is
   finer than the serial board's command) and advances the twin ``step_s``.

The harness also counts the cycles the board's CPU sleeps (the firmware sleeps whenever it has nothing to do):
:attr:`HilRig.idle_cycles` against :attr:`HilRig.board_cycles`, the share ``stats()`` reports as ``idle_fraction``
(what is left of the CPU: ``python -m benchmarks bench_board``).

A digit of issue 24 (``params``, ``flexdigit run --on-board --params D.toml``) runs on an image built for it
(``make firmware PARAMS=D.toml``); the board's banner says what its image was built for (gauges, straight command,
range), and another digit's image is refused in one line (:func:`~flexdigit.rig.backends.board_link.check_board_image`).

The firmware's UART is a pseudo-terminal (``uart=pty``, the default): the harness makes one and the host opens
it as it opens an Uno's port (pyserial, 250000 baud, raw), so the host's bytes cross a serial port as on the
bench; the exchange still gives the time (the harness says how many bytes each step sent; the host says how many
it wrote), so nothing waits on the kernel's timing. ``uart=pipe`` carries the bytes in the exchange's lines.

Nothing here reads the wall clock (unless ``paced``, for the live page): a run repeats exactly. Two modes (``mode=``):

- ``host``: the board streams the gauges and follows ``C<command>`` lines; flexdigit's loop on the host closes the
  loop through it (``flexdigit run --backend hil://...``), so the whole host stack meets the real firmware;
- ``board``: the loop closes on the board (the exported controller in the image); the host sends the setpoint
  (:meth:`HilRig.set_setpoint`) and watches (``flexdigit run --on-board``).

A fault the board reports (``# fault <code> <name>``: host silent, ADC at a rail, rotation past its bound, command
out of range, controller fault) raises :class:`~flexdigit.errors.RigError` at the next read: the loop's safe state.
"""

from __future__ import annotations

import math
import shutil
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from flexdigit.errors import ParameterError, RigError
from flexdigit.params import RigParams
from flexdigit.rig.backends.board_link import (
    BAUD,
    FAULTS,
    HEARTBEAT_S,
    VOLTS_PER_COUNT,
    BoardState,
    check_board_digit,
    check_board_image,
)
from flexdigit.rig.base import Rig, RigURL, UrlOption, rig_url_options
from flexdigit.rig.pacing import WallPacer
from flexdigit.twin.digit import ORIENTATIONS
from flexdigit.twin.twin import Twin

__all__ = [
    "HilRig",
    "from_url",
    "URL_OPTIONS",
    "pulse_to_command",
    "HARNESS_NAME",
    "FAULTS",
    "BoardRun",
    "run_on_board",
]

#: The harness executable ``make firmware`` builds beside the image.
HARNESS_NAME = "flexdigit_hil"
#: The AVR's clock, Hz (an Uno's crystal).
F_CPU_HZ = 16_000_000
#: The front end: gauge volts ride on 2.5 V into the 0..5 V ADC (VOLTS_PER_COUNT: 10 bits over 5 V).
MID_V = 2.5
#: The harness takes the pins' voltages in tenths of a millivolt (a fiftieth of an ADC step).
VOLT_UNITS_PER_V = 10_000
#: How long before the board's control tick at 0.2 s the opening sends its mode line: its ~15 bytes at BYTE_US
#: (50 us) take 0.75 ms to arrive (firmware/hil/flexdigit_hil.c).
LEAD_S = 0.002
#: How long the host waits for bytes the harness said it put on the pty (wall clock): past it, the harness is gone.
PTY_TIMEOUT_S = 5.0

URL_OPTIONS = (
    UrlOption("seed", "int", low=0, help="the twin's noise seed"),
    UrlOption("mode", "choice", choices=("host", "board"), help="who closes the loop: the host or the board"),
    UrlOption("setpoint_deg", "float", low=-60.0, high=120.0, help="board mode: the setpoint sent at opening"),
    UrlOption("safe", "choice", choices=("relax", "hold"), help="the board's safe state: relax or hold"),
    UrlOption("harness", "str", help="the simavr harness (default: flexdigit_hil beside the image)"),
    UrlOption("step_s", "float", low=1e-4, high=0.01, help="the AVR/twin exchange step, s"),
    UrlOption("orientation", "choice", choices=tuple(ORIENTATIONS), help="how the twin's digit lies (as sim's)"),
    UrlOption("cable", "bool", help="the twin's cable attached (as sim's)"),
    UrlOption("paced", "bool", help="keep the emulated board at the wall clock's time (the live page)"),
    UrlOption("uart", "choice", choices=("pty", "pipe"), help="the firmware's UART: a pty the host opens, or a pipe"),
)
PYTHON_OPTIONS = ("twin", "operator", "calibration", "wall_clock", "start_paced")


def pulse_to_command(pulse_cycles: int, params: RigParams | None = None) -> float:
    """The servo command a pulse stands for: 1..2 ms over ``command_min..command_max`` (unrounded).

    >>> round(pulse_to_command(16504), 3)          # 1031.5 us: command 8 (1000 + 8 x 1000/254 = 1031.5)
    8.001
    """
    a = (params or RigParams()).actuator
    pulse_us = pulse_cycles / (F_CPU_HZ / 1e6)
    span = float(min(a.command_max, 254) - a.command_min)
    return a.command_min + (pulse_us - 1000.0) / 1000.0 * span


def _find_harness(elf, elf_path: Path, harness) -> Path:
    """The simavr harness: the one given, else the one built next to the firmware, else one on the PATH."""
    harness = Path(harness) if harness else elf_path.parent / HARNESS_NAME
    if not harness.is_file():
        found = shutil.which(HARNESS_NAME)
        if found is None:
            raise ParameterError(f"hil://{elf}: no simavr harness at {harness} (build it with 'make firmware')")
        harness = Path(found)
    return harness


class HilRig(Rig):
    """The firmware on simavr, joined to the twin (see the module docstring).

    Parameters
    ----------
    elf : path
        The firmware image.
    params : RigParams, optional
    seed : int
        The twin's noise seed.
    mode : {"host", "board"}
    setpoint_deg : float
        Board mode: the setpoint sent when the board is put in closed loop.
    safe : {"relax", "hold"}
        What the board does on a fault.
    harness : path, optional
    orientation, cable :
        The twin's mounting and cable (as the ``sim`` backend's; ``flexdigit collect`` sets them from its protocol).
    paced : bool
        Keep the board at the wall clock's time: before each read and command (and in :meth:`wait`, after
        sleeping) it runs up to it, as ``sim+paced`` keeps the twin (``flexdigit live`` opens it so), at most
        :attr:`MAX_CATCH_UP_S` a call (:class:`~flexdigit.rig.pacing.WallPacer`): on a machine slower than real
        time the board falls behind by :attr:`lag_s`, rather than each catch-up growing on the last. The rig's
        clock is the board's time.
    start_paced : bool
        Paced: from opening (default), or in simulated time until :meth:`start_pacing` (the live page's start).
    wall_clock : callable, optional
        Paced: the wall clock (:func:`time.monotonic`; tests pass a slow fake one).
    uart : {"pty", "pipe"}
        The firmware's UART: a pty the host opens as a serial port (pyserial), or carried in the exchange.
    step_s : float
        AVR/twin exchange step (s). The pins hold the twin's volts for a step, so the board's samples are up to a
        step older than a real ADC's: 0.5 ms, not 1 ms, brings the loop at 2 ms within a point of the Python
        loop's overshoot (17.5 % at 1 ms, 16.3 % at 0.5 ms, against 16.1 %).
    twin : flexdigit.twin.Twin, optional
    """

    name = "hil"
    accepts_loads = True
    #: Paced: the most board time one read, command or wait runs to catch up with the wall clock, s (five of the live
    #: page's 20 ms frames: a stall is made up over a few frames, and a machine slower than real time leaves the
    #: board behind, :attr:`lag_s`, with every call bounded).
    MAX_CATCH_UP_S = 0.1
    #: A reading's step (V): the board's 10-bit count, whatever ADC the parameters describe (what a still gauge's
    #: reading toggles by: :func:`flexdigit.tactile.runner.still_scatter_v`)
    adc_lsb_v = VOLTS_PER_COUNT

    @property
    def deterministic(self) -> bool:  # simulated time: the same actions, the same readings
        return not self.paced

    def __init__(
        self,
        elf,
        params: RigParams | None = None,
        *,
        seed: int = 0,
        mode: str = "host",
        setpoint_deg: float = 0.0,
        safe: str = "relax",
        harness=None,
        step_s: float = 0.0005,
        uart: str = "pty",
        paced: bool = False,
        start_paced: bool = True,
        wall_clock=None,
        orientation: str = "vertical",
        cable: bool = True,
        twin: Any = None,
        operator=None,
        calibration=None,
    ) -> None:
        self.elf = Path(elf)
        if not self.elf.is_file():
            raise ParameterError(f"hil://{elf}: no firmware image there (build it with 'make firmware')")
        check_board_digit(params if twin is None else twin.params, f"hil://{elf}")
        self.harness = _find_harness(elf, self.elf, harness)
        if twin is None:
            options = {} if calibration is None else {"calibration": calibration}
            # the servo follows the pulses the board generates (measured below); "timer" says so in the twin's
            # settings, and is how a host loop on the twin alone is driven to compare with it (sim?servo_drive=timer)
            twin = Twin(
                params, seed=int(seed), dt_s=0.002, servo_drive="timer", orientation=orientation, cable=cable, **options
            )
        self.twin = twin
        self.seed, self.mode, self.safe, self.step_s = int(seed), mode, safe, float(step_s)
        self.uart = uart
        self.port = None  # the pty, opened as a serial port (uart="pty")
        self.port_path: str | None = None
        self.setpoint_deg = float(setpoint_deg)
        self._time_s = 0.0
        self.paced = bool(paced)
        self._pacer = WallPacer(wall_clock or time.monotonic, self.MAX_CATCH_UP_S) if self.paced else None
        super().__init__(twin.params, clock=self._now, sleep=self._wait_alive, operator=operator or (lambda m: None))
        self._outbox = bytearray()
        self._last_said_s = 0.0
        #: what the board said (its samples, faults, mode changes, tare): :class:`BoardState`
        self.board = BoardState()
        self.board_command = float("nan")
        self.pulses = 0
        self.exec_max_cycles = 0
        self.exec_cycles: list[int] = []
        #: the board's clock and the cycles its CPU has slept (idle) so far, both from its start: the idle share
        #: of a stretch of a run is the difference of ``idle_cycles`` over that of ``board_cycles``
        self.board_cycles = 0
        self.idle_cycles = 0
        #: ``{channel: gauge volts}`` forced onto ADC pins instead of the twin's (a gauge wire off: ``{1: -2.5}``)
        self.gauge_override: dict[int, float] = {}
        self._start_board()
        if start_paced:  # from here on the board keeps the wall clock's time (its opening ran as fast as it could)
            self.start_pacing()

    def _start_board(self) -> None:
        """Start the harness running the firmware, take the board's banner and rest readings, and put it in its
        mode; the harness stopped again if any of that fails."""
        self._stderr = tempfile.TemporaryFile(mode="w+")  # simavr's own messages: quoted if the harness stops
        self._proc = subprocess.Popen(
            [str(self.harness), str(self.elf), *(["--pty"] if self.uart == "pty" else [])],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=self._stderr,
            text=True,
            bufsize=1,
        )
        try:
            if self.uart == "pty":
                self._open_port()
            # the banner, and the rest readings the board tares its map on; the mode line goes out LEAD_S before
            # 0.2 s so it has arrived before the control tick at 0.2 s, where the board starts its loop (at the first
            # tick after the line's arrival, whenever its main loop reads it), a servo frame boundary (every period
            # divides 20 ms; the pulse latching that tick's command begins 1 ms later): the loop's first command
            # then reaches the servo at once, as the host loop's first does on the twin's serial board (its frame
            # at t = 0). Starting at a random phase instead delays the first command by up to 19 ms.
            self._advance(0.2 - LEAD_S)
            if self.latest is None:
                raise RigError(f"hil://{self.elf}: the firmware sent no sample in 0.2 s ({self.info_lines[-3:]})")
            check_board_image(self.board, self.twin.params, f"hil://{self.elf}")
            self._say("F1" if self.safe == "hold" else "F0")  # once the board listens
            if self.mode == "board":
                self.set_setpoint(self.setpoint_deg)
                self._say("M2")
            else:
                self._say("M1")
            self._advance(LEAD_S)
        except BaseException:
            self._stop()
            raise

    def _open_port(self) -> None:
        """Open the harness's pty as the host opens a board's serial port."""
        import serial

        said = self._proc.stdout.readline().split()
        if len(said) != 2 or said[0] != "T":
            raise RigError(
                f"hil://{self.elf}: the harness made no pty ({self._harness_said() or 'no reply'}); "
                f"hil://{self.elf}?uart=pipe carries the UART without one"
            )
        self.port_path = said[1]
        try:
            self.port = serial.Serial(self.port_path, baudrate=BAUD, timeout=PTY_TIMEOUT_S, write_timeout=PTY_TIMEOUT_S)
        except (serial.SerialException, OSError) as exc:
            raise RigError(f"hil://{self.elf}: cannot open the board's pty {self.port_path} ({exc})") from None

    # -- the exchange --------------------------------------------------------------------------------------------
    def _say(self, line: str) -> None:
        self._outbox += line.encode("ascii") + b"\n"
        self._last_said_s = self._time_s

    def _exchange(self) -> None:
        gauges, _ = self.twin.read()
        volts = [MID_V + float(g) for g in gauges]  # gauge k on ADCk (the board reads no pot)
        for channel, v in self.gauge_override.items():  # a wire off, a short: the fault tests
            volts[channel] = MID_V + v
        out = "V " + " ".join(str(int(round(v * VOLT_UNITS_PER_V))) for v in volts) + "\n"
        if self._outbox:
            out += self._uart_to_board(bytes(self._outbox))
            self._outbox.clear()
        out += f"R {int(round(self.step_s * 1e6))}\n"
        try:
            self._proc.stdin.write(out)
            self._proc.stdin.flush()
            reply = self._proc.stdout.readline()
        except (BrokenPipeError, OSError) as exc:
            raise RigError(f"hil://{self.elf}: the simavr harness failed ({exc})") from None
        parts = reply.split()
        if len(parts) < 9 or parts[0] != "P":
            raise RigError(f"hil://{self.elf}: the simavr harness stopped ({self._harness_said() or 'no reply'})")
        pulse, self.pulses = int(parts[2]), int(parts[3])
        exec_last, self.exec_max_cycles, execs = int(parts[4]), int(parts[5]), int(parts[6])
        if execs > len(self.exec_cycles):
            self.exec_cycles.append(exec_last)
        self.board_cycles, self.idle_cycles = int(parts[1]) * (F_CPU_HZ // 1_000_000), int(parts[8])
        uart = self._uart_from_board(parts[9] if len(parts) > 9 else "")
        if pulse:
            command = pulse_to_command(pulse, self.params)
            if command != self.board_command:
                self.board_command = command
                a = self.params.actuator
                self.twin.servo.pending.clear()
                self.twin.servo.command = min(max(command, a.command_min), a.command_max)
        self.board.feed(uart, self._time_s)

    def _uart_to_board(self, data: bytes) -> str:
        """Send ``data`` to the board's receiver; the exchange's line saying so."""
        if self.port is None:
            return f"U {data.hex()}\n"
        try:
            self.port.write(data)
            self.port.flush()
        except (OSError, ValueError) as exc:  # pyserial's SerialException and SerialTimeoutException are OSErrors
            raise RigError(f"hil://{self.elf}: cannot write to the board's pty {self.port_path} ({exc})") from None
        return f"U {len(data)}\n"

    def _uart_from_board(self, field: str) -> bytes:
        """What the board's UART sent in this step: in the reply (pipe), or that many bytes from the pty."""
        if self.port is None:
            return bytes.fromhex(field)
        count = int(field or 0)
        if not count:
            return b""
        try:
            data = self.port.read(count)
        except (OSError, ValueError) as exc:
            raise RigError(f"hil://{self.elf}: cannot read the board's pty {self.port_path} ({exc})") from None
        if len(data) != count:
            raise RigError(f"hil://{self.elf}: {count} bytes from the board did not arrive on {self.port_path}")
        return data

    def _harness_said(self) -> str:
        """The harness's last line on stderr (why it stopped), or ''."""
        try:
            self._proc.wait(timeout=2)
            self._stderr.seek(0)
            lines = [line.strip() for line in self._stderr.read().splitlines() if line.strip()]
        except (OSError, subprocess.TimeoutExpired):
            return ""
        return lines[-1] if lines else ""

    def _advance(self, seconds: float) -> None:
        steps = int(round(seconds / self.step_s))
        for _ in range(steps):
            self._exchange()
            self.twin.advance(self.step_s)
            self._time_s += self.step_s

    def _now(self) -> float:
        """The rig's clock: the board's (simulated) time; paced, it follows the wall clock's, :attr:`lag_s` behind."""
        return self._time_s

    @property
    def _pacing(self) -> bool:
        return self._pacer is not None and self._pacer.started

    def start_pacing(self) -> None:
        """Paced: keep the board at the wall clock's time from now on, from its time now (idempotent)."""
        if self._pacer is not None:
            self._pacer.start(self._time_s)

    @property
    def lag_s(self) -> float:
        """How far the board was behind the wall clock after its last catch-up, s (0 unless paced and the machine
        is slower than real time)."""
        return self._pacer.lag_s if self._pacer is not None else 0.0

    def _catch_up(self) -> None:
        """Paced: run the board (host alive) up to the wall clock's time, at most :attr:`MAX_CATCH_UP_S`."""
        if self._pacing:
            self._run_alive(self._pacer.due(self._time_s))

    def _wait_alive(self, seconds: float) -> None:
        """:meth:`wait`: time passes with the host alive; paced, the wall clock's."""
        if self._pacing:
            time.sleep(seconds)
            self._catch_up()
        else:
            self._run_alive(seconds)

    def _run_alive(self, seconds: float) -> None:
        """Run the board ``seconds`` of simulated time, the host alive (a heartbeat line every HEARTBEAT_S)."""
        steps = int(round(seconds / self.step_s))
        for _ in range(steps):
            if self._time_s - self._last_said_s >= HEARTBEAT_S:
                self._say("W")
            self._advance(self.step_s)

    def advance_silently(self, seconds: float) -> None:
        """Let time pass without the host saying anything (the host-timeout test)."""
        self._advance(seconds)

    # -- the Rig contract ------------------------------------------------------------------------------------
    # what the board said, by the names the tests and run_on_board read
    latest = property(lambda self: self.board.latest, doc="The newest stream sample.")
    samples = property(lambda self: self.board.samples, doc="Every stream sample, up to a limit.")
    faults = property(lambda self: self.board.faults, doc="``(time_s, code, name)`` of each fault reported.")
    info_lines = property(lambda self: self.board.info_lines, doc="The board's last information lines.")
    mode_marks = property(lambda self: self.board.mode_marks, doc="``(index into samples, mode)`` per mode change.")
    board_tare_deg = property(lambda self: self.board.tare_deg, doc="The rotation the board's map read at rest.")

    def _check_faults(self) -> None:
        self.board.raise_new_fault(f"hil://{self.elf.name}")

    def _read(self) -> tuple[np.ndarray, float]:
        self._catch_up()
        if self._time_s - self._last_said_s >= HEARTBEAT_S:
            self._say("W")
        self._check_faults()
        sample = self.latest
        gauges = np.array(sample.gauges, dtype=float) * VOLTS_PER_COUNT
        return gauges, math.nan

    def _send(self, command: int) -> None:
        self._catch_up()
        self._check_faults()
        self._say(f"C{int(command)}")

    def set_setpoint(self, degrees: float) -> None:
        """Board mode: the beam rotation the board's loop holds (deg)."""
        self.setpoint_deg = float(degrees)
        self._say(f"S{int(round(degrees * 1000))}")

    def set_mode(self, mode: str) -> None:
        """``"safe"``, ``"host"`` or ``"board"`` (clears a latched fault)."""
        code = {"safe": 0, "host": 1, "board": 2}[mode]
        self.mode = mode
        self._say(f"M{code}")

    def send_raw(self, line: str) -> None:
        """A line to the board as is (tests: an out-of-range command)."""
        self._say(line)

    def tip_rotation_deg(self) -> float:
        """The twin's true tip rotation now, deg (not measurable on hardware)."""
        psi, _ = self.twin.state()
        return math.degrees(float(psi[-1]))

    def _apply_load(self, mass_kg: float, position_from_base_m: float) -> None:
        self.twin.place_load(mass_kg, position_from_base_m)

    def _remove_loads(self) -> None:
        self.twin.clear_loads()

    def _rehang(self, settle_s: float) -> None:
        self.twin.disturb()

    def relax(self) -> int:
        """Host mode: the equilibrium command; board mode: the board's safe state."""
        if self.mode == "board" and not self._closed:
            self.set_mode("safe")
            self._advance(self.step_s)
            self._command = int(self.params.actuator.equilibrium_command)
            return self._command
        return super().relax()

    def _close(self) -> None:
        self._stop()

    def _stop(self) -> None:
        if self.port is not None:
            self.port.close()
        proc = self._proc
        try:
            if proc.poll() is None:
                proc.stdin.write("Q\n")
                proc.stdin.flush()
        except (BrokenPipeError, OSError):
            pass
        try:
            proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        self._stderr.close()

    def stats(self) -> dict[str, Any]:
        return {
            "pulses": self.pulses,
            "faults": [{"t_s": t, "code": c, "name": n} for t, c, n in self.faults],
            "exec_max_cycles": self.exec_max_cycles,
            "idle_fraction": self.idle_cycles / self.board_cycles if self.board_cycles else None,
            "info_lines": list(self.info_lines[-10:]),
        }

    def settings(self) -> dict[str, Any]:
        return {
            "backend": "hil",
            "elf": str(self.elf),
            "seed": self.seed,
            "mode": self.mode,
            "safe": self.safe,
            "step_s": self.step_s,
            "uart": self.uart,
            "paced": self.paced,
            "orientation": self.twin.orientation,
            "cable": bool(self.twin.cable),
            "harness": str(self.harness),
        }

    def __repr__(self) -> str:
        state = "closed" if self._closed else "open"
        port = f", port={self.port_path!r}" if self.port_path else ""
        return (
            f"HilRig(elf={str(self.elf)!r}, mode={self.mode!r}, seed={self.seed}, safe={self.safe!r}, "
            f"uart={self.uart!r}{port}, {state})"
        )


def from_url(location: str, params: RigParams | None, options: dict[str, Any]) -> HilRig:
    """``hil://PATH.elf?seed=0&mode=host`` (see the module docstring)."""
    if not location:
        raise ParameterError("hil:// needs a firmware image, e.g. hil://firmware/build/flexdigit_board.elf")
    checked = rig_url_options(RigURL("hil", location), **options)[1]
    return HilRig(location, params, **checked)


class BoardRun:
    """What :func:`run_on_board` watched: per board period, the time, the twin's true rotation, the command, and the
    board's own rotation estimate (NaN where its line carried none: an image before the estimate was streamed)."""

    def __init__(
        self, time_s, true_rotation_deg, command, status: str, message: str, period_s: float, estimate_deg=None
    ) -> None:
        self.time_s = np.asarray(time_s, dtype=float)
        self.true_rotation_deg = np.asarray(true_rotation_deg, dtype=float)
        self.command = np.asarray(command, dtype=float)
        self.estimate_deg = (
            np.full(self.time_s.size, math.nan) if estimate_deg is None else np.asarray(estimate_deg, dtype=float)
        )
        self.status, self.message, self.period_s = status, message, period_s

    def __repr__(self) -> str:
        return (
            f"BoardRun({self.status!r}, {self.time_s.size} periods of {self.period_s * 1000:g} ms, "
            f"message={self.message!r})"
        )


def board_period_s(rig: HilRig) -> float:
    """The control period the image was built with (its banner's ``period_us``)."""
    return rig.board.period_s(f"hil://{rig.elf.name}")


def run_on_board(rig: HilRig, setpoint_deg: float, duration_s: float, on_period=None) -> BoardRun:
    """Close the loop on the board: send the setpoint, then watch (read every board period, which is also the
    host's heartbeat) for ``duration_s``. A fault the board reports ends the run with status ``"fault"``.

    Times are from the setpoint's sending, as the host's loop counts them from its first sample (the step's
    time 0 in both): the rig's clock already counts the opening's 0.2 s of rest readings. ``on_period(t, reading,
    true_deg, command, estimate_deg)``, when given, sees every period as it is watched (the run's log);
    ``estimate_deg`` is the board's streamed rotation estimate of the period's newest line (NaN if it sends none)."""
    period = board_period_s(rig)
    t0 = rig.clock()
    rig.set_setpoint(setpoint_deg)
    if rig.mode != "board":
        rig.set_mode("board")
    t, truth, command, estimate = [], [], [], []
    status, message = "completed", f"{duration_s:g} s on the board"
    n = int(round(duration_s / period))
    try:
        for _ in range(n):
            rig.wait(period)
            reading = rig.read()
            t.append(rig.clock() - t0)
            truth.append(rig.tip_rotation_deg())
            command.append(rig.board_command)
            streamed = rig.latest.rotation_deg  # the line read() took its gauges from
            estimate.append(math.nan if streamed is None else streamed)
            if on_period is not None:
                on_period(t[-1], reading, truth[-1], command[-1], estimate[-1])
    except RigError as exc:
        status, message = "fault", str(exc)
    return BoardRun(t, truth, command, status, message, period, estimate)
