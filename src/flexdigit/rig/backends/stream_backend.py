"""The ``stream://`` backend: gauges (and the pot) from a microcontroller ADC over USB serial (thesis 2.5.1 today).

The thesis's DAQ card (an MCC PCI card) is long out of production; a rig rebuilt today reads the amplified
half-bridges with an ADS1115 or HX711 on an Arduino-class board, which sends them as checksummed ASCII lines
(:mod:`flexdigit.rig.backends.stream_framing`; reference firmware in ``examples/flexdigit_stream/``). This module reads
that stream:

- on its own, as a read-only :class:`StreamRig`: ``stream:///dev/ttyACM0?baud=115200``;
- as the gauge source of the servo board: ``serial:///dev/ttyUSB0?daq=stream:///dev/ttyACM0&daq.baud=115200``
  (options of the gauge source carry a ``daq.`` prefix; see :mod:`flexdigit.rig.backends.serial_backend`).

A background thread reads the port (pyserial ``serial_for_url``, so ``loop://`` and ``socket://`` work too) and
keeps the newest valid sample; :meth:`StreamSource.read_gauges` returns it in volts (counts x ``scale``). Dropped
lines (gaps in the sequence number), garbled lines (bad checksum or fields), duplicated and out-of-order lines,
board restarts and information lines are counted (:meth:`StreamSource.stats`). It raises
:class:`~flexdigit.errors.RigError`, which the real-time loop turns into its safe state (digit relaxed, ports
closed, log closed with the reason), when

- no valid line came for ``timeout`` seconds (a silent board, a pulled cable, a board repeating an old line);
- more than ``max_bad`` of the last ``window`` expected lines were dropped, garbled, duplicated or out of order
  (wrong baud rate, noise); what comes before the first valid line (a partial line, a bootloader's bytes while
  the board resets on opening) is counted but not held against the stream;
- a gauge sits on the ADC's rail or beyond it (``bits``-bit signed counts);
- the port itself fails (USB unplugged).

URL options (all optional): ``baud`` (115200), ``scale`` (volts per count, 0.000125: an ADS1115 at +-4.096 V),
``pot_scale`` (volts per pot count, default ``scale``), ``bits`` (ADC resolution, 16), ``timeout`` (s, 0.25),
``startup`` (s to wait for the first valid line, 3: an Arduino resets when its port is opened), ``window`` (50)
and ``max_bad`` (0.2). Unknown options are refused by name.
"""

from __future__ import annotations

import collections
import math
import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from flexdigit.errors import ParameterError, RigError
from flexdigit.params import RigParams
from flexdigit.rig.backends.stream_framing import PROTOCOL_VERSIONS, SEQ_MODULUS, LineDecoder, Sample
from flexdigit.rig.base import Rig, RigURL, UrlOption, rig_url_options

__all__ = ["StreamSource", "StreamRig", "from_url", "source_from_url", "URL_OPTIONS"]

#: What a ``stream://`` URL may carry, each checked by the one parser (:func:`~flexdigit.rig.base.rig_url_options`).
URL_OPTIONS = (
    UrlOption("baud", "int", low=50, high=4_000_000, help="the baud rate, 115200 in the reference firmware"),
    UrlOption("scale", "float", low=0.0, low_open=True, help="volts per ADC count of the gauges"),
    UrlOption("pot_scale", "float", low=0.0, low_open=True, none=True, help="volts per count of the pot"),
    UrlOption("bits", "int", low=2, high=32, help="the ADC resolution"),
    UrlOption("timeout", "float", low=0.0, high=60.0, low_open=True, help="seconds without a line: silent"),
    UrlOption("startup", "float", low=0.0, high=60.0, help="seconds to wait for the first line"),
    UrlOption("window", "int", low=5, high=100_000, help="lines over which garbling is judged"),
    UrlOption("max_bad", "float", low=0.0, high=1.0, help="the share of bad lines that is garbled"),
)
#: Keyword arguments that only Python callers pass (not URL text).
PYTHON_OPTIONS = ("serial", "clock", "sleep", "operator")


class StreamSource:
    """The gauge stream on a serial port, read by a background thread.

    Parameters
    ----------
    port : str
        Device or pyserial URL (``/dev/ttyACM0``, ``COM4``, ``socket://host:port``).
    baud : int
        Baud rate (115200 in the reference firmware).
    scale, pot_scale : float
        Volts per ADC count of the gauges and of the pot (``pot_scale`` defaults to ``scale``).
    bits : int
        ADC resolution: counts are signed ``bits``-bit numbers; a gauge at either rail is a sensor fault.
    timeout : float
        A read with no valid line for this long (s) is a silent stream.
    startup : float
        Seconds to wait for the first valid line when opening.
    window, max_bad : int, float
        The stream is garbled when more than ``max_bad`` of the last ``window`` expected lines were dropped or bad.
    serial : object, optional
        An already open pyserial-like port (tests).
    clock, sleep : callable, optional
        Monotonic clock and sleep (``time.monotonic``, ``time.sleep``).
    """

    def __init__(
        self,
        port: str,
        *,
        baud: int = 115200,
        scale: float = 0.000125,
        pot_scale: float | None = None,
        bits: int = 16,
        timeout: float = 0.25,
        startup: float = 3.0,
        window: int = 50,
        max_bad: float = 0.2,
        serial: Any = None,
        clock: Callable[[], float] | None = None,
        sleep: Callable[[float], None] | None = None,
    ) -> None:
        checked = _check_options(
            str(port),
            {"baud": baud, "scale": scale, "bits": bits, "timeout": timeout, "startup": startup, "window": window}
            | {"max_bad": max_bad}
            | ({} if pot_scale is None else {"pot_scale": pot_scale}),
        )
        self.port = str(port)
        self.name = f"stream {self.port}"
        self.baud, self.scale, self.bits = checked["baud"], checked["scale"], checked["bits"]
        self.pot_scale = checked["pot_scale"] if pot_scale is not None else self.scale
        self.timeout, self.startup = checked["timeout"], checked["startup"]
        self.window, self.max_bad = checked["window"], checked["max_bad"]
        self._clock = clock or time.monotonic
        self._sleep = sleep or time.sleep
        self._rail = (-(2 ** (self.bits - 1)), 2 ** (self.bits - 1) - 1)
        self._lock = threading.Lock()
        self._decoder = LineDecoder()
        self._latest: Sample | None = None
        self._latest_at = -math.inf
        self._last_seq: int | None = None
        self._recent: collections.deque[bool] = collections.deque(maxlen=self.window)  # True: dropped or garbled
        self._counts = dict.fromkeys(("samples", "garbled", "dropped", "duplicated", "out_of_order", "info"), 0)
        self._counts["restarts"] = 0
        self._reasons: collections.Counter[str] = collections.Counter()
        self.info_lines: list[str] = []
        self._error: BaseException | None = None
        self._halt = threading.Event()
        self._opened_at = self._clock()
        self._port = serial if serial is not None else _open_port(self.port, self.baud)
        self._thread = threading.Thread(target=self._run, name=f"flexdigit {self.name}", daemon=True)
        self._thread.start()
        try:
            self._wait_for_first_line()
        except BaseException:
            self.close()
            raise

    # -- the reader thread -------------------------------------------------------------------------------------
    def _run(self) -> None:
        while not self._halt.is_set():
            try:
                data = self._port.read(max(1, getattr(self._port, "in_waiting", 0) or 0))
            except Exception as exc:  # noqa: BLE001 - SerialException, OSError, termios.error: the port is gone
                if not self._halt.is_set():
                    with self._lock:
                        self._error = exc
                return
            if data:
                events = self._decoder.feed(data)
                now = self._clock()
                with self._lock:
                    for event in events:
                        self._take(event, now)

    def _take(self, event, now: float) -> None:
        # Until the first valid line (and again after a restart) the board may still be booting: a partial first
        # line, a bootloader's bytes. Those are counted, but only lines after it count towards "garbled".
        synced = self._last_seq is not None
        if event.kind == "info":
            self._counts["info"] += 1
            self.info_lines = [*self.info_lines[-19:], event.text]
            words = event.text.split()
            known = [str(v) for v in PROTOCOL_VERSIONS]
            if len(words) >= 2 and words[0] == "flexdigit-stream" and words[1] not in known:
                self._error = RigError(
                    f"{self.name}: the board speaks flexdigit-stream protocol {words[1]}; this flexdigit reads "
                    f"versions {' and '.join(known)}"
                )
            return
        if event.kind == "garbled":
            self._counts["garbled"] += 1
            self._reasons[event.reason] += 1
            if synced:
                self._recent.append(True)
            return
        sample = event.sample
        if synced:
            gap = (sample.seq - self._last_seq - 1) % SEQ_MODULUS
            behind = (self._last_seq - sample.seq) % SEQ_MODULUS  # 0: the same line again
            if sample.seq == 0 and gap:  # the board's first line after power-up or reset
                self._restart()
            elif behind <= self.window:  # the same line again, or one from just before: older than what we have
                self._counts["duplicated" if behind == 0 else "out_of_order"] += 1
                self._recent.append(True)
                return
            elif gap >= SEQ_MODULUS // 2:  # further back than the window: the board restarted (its counter too)
                self._restart()
            elif gap:
                self._counts["dropped"] += gap
                self._recent.extend([True] * min(gap, self.window))
        self._last_seq = sample.seq
        self._counts["samples"] += 1
        self._recent.append(False)
        self._latest, self._latest_at = sample, now

    def _restart(self) -> None:
        self._counts["restarts"] += 1
        self._recent.clear()

    def _wait_for_first_line(self) -> None:
        deadline = self._opened_at + self.startup
        while True:
            with self._lock:
                if self._error is not None:
                    raise RigError(f"{self.name}: {self._error}") from None
                if self._latest is not None:
                    return
            if self._clock() >= deadline:
                raise RigError(
                    f"{self.name}: no valid line within {self.startup:g} s of opening ({self._summary()}); check the "
                    f"board runs the flexdigit-stream firmware at baud={self.baud}"
                )
            self._sleep(0.005)

    # -- what the rig reads ------------------------------------------------------------------------------------
    def read_gauges(self) -> tuple[np.ndarray, float]:
        """``(gauges_v, pot_v)`` of the newest valid line (pot NaN if the board sends none); RigError on a fault."""
        now = self._clock()
        with self._lock:
            error, sample, at = self._error, self._latest, self._latest_at
            recent = list(self._recent)
        if error is not None:
            if isinstance(error, RigError):
                raise error
            raise RigError(f"{self.name}: the port failed ({error}); stream lost")
        age = now - at
        if sample is None or age > self.timeout:
            raise RigError(
                f"{self.name}: stream silent: no valid line for {age:.3f} s (timeout {self.timeout:g} s; "
                f"{self._summary()})"
            )
        if len(recent) >= min(self.window, 10) and sum(recent) > self.max_bad * len(recent):
            raise RigError(
                f"{self.name}: stream garbled: {sum(recent)} of the last {len(recent)} lines dropped or bad "
                f"(limit {self.max_bad:g}; {self._summary()})"
            )
        for i, count in enumerate(sample.gauges):
            if count < self._rail[0] or count > self._rail[1]:
                raise RigError(
                    f"sensor fault: gauge {i + 1} read {count} counts, beyond a {self.bits}-bit ADC's "
                    f"{self._rail[0]}..{self._rail[1]} on {self.name}: is bits= right (24 for an HX711)?"
                )
            if count in self._rail:
                raise RigError(
                    f"sensor fault: gauge {i + 1} at the stream ADC's rail ({count} counts, {self.bits}-bit) "
                    f"on {self.name}"
                )
        gauges = np.array(sample.gauges, dtype=float) * self.scale
        pot = math.nan if sample.pot is None else sample.pot * self.pot_scale
        return gauges, pot

    def stats(self) -> dict[str, Any]:
        """Counts so far: valid ``samples``; ``garbled`` (with their ``reasons``), ``dropped`` (gaps in the sequence),
        ``duplicated`` and ``out_of_order`` lines (never used); ``info`` lines (the last ones in ``info_lines``);
        board ``restarts``."""
        with self._lock:
            return {**self._counts, "reasons": dict(self._reasons), "info_lines": list(self.info_lines)}

    def _summary(self) -> str:
        c = self._counts
        reasons = ", ".join(f"{k}: {v}" for k, v in self._reasons.most_common(2))
        stale = ", ".join(f"{c[k]} {k.replace('_', ' ')}" for k in ("duplicated", "out_of_order") if c[k])
        return (
            f"{c['samples']} valid lines, {c['dropped']} dropped, {c['garbled']} garbled"
            + (f" ({reasons})" if reasons else "")
            + (f", {stale}" if stale else "")
        )

    @property
    def closed(self) -> bool:
        return self._halt.is_set()

    def close(self) -> None:
        """Stop the reader and release the port. Safe to call twice."""
        if self._halt.is_set():
            return
        self._halt.set()
        cancel = getattr(self._port, "cancel_read", None)
        if cancel is not None:
            try:
                cancel()
            except Exception:  # noqa: BLE001 - a vanished port
                pass
        if self._thread.is_alive() and self._thread is not threading.current_thread():
            self._thread.join(1.0)
        try:
            self._port.close()
        except Exception:  # noqa: BLE001 - closing a port that already vanished must not raise
            pass

    def settings(self) -> dict[str, Any]:
        """What decides the readings (JSON-able; logged and recorded with the servo board's settings)."""
        return {
            "backend": "stream",
            "port": self.port,
            "baud": self.baud,
            "scale": self.scale,
            "pot_scale": self.pot_scale,
            "bits": self.bits,
            "timeout": self.timeout,
            "startup": self.startup,
            "window": self.window,
            "max_bad": self.max_bad,
        }

    def __repr__(self) -> str:
        state = "closed" if self.closed else "open"
        return (
            f"StreamSource(port={self.port!r}, baud={self.baud}, scale={self.scale:g}, pot_scale={self.pot_scale:g}, "
            f"bits={self.bits}, timeout={self.timeout:g}, window={self.window}, max_bad={self.max_bad:g}, {state})"
        )


class StreamRig(Rig):
    """The gauge stream as a read-only rig (``stream://PORT``): it reads; it cannot move the servo."""

    name = "stream"

    def __init__(self, source: StreamSource, params: RigParams | None = None, **kwargs: Any) -> None:
        self.source = source
        kwargs.setdefault("clock", source._clock)
        kwargs.setdefault("sleep", source._sleep)
        super().__init__(params, **kwargs)
        self.name = source.name

    def _read(self) -> tuple[np.ndarray, float]:
        gauges, pot = self.source.read_gauges()
        expected = len(self.params.geometry.gauge_positions_m)
        if gauges.size != expected:  # a board wired for another digit: its readings would be read as this one's
            raise RigError(
                f"{self.name}: the board sends {gauges.size} gauge(s) a line but the digit has {expected}: flash the "
                "firmware with its gauge count, or give the digit's parameters (--params)"
            )
        return gauges, pot

    def _send(self, command: int) -> None:
        raise RigError(
            f"{self.name}: a gauge stream cannot move the servo; open 'serial://PORT?daq=stream://{self.source.port}'"
        )

    def stats(self) -> dict[str, Any]:
        return self.source.stats()

    def settings(self) -> dict[str, Any]:
        return self.source.settings()

    def close(self) -> None:  # read-only: nothing to relax
        if self._closed:
            return
        self._closed = True
        self.source.close()

    def __repr__(self) -> str:
        return f"StreamRig({self.source!r})"


def _open_port(port: str, baud: int) -> Any:
    import serial

    try:
        return serial.serial_for_url(port, baudrate=baud, timeout=0.05)
    except (serial.SerialException, ValueError) as exc:
        raise RigError(f"stream {port}: cannot open the gauge stream port ({exc})") from exc


def _check_options(location: str, options: dict[str, Any]) -> dict[str, Any]:
    """URL (or keyword) options converted and range-checked; unknown ones refused by name."""
    return rig_url_options(RigURL("stream", location), **options)[1]


def source_from_url(location: str, options: dict[str, Any]) -> StreamSource:
    """A :class:`StreamSource` from a URL's location and options (``stream:///dev/ttyACM0?baud=115200``)."""
    if not location:
        raise ParameterError("stream:// needs a port, e.g. stream:///dev/ttyACM0 or stream://COM4")
    checked = _check_options(location, options)
    checked.pop("operator", None)
    return StreamSource(location, **checked)


def from_url(location: str, params: RigParams | None, options: dict[str, Any]) -> StreamRig:
    """``stream:///dev/ttyACM0?baud=115200&scale=0.000125`` as a read-only rig (see the module docstring)."""
    source = source_from_url(location, options)
    try:
        return StreamRig(source, params, operator=options.get("operator"))
    except BaseException:
        source.close()
        raise
