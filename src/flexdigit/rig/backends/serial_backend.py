"""The serial backend: the MILINST servo board over pyserial (thesis 2.5.3, 5.2).

The board only drives the servo; it has no inputs. Gauges come from a separate source (the DAQ card in the thesis):
pass ``sensor=`` (a callable returning ``(gauges_v, pot_v)``) or, in the URL, ``daq=<board number>`` (and
``pot=<channel>``), ``daq=daq://N`` or ``daq=stream://PORT`` (a microcontroller ADC,
:mod:`flexdigit.rig.backends.stream_backend`); options of the gauge source follow with a ``daq.`` prefix
(``&daq.baud=115200&daq.scale=0.000125``) and are checked by that source's own declarations. Without one,
:meth:`read` raises :class:`~flexdigit.errors.RigError` ("no gauge source configured") rather than let anything
control blind. The frame layout (sync byte, highest channel and position) is set by URL
options or a :class:`~flexdigit.rig.backends.servo_board.Framing`; see :func:`from_url`.

The port is opened with pyserial's ``serial_for_url``, so ``loop://`` and ``socket://`` work too. A port that
vanishes mid-run (USB unplugged, board powered off) raises :class:`~flexdigit.errors.RigError` naming the port;
:meth:`close` then still releases the port.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Any

import numpy as np

from flexdigit._validation import check_int, check_positive
from flexdigit.errors import ParameterError, RigError
from flexdigit.params import RigParams
from flexdigit.rig.backends.daq_backend import from_url as daq_from_url
from flexdigit.rig.backends.servo_board import MINI_SSC, Framing, encode_frame
from flexdigit.rig.backends.stream_backend import source_from_url
from flexdigit.rig.base import Rig, RigURL, UrlOption, clamp_command, parse_rig_url, rig_url_options

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
        if self.sensor is None:  # the board has no inputs: reading it would only give NaN to control blind on
            raise RigError(
                f"{self.name}: no gauge source configured; the servo board has no inputs: add the gauge card "
                "to the URL (serial://PORT?daq=0) or pass sensor="
            )
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

    def settings(self) -> dict[str, Any]:
        sensor = [c.settings() for c in self.companions] or (["python callable"] if self.sensor else [])
        return {
            "backend": "serial",
            "port": self.port,
            "baud": self.baud,
            "channel": self.channel,
            "framing": {
                "sync": self.framing.sync,
                "max_channel": self.framing.max_channel,
                "max_position": self.framing.max_position,
            },
            "gauge_source": sensor[0] if sensor else None,
        }

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
URL_OPTIONS = (
    UrlOption("baud", "int", low=50, high=4_000_000, help="the baud rate: 2400 or 9600 on the 1-904 board"),
    UrlOption("channel", "int", low=0, high=254, help="the servo number on the board"),
    UrlOption("sync", "int", low=0, high=255, help="the frame's sync byte, 0xFF on a Mini SSC"),
    UrlOption("max_channel", "int", low=0, high=254, help="the highest servo number, 7 on a Mini SSC"),
    UrlOption("max_position", "int", low=1, high=254, help="the highest position byte, 254 on a Mini SSC"),
    UrlOption("daq", "str", help="the gauge source: an MCC board number, daq://BOARD or stream://PORT"),
    UrlOption("pot", "int", low=0, none=True, help="the analog input the servo potentiometer is wired to"),
)
_FRAMING_OPTIONS = ("sync", "max_channel", "max_position")
#: Keyword arguments open_rig may pass from Python (not from the URL text).
PYTHON_OPTIONS = ("framing", "sensor", "write_timeout_s", "serial", "uldaq", "clock", "sleep", "operator")
#: Options with this prefix belong to the gauge source (``daq.baud=115200``): checked by its backend.
URL_PREFIXES = ("daq.",)


def _gauge_source(where: str, params, daq: str, pot: int | None, source_options: dict[str, str], uldaq):
    """The servo board's gauge source from ``daq=``: an MCC board number, ``daq://N`` or ``stream://PORT``.

    The source's own options (``daq.NAME=`` in the serial URL, or in the nested URL) are checked by that backend's
    declarations through the one parser, so an unknown one is refused by name as anywhere else.
    """
    bad = ParameterError(f"{where}: option daq={daq!r} must be a board number, daq://BOARD or stream://PORT")
    text = daq.strip()
    if "://" not in text:
        if not (text.isascii() and text.isdigit()):  # '²' is a digit to isdigit(), not to int()
            raise bad
        url = RigURL("daq", str(int(text)))
    else:
        try:
            url = parse_rig_url(text)
        except ParameterError:
            raise bad from None
        if url.scheme not in ("daq", "stream"):
            raise bad
    twice = sorted(set(url.options) & set(source_options))
    if twice:
        raise ParameterError(f"{where}: option {twice[0]} of the gauge source is given twice (in daq= and as daq.)")
    python: dict[str, Any] = {}
    if url.scheme == "stream" and pot is not None:
        raise ParameterError(f"{where}: option pot={pot!r} is for a DAQ card; a stream sends the pot in its lines")
    if url.scheme == "daq":
        python = {"pot": pot} if pot is not None else {}
        if uldaq is not None:
            python["uldaq"] = uldaq
    nested, checked = rig_url_options(RigURL(url.scheme, url.location, {**url.options, **source_options}), **python)
    if url.scheme == "stream":
        return source_from_url(nested.location, checked)
    return daq_from_url(nested.location, params, checked)


def from_url(location: str, params: RigParams | None, options: dict[str, Any]) -> SerialRig:
    """``serial://PORT?baud=9600&channel=0&daq=0&pot=3&sync=0xFF&max_channel=7&max_position=254``.

    ``daq`` adds the gauge card (board number) as the sensor, ``pot`` its potentiometer channel
    (:mod:`flexdigit.rig.backends.daq_backend`); ``sync``, ``max_channel`` and ``max_position`` describe the board's
    frame
    (:class:`~flexdigit.rig.backends.servo_board.Framing`, Mini SSC by default: any left out keeps its Mini SSC value).
    ``options`` arrive checked and typed (:func:`~flexdigit.rig.base.rig_url_options`).

    Examples
    --------
    >>> from flexdigit.rig.base import open_rig
    >>> rig = open_rig("serial://loop://?sync=0xFE&max_position=200&channel=2")
    >>> rig.framing, rig.channel
    (Framing(sync=254, max_channel=7, max_position=200), 2)
    >>> rig.close()
    """
    if not location:
        raise ParameterError("serial:// needs a port, e.g. serial:///dev/ttyUSB0 or serial://COM3")
    options = dict(options)
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
        raise ParameterError(f"serial://{location}: option pot={pot} needs the gauge card too (daq=BOARD)")
    if source_options and daq is None:
        raise ParameterError(
            f"serial://{location}: option daq.{next(iter(source_options))} needs a gauge source (daq=...)"
        )
    if daq is not None and "sensor" in options:
        raise ParameterError(f"serial://{location}: give the gauges either as daq={daq} or as sensor=..., not both")
    card = None
    if daq is not None:
        card = _gauge_source(f"serial://{location}", params, daq, pot, source_options, uldaq)
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
