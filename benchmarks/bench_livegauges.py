"""The live page on an 8-gauge, 5-section, 0.5 m digit beside the thesis rig (issue 24, ``live --params``), in one
run, Debian's chromium through Playwright against ``flexdigit live [--params FILE]``:

- ``page update rate``: redraws per second while the controller holds 20 deg (goal >= 20 Hz, as bench_live's);
- ``page draw``: one redraw's time in the browser (the shape, the G gauge traces, the panels), p95, ms;
- ``server CPU``: the ``flexdigit live`` process's user + system CPU over the window, % of one core (the twin, the
  controller, the shape estimate of G gauges, the WebSocket);
- ``start``: from starting ``flexdigit live`` to its URL printed (the digit's rotation map is swept first).

``python -m benchmarks livegauges``. The 8-gauge digit is the test digits' ``five-sections-eight-gauges``
(``tests/digits.py``), written here as a user would write its file.
"""

from __future__ import annotations

import signal
import tempfile
from pathlib import Path

import numpy as np

from benchmarks.bench_live import _cpu_s, _start_server

HOLD_S = 8.0  # the window measured, holding 20 deg
EIGHT_GAUGES = """[geometry]
section_count = 5
section_length_m = 0.09
strip_length_m = 0.45
digit_length_m = 0.5
gauge_positions_m = [0.03, 0.07, 0.13, 0.17, 0.23, 0.27, 0.33, 0.37]

[sensors]
bridge = "full"
adc_channels = [0, 1, 2, 3, 4, 5, 6, 7]
"""


def measure(*args: str) -> dict:
    """The page of ``flexdigit live ARGS`` holding 20 deg for :data:`HOLD_S`: rates, draw time, CPU, start."""
    import time

    from playwright.sync_api import sync_playwright

    from flexdigit.live.browser import launch

    with tempfile.TemporaryDirectory() as tmp:
        proc, url, start_s = _start_server(Path(tmp) / "live.err", *args)
        try:
            with sync_playwright() as pw:
                browser = launch(pw)
                page = browser.new_page(viewport={"width": 1280, "height": 860})
                page.goto(url)
                page.wait_for_function("() => flexdigit.last && flexdigit.last.shape", timeout=120_000)
                page.locator("#setpoint").fill("20")
                page.wait_for_timeout(3000)
                before = page.evaluate("() => ({d: flexdigit.draws, s: flexdigit.samples})")
                cpu0, t0 = _cpu_s(proc.pid), time.monotonic()
                page.wait_for_timeout(HOLD_S * 1000)
                cpu1, t1 = _cpu_s(proc.pid), time.monotonic()
                after = page.evaluate(
                    "() => ({d: flexdigit.draws, s: flexdigit.samples, draw: flexdigit.drawTimes.slice(),"
                    " traces: flexdigit.traces})"
                )
                browser.close()
        finally:
            proc.send_signal(signal.SIGINT)
            proc.wait(timeout=30)
    wall, draws = t1 - t0, int(after["d"] - before["d"])
    return {
        "update_hz": draws / wall,
        "samples_hz": (after["s"] - before["s"]) / wall,
        "draw_p95_ms": float(np.percentile(np.array(after["draw"])[-max(draws, 1) :], 95)),
        "cpu_percent": 100.0 * (cpu1 - cpu0) / wall,
        "start_s": start_s,
        "traces": after["traces"],
    }


def run() -> list[dict]:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "eight-gauges.toml"
        path.write_text(EIGHT_GAUGES)
        thesis, eight = measure(), measure("--params", str(path))
    rows = []
    for label, m in (("thesis rig, 3 gauges", thesis), ("5 sections, 8 gauges, 0.5 m", eight)):
        note = f"{m['traces']} traces drawn; {m['samples_hz']:.0f} samples/s reached the page; holding 20 deg"
        rows += [
            {"name": f"live page update rate, {label}", "value": m["update_hz"], "unit": "Hz", "goal": ">= 20",
             "note": note},
            {"name": f"live page draw p95, {label}", "value": m["draw_p95_ms"], "unit": "ms", "goal": "",
             "note": "one redraw in chromium: shape, gauge traces, panels"},
            {"name": f"live server CPU at 50 Hz, {label}", "value": m["cpu_percent"], "unit": "% core",
             "goal": "<= 20", "note": "user + system time of the flexdigit live process, the twin included"},
            {"name": f"flexdigit live start, to its URL, {label}", "value": m["start_s"], "unit": "s", "goal": "",
             "note": "the digit's rotation map swept on its twin first"},
        ]  # fmt: skip
    return rows
