"""``flexdigit`` commands in child processes, stopped by a signal as kill, systemd or a closed terminal would.

A child started from a non-interactive shell (CI, ``make test &``) inherits SIGINT ignored, and Python then leaves
it ignored: :func:`start` restores its default in the child first, so SIGINT reaches the child as Ctrl-C would.
(A ``preexec_fn`` would too, but it is unsafe when the test runs threads: an emulator on a pty.) Every wait is
bounded and polls; none is an assertion of timing.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

#: Start-up of a command on a busy 2-core machine (imports, the twin's rotation calibration), s.
START_TIMEOUT_S = 180.0
#: From the signal to the exit: the safe command, the footers, the result, s.
STOP_TIMEOUT_S = 60.0

_SIGINT_AS_IN_A_TERMINAL = (
    "import signal\n"
    "signal.signal(signal.SIGINT, signal.default_int_handler)  # inherited ignored: Ctrl-C as in a terminal\n"
)
_CLI = (
    "import runpy, sys\n"
    "sys.argv = ['flexdigit', *sys.argv[1:]]\n"
    "runpy.run_module('flexdigit.cli', run_name='__main__')\n"
)


def start(*argv: str, cwd: str | Path | None = None, operator: str | None = None) -> subprocess.Popen:
    """``flexdigit ARGV`` in a child process, its stdout and stderr piped; ``operator``: what the operator types
    (on hardware a command asks, e.g. to place the tissue, on stdin)."""
    return start_code(_CLI, *argv, cwd=cwd, operator=operator)


def start_code(
    code: str, *argv: str, cwd: str | Path | None = None, env: dict | None = None, operator: str | None = None
) -> subprocess.Popen:
    """``python -c CODE ARGV`` in a child process (SIGINT as in a terminal), its stdout and stderr piped."""
    proc = subprocess.Popen(
        [sys.executable, "-c", _SIGINT_AS_IN_A_TERMINAL + code, *map(str, argv)],
        stdin=subprocess.PIPE if operator is not None else subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=cwd,
        env=env,
    )
    if operator is not None:
        proc.stdin.write(operator)
        proc.stdin.flush()
    return proc


def wait_until(condition, proc: subprocess.Popen, timeout_s: float = START_TIMEOUT_S) -> None:
    """Poll ``condition`` every 20 ms until it holds; fail (with the child's stderr) if the child exits first or
    ``timeout_s`` passes."""
    deadline = time.monotonic() + timeout_s
    while not condition():
        if proc.poll() is not None:
            raise AssertionError(f"the child exited ({proc.returncode}) first: {proc.stderr.read()[-2000:]}")
        if time.monotonic() > deadline:
            proc.kill()
            raise AssertionError(f"no progress in {timeout_s} s: {proc.communicate()[1][-2000:]}")
        time.sleep(0.02)


def stop(proc: subprocess.Popen, signum: int) -> tuple[int, dict | None, str]:
    """Send ``signum`` and wait for the exit: ``(exit code, the --json object or None, stderr)``."""
    proc.send_signal(signum)
    try:
        out, err = proc.communicate(timeout=STOP_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, err = proc.communicate()
        name = signal.Signals(signum).name
        raise AssertionError(f"still running {STOP_TIMEOUT_S} s after {name}: {err[-2000:]}") from None
    return proc.returncode, (json.loads(out) if out.strip() else None), err


def cpu_s(pid: int) -> float:
    """User + system CPU time of process ``pid`` so far, s (Linux /proc): how far a child that writes nothing as it
    goes (a fit, an import) has got."""
    with open(f"/proc/{pid}/stat") as fh:
        fields = fh.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def lines(path: Path) -> int:
    """Complete lines in ``path`` so far (0 while it does not exist)."""
    try:
        return path.read_bytes().count(b"\n")
    except FileNotFoundError:
        return 0


#: The stop signals, with the exit code the shell gives a process they end: 128 + the signal's number.
STOPS = [
    (signal.SIGTERM, 143),
    (signal.SIGHUP, 129),
    (signal.SIGINT, 130),
]
