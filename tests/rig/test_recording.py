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
from flexdigit.rig.loop import read_log, run_loop
from flexdigit.rig.recording import SAMPLE_TOPIC, Recording, read_recording, rig_metadata
from flexdigit.rig.rotation import calibrate_rotation


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
        assert summary is not None and summary.statistics.message_count == result.timing.samples == 50
        count = 0
        for schema, channel, message in reader.iter_messages():
            assert channel.topic == SAMPLE_TOPIC and channel.message_encoding == "json"
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
    assert header["backend"] == "sim" and header["seed"] == 0


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
    assert footer is None and header["backend"] == "sim"
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
    assert replayed["status"] == "completed" and replayed["samples"] == 45
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
    assert [e["event"] for e in events] == ["load", "clear"] and events[0]["mass_kg"] == 0.025
    _, samples, footer = read_recording(path)
    assert [s["gauges_v"] for s in samples] == [list(r.gauges_v) for r in readings]
    assert footer["stop"] == "closed"
