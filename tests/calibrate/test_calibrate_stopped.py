"""``flexdigit calibrate --force`` stopped by a signal mid-fit (issue 22): exit 128 + the signal with the JSON
error naming it, the calibration it was to replace left as it was, no temporary file. Its friction fit runs in
numba-compiled kernels, which hand a signal back as ``SystemError`` ("CPUDispatcher(...) returned a result with an
exception set"): that was reported as an internal error (exit 2)."""

from __future__ import annotations

import signal
import sys

import pytest

from children import STOPS, cpu_s, start, stop, wait_until

#: CPU time the child has spent before the signal, s: past its imports (~2 s), inside the fit (~15 s in all).
CPU_BEFORE_STOP_S = 5.0


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads the child's CPU time from /proc")
@pytest.mark.parametrize("signum, code", STOPS, ids=[s.name for s, _ in STOPS])
def test_a_stopped_calibration_leaves_the_old_file(tmp_path, signum, code):
    out = tmp_path / "cal.toml"
    out.write_text("# the calibration of last week\n")
    proc = start("calibrate", "--thesis", "--out", out, "--force", "--json")
    wait_until(lambda: cpu_s(proc.pid) > CPU_BEFORE_STOP_S, proc)
    exit_code, result, err = stop(proc, signum)
    name = signal.Signals(signum).name
    assert exit_code == code, err
    assert result["signal"] == name
    assert result["error"] == f"interrupted by {name}"
    assert out.read_text() == "# the calibration of last week\n"
    assert [p.name for p in tmp_path.iterdir()] == ["cal.toml"]  # no temporary file
