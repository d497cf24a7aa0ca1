"""The fault-injection matrix (issue 16): every fault on every backend ends in the safe state with the log readable.

Backends: the twin in virtual time (``sim``) and paced to the wall clock (``sim+paced``); the servo board on a
serial port with its gauges from a Python source (``serial``) or from the DAQ card the URL names
(``serial+daq``: ``serial://PORT?daq=0``, the thesis rig, with a fake port and a fake uldaq) or from a
microcontroller's gauge stream (``serial+stream``: ``serial://PORT?daq=stream://PTY``, the stream emulator on a
pseudo-terminal, on the wall clock); and a recorded run played back (``replay``). A bare ``stream://`` rig reads
only: it refuses the loop's first command (tests/rig/backends/test_stream_backend.py). Faults are injected at the
6th sample of a 20 ms loop:

- port lost: the serial port's writes fail (USB unplugged); the safe command cannot go out, the port is closed;
- DAQ silent: the gauge source raises (a dead card) or blocks for a second (a stall); a recording that ends; a
  stream that stops sending;
- NaN gauge, clipped ADC (a gauge on the +5 V rail); on a stream, whose values are integer counts, the unreadable
  value is a garbled line (the stream turns to garbage) and the clipped one a count at the ADC's rail;
- Ctrl-C during the run;
- disk full: the log's writes fail with ENOSPC.

Each cell checks: the run stops with ``fault`` or ``interrupted`` and a message naming the fault, the equilibrium
command (8) was the last one the actuator got (where a port exists to take it), the rig is closed, and the log
reads back (``read_log``) with every sample the loop took before the fault (and, unless the disk was full, the
footer naming why it stopped). The fault table of docs/guide/rig.md is this matrix.
"""

from __future__ import annotations

import errno
import json
import math
import types

import numpy as np
import pytest

from flexdigit.rig.base import open_rig
from flexdigit.rig.loop import run_loop
from flexdigit.rig.sample_log import read_log_runs

from .helpers import PI, FakeClock

FAULT_AT = 6  # the 6th read
RAIL_V = 5.0

BACKENDS = ("sim", "sim+paced", "serial", "serial+daq", "serial+stream", "replay")
FAULTS = ("port lost", "DAQ silent", "DAQ stall", "NaN gauge", "clipped ADC", "Ctrl-C", "disk full")
#: What each cell must report (a fragment of the message), or None where the fault has no meaning there.
MESSAGES = {
    "port lost": "port lost",
    "DAQ silent": "",  # per backend, below
    "DAQ stall": "the loop stalled",
    "NaN gauge": "read nan",
    "clipped ADC": "clipped at +5.000 V",
    "Ctrl-C": "interrupted by Ctrl-C",
    "disk full": "No space left on device",
}
NOT_APPLICABLE = {
    ("sim", "port lost"): "the twin has no port",
    ("sim+paced", "port lost"): "the twin has no port",
    ("replay", "port lost"): "a replay sends its commands nowhere",
    ("replay", "DAQ stall"): "a replay's clock moves only when the loop waits",
    ("serial+stream", "DAQ stall"): "a stream's reads never block (its thread keeps the newest line): see silent",
}
#: The stream's own words for the faults whose message differs there.
STREAM_MESSAGES = {"DAQ silent": "stream silent", "NaN gauge": "stream garbled", "clipped ADC": "stream ADC's rail"}


class FakePort:
    """A pyserial-like port: keeps the frames written, and can vanish (writes then fail like an unplugged USB)."""

    def __init__(self) -> None:
        self.frames: list[bytes] = []
        self.lost = False
        self.closed = False

    def write(self, data: bytes) -> int:
        if self.lost:
            raise OSError(errno.EIO, "Input/output error")
        self.frames.append(bytes(data))
        return len(data)

    def flush(self) -> None:
        if self.lost:
            raise OSError(errno.EIO, "Input/output error")

    def close(self) -> None:
        self.closed = True

    @property
    def last_command(self) -> int:
        return self.frames[-1][2]


class Source:
    """Gauge volts that follow the command (a first-order-free toy: 10 mV per command above 8) with faults."""

    def __init__(self, rig_command, fault: str | None, clock_jump=None) -> None:
        self.rig_command, self.fault, self.clock_jump = rig_command, fault, clock_jump
        self.reads = 0

    def __call__(self):
        self.reads += 1
        gauges = np.full(3, 0.01 * (self.rig_command() - 8))
        if self.reads >= FAULT_AT:
            if self.fault == "NaN gauge":
                gauges[1] = math.nan
            elif self.fault == "clipped ADC":
                gauges[0] = RAIL_V
            elif self.fault == "DAQ silent":
                raise TimeoutError(errno.ETIMEDOUT, "the gauge source did not answer")
            elif self.fault == "DAQ stall" and self.reads == FAULT_AT:
                self.clock_jump(1.0)
        return gauges, 1.0


def fake_uldaq(source: Source):
    """Enough of uldaq (names as in uldaq 1.2.3) for DaqRig: a_in returns the source's volts, channel by channel."""

    class ULException(Exception):
        pass

    state = {"values": None}

    class Ai:
        def a_in(self, channel, mode, rng, flags):
            if channel == 0:
                try:
                    state["values"] = source()[0]
                except TimeoutError as exc:
                    raise ULException(f"Device is not responding ({exc.strerror})") from None
            return float(state["values"][channel])

    class Device:
        def __init__(self, descriptor):
            pass

        def connect(self):
            pass

        def get_ai_device(self):
            return Ai()

        def disconnect(self):
            pass

        def release(self):
            pass

    return types.SimpleNamespace(
        Range=types.SimpleNamespace(BIP5VOLTS=6),
        AiInputMode=types.SimpleNamespace(SINGLE_ENDED=2, DIFFERENTIAL=1),
        AInFlag=types.SimpleNamespace(DEFAULT=0),
        InterfaceType=types.SimpleNamespace(ANY=7),
        get_daq_device_inventory=lambda interface: ["fake card"],
        DaqDevice=Device,
    )


def _recording(path, fault):
    """A loop log to replay: 40 samples, the fault baked in from the 6th (a null gauge is a NaN reading)."""
    lines = [{"format": "flexdigit-loop-log/1", "controller": "recorded", "period_s": 0.02}]
    n = FAULT_AT + 1 if fault == "DAQ silent" else 40  # silent: the recording ends just after the fault point
    for k in range(n):
        gauges = [0.05, 0.05, 0.05]
        if k + 1 >= FAULT_AT and fault == "NaN gauge":
            gauges[1] = None
        if k + 1 >= FAULT_AT and fault == "clipped ADC":
            gauges[0] = RAIL_V
        lines.append({"k": k, "t": 0.02 * k, "gauges_v": gauges, "pot_v": None, "command": 13})
    path.write_text("\n".join(json.dumps(line) for line in lines) + "\n")


def _stream(fault, port, request):
    """``serial://fake?daq=stream://PTY``: the emulator streams volts that follow the servo's last command; at the
    6th read of the loop the fault is switched on in the emulator (it then stops, garbles or sends the rail)."""
    from flexdigit.rig.backends.stream_emulator import Faults, StreamEmulator

    state = {"rail": False}

    def source(t_s):
        command = port.last_command if port.frames else 8
        gauges = np.full(3, 0.01 * (command - 8))
        if state["rail"]:
            gauges[0] = RAIL_V  # beyond the ADS1115's +4.096 V: the count is clipped at the rail
        return gauges, None

    emulator = StreamEmulator(source)
    request.addfinalizer(emulator.close)
    # the stream's silence (0.25 s by default) is the silent cell's fault; in the others a pause of the emulator's
    # thread on a loaded machine is not, so they give the stream 5 s before it counts as silent
    timeout = "" if fault == "DAQ silent" else "&daq.timeout=5"
    rig = open_rig(f"serial://fake?daq=stream://{emulator.port}{timeout}", serial=port)
    read, reads = rig.sensor, [0]

    def sensor():
        reads[0] += 1
        if reads[0] == FAULT_AT:
            if fault == "DAQ silent":
                emulator.faults = Faults(stop_after=0)
            elif fault == "NaN gauge":
                emulator.faults = Faults(garble_after=0)
            elif fault == "clipped ADC":
                state["rail"] = True
        return read()

    rig.sensor = sensor
    return rig


def _open(backend, fault, tmp_path, request=None):
    """(rig, port or None)."""
    port = FakePort() if backend.startswith("serial") else None
    clock = FakeClock()
    if backend in ("sim", "sim+paced"):
        rig = open_rig(backend, seed=0)
        source = Source(lambda: rig.command, fault, rig.twin.advance if backend == "sim" else None)
        read = rig._read

        def faulty():
            gauges, pot = read()
            injected, _ = source()
            return np.where(np.isfinite(injected) & (np.abs(injected) < RAIL_V), gauges, injected), pot

        rig._read = faulty
        if backend == "sim+paced" and fault == "DAQ stall":
            import time

            source.clock_jump = time.sleep
        return rig, None
    if backend == "serial":
        rig = open_rig("serial://fake", serial=port, clock=clock, sleep=clock.sleep)
        rig.sensor = Source(lambda: rig.command, fault, clock.sleep)
        return rig, port
    if backend == "serial+stream":
        return _stream(fault, port, request), port
    if backend == "serial+daq":
        holder = {}
        source = Source(lambda: holder["rig"].command, fault, clock.sleep)
        rig = open_rig("serial://fake?daq=0", serial=port, uldaq=fake_uldaq(source), clock=clock, sleep=clock.sleep)
        holder["rig"] = rig
        return rig, port
    recording = tmp_path / "recorded.jsonl"
    _recording(recording, fault)
    return open_rig(f"replay://{recording}"), None


def _full_disk(monkeypatch, after_lines=FAULT_AT + 1):
    """The log's file refuses writes (ENOSPC) after the header and the first samples."""
    from flexdigit.rig.sample_log import SampleLog

    original = SampleLog.write

    def write(self, record):
        if self.lines >= after_lines:
            raise OSError(errno.ENOSPC, "No space left on device")
        original(self, record)

    monkeypatch.setattr(SampleLog, "write", write)


#: the cells that apply (docs/guide/rig.md's table shows the others as "n/a" with NOT_APPLICABLE's reason)
CELLS = [(b, f) for f in FAULTS for b in BACKENDS if (b, f) not in NOT_APPLICABLE]


@pytest.mark.parametrize("backend, fault", CELLS, ids=[f"{b}-{f}" for b, f in CELLS])
def test_fault_ends_safe_with_the_log_readable(backend, fault, tmp_path, monkeypatch, request):
    rig, port = _open(backend, fault, tmp_path, request)
    # the stream's faults show a few of its lines after they start (0.25 s silent, 20 % of 50 lines garbled); on the
    # wall clock (the stream, the paced twin) a loaded machine may take longer to get there, so those runs may last
    # seconds: each stops at its fault, the check is that it stopped before the end
    duration, samples_max = {"serial+stream": (10.0, 500), "sim+paced": (4.0, 200)}.get(backend, (0.4, 20))
    # a paced twin on a loaded machine may start a sample late: only the stall cell's 1 s stall is the fault
    stall = {"stall_s": 5.0} if backend == "sim+paced" and fault != "DAQ stall" else {}
    log = tmp_path / "run.jsonl"
    on_sample = None
    if fault == "Ctrl-C":

        def on_sample(k, t, y, command):
            if k + 1 >= FAULT_AT:
                raise KeyboardInterrupt

    if fault == "port lost":

        def on_sample(k, t, y, command):
            if k + 1 >= FAULT_AT - 1:
                port.lost = True

    if fault == "disk full":
        _full_disk(monkeypatch)
    result = run_loop(rig, PI(), 0.3, duration, 0.02, log_path=log, on_sample=on_sample, check_sensors=True, **stall)

    # -- the run stopped, saying why ------------------------------------------------------------------------------
    assert result.status == ("interrupted" if fault == "Ctrl-C" else "fault"), result.message
    expected = MESSAGES[fault] or {"replay": "recording ends", "serial+daq": "analog read failed"}.get(
        backend, "did not answer"
    )
    if backend == "serial+stream":
        expected = STREAM_MESSAGES.get(fault, expected)
    assert expected in result.message, result.message
    assert result.timing.samples < samples_max  # it did not run on to the end
    # -- the safe state: relaxed where a port can take it, the port closed either way ------------------------------
    assert rig.closed
    if fault == "port lost":
        assert not result.safe_command_sent
        assert "could NOT send the safe command" in result.message
        assert port.closed
        assert port.last_command != 8  # the safe frame could not go out: the port was gone
    else:
        assert result.safe_command_sent
        assert "relaxed to command 8" in result.message
        if port is not None:
            assert port.last_command == 8
            assert port.closed
        if backend == "replay":
            assert rig.commands_sent[-1][1] == 8
        if backend.startswith("sim"):
            assert rig.command == 8  # the last command sent to the twin (latched on its next frame)
    # -- the log reads back with every sample taken -----------------------------------------------------------------
    ((_, header, samples, footer),) = read_log_runs(log)
    if fault == "disk full":
        assert footer is None
        assert len(samples) == FAULT_AT
        assert "its last lines are lost" in result.message
    else:
        assert footer["stop"] == result.status
        assert len(samples) == result.timing.samples
        assert footer["safe_command_sent"] == result.safe_command_sent
