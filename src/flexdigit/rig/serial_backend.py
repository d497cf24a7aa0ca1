"""The serial backend: the MILINST servo board over pyserial (thesis 2.5.3, 5.2).

The board only drives the servo; it has no inputs. Gauges come from a separate source (the DAQ card in the thesis):
pass ``sensor=`` (a callable returning ``(gauges_v, pot_v)``) or, in the URL, ``daq=<board number>`` (and
``pot=<channel>``), ``daq=daq://N`` or ``daq=stream://PORT`` (a microcontroller ADC,
:mod:`flexdigit.rig.stream_backend`); options of the gauge source follow with a ``daq.`` prefix
(``&daq.baud=115200&daq.scale=0.000125``). Without one, :meth:`read` returns NaN gauges and the loop stops with a
sensor fault rather than control blind. The frame layout (sync byte, highest channel and position) is set by URL
options or a :class:`~flexdigit.rig.servo_board.Framing`; see :func:`from_url`.

The port is opened with pyserial's ``serial_for_url``, so ``loop://`` and ``socket://`` work too. A port that
vanishes mid-run (USB unplugged, board powered off) raises :class:`~flexdigit.errors.RigError` naming the port;
:meth:`close` then still releases the port.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from flexdigit._validation import check_int, check_positive
from flexdigit.errors import ParameterError, RigError
from flexdigit.params import RigParams
from flexdigit.rig.base import Rig, clamp_command
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

    def write_command(self, command: object) -> int:
        """Send a servo command clamped to the actuator range and to the framing's highest position."""
        return super().write_command(min(clamp_command(command, self.params), self.framing.max_position))

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


#: Options a ``serial://`` URL may carry; ``sync``, ``max_channel`` and ``max_position`` build the :class:`Framing`.
URL_OPTIONS = ("baud", "channel", "sync", "max_channel", "max_position", "daq", "pot")
_FRAMING_OPTIONS = ("sync", "max_channel", "max_position")
#: Keyword arguments open_rig may pass from Python (not from the URL text).
_PYTHON_OPTIONS = ("framing", "sensor", "write_timeout_s", "serial", "uldaq", "clock", "sleep", "operator")


def _int_option(location: str, key: str, value: Any) -> Any:
    """A URL option as an integer (decimal, or 0x.. hexadecimal for bytes such as the sync byte)."""
    if not isinstance(value, str):
        return value
    try:
        return int(value.strip(), 0)
    except ValueError:
        raise ParameterError(
            f"serial://{location}: option {key}={value!r} must be an integer (decimal, or hexadecimal as 0xFF)"
        ) from None


def _gauge_source(location: str, params, daq: str, pot, source_options: dict, uldaq):
    """The servo board's gauge source from ``daq=``: an MCC board number, ``daq://N`` or ``stream://PORT``."""
    from flexdigit.rig.base import parse_rig_url
    from flexdigit.rig.daq_backend import DaqRig, pot_option

    where = f"serial://{location}"
    if "://" not in daq:
        try:
            board = int(daq)
        except ValueError:
            raise ParameterError(
                f"{where}: option daq={daq!r} must be a board number, daq://BOARD or stream://PORT"
            ) from None
        if source_options:
            raise ParameterError(
                f"{where}: option daq.{next(iter(source_options))} is for a daq:// or stream:// source"
            )
        return DaqRig(board, params, uldaq=uldaq, pot_channel=pot_option(pot, where))
    try:
        url = parse_rig_url(daq)
    except ParameterError:
        url = None
    if url is None or url.scheme not in ("daq", "stream"):
        raise ParameterError(f"{where}: option daq={daq!r} must be a board number, daq://BOARD or stream://PORT")
    merged = {**url.options, **source_options}
    if url.scheme == "stream":
        from flexdigit.rig.stream_backend import source_from_url

        if pot is not None:
            raise ParameterError(f"{where}: option pot={pot!r} is for a DAQ card; a stream sends the pot in its lines")
        return source_from_url(url.location, merged)
    from flexdigit.rig.daq_backend import from_url as daq_from_url

    if pot is not None:
        merged.setdefault("pot", pot)
    return daq_from_url(url.location, params, {**merged, **({"uldaq": uldaq} if uldaq is not None else {})})


def from_url(location: str, params: RigParams | None, options: dict[str, Any]) -> SerialRig:
    """``serial://PORT?baud=9600&channel=0&daq=0&pot=3&sync=0xFF&max_channel=7&max_position=254``.

    ``daq`` adds the gauge card (board number) as the sensor, ``pot`` its potentiometer channel
    (:mod:`flexdigit.rig.daq_backend`); ``sync``, ``max_channel`` and ``max_position`` describe the board's frame
    (:class:`~flexdigit.rig.servo_board.Framing`, Mini SSC by default: any left out keeps its Mini SSC value).

    Examples
    --------
    >>> rig = from_url("loop://", None, {"sync": "0xFE", "max_position": "200", "channel": "2"})
    >>> rig.framing, rig.channel
    (Framing(sync=254, max_channel=7, max_position=200), 2)
    >>> rig.close()
    """
    if not location:
        raise ParameterError("serial:// needs a port, e.g. serial:///dev/ttyUSB0 or serial://COM3")
    options = dict(options)
    unknown = sorted(k for k in set(options) - set(URL_OPTIONS) - set(_PYTHON_OPTIONS) if not k.startswith("daq."))
    if unknown:
        raise ParameterError(
            f"serial://{location}: unknown option {unknown[0]!r}; a serial URL takes {', '.join(URL_OPTIONS)}"
        )
    for key in ("baud", "channel", *_FRAMING_OPTIONS):
        if key in options:
            options[key] = _int_option(location, key, options[key])
    framing_keys = {key: options.pop(key) for key in _FRAMING_OPTIONS if key in options}
    if framing_keys:
        if "framing" in options:
            raise ParameterError(
                f"serial://{location}: give the framing either as URL options ({', '.join(framing_keys)}) or as "
                "framing=Framing(...), not both"
            )
        try:
            options["framing"] = replace(MINI_SSC, **framing_keys)
        except ParameterError as exc:
            raise ParameterError(f"serial://{location}: {exc}") from None
    daq = options.pop("daq", None)
    pot = options.pop("pot", None)
    uldaq = options.pop("uldaq", None)
    source_options = {key[4:]: options.pop(key) for key in list(options) if key.startswith("daq.")}
    if pot is not None and daq is None:
        raise ParameterError(f"serial://{location}: option pot={pot!r} needs the gauge card too (daq=BOARD)")
    if source_options and daq is None:
        raise ParameterError(
            f"serial://{location}: option daq.{next(iter(source_options))} needs a gauge source (daq=...)"
        )
    card = None
    if daq is not None and "sensor" not in options:
        card = _gauge_source(location, params, str(daq), pot, source_options, uldaq)
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
