"""SIGTERM, SIGHUP and SIGINT stop ``flexdigit run`` as Ctrl-C does (issue 22): the digit relaxed to the safe
command, the log and the MCAP recording closed with a footer naming the signal (the recording read by the mcap
library's own reader), the JSON result naming it, exit code 128 + the signal, nothing else left behind.

Before, SIGTERM ended the run with exit 143, no JSON, a log without footer, an MCAP file mcap refused ("record has
length 4209084189351346176"), and on a serial rig the servo at its last command."""

from __future__ import annotations

import json
import signal
import sys

import pytest

from children import STOPS, lines, start, stop, wait_until
from flexdigit.rig.sample_log import read_log
from oracles import eventually

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="POSIX signals and ptys")

#: Samples logged before the signal: the run is under way (the step has started), not starting up.
SAMPLES_BEFORE_STOP = 15


def _check_footer(footer: dict, name: str) -> None:
    assert footer["stop"] == "interrupted"
    assert footer["signal"] == name
    assert f"interrupted by {name}" in footer["message"]
    assert footer["safe_command_sent"] is True
    assert "digit relaxed to command 8" in footer["message"]


def _read_with_mcap(path):
    """The recording through the mcap library's reader (its summary and footer, not flexdigit's record-by-record
    reader): the messages' data and the ``flexdigit.stop`` metadata."""
    from mcap.reader import make_reader

    with open(path, "rb") as fh:
        reader = make_reader(fh)
        samples = [json.loads(message.data) for _, _, message in reader.iter_messages()]
        stops = [m.metadata for m in reader.iter_metadata() if m.name == "flexdigit.stop"]
        statistics = reader.get_summary().statistics
    return samples, stops, statistics


@pytest.mark.slow
@pytest.mark.parametrize("signum, code", STOPS, ids=[s.name for s, _ in STOPS])
def test_run_with_log_and_record_stops_cleanly(tmp_path, rotation_map_file, signum, code):
    name = signal.Signals(signum).name
    log, record = tmp_path / "run.jsonl", tmp_path / "run.mcap"
    # (--rotation-map: the twin's map made once, not calibrated again in each child; the stop is the claim)
    proc = start("run", "--backend", "sim+paced", "--rotation-map", rotation_map_file, "--duration", "120",
                 "--log", log, "--record", record, "--json")  # fmt: skip
    wait_until(lambda: lines(log) > SAMPLES_BEFORE_STOP, proc)
    exit_code, result, err = stop(proc, signum)
    assert exit_code == code, err
    assert result["status"] == "interrupted"
    assert result["signal"] == name
    assert f"interrupted by {name}" in result["message"]
    assert "Traceback" not in err
    _, samples, footer = read_log(log)
    _check_footer(footer, name)
    assert len(samples) == result["samples"] >= SAMPLES_BEFORE_STOP  # lines: the header and the samples
    recorded, stops, statistics = _read_with_mcap(record)
    assert [s["k"] for s in recorded] == [s["k"] for s in samples]  # every logged sample, in order
    assert statistics.message_count == len(samples)
    (stopped,) = stops
    assert stopped["stop"] == "interrupted"
    assert stopped["signal"] == name
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.jsonl", "run.mcap"]  # no temporary file left


# -- a serial rig: a servo board and a gauge stream on pseudo-terminals ------------------------------------------
@pytest.fixture(scope="module")
def rotation_map_file(tmp_path_factory):
    from flexdigit.rig.base import open_rig
    from flexdigit.rig.rotation import calibrate_rotation, save_rotation_map

    # the emulator's twin is the default twin: its map, calibrated on another twin in virtual time
    path = tmp_path_factory.mktemp("map") / "map.json"
    save_rotation_map(calibrate_rotation(open_rig("sim", seed=1)), path)
    return path


@pytest.mark.slow
@pytest.mark.parametrize("signum, code", STOPS, ids=[s.name for s, _ in STOPS])
def test_a_serial_rig_is_left_at_the_safe_command(tmp_path, rotation_map_file, signum, code):
    from flexdigit.rig.backends.stream_emulator import StreamEmulator

    name = signal.Signals(signum).name
    log = tmp_path / "run.jsonl"
    with StreamEmulator(twin=True, seed=0) as emulator:
        # (daq.timeout: the stop is the signal; a pause of the emulator on a loaded machine is no silent stream here)
        url = f"serial://{emulator.servo_port}?daq=stream://{emulator.port}&daq.timeout=5"
        proc = start("run", "--backend", url, "--rotation-map", rotation_map_file, "--setpoint-deg", "20",
                     "--duration", "120", "--log", log, "--json")  # fmt: skip
        # the loop has stepped: the board's last frame is the controller's, not the resting command 8
        wait_until(lambda: lines(log) > SAMPLES_BEFORE_STOP and emulator.commands[-1] != 8, proc)
        exit_code, result, err = stop(proc, signum)
        # the last frame the board got is the safe one (before: the servo stayed at its last command, e.g. 32)
        assert eventually(lambda: emulator.commands[-1] == 8, timeout_s=30.0), emulator.commands[-5:]
    assert exit_code == code, err
    assert result["status"] == "interrupted"
    assert result["signal"] == name
    _, _, footer = read_log(log)
    _check_footer(footer, name)


def _pressing_sweep(tmp_path):
    """The default sweep's staircase from command 12 (pressing into soft-block, as in the issue) with 0.9 s plateaus:
    the default's first two plateaus (the tare and command 8, 2.9 s each) kept the board at 8 for ~6 s before the
    stop could test anything; 17 plateaus (~15 s) still leave the signal far from the closing tare."""
    path = tmp_path / "pressing.toml"
    path.write_text("[sweep]\ncommands = { from = 12, to = 26, step = 1 }\nsettle_s = 0.5\nreadings = 20\n")
    return path


@pytest.mark.slow
@pytest.mark.parametrize("signum, code", STOPS, ids=[s.name for s, _ in STOPS])
def test_a_palpation_sweep_on_a_serial_rig_stops_at_the_safe_command(tmp_path, signum, code):
    """The issue's palpation case: stopped mid-sweep, the servo was left pressing into the tissue (command 12)."""
    from flexdigit.rig.backends.stream_emulator import StreamEmulator

    name = signal.Signals(signum).name
    log = tmp_path / "sweep.jsonl"
    with StreamEmulator(twin=True, seed=0) as emulator:
        # (daq.timeout: the stop is the signal; a pause of the emulator on a loaded machine is no silent stream here)
        url = f"serial://{emulator.servo_port}?daq=stream://{emulator.port}&daq.timeout=5"
        argv = ["palpate", "--tissue", "soft-block", "--protocol", _pressing_sweep(tmp_path), "--backend", url,
                "--log", log, "--json"]  # fmt: skip
        proc = start(*argv, operator="\n")  # Enter: the tissue is placed
        # the sweep is pressing: the board's last frame is a step of the staircase, not the resting command 8
        wait_until(lambda: lines(log) > SAMPLES_BEFORE_STOP and emulator.commands[-1] != 8, proc)
        exit_code, result, err = stop(proc, signum)
        assert eventually(lambda: emulator.commands[-1] == 8, timeout_s=30.0), emulator.commands[-5:]
    assert exit_code == code, err
    assert result["signal"] == name
    assert result["error"] == f"interrupted by {name}"
    _, _, footer = read_log(log)
    _check_footer(footer, name)


@pytest.mark.slow
@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGHUP], ids=["SIGTERM", "SIGHUP"])
def test_the_stream_emulator_stops_as_with_ctrl_c(signum):
    """``stream-emulator`` runs until stopped: SIGTERM and SIGHUP end it as Ctrl-C does, ptys closed, its count
    of lines said, exit 0 (stopping is how it ends); before, they killed it mid-line."""
    proc = start("stream-emulator")
    assert proc.stdout.readline().startswith("gauge stream on /dev/")  # serving
    proc.send_signal(signum)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, err
    assert f"stopped by {signal.Signals(signum).name}" in out
    assert "lines (" in out
