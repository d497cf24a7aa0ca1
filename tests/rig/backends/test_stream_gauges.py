"""Version 2 of the gauge stream on the wire (issue 24): a board streaming any digit's 1 to 8 gauges, read through
``stream://`` as that digit's rig; a board of another gauge count refused in one line; version 1's three-gauge
lines still read. The emulator stands in for the reference firmware (examples/flexdigit_stream)."""

from __future__ import annotations

import numpy as np
import pytest

from digits import write_digit
from flexdigit.errors import ParameterError, RigError
from flexdigit.params import RigParams, load_params
from flexdigit.rig.backends.stream_emulator import StreamEmulator
from flexdigit.rig.base import open_rig

#: The emulator's resting digit: 0.1 V per gauge number with 2 mV of noise, quantised to 125 uV; a mean of ten
#: readings is within 5 mV (2.5 sigma of one reading).
REST_ATOL_V = 0.005

pytestmark = pytest.mark.skipif(not hasattr(__import__("os"), "openpty"), reason="POSIX pty")


@pytest.mark.parametrize("name", ["one-section", "five-sections-eight-gauges", "six-gauges-geared"])
def test_a_version_2_board_streams_the_digits_gauges(name, tmp_path):
    params = load_params(write_digit(name, tmp_path))
    count = len(params.geometry.gauge_positions_m)
    with StreamEmulator(seed=4, params=params) as emulator, open_rig(f"stream://{emulator.port}", params) as rig:
        readings = []
        for _ in range(10):
            rig.wait(0.03)  # 100 lines/s: a fresh line between reads
            readings.append(rig.read().gauges_v)
        assert rig.source.stats()["garbled"] == 0
    np.testing.assert_allclose(np.mean(readings, axis=0), 0.1 * np.arange(1, count + 1), atol=REST_ATOL_V)


def test_a_version_1_board_still_reads_on_the_thesis_rig():
    with StreamEmulator(seed=5, version=1) as emulator, open_rig(f"stream://{emulator.port}") as rig:
        rig.wait(0.03)
        np.testing.assert_allclose(rig.read().gauges_v, [0.1, 0.5, 0.2], atol=REST_ATOL_V * 3)
        assert rig.source.stats()["garbled"] == 0


def test_a_board_with_another_gauge_count_is_refused_in_one_line(tmp_path):
    five = load_params(write_digit("five-sections-eight-gauges", tmp_path))
    with StreamEmulator(seed=6) as emulator, open_rig(f"stream://{emulator.port}", five) as rig:
        rig.wait(0.03)
        with pytest.raises(RigError, match=r"sends 3 gauge\(s\) a line but the digit has 8") as err:
            rig.read()
        assert "\n" not in str(err.value)


def test_a_version_1_emulator_of_another_digit_is_refused(tmp_path):
    with pytest.raises(ParameterError, match="version 2"):
        StreamEmulator(params=load_params(write_digit("short", tmp_path)), version=1)
    assert RigParams().geometry.gauge_positions_m == (0.045, 0.135, 0.225)


def test_the_emulator_command_streams_a_digits_gauges(tmp_path, capsys):
    # `flexdigit stream-emulator --params FILE`: the stream carries that digit's G gauges (run_emulator is the
    # command's one library call; its first line names the port while it runs)
    import json
    import queue
    import threading

    from flexdigit.cli import main
    from flexdigit.rig.backends.stream_emulator import run_emulator

    path = write_digit("five-sections-eight-gauges", tmp_path)
    said: queue.Queue = queue.Queue()
    thread = threading.Thread(target=run_emulator, args=(False, 100.0, 4, 1.0, said.put), kwargs={"params_path": path})
    thread.start()
    try:
        first = said.get(timeout=10)
        assert first.endswith("(8 gauges a line)")
        port = first.split("stream://")[1].split()[0]
        with open_rig(f"stream://{port}", load_params(path)) as rig:
            readings = []
            for _ in range(10):
                rig.wait(0.03)
                readings.append(rig.read().gauges_v)
    finally:
        thread.join()
    np.testing.assert_allclose(np.mean(readings, axis=0), 0.1 * np.arange(1, 9), atol=REST_ATOL_V)
    # the command: the digit's twin, and the whole rig's command line names the digit
    assert main(["stream-emulator", "--twin", "--params", str(path), "--duration", "0.1", "--json"]) == 0
    lines = json.loads(capsys.readouterr().out)["lines"]
    assert lines[0].endswith("(8 gauges a line)")
    assert f"flexdigit run --params {path} --backend 'serial://" in lines[2]
    # a calibration is the twin's: refused without --twin, in one line naming the flag
    calibration = tmp_path / "cal.toml"
    assert main(["stream-emulator", "--calibration", str(calibration), "--duration", "0.1"]) == 2
    err = capsys.readouterr().err.strip()
    assert "--calibration" in err
    assert "--twin" in err
    assert "\n" not in err


@pytest.mark.slow
def test_run_params_closes_a_digits_loop_through_the_stream(tmp_path, capsys):
    # `flexdigit run --params D --backend serial://SERVO?daq=stream://PORT` on the emulator's twin of that digit (4
    # gauges, the cable pair): the hardware path of a digit other than the thesis rig, bending below straight
    import json
    import math

    from flexdigit.cli import main

    path = write_digit("four-sections-two-cables", tmp_path)
    params = load_params(path)
    with StreamEmulator(twin=True, seed=0, params=params) as emulator:
        twin, seen = emulator.twin, []
        command = twin.command

        def watched(value):  # the twin's true tip rotation as each servo frame arrives, the run's relax the last
            seen.append(math.degrees(float(twin.state()[0][-1])))
            command(value)

        twin.command = watched
        backend = f"serial://{emulator.servo_port}?daq=stream://{emulator.port}"
        args = ["run", "--params", str(path), "--backend", backend, "--map-from", "twin", "--duration", "3", "--json"]
        assert main([*args, "--setpoint-deg", "-20"]) == 0
        run = json.loads(capsys.readouterr().out)
        # the emulator's twin (its true rotation) held -20 deg within one command quantum (1.7 deg on this digit)
        quantum = run["rotation_map"]["deg_per_command"]
        assert seen[-1] == pytest.approx(-20.0, abs=quantum)
        assert run["gauge_source"]["garbled"] == 0
        assert len(run["rotation_map"]["coef_deg_per_v"]) == 4


def test_live_params_reads_a_digits_gauges_through_the_stream(tmp_path):
    # `flexdigit live --params D --backend serial://SERVO?daq=stream://PORT`: the live page's loop on the hardware
    # path of the 4-gauge pair digit (its emulated twin), open loop at the digit's straight command
    import time

    from flexdigit.live.session import LiveSession

    params = load_params(write_digit("four-sections-two-cables", tmp_path))
    with StreamEmulator(twin=True, seed=2, params=params) as emulator:
        holder: dict = {}

        def sleep(seconds):
            time.sleep(seconds)
            if len(holder["session"].state.samples) >= 15:
                holder["session"]._stop.set()

        backend = f"serial://{emulator.servo_port}?daq=stream://{emulator.port}"
        session = LiveSession(backend, params=params, sleep=sleep)
        holder["session"] = session
        try:
            session._run()
        finally:
            session.rig.close()
        assert session.error is None
        samples = session.state.samples
        assert len(samples) >= 15
        assert all(len(s.gauges_v) == 4 for s in samples)
        assert {s.command for s in samples} == {params.actuator.equilibrium_command}  # straight: 127, not 8
        assert abs(emulator.tip_rotation_deg()) < 1.0  # the pair's digit held straight
