"""A real ``flexdigit live`` server in a subprocess, and the page's own counters read from a test with a bounded
wait on them: a plain module the live tests import (``from .live_helpers import LiveServer, wait_for``);
tests/live/conftest.py only makes the fixtures (issue 23: shared helpers in a module, not in a conftest)."""

from __future__ import annotations

import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

START_TIMEOUT_S = 120  # imports and the twin's rotation calibration, on a busy 2-core machine


class LiveServer:
    """``flexdigit live`` as a user starts it; :meth:`stop` sends Ctrl-C (SIGINT) and returns its JSON result."""

    def __init__(self, tmp_path: Path, *args: str, port: int = 0) -> None:
        self.stderr_path = tmp_path / f"live-{time.monotonic_ns()}.err"
        self.stderr = open(self.stderr_path, "w")  # noqa: SIM115 - closed in stop()
        cmd = [sys.executable, "-m", "flexdigit.cli", "live", "--port", str(port), "--json", *args]
        self.proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=self.stderr, text=True)
        deadline = time.monotonic() + START_TIMEOUT_S
        self.url = None
        while time.monotonic() < deadline and self.proc.poll() is None:
            match = re.search(r"(http://127\.0\.0\.1:\d+/)", self.stderr_path.read_text())
            if match:
                self.url = match.group(1)
                break
            time.sleep(0.2)
        if self.url is None:
            self.proc.kill()
            raise RuntimeError(f"flexdigit live did not start: {self.stderr_path.read_text()[-2000:]}")
        self.port = int(self.url.rsplit(":", 1)[1].strip("/"))
        self._wait_listening()

    def _wait_listening(self) -> None:
        import urllib.request

        for _ in range(100):
            try:
                urllib.request.urlopen(self.url, timeout=2).read()
                return
            except OSError:
                time.sleep(0.1)

    def stop(self, signum: int = signal.SIGINT) -> dict:
        """Ctrl-C (or ``signum``: SIGTERM as systemd, SIGHUP as a closed terminal stops it); the exit code and the
        --json summary."""
        import json

        self.proc.send_signal(signum)
        out, _ = self.proc.communicate(timeout=30)
        self.stderr.close()
        self.returncode = self.proc.returncode
        return json.loads(out) if out.strip() else {}


def stats(page) -> dict:
    """The page's own counters (window.flexdigit): frames received, draws, samples, latencies, state."""
    return page.evaluate(
        "() => ({frames: flexdigit.frames, draws: flexdigit.draws, samples: flexdigit.samples,"
        " connected: flexdigit.connected, reconnects: flexdigit.reconnects, errors: flexdigit.errors,"
        " last: flexdigit.last, hello: flexdigit.hello, locMap: flexdigit.locMap || null})"
    )


def wait_for(page, predicate, timeout_s: float = 20.0, what: str = "condition"):
    """Poll the page's stats until ``predicate(stats)`` holds; return the stats (fail naming ``what``)."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        s = stats(page)
        if s["last"] is not None and predicate(s):
            return s
        page.wait_for_timeout(200)
    pytest.fail(f"timed out after {timeout_s} s waiting for {what}; last: {str(stats(page)['last'])[:600]}")
