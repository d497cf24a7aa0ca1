"""What the reference firmware (``firmware/flexdigit_board.c``, issue 25) says to the host, apart from how its bytes
travel: the board on simavr (:mod:`flexdigit.rig.backends.hil_backend`) and a real Uno
(:mod:`flexdigit.rig.backends.board_backend`) share it.

The board streams each control period's ADC counts (signed about its 2.5 V midpoint) and the command it applied
in the stream protocol (:mod:`flexdigit.rig.backends.stream_framing`, version 2: its G gauges, its command in the
pot's field and its rotation estimate, the map's reading minus its tare, in micro-degrees), and information
lines: its banner (``# flexdigit-stream 2 ... period_us=20000 fixed=0 gauges=3 straight=8 range=0..254
pulse_delay_ms=1 target=uno adc_channels=6``: the digit its image was built for, and the board it needs: an Uno's six
analogue inputs, or a Nano's or Pro Mini's eight), ``# mode <0|1|2>``, ``# tare <micro-deg>`` (the rotation its map
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
    "BOARD_WINDOW_V",
    "HEARTBEAT_S",
    "BAUD",
    "MAX_KEPT_SAMPLES",
    "FIRMWARE_GAUGES",
    "MAX_BOARD_GAUGES",
    "UNO_ADC_CHANNELS",
    "check_board_digit",
    "check_board_image",
    "check_board_channels",
]

#: Gauges the reference firmware reads when its banner does not say (an image built before issue 24's G gauges):
#: the thesis rig's three.
FIRMWARE_GAUGES = 3
#: Most gauges the reference firmware reads: the ATmega328P's ADC0..ADC7. An Uno (the DIP chip) brings out six,
#: A0..A5; a Nano or Pro Mini (the TQFP/MLF chip) eight, A6 and A7 analogue-only inputs.
MAX_BOARD_GAUGES = 8
#: The analogue inputs a board declares when its banner does not say (an image built before the 8-gauge boards:
#: for an Uno).
UNO_ADC_CHANNELS = 6

#: The front end: gauge volts ride on 2.5 V into the 0..5 V ADC; 10 bits over 5 V.
VOLTS_PER_COUNT = 5.0 / 1024.0
#: The gauge volts the board reads without faulting "adc_rail" (firmware/flexdigit_board.c: a count of 0 or 1023
#: faults; count = floor((v + 2.5) / VOLTS_PER_COUNT)), V.
BOARD_WINDOW_V = (-2.5 + VOLTS_PER_COUNT, 2.5 - VOLTS_PER_COUNT)
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
        value = self.banner_value("period_us")
        if value is None:
            raise RigError(f"{where}: the firmware's banner does not give its period")
        return int(value) / 1e6

    def banner_value(self, key: str) -> str | None:
        """The banner's ``key=value`` (``gauges``, ``straight``, ``range``, ``period_us``...), or None."""
        for line in self.info_lines:
            words = line.split()
            if words[:1] != ["flexdigit-stream"]:
                continue
            for word in words:
                if word.startswith(key + "="):
                    return word.split("=", 1)[1]
        return None

    def image_digit(self) -> tuple[int, int, tuple[int, int]]:
        """``(gauges, straight command, (command min, max))`` the image was built for (its banner; an image that
        does not say is the thesis rig's: 3 gauges, straight at 8, 0..254)."""
        gauges = self.banner_value("gauges")
        straight = self.banner_value("straight")
        span = self.banner_value("range")
        low, high = (0, 254) if span is None else (int(v) for v in span.split(".."))
        return (
            FIRMWARE_GAUGES if gauges is None else int(gauges),
            8 if straight is None else int(straight),
            (low, high),
        )


def check_board_digit(params, where: str) -> None:
    """Refuse, in one line naming the backend and the key, a digit no image of the reference firmware can serve.

    The firmware reads gauge k on the ATmega328P's ADCk, so a digit of more than :data:`MAX_BOARD_GAUGES` gauges
    cannot be read (the description refuses 9 already: this says so for the board). Any other digit is served by
    an image built for it (``make firmware PARAMS=D.toml``: its own controller, map, straight command, and a
    Nano/Pro Mini-class board for 7 or 8 gauges); :func:`check_board_image` then checks, once the board has said
    what it was built for and which board it is, that the image is that digit's and the board has its inputs.

    Examples
    --------
    >>> from flexdigit.params import RigParams
    >>> check_board_digit(RigParams(), "hil://board.elf")
    >>> eight = RigParams.from_dict({"sensors": {"adc_channels": list(range(8))},
    ...     "geometry": {"gauge_positions_m": [0.02, 0.05, 0.08, 0.11, 0.14, 0.17, 0.2, 0.23]}})
    >>> check_board_digit(eight, "hil://board.elf")
    """
    if params is None:  # the thesis rig
        return
    gauges = len(params.geometry.gauge_positions_m)
    if gauges > MAX_BOARD_GAUGES:
        raise ParameterError(
            f"{where}: the digit's [geometry] gauge_positions_m has {gauges} gauges; the reference firmware reads "
            f"at most {MAX_BOARD_GAUGES} (the ATmega328P's ADC0..ADC7, gauge k on ADCk): not supported on the "
            "board (docs/board.md); close the loop on the host through a gauge stream instead "
            "(flexdigit stream-emulator --params)"
        )


def check_board_image(board: BoardState, params, where: str) -> None:
    """Refuse, in one line, an image built for another digit than ``params`` (its banner's gauges, straight
    command and range, :meth:`BoardState.image_digit`): it would read the gauges wrong, or relax into a bend."""
    p = params or RigParams()
    a = p.actuator
    want = (len(p.geometry.gauge_positions_m), int(a.equilibrium_command), (int(a.command_min), int(a.command_max)))
    check_board_channels(board, want[0], where)
    try:
        got = board.image_digit()
    except ValueError:
        words = [board.banner_value(k) for k in ("gauges", "straight", "range")]
        raise RigError(
            f"{where}: the firmware's banner does not say which digit its image was built for as expected "
            f"(gauges={words[0]} straight={words[1]} range={words[2]}: integers, range LOW..HIGH)"
        ) from None
    if got != want:
        raise ParameterError(
            f"{where}: the firmware image was built for {got[0]} gauges, straight command {got[1]}, commands "
            f"{got[2][0]}..{got[2][1]}; the digit has {want[0]} gauges, straight command {want[1]}, commands "
            f"{want[2][0]}..{want[2][1]}: build the image for it (make firmware PARAMS=your-digit.toml)"
        )


def check_board_channels(board: BoardState, gauges: int, where: str) -> None:
    """Refuse, in one line, a digit of more gauges than the board declares analogue inputs (its banner's
    ``adc_channels``: 6 on an Uno, 8 on a Nano or Pro Mini; an image that does not say was built for an Uno).

    Examples
    --------
    >>> uno = BoardState()
    >>> _ = uno.feed(b"# flexdigit-stream 2 gauges=6 target=uno adc_channels=6\\r\\n", time_s=0.0)
    >>> check_board_channels(uno, 6, "board:///dev/ttyACM0")
    >>> check_board_channels(uno, 8, "board:///dev/ttyACM0")
    Traceback (most recent call last):
    ...
    flexdigit.errors.ParameterError: board:///dev/ttyACM0: the board declares 6 analogue inputs (uno: A0..A5); ...
    """
    declared = board.banner_value("adc_channels")
    try:
        channels = UNO_ADC_CHANNELS if declared is None else int(declared)
    except ValueError:
        raise RigError(f"{where}: the firmware's banner gives adc_channels={declared}: expected 6 or 8") from None
    if gauges > channels:
        target = board.banner_value("target") or "uno"
        raise ParameterError(
            f"{where}: the board declares {channels} analogue inputs ({target}: A0..A{channels - 1}); the digit has "
            f"{gauges} gauges (one an input): use a Nano or Pro Mini (A6, A7) and an image built for it "
            "(make firmware PARAMS=your-digit.toml BOARD=nano)"
        )
