"""What the reference firmware (``firmware/flexdigit_board.c``, issue 25) says to the host, apart from how its bytes
travel: the board on simavr (:mod:`flexdigit.rig.backends.hil_backend`) and a real Uno
(:mod:`flexdigit.rig.backends.board_backend`) share it.

The board streams each control period's ADC counts (signed about its 2.5 V midpoint) and the command it applied
in the stream protocol (:mod:`flexdigit.rig.backends.stream_framing`), and information lines: its banner
(``# flexdigit-stream 1 ... period_us=20000``), ``# mode <0|1|2>``, ``# tare <micro-deg>`` (the rotation its map
read at rest when its loop started) and ``# fault <code> <name>``. The host sends one command a line: ``S<millideg>``
setpoint, ``M<0|1|2>`` mode (safe, host commands, loop on the board), ``C<command>``, ``F<0|1>`` safe action
(relax, hold), ``W`` heartbeat (the board's safe state follows 0.5 s of silence).

Examples
--------
>>> state = BoardState()
>>> state.feed(b"# flexdigit-stream 1 period_us=20000\\r\\n# fault 2 adc_rail\\r\\n", time_s=1.5)
0
>>> state.period_s("hil://board.elf"), state.faults
(0.02, [(1.5, 2, 'adc_rail')])
"""

from __future__ import annotations

import math

from flexdigit.errors import ParameterError, RigError
from flexdigit.params import RigParams
from flexdigit.rig.backends.stream_framing import LineDecoder

__all__ = [
    "BoardState",
    "FAULTS",
    "VOLTS_PER_COUNT",
    "HEARTBEAT_S",
    "BAUD",
    "MAX_KEPT_SAMPLES",
    "FIRMWARE_GAUGES",
    "check_board_digit",
]

#: Gauges the reference firmware reads (ADC0..ADC2; ADC3 is the servo's pot): the thesis rig's three.
FIRMWARE_GAUGES = 3

#: The front end: gauge volts ride on 2.5 V into the 0..5 V ADC; 10 bits over 5 V.
VOLTS_PER_COUNT = 5.0 / 1024.0
#: The board's fault codes (firmware/flexdigit_board.c).
FAULTS = {1: "host_timeout", 2: "adc_rail", 3: "rotation_bound", 4: "command_range", 5: "controller"}
#: The host sends a heartbeat line if it has said nothing for this long (the board's timeout is 0.5 s).
HEARTBEAT_S = 0.1
#: The board's baud rate (firmware/flexdigit_board.c: BAUD).
BAUD = 250_000
#: Stream samples kept in :attr:`BoardState.samples` (a day at 50 Hz would be 4 million: runs here are seconds).
MAX_KEPT_SAMPLES = 200_000


class BoardState:
    """What the board has said: its samples, faults, mode changes, tare and information lines."""

    def __init__(self) -> None:
        self._decoder = LineDecoder()
        self.latest = None  # the newest stream sample
        #: every stream sample (the ADC counts each board period used, and the command it applied), up to a limit
        self.samples: list = []
        #: ``(time_s, code, name)`` of each fault the board reported
        self.faults: list[tuple[float, int, str]] = []
        self.info_lines: list[str] = []
        #: ``(index into samples, mode)`` at each mode change the board announced
        self.mode_marks: list[tuple[int, int]] = []
        #: the rotation the board's map read at rest when its loop started (it subtracts it), deg
        self.tare_deg = math.nan
        self._fault_seen = 0

    def feed(self, data: bytes, time_s: float) -> int:
        """Take the bytes the board sent (at host time ``time_s``, s); returns how many samples they held."""
        new = 0
        for event in self._decoder.feed(data):
            if event.kind == "sample":
                self.latest = event.sample
                new += 1
                if len(self.samples) < MAX_KEPT_SAMPLES:
                    self.samples.append(event.sample)
            elif event.kind == "info":
                self.info_lines = [*self.info_lines[-49:], event.text]
                words = event.text.split()
                if len(words) >= 3 and words[0] == "fault":
                    self.faults.append((time_s, int(words[1]), words[2]))
                elif len(words) == 2 and words[0] == "mode":
                    self.mode_marks.append((len(self.samples), int(words[1])))
                elif len(words) == 2 and words[0] == "tare":
                    self.tare_deg = int(words[1]) / 1e6
        return new

    def raise_new_fault(self, where: str) -> None:
        """Raise :class:`RigError` for a fault reported since the last call (the host loop's safe path)."""
        if len(self.faults) > self._fault_seen:
            t, code, name = self.faults[-1]
            self._fault_seen = len(self.faults)
            raise RigError(f"{where}: the board reported fault {code} ({name}) at t = {t:.3f} s")

    def period_s(self, where: str) -> float:
        """The control period the image was built with (its banner's ``period_us``), s."""
        for line in self.info_lines:
            for word in line.split():
                if word.startswith("period_us="):
                    return int(word.split("=", 1)[1]) / 1e6
        raise RigError(f"{where}: the firmware's banner does not give its period")


def check_board_digit(params, where: str) -> None:
    """Refuse, in one line naming the backend, a digit the reference firmware cannot serve (issue 24).

    The firmware reads :data:`FIRMWARE_GAUGES` gauges, and its image carries the thesis rig's exported controller:
    its straight command (where its safe state relaxes) and its command range are the thesis rig's
    (``flexdigit export controller`` designs for the thesis rig only). A digit with another gauge count, or another
    straight command or range (an antagonistic pair straightens mid-range), would be read wrong or relaxed into a
    bend. A digit of three gauges with the thesis's commands (another length, sections, bridge) is served.

    Examples
    --------
    >>> from flexdigit.params import RigParams
    >>> check_board_digit(RigParams(), "hil://board.elf")
    >>> four = RigParams.from_dict({"sensors": {"adc_channels": [0, 1, 2, 3]},
    ...     "geometry": {"gauge_positions_m": [0.045, 0.1, 0.15, 0.2]}})
    >>> check_board_digit(four, "hil://board.elf")
    Traceback (most recent call last):
    ...
    flexdigit.errors.ParameterError: hil://board.elf: the reference firmware reads 3 gauges ...; the digit has 4 ...
    """
    if params is None:  # the thesis rig
        return
    thesis, a = RigParams().actuator, params.actuator
    gauges = len(params.geometry.gauge_positions_m)
    commands = (a.equilibrium_command, a.command_min, a.command_max)
    if gauges == FIRMWARE_GAUGES and commands == (thesis.equilibrium_command, thesis.command_min, thesis.command_max):
        return
    raise ParameterError(
        f"{where}: the reference firmware reads {FIRMWARE_GAUGES} gauges and relaxes to the thesis rig's straight "
        f"command {thesis.equilibrium_command} (range {thesis.command_min}..{thesis.command_max}); the digit has "
        f"{gauges} gauges, straight command {a.equilibrium_command} (range {a.command_min}..{a.command_max}): not "
        "supported on the board (docs/digits.md); close the loop on the host through the stream instead "
        "(flexdigit stream-emulator --params)"
    )
