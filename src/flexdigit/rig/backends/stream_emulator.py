"""A microcontroller on a pseudo-terminal: the ``stream://`` gauge stream (and a servo board) without hardware.

:class:`StreamEmulator` opens a pty pair and, from a background thread, writes the flexdigit-stream protocol
(:mod:`flexdigit.rig.backends.stream_framing`) on its master side as the reference firmware would; pyserial opens the
slave side (:attr:`StreamEmulator.port`) like any USB serial port. With ``twin=True`` the gauges and pot come from
a :class:`~flexdigit.twin.Twin` run on the wall clock, and a second pty (:attr:`StreamEmulator.servo_port`) decodes
Mini SSC frames into the twin's commands, as the MILINST board does: the whole rig,
``serial://SERVO_PORT?daq=stream://PORT``, for rehearsing a controller or testing the hardware path end to end.

Faults a real board shows can be injected (:class:`Faults`): a stream that stops (``stop_after`` lines), that
turns to garbage (``garble_after``), that drops or corrupts every n-th line; a seed makes the corruption
reproducible.

    python -m flexdigit.rig.backends.stream_emulator --twin           # prints the two ports; Ctrl-C to stop
    flexdigit stream-emulator --twin --duration 60

POSIX only (``os.openpty``).
"""

from __future__ import annotations

import math
import os
import select
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from flexdigit._validation import SEED, Flag, Plausible, check_int, check_param, check_positive
from flexdigit.errors import ParameterError
from flexdigit.params import RigParams, load_params
from flexdigit.rig.backends.servo_board import FrameDecoder
from flexdigit.rig.backends.stream_framing import PROTOCOL_VERSION, encode_line
from flexdigit.twin.digit_calibration import twin_calibration

#: Lines per second: the firmware streams 100; a 115200-baud serial line carries ~2,000 of these lines.
RATE_HZ = Plausible("Hz", 0.1, 10_000.0, "lines per second: the firmware streams 100, a serial line carries ~2,000")
#: How long the emulator runs when told: a week at most (a longer one is a typo; leave --duration out to run on).
DURATION_S = Plausible("s", 0.0, 7 * 86_400.0, "a week at most; leave it out to run until Ctrl-C", closed="right")

__all__ = ["Faults", "StreamEmulator", "main"]

#: ``source(t_s) -> (gauges_v (3,), pot_v or None)``
Source = Callable[[float], tuple[np.ndarray, float | None]]


@dataclass(frozen=True)
class Faults:
    """Faults to inject (None: never). Counts are of lines the firmware produced (sequence numbers).

    stop_after : the board falls silent after this many lines (the port stays open)
    garble_after : every line after this many is corrupted (one byte changed: the checksum fails)
    garble_every : every n-th line is corrupted
    drop_every : every n-th line is never sent (a gap in the sequence numbers)
    """

    stop_after: int | None = None
    garble_after: int | None = None
    garble_every: int | None = None
    drop_every: int | None = None

    def __post_init__(self) -> None:
        for name in ("stop_after", "garble_after", "garble_every", "drop_every"):
            value = getattr(self, name)
            if value is not None:
                check_int(value, name, "Faults", low=0 if name.endswith("after") else 1)


class StreamEmulator:
    """The reference firmware on a pty (see the module docstring).

    Parameters
    ----------
    source : callable, optional
        ``source(t_s) -> (gauges_v, pot_v or None)`` in volts; default a resting digit (0.1, 0.5, 0.2 V with 2 mV of
        seeded noise, no pot; on a ``params`` digit of G gauges, G values from 0.1 V up). Ignored with ``twin``.
    twin : bool or flexdigit.twin.Twin
        Stream a twin's gauges and pot (True: ``Twin(params, seed=seed)`` with the digit's derived calibration) and
        serve a servo board on :attr:`servo_port`.
    params : RigParams, optional
        The digit (default the thesis rig): its gauge count, and the twin's digit.
    calibration : Calibration, optional
        The twin's calibration (default :func:`~flexdigit.twin.digit_calibration.twin_calibration` of ``params``:
        the packaged one on the thesis rig, the thesis's scaled to any other digit). Only with ``twin=True``.
    version : {1, 2}
        The protocol version of the lines (the reference firmware's 2; 1, as boards flashed before it, carries
        three gauges only).
    rate_hz : float
        Lines per second (the firmware's 100).
    scale : float
        Volts per count (ADS1115 at +-4.096 V: 0.000125); ``bits`` the ADC resolution (counts are clipped to it).
    faults : Faults
    seed : int
        Seeds the default source's noise and the corruption.
    banner : bool
        Send the ``# flexdigit-stream 2 ... gauges=G`` information line first.
    """

    def __init__(
        self,
        source: Source | None = None,
        *,
        twin=False,
        rate_hz: float = 100.0,
        scale: float = 0.000125,
        bits: int = 16,
        faults: Faults | None = None,
        seed: int = 0,
        banner: bool = True,
        params=None,
        version: int = PROTOCOL_VERSION,
        calibration=None,
    ) -> None:
        import tty

        self.rate_hz = check_param(rate_hz, RATE_HZ, "rate_hz", "StreamEmulator")
        self.scale = check_positive(scale, "scale", "StreamEmulator")
        self.bits = check_int(bits, "bits", "StreamEmulator", low=2, high=32)
        self.faults = faults or Faults()
        self.seed = check_int(seed, "seed", "StreamEmulator", low=0)
        self.rng = np.random.default_rng(self.seed)
        self.banner = bool(banner)
        self.params = params or RigParams()
        self.gauges = len(self.params.geometry.gauge_positions_m)
        self.version = check_int(version, "version", "StreamEmulator", low=1, high=PROTOCOL_VERSION)
        if self.version == 1 and self.gauges != 3:
            raise ParameterError(
                f"The 'version' parameter of StreamEmulator is 1, whose lines carry 3 gauges; the digit has "
                f"{self.gauges}: use version 2"
            )
        self.twin = None
        if twin is not False:
            from flexdigit.twin.twin import Twin

            calibration = twin_calibration(self.params) if calibration is None else calibration
            self.twin = Twin(self.params, seed=self.seed, dt_s=0.002, calibration=calibration) if twin is True else twin
        self.source = source or self._resting
        self.master, self._slave = os.openpty()
        tty.setraw(self._slave)  # no echo, no newline translation: bytes pass as the firmware wrote them
        os.set_blocking(self.master, False)
        self.port = os.ttyname(self._slave)
        self.servo_port = None
        self._servo_master = self._servo_slave = None
        self.commands: list[int] = []
        if self.twin is not None:
            self._servo_master, self._servo_slave = os.openpty()
            tty.setraw(self._servo_slave)
            self.servo_port = os.ttyname(self._servo_slave)
            self._frames = FrameDecoder()
        self.lines_sent = 0
        self.overflows = 0
        self._halt = threading.Event()
        self._lock = threading.Lock()
        self._thread = threading.Thread(target=self._run, name="flexdigit stream emulator", daemon=True)
        self._t0 = time.monotonic()
        self._thread.start()

    def _resting(self, t_s: float):
        rest = np.array([0.1, 0.5, 0.2]) if self.gauges == 3 else 0.1 * np.arange(1, self.gauges + 1)
        return rest + 0.002 * self.rng.standard_normal(self.gauges), None

    def _twin_source(self, t_s: float):
        twin = self.twin
        ahead = t_s - twin.time_s
        if ahead > 0:
            twin.advance(ahead)
        gauges, pot = twin.read()
        return gauges, pot

    def tip_rotation_deg(self) -> float:
        """The twin's true tip rotation now (deg), for tests."""
        with self._lock:
            psi, _ = self.twin.state()
            return math.degrees(float(psi[-1]))

    def _serve_servo(self) -> None:
        while True:
            ready, _, _ = select.select([self._servo_master], [], [], 0)
            if not ready:
                return
            data = os.read(self._servo_master, 256)
            if not data:
                return
            for _, position in self._frames.feed(data):
                self.commands.append(position)
                self.twin.command(position)

    def _run(self) -> None:
        period = 1.0 / self.rate_hz
        seq = 0
        low, high = -(2 ** (self.bits - 1)), 2 ** (self.bits - 1) - 1
        try:
            if self.banner:
                text = (
                    f"# flexdigit-stream {self.version} adc=emulator v_per_count={self.scale:g} "
                    f"rate_hz={self.rate_hz:g} gauges={self.gauges}\r\n"
                )
                self._write(text.encode("ascii"))
            next_at = time.monotonic()
            while not self._halt.is_set():
                now = time.monotonic()
                if now < next_at:
                    time.sleep(min(next_at - now, 0.01))
                    continue
                next_at += period
                t = now - self._t0
                with self._lock:
                    if self.twin is not None:
                        self._serve_servo()
                        gauges, pot = self._twin_source(t)
                    else:
                        gauges, pot = self.source(t)
                f = self.faults
                if f.stop_after is not None and seq >= f.stop_after:
                    seq += 1
                    continue
                counts = np.clip(np.round(np.asarray(gauges, dtype=float) / self.scale), low, high).astype(int)
                pot_counts = None if pot is None or not math.isfinite(pot) else int(round(pot / self.scale))
                line = encode_line(seq, int(t * 1e6), counts, pot_counts, version=self.version)
                garble = (f.garble_after is not None and seq >= f.garble_after) or (
                    f.garble_every is not None and seq % f.garble_every == f.garble_every - 1
                )
                if garble:
                    line = self._corrupt(line)
                drop = f.drop_every is not None and seq % f.drop_every == f.drop_every - 1
                if not drop:
                    self._write(line)
                seq += 1
        except OSError:
            return  # the pty was closed under us

    def _corrupt(self, line: bytes) -> bytes:
        """Change one payload byte (between '$' and '*'), as line noise would: the checksum no longer matches."""
        star = line.index(b"*")
        i = int(self.rng.integers(1, star))
        buf = bytearray(line)
        buf[i] = b"0123456789,"[(b"0123456789,".find(bytes([buf[i]])) + 1 + int(self.rng.integers(0, 9))) % 11]
        return bytes(buf)

    def _write(self, data: bytes) -> None:
        try:
            os.write(self.master, data)
            self.lines_sent += 1
        except BlockingIOError:
            self.overflows += 1  # nobody reads the port: the line is lost, as on a USB CDC device

    def close(self) -> None:
        """Stop the firmware and close the ptys (a reader sees the port vanish)."""
        if self._halt.is_set():
            return
        self._halt.set()
        self._thread.join(2.0)
        for fd in (self.master, self._slave, self._servo_master, self._servo_slave):
            if fd is not None:
                try:
                    os.close(fd)
                except OSError:
                    pass

    def __enter__(self) -> StreamEmulator:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        state = "closed" if self._halt.is_set() else "running"
        return (
            f"StreamEmulator(port={self.port!r}, servo_port={self.servo_port!r}, rate_hz={self.rate_hz:g}, "
            f"scale={self.scale:g}, bits={self.bits}, faults={self.faults}, seed={self.seed}, {state})"
        )


def main(argv: list[str] | None = None) -> int:
    """``python -m flexdigit.rig.backends.stream_emulator [--twin] [--rate 100] [--seed 0] [--duration S]``."""
    import argparse

    parser = argparse.ArgumentParser(
        prog="python -m flexdigit.rig.backends.stream_emulator", description=__doc__.split("\n")[0]
    )
    parser.add_argument("--twin", action="store_true", help="stream a twin's gauges and serve a servo board too")
    parser.add_argument("--params", default=None, metavar="FILE", help="the digit's parameters TOML (thesis rig)")
    parser.add_argument("--rate", type=Flag(RATE_HZ), default=100.0, help="lines per second (100)")
    parser.add_argument("--seed", type=Flag(SEED), default=0)
    parser.add_argument(
        "--duration", type=Flag(DURATION_S), default=None, help="stop after this many seconds (default: Ctrl-C)"
    )
    args = parser.parse_args(argv)
    return run_emulator(args.twin, args.rate, args.seed, args.duration, print, params_path=args.params)


def run_emulator(
    twin: bool,
    rate_hz: float,
    seed: int,
    duration_s: float | None,
    say,
    *,
    params_path=None,
    calibration_path=None,
) -> int:
    """Run an emulator until ``duration_s`` (or Ctrl-C), telling ``say`` the ports and how to use them.

    ``params_path`` is a digit's parameters TOML (default the thesis rig): the stream carries its G gauges (protocol
    version 2) and, with ``twin``, the twin is that digit's, with the calibration of ``calibration_path`` (default
    the thesis's scaled to the digit, :func:`~flexdigit.twin.digit_calibration.twin_calibration`).
    """
    duration = None if duration_s is None else check_param(duration_s, DURATION_S, "--duration", "stream-emulator")
    if calibration_path is not None and not twin:
        raise ParameterError(
            f"--calibration {calibration_path} is the twin's calibration: it needs --twin (the resting digit has none)"
        )
    params = None if params_path is None else load_params(params_path)
    calibration = None if calibration_path is None else twin_calibration(params, calibration_path)
    with StreamEmulator(twin=twin, rate_hz=rate_hz, seed=seed, params=params, calibration=calibration) as emulator:
        try:  # serving from the first line said: a stop from then on ends it as its duration would
            say(f"gauge stream on {emulator.port}: stream://{emulator.port} ({emulator.gauges} gauges a line)")
            if emulator.servo_port:
                digit = "" if params_path is None else f" --params {params_path}"
                say(f"servo board on {emulator.servo_port}; the whole rig:")
                say(f"  flexdigit run{digit} --backend 'serial://{emulator.servo_port}?daq=stream://{emulator.port}'")
            if duration is None:
                while True:
                    time.sleep(1.0)
            else:
                time.sleep(duration)
        except KeyboardInterrupt as exc:  # Ctrl-C, SIGTERM or SIGHUP (flexdigit.interrupts): how it ends
            say(f"stopped by {getattr(exc, 'signal_name', 'SIGINT')}")
        say(f"sent {emulator.lines_sent} lines ({emulator.overflows} lost: nobody was reading)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
