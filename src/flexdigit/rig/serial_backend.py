"""The serial backend: the MILINST servo board over pyserial (thesis 2.5.3, 5.2).

The board only drives the servo; it has no inputs. Gauges come from a separate source (the DAQ card in the thesis):
pass ``sensor=`` (a callable returning ``(gauges_v, pot_v)``) or ``daq=<board number>`` in the URL. Without one,
:meth:`read` returns NaN gauges and the loop stops with a sensor fault rather than control blind.

The port is opened with pyserial's ``serial_for_url``, so ``loop://`` and ``socket://`` work too. A port that
vanishes mid-run (USB unplugged, board powered off) raises :class:`~flexdigit.errors.RigError` naming the port;
:meth:`close` then still releases the port.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from flexdigit._validation import check_int, check_positive
from flexdigit.errors import ParameterError, RigError
from flexdigit.params import RigParams
from flexdigit.rig.base import Rig
from flexdigit.rig.servo_board import MINI_SSC, Framing, encode_frame

__all__ = ["SerialRig", "from_url"]

Sensor = Callable[[], tuple[np.ndarray, float]]


class SerialRig(Rig):
    """The servo board on a serial port.

    Parameters
    ----------
    port : str
        Device or pyserial URL (``/dev/ttyUSB0``, ``COM3``, ``loop://``).
    params : RigParams, optional
    baud : int
        Baud rate (the 1-904 board: 2400 or 9600; 9600 by default).
    channel : int
        Servo number on the board (0).
    framing : Framing
        Frame layout (Mini SSC).
    sensor : callable, optional
        ``sensor() -> (gauges_v (3,), pot_v)``; NaN gauges without one.
    write_timeout_s : float
        A write that blocks longer than this is a vanished board (0.1 s: five 20 ms periods).
    serial : object, optional
        An already open pyserial-like port (tests); ``port`` is then only used in messages.
    """

    name = "serial"

    def __init__(
        self,
        port: str,
        params: RigParams | None = None,
        *,
        baud: int = 9600,
        channel: int = 0,
        framing: Framing = MINI_SSC,
        sensor: Sensor | None = None,
        write_timeout_s: float = 0.1,
        serial: Any = None,
        **kwargs: Any,
    ) -> None:
        self.port = str(port)
        self.baud = check_int(baud, "baud", "SerialRig", low=50, high=4_000_000)
        self.framing = framing
        self.channel = check_int(channel, "channel", "SerialRig", low=0, high=framing.max_channel)
        self.write_timeout_s = check_positive(write_timeout_s, "write_timeout_s", "SerialRig")
        self.sensor = sensor
        self.name = f"serial {self.port}"
        if serial is None:
            serial = _open_port(self.port, self.baud, self.write_timeout_s)
        self._port = serial
        self.companions: list = []
        super().__init__(params, **kwargs)
        # Bumpless start: the board holds its last position, so we start by sending equilibrium explicitly.
        self.write_command(self.params.actuator.equilibrium_command)

    def _read(self) -> tuple[np.ndarray, float]:
        if self.sensor is None:
            return np.full(3, math.nan), math.nan
        gauges, pot = self.sensor()
        return np.asarray(gauges, dtype=float), float(pot)

    def _send(self, command: int) -> None:
        frame = encode_frame(self.channel, command, self.framing)
        try:
            written = self._port.write(frame)
            self._port.flush()
        except Exception as exc:  # pyserial raises SerialException/OSError/termios.error when the device is gone
            raise RigError(f"{self.name}: the servo board stopped answering ({exc}); port lost") from exc
        if written is not None and written != len(frame):
            raise RigError(f"{self.name}: only {written} of {len(frame)} bytes written; board not accepting data")

    def _close(self) -> None:
        try:
            self._port.close()
        except Exception:  # noqa: BLE001 - closing a port that already vanished must not raise
            pass
        for companion in self.companions:  # the gauge card opened with it (serial://...?daq=0)
            companion.close()

    def __repr__(self) -> str:
        state = "closed" if self.closed else "open"
        return (
            f"SerialRig(port={self.port!r}, baud={self.baud}, channel={self.channel}, framing={self.framing}, "
            f"command={self.command}, {state})"
        )


def _open_port(port: str, baud: int, write_timeout_s: float) -> Any:
    import serial

    try:
        return serial.serial_for_url(port, baudrate=baud, timeout=0, write_timeout=write_timeout_s)
    except (serial.SerialException, ValueError) as exc:
        raise RigError(f"serial {port}: cannot open the servo board port ({exc})") from exc


def from_url(location: str, params: RigParams | None, options: dict[str, Any]) -> SerialRig:
    """``serial://PORT?baud=9600&channel=0&daq=0`` (``daq`` adds the gauge card as the sensor)."""
    if not location:
        raise ParameterError("serial:// needs a port, e.g. serial:///dev/ttyUSB0 or serial://COM3")
    options = dict(options)
    for key in ("baud", "channel"):
        if key in options and isinstance(options[key], str):
            try:
                options[key] = int(options[key])
            except ValueError:
                raise ParameterError(f"serial://{location}: option {key}={options[key]!r} must be an integer") from None
    daq = options.pop("daq", None)
    uldaq = options.pop("uldaq", None)
    card = None
    if daq is not None and "sensor" not in options:
        from flexdigit.rig.daq_backend import DaqRig

        try:
            board = int(daq)
        except ValueError:
            raise ParameterError(f"serial://{location}: option daq={daq!r} must be a board number") from None
        card = DaqRig(board, params, uldaq=uldaq)
        options["sensor"] = card.read_gauges
    try:
        rig = SerialRig(location, params, **options)
    except BaseException:
        if card is not None:
            card.close()
        raise
    if card is not None:
        rig.companions.append(card)
    return rig
