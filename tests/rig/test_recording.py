"""MCAP recordings: read by the mcap library's own reader and checked against their JSON schemas (code that is not
flexdigit's), replayed as the JSON-lines logs are, and never lost or clobbered."""

import json
import shutil

import jsonschema
import numpy as np
import pytest
from mcap.reader import make_reader

from flexdigit.errors import DataFileError, OutputExistsError
from flexdigit.rig.base import open_rig
from flexdigit.rig.controllers import make_controller
from flexdigit.rig.loop import run_loop
from flexdigit.rig.recording import SAMPLE_TOPIC, Recording, read_recording, rig_metadata
from flexdigit.rig.rotation import calibrate_rotation
from flexdigit.rig.sample_log import read_log


def _run(tmp_path, seed=0, duration=1.0):
    rig = open_rig("sim", seed=seed)
    est = calibrate_rotation(open_rig("sim", seed=seed + 1))
    controller = make_controller("digital20", rig, period_s=0.02, estimator=est)
    rec = Recording(tmp_path / "run.mcap", header={"backend": "sim", "seed": seed}, metadata=rig_metadata(rig))
    result = run_loop(rig, controller, 20.0, duration, 0.02, log_path=tmp_path / "run.jsonl", recording=rec)
    return result, tmp_path / "run.mcap", tmp_path / "run.jsonl"


def test_recording_opens_in_the_mcap_reader_and_every_message_meets_its_schema(tmp_path):
    result, path, _ = _run(tmp_path)
    with open(path, "rb") as fh:
        reader = make_reader(fh)  # the mcap library's seeking reader: it needs the summary a clean close writes
        summary = reader.get_summary()
        assert summary is not None
        assert summary.statistics.message_count == result.timing.samples == 50
        count = 0
        for schema, channel, message in reader.iter_messages():
            assert channel.topic == SAMPLE_TOPIC
            assert channel.message_encoding == "json"
            assert schema.encoding == "jsonschema"
            jsonschema.validate(json.loads(message.data), json.loads(schema.data))
            count += 1
        metadata = {m.name: m.metadata for m in reader.iter_metadata()}
    assert count == 50
    assert json.loads(metadata["flexdigit.rig"]["params"])["geometry"]["digit_length_m"] == 0.27
    assert "twin_calibration" in metadata["flexdigit.rig"]
    assert metadata["flexdigit.stop"]["stop"] == "completed"


def test_recording_holds_the_same_samples_as_the_json_lines_log(tmp_path):
    _, mcap_path, log_path = _run(tmp_path)
    header, samples, footer = read_recording(mcap_path)
    log_header, log_samples, log_footer = read_log(log_path)
    assert samples == log_samples
    assert footer["stop"] == log_footer["stop"] == "completed"
    assert header["backend"] == "sim"
    assert header["seed"] == 0


def test_replay_reads_a_recording_as_it_reads_a_log(tmp_path):
    _, mcap_path, log_path = _run(tmp_path)
    readings = {}
    for name, path in (("mcap", mcap_path), ("log", log_path)):
        with open_rig(f"replay://{path}") as rig:
            values = []
            for _ in range(40):
                values.append(rig.read().gauges_v)
                rig.wait(0.02)
            readings[name] = np.array(values)
    assert readings["mcap"] == pytest.approx(readings["log"], abs=0)
    assert np.ptp(readings["mcap"][:, 2]) > 0.05  # the digit moved: a real run, not a constant


def test_a_killed_run_keeps_every_flushed_sample(tmp_path):
    path = tmp_path / "killed.mcap"
    rec = Recording(path, header={"backend": "sim"}, chunk_size=512)
    for k in range(200):
        rec.write_sample({"k": k, "t": 0.02 * k, "gauges_v": [0.1, 0.2, 0.3], "pot_v": None, "command": 8})
    rec.flush()
    # the process dies here: no summary, no footer; copy the file as it is on disk
    copy = tmp_path / "copy.mcap"
    shutil.copyfile(path, copy)
    with open(copy, "ab") as fh:
        fh.write(b"\x06\x40\x00\x00")  # and a record torn mid-write
    header, samples, footer = read_recording(copy)
    assert footer is None
    assert header["backend"] == "sim"
    assert [s["k"] for s in samples] == list(range(200))
    rec.close()


def test_an_existing_recording_is_never_overwritten_without_force(tmp_path):
    path = tmp_path / "run.mcap"
    Recording(path).close()
    before = path.read_bytes()
    with pytest.raises(OutputExistsError, match="--force"):
        Recording(path)
    assert path.read_bytes() == before
    Recording(path, force=True).close()


@pytest.mark.parametrize(
    ("content", "match"),
    [(b"not an mcap file", "not an MCAP file"), (None, "not a flexdigit recording")],
)
def test_bad_recordings_are_named(tmp_path, content, match):
    path = tmp_path / "bad.mcap"
    if content is None:  # a valid MCAP file that flexdigit did not write
        from mcap.writer import Writer

        with open(path, "wb") as fh:
            writer = Writer(fh)
            writer.start()
            writer.finish()
    else:
        path.write_bytes(content)
    with pytest.raises(DataFileError, match=match):
        read_recording(path)
    with pytest.raises(DataFileError):
        open_rig(f"replay://{path}")


def test_run_records_and_replays_from_the_command_line(tmp_path, capsys):
    from flexdigit.cli import main

    path = tmp_path / "cli.mcap"
    assert main(["run", "--backend", "sim", "--duration", "1", "--record", str(path), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["record"] == str(path)
    # the replay finds the rotation map the recording kept, so it needs no --calibration
    assert main(["run", "--backend", f"replay://{path}", "--duration", "0.9", "--json"]) == 0
    replayed = json.loads(capsys.readouterr().out)
    assert replayed["status"] == "completed"
    assert replayed["samples"] == 45
    assert main(["run", "--backend", "sim", "--duration", "1", "--record", str(path)]) == 2
    assert "exists" in capsys.readouterr().err


def test_a_recorded_rig_keeps_every_reading_and_load(tmp_path):
    from flexdigit.rig.recording import EVENT_TOPIC, iter_messages, recording_rig

    path = tmp_path / "collect.mcap"
    inner = open_rig("sim?orientation=horizontal", seed=2)
    rig = recording_rig(inner, Recording(path, header={"source": "collect"}))
    readings = []
    rig.place_load(0.025, 0.2)
    rig.wait(0.5)
    readings.append(rig.read())
    rig.clear_loads()
    rig.wait(0.5)
    readings.append(rig.read())
    assert rig.twin is inner.twin  # the inner rig's extras stay reachable
    rig.close()
    assert inner.closed
    messages = list(iter_messages(path))
    events = [m for topic, _, m in messages if topic == EVENT_TOPIC]
    assert [e["event"] for e in events] == ["load", "clear"]
    assert events[0]["mass_kg"] == 0.025
    _, samples, footer = read_recording(path)
    assert [s["gauges_v"] for s in samples] == [list(r.gauges_v) for r in readings]
    assert footer["stop"] == "closed"


_WRITER = """
import sys, time
from flexdigit.rig.recording import Recording
rec = Recording(sys.argv[1], header={"backend": "test writer"})
start = time.monotonic()
print("started", flush=True)
k = 0
while True:  # a 50 Hz run until killed
    t = time.monotonic() - start
    rec.write_sample({"k": k, "t": t, "gauges_v": [0.1, 0.2, 0.3], "pot_v": None, "command": 8 + k % 40})
    k += 1
    time.sleep(max(0.0, 0.02 * k - (time.monotonic() - start)))
"""


@pytest.mark.slow
def test_a_run_killed_with_sigkill_keeps_all_but_its_last_second(tmp_path):
    import signal
    import subprocess
    import sys
    import time

    from mcap.records import Message
    from mcap.stream_reader import StreamReader

    path = tmp_path / "killed.mcap"
    child = subprocess.Popen([sys.executable, "-c", _WRITER, str(path)], stdout=subprocess.PIPE, text=True)
    assert child.stdout.readline().strip() == "started"
    started = time.monotonic()
    time.sleep(2.0)  # 100 samples, 11 kB: less than one chunk's 16 kB, so only the time-based close saves them
    child.send_signal(signal.SIGKILL)
    killed_after = time.monotonic() - started
    child.wait(timeout=10)
    # the mcap library's own streaming reader (not flexdigit's code) reads every closed chunk, then meets the cut
    times = []
    with open(path, "rb") as fh:
        try:
            for record in StreamReader(fh).records:
                if isinstance(record, Message):
                    times.append(json.loads(record.data)["t"])
        except Exception:  # noqa: BLE001 - the torn end of a killed file: what came before it is the point
            pass
    _, samples, footer = read_recording(path)
    assert footer is None  # never closed
    assert [s["k"] for s in samples] == list(range(len(samples)))  # nothing missing or mixed
    assert [s["t"] for s in samples] == times
    # the chunk is closed at least once a second: all but the last second (and the scheduler's slack) survive
    assert times[-1] >= killed_after - 1.0 - 0.5, (times[-1], killed_after)


def _foreign(path, samples, *, topic=SAMPLE_TOPIC, encoding="json", raw=None):
    """An MCAP written by the mcap library directly, as another program would from the recordings guide: the documented
    topic and fields, no flexdigit metadata."""
    from mcap.writer import Writer

    schema = {"type": "object", "required": ["t", "gauges_v", "command"]}
    with open(path, "wb") as fh:
        writer = Writer(fh)
        writer.start(profile="", library="another writer")
        schema_id = writer.register_schema("Sample", "jsonschema", json.dumps(schema).encode())
        channel = writer.register_channel(topic, encoding, schema_id)
        for i, sample in enumerate(samples):
            data = raw if raw is not None else json.dumps(sample).encode()
            writer.add_message(channel, log_time=10**9 * 100 + i, publish_time=0, data=data, sequence=i)
        writer.finish()
    return path


def _gauges(t):  # known readings: a function of the recorded time
    return [0.01 * t, -0.02 * t, 0.5]


def test_a_recording_by_another_writer_replays(tmp_path):
    # 100 Hz, starting at t = 100 s of the other program's clock, no pot channel, no flexdigit metadata
    samples = [{"t": 100 + 0.01 * k, "gauges_v": _gauges(100 + 0.01 * k), "command": 8 + k % 30} for k in range(300)]
    path = _foreign(tmp_path / "other.mcap", samples)
    header, read, footer = read_recording(path)
    assert header == {"format": None}
    assert footer is None
    assert read == samples
    with open_rig(f"replay://{path}") as rig:
        for tau in (0.0, 0.505, 1.234, 2.99):
            rig.wait(tau - rig.clock())
            reading = rig.read()
            held = 100 + 0.01 * int(tau / 0.01 + 1e-6)  # sample and hold: the last sample at or before tau
            assert reading.gauges_v == pytest.approx(_gauges(held), abs=1e-12)
            assert np.isnan(reading.pot_v)


@pytest.mark.parametrize(
    ("samples", "options", "says"),
    [
        ([{"t": 0.0, "gauges_v": [], "command": 8}], {}, "'gauges_v' must be a list of 1 to 8 voltages"),
        (
            [{"t": 0.0, "gauges_v": [0.1, 0.2], "command": 8}, {"t": 0.1, "gauges_v": [0.1, 0.2, 0.3], "command": 8}],
            {},
            "'gauges_v' has 3 voltages but the run's first sample has 2",
        ),
        ([{"t": 0.0, "gauges_v": ["a", 0.2, 0.3], "command": 8}], {}, "'gauges_v' must be a list of numbers"),
        ([{"t": 0.0, "gauges_v": [0.1, 0.2, 0.3], "command": 8.5}], {}, "'command' must be an integer 0..254"),
        ([{"t": 0.0, "gauges_v": [0.1, 0.2, 0.3], "command": 999}], {}, "'command' must be an integer 0..254"),
        ([{"t": None, "gauges_v": [0.1, 0.2, 0.3], "command": 8}], {}, "'t' must be a number"),
        ([{"t": 0.0, "gauges_v": [0.1, 0.2, 0.3], "command": 8, "pot_v": "x"}], {}, "'pot_v' must be a number or null"),
        # another writer's JSON may carry NaN / Infinity (flexdigit writes null for them)
        ([{"t": float("nan"), "gauges_v": [0.1, 0.2, 0.3], "command": 8}], {}, "'t' must be a finite number"),
        ([{"t": 0.0, "gauges_v": [0.1, float("inf"), 0.3], "command": 8}], {}, "'gauges_v' must be a list of finite"),
        ([{"t": 0.0, "gauges_v": [0.1, 0.2, 0.3], "command": 8, "pot_v": 10**400}], {}, "'pot_v' must be a finite"),
        ([[1, 2, 3]], {}, "lacks t, gauges_v or command"),
        ([{"t": 0.0}] * 3, {"raw": b"\x00\x01"}, "not JSON"),
        ([{"t": 0.0}], {"encoding": "cdr"}, "encoded as 'cdr'"),
        ([{"t": 0.0, "gauges_v": [0.1, 0.2, 0.3], "command": 8}], {"topic": "/imu"}, "no /flexdigit/sample"),
    ],
)
def test_a_malformed_foreign_recording_is_named_in_one_line(tmp_path, samples, options, says, capsys):
    from flexdigit.cli import main

    path = _foreign(tmp_path / "foreign.mcap", samples, **options)
    with pytest.raises(DataFileError, match=says) as err:
        open_rig(f"replay://{path}")
    assert str(path) in str(err.value)
    assert "\n" not in str(err.value)
    assert main(["live", "--backend", f"replay://{path}"]) == 2
    message = capsys.readouterr().err
    assert says in message
    assert str(path) in message
    assert message.count("\n") == 1


def test_a_damaged_recording_says_so(tmp_path):
    whole = _foreign(tmp_path / "whole.mcap", [{"t": 0.01 * k, "gauges_v": [0, 0, 0], "command": 8} for k in range(9)])
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(whole.read_bytes()[:60])  # cut inside its first records
    with pytest.raises(DataFileError, match="damaged or cut short"):
        read_recording(cut)
    empty = tmp_path / "empty.mcap"
    empty.write_bytes(b"")
    with pytest.raises(DataFileError, match="not an MCAP file"):
        open_rig(f"replay://{empty}")


@pytest.mark.parametrize(("stop", "replaced"), [("completed", True), ("interrupted", False), ("fault", False)])
def test_a_forced_recording_replaces_the_old_one_only_when_its_run_completes(tmp_path, stop, replaced):
    """Written beside the old file; a stopped run leaves it intact and its own, readable, in rec.partial.mcap."""
    path = tmp_path / "rec.mcap"
    path.write_bytes(b"old recording")
    rec = Recording(path, header={"backend": "sim"}, force=True)
    rec.write_sample({"k": 0, "t": 0.0, "gauges_v": [0.1, 0.2, 0.3], "command": 8})
    assert path.read_bytes() == b"old recording"  # while the run goes on
    rec.close({"stop": stop})
    written = path if replaced else tmp_path / "rec.partial.mcap"
    assert rec.path == written
    assert (path.read_bytes() == b"old recording") != replaced
    with written.open("rb") as fh:
        assert sum(1 for _ in make_reader(fh).iter_messages()) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted({"rec.mcap", written.name})
