"""``flexdigit live --robot``: the tendon robot's 3D page in a real browser (Debian's chromium through Playwright),
against a real server. The page loads three.js from the package (vendored by ``make three``, no CDN), draws with
no console error, replays the motion and ends on its last frame: the tip it draws is ``/motion.json``'s last tip,
which is the simulation's (the JSON round trip and float32 vertices: ``TIP_ATOL_M``)."""

from __future__ import annotations

import json
import time
import urllib.request

import pytest

TIP_ATOL_M = 1e-6  # the page hands float64 JSON to float32 vertex buffers: ~3e-8 of 0.4 m

pytestmark = pytest.mark.slow


def _state(page) -> dict:
    return page.evaluate("() => window.flexdigitRobot ? Object.assign({}, window.flexdigitRobot) : null")


def test_the_robot_page_draws_the_motion_to_its_end(live_server, page):
    server = live_server("--robot", "rao2021", "--tension-n", "4,0,0,0,2,0", "--duration-s", "0.4")
    requests = []
    page.on("request", lambda r: requests.append(r.url))
    page.goto(server.url)
    motion = json.loads(urllib.request.urlopen(server.url + "motion.json", timeout=10).read())
    deadline = time.monotonic() + 30
    state = _state(page)
    while time.monotonic() < deadline and not (state and state["ready"] and state["frame"] == state["frames"] - 1):
        page.wait_for_timeout(200)
        state = _state(page)
    server.stop()
    assert page.console_errors == []
    assert state["error"] is None
    assert (state["frames"], state["points"]) == (21, 21)  # 0.4 s at 50 frames a second; the base and 20 disks
    assert state["frame"] == state["frames"] - 1
    for drawn, expected in zip(state["tip_m"], motion["backbone_m"][-1][-1], strict=True):
        assert drawn == pytest.approx(expected, abs=TIP_ATOL_M)
    assert all(url.startswith(server.url) for url in requests)  # nothing from elsewhere (no CDN)
