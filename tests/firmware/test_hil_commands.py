"""The whole host stack against the firmware on simavr, over its UART as a pty (issue 25, step 3): the harness makes
a pseudo-terminal, the ``hil://`` backend opens it as a board's serial port (pyserial), and ``flexdigit run``,
``collect`` and ``live``'s session loop run through it. Short runs: each is a fraction of a simulated second to a
few seconds.
"""

from __future__ import annotations

import json
import os

import numpy as np
import pytest
import serial

from flexdigit.cli import main
from flexdigit.live.session import LiveSession
from flexdigit.rig.base import open_rig
from flexdigit.tactile.dataset import load_dataset

#: A command is 1.735 deg of rotation on the design model; 1 deg of the twin's true rotation is a command's worth.
TRUE_ROTATION_TOLERANCE_DEG = 1.0
#: The board's readings against the twin's own (``collect`` on ``sim``, same protocol and seed, on the board twin's
#: 2 ms step), V: three of the board's 10-bit counts (4.9 mV each: half a count of quantisation, the rest the
#: noise drawn at other times; measured: at most 1.9 counts).
BOARD_READING_TOLERANCE_V = 3 * 5.0 / 1024
#: 12.5 g at 4 cm from the tip of the horizontal digit moves gauge 1 by 39-44 mV (both backends): at least this.
LOAD_SIGNAL_MIN_V = 0.03
PROTOCOL = (
    'name = "hil"\nloads_g = [12.5]\npositions_from_tip_cm = [4]\nactuation_commands = [20]\n'
    "repetitions = 1\nno_load_repetitions = 1\nsettle_s = 1.0\nrehang = false\n"
)


@pytest.mark.slow
def test_the_uart_is_a_pty_the_host_opens_as_a_serial_port(firmware):
    elf = firmware(0.020, "float")
    with open_rig(f"hil://{elf}", mode="host") as rig:
        assert isinstance(rig.port, serial.Serial)
        assert rig.port_path.startswith("/dev/pts/")
        assert os.path.exists(rig.port_path)
        assert rig.port.baudrate == 250_000
        assert rig.settings()["uart"] == "pty"
        rig.write_command(30)
        rig.wait(0.3)
        over_pty = [(s.t_us, s.gauges, s.pot) for s in rig.samples]
        command = rig.board_command
    assert rig.port is not None
    assert not rig.port.is_open  # closed with the rig
    # the same bytes as when they travel in the exchange: a pty changes the transport, not the run
    with open_rig(f"hil://{elf}?uart=pipe", mode="host") as rig:
        rig.write_command(30)
        rig.wait(0.3)
        over_pipe = [(s.t_us, s.gauges, s.pot) for s in rig.samples]
    assert over_pty == over_pipe
    assert command == pytest.approx(30, abs=0.07)  # the board followed the host's command (0.5 us pulse steps)


@pytest.mark.slow
def test_run_through_the_firmware_over_the_pty(firmware, capsys):
    elf = firmware(0.020, "float")
    code = main(["run", "--backend", f"hil://{elf}", "--map-from", "twin", "--duration", "2", "--json"])
    doc = json.loads(capsys.readouterr().out)
    assert code == 0
    assert doc["loop"] == "host"
    assert doc["rig"]["uart"] == "pty"
    assert abs(doc["true_final_rotation_deg"] - 30.0) < TRUE_ROTATION_TOLERANCE_DEG


@pytest.mark.slow
def test_collect_through_the_firmware_over_the_pty(firmware, tmp_path):
    elf = firmware(0.020, "float")
    protocol = tmp_path / "p.toml"
    protocol.write_text(PROTOCOL)
    out, reference = tmp_path / "hil.parquet", tmp_path / "sim.parquet"
    for backend, path in ((f"hil://{elf}", out), ("sim?dt_s=0.002", reference)):
        assert main(["collect", str(protocol), "--backend", backend, "--out", str(path), "--no-progress"]) == 0
    data, twin = load_dataset(out), load_dataset(reference)
    rig = data.meta["rig"]["settings"]
    assert rig["uart"] == "pty"
    assert rig["orientation"] == "horizontal"  # the protocol's mounting reached the board's twin
    loads = np.asarray(data.columns["load_kg"])
    np.testing.assert_array_equal(loads, twin.columns["load_kg"])
    np.testing.assert_allclose(data.gauges_v, twin.gauges_v, atol=BOARD_READING_TOLERANCE_V)
    gauge1 = np.asarray(data.gauges_v)[:, 0]
    assert gauge1[loads == 0][0] - gauge1[loads > 0][0] > LOAD_SIGNAL_MIN_V  # the weight bends it down


@pytest.mark.slow
def test_live_session_loop_through_the_firmware_over_the_pty(firmware):
    elf = firmware(0.020, "float")
    holder: dict = {}
    frames = []

    def sleep(seconds):  # the loop's pacing on the board's simulated clock
        rig = holder["session"].rig
        rig.wait(seconds)
        frames.append(rig.latest)
        if len(frames) == 25:
            holder["session"]._stop.set()

    session = LiveSession(  # paced=0: the board's simulated time, given by the loop's sleep (exactly repeatable)
        f"hil://{elf}?paced=0",
        clock=lambda: holder["session"].rig.clock() if "session" in holder else 0.0,
        sleep=sleep,
    )
    holder["session"] = session
    try:
        assert session.rig.settings()["uart"] == "pty"
        session._run()
    finally:
        session.rig.close()
    assert session.error is None
    assert len(session.state.samples) >= 20  # the loop read the board every period
    seqs = [f.seq for f in frames]
    assert seqs == sorted(seqs)
    assert len(set(seqs)) >= 20  # fresh samples from the firmware each period


@pytest.mark.slow
def test_live_keeps_the_board_at_the_wall_clocks_time(firmware):
    """``flexdigit live --backend hil://...``: the session opens the board paced (as it opens the twin
    ``sim+paced``), so the page's loop, sleeping on the wall clock, sees the board run and stream."""
    import time

    elf = firmware(0.020, "float")
    frames = []

    def sleep(seconds):  # the page's own pacing (the wall clock); it stops after 15 frames
        time.sleep(seconds)
        frames.append(session.rig.latest.seq)
        if len(frames) == 15:
            session._stop.set()

    session = LiveSession(f"hil://{elf}", sleep=sleep)
    try:
        assert session.rig.settings()["paced"] is True
        start = session.rig.board.latest.t_us
        session._run()
        end = session.rig.board.latest.t_us
    finally:
        session.rig.close()
    assert session.error is None
    # 15 frames of 20 ms on the wall clock: the board ran (without pacing it would still be at its opening)
    assert end - start >= 10 * 20_000
    assert len(set(frames)) >= 10


@pytest.mark.slow
def test_a_paced_board_on_a_slow_machine_runs_a_bounded_step_a_call_and_reports_its_lag(firmware):
    """A machine slower than real time (a fake wall clock: each simulated second costs two, each frame 20 ms more):
    each read runs at most ``MAX_CATCH_UP_S`` of the board, which falls behind by what it reports (unbounded, each
    catch-up would run what the one before cost twice over: 15 frames, 11 minutes of board time)."""
    elf = firmware(0.020, "float")
    frames = [0]
    rig = open_rig(f"hil://{elf}", paced=True, start_paced=False, wall_clock=lambda: wall())

    def wall():  # the fake machine's wall clock
        return frames[0] * 0.020 + 2.0 * (rig.clock() - opened_s)

    runs, lags, behind = [], [], []
    try:
        opened_s = rig.clock()
        rig.start_pacing()
        for _ in range(15):
            frames[0] += 1
            at_call, before = wall(), rig.clock()
            rig.read()
            runs.append(rig.clock() - before)
            lags.append(rig.lag_s)
            behind.append(at_call - (rig.clock() - opened_s))  # the wall clock's time on the board's axis, less its
    finally:
        rig.close()
    for k, run in enumerate(runs):
        assert run <= rig.MAX_CATCH_UP_S + rig.step_s, f"read {k} ran {run} s of the board"
    # 0.02 s and 0.06 s (under the bound), then the bound every read: linear, not geometric
    assert sum(runs) == pytest.approx(0.08 + 13 * rig.MAX_CATCH_UP_S, abs=15 * rig.step_s)
    assert lags == pytest.approx(behind, abs=rig.step_s)  # the lag reported is the fake clock's
    # 15 frames and twice the board time run before the last read, less all it ran: 0.3 + 2.56 - 1.38 s behind
    last = 15 * 0.020 + 2.0 * (0.08 + 12 * rig.MAX_CATCH_UP_S) - (0.08 + 13 * rig.MAX_CATCH_UP_S)
    assert lags[-1] == pytest.approx(last, abs=30 * rig.step_s)


def test_a_harness_without_a_pty_is_refused_naming_the_pipe(tmp_path):
    """A machine without ptys (no /dev/pts): one line saying so and how to run without one, no hang."""
    elf = tmp_path / "board.elf"
    elf.write_bytes(b"\x7fELF")
    harness = tmp_path / "flexdigit_hil"
    harness.write_text("#!/bin/sh\necho 'flexdigit_hil: cannot open a pty (No such device)' >&2\nexit 2\n")
    harness.chmod(0o755)
    with pytest.raises(OSError, match=r"no pty \(flexdigit_hil: cannot open a pty.*\?uart=pipe"):
        open_rig(f"hil://{elf}?harness={harness}")


@pytest.mark.slow
def test_run_params_of_a_digit_the_firmware_serves(firmware, tmp_path, capsys):
    # issue 24: a 0.30 m digit of 3 sections and 3 gauges at other places (the thesis's commands) through the
    # firmware, its twin from --params: the loop on the host, the true rotation at the setpoint
    digit = tmp_path / "three.toml"
    digit.write_text(
        "[geometry]\nsection_count = 3\nsection_length_m = 0.09\nstrip_length_m = 0.27\ndigit_length_m = 0.30\n"
        "gauge_positions_m = [0.05, 0.15, 0.25]\n"
    )
    elf = firmware(0.020, "float")
    args = ["run", "--params", str(digit), "--backend", f"hil://{elf}", "--map-from", "twin", "--duration", "2"]
    assert main([*args, "--setpoint-deg", "20", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["params"] == str(digit)
    assert abs(doc["true_final_rotation_deg"] - 20.0) < TRUE_ROTATION_TOLERANCE_DEG
