"""The live page in a real browser (Debian's chromium through Playwright), against a real ``flexdigit live``.

What the issue asks: the page loads with no console errors, the traces advance, the slider moves the digit, a click
loads the twin and the contact estimate settles within 1 cm of the click wherever the gauges can see a load (the
page says so where they cannot), and the page reconnects after a server restart. References: the twin's own state
(the load it was given, its commanded rotation), the click's arc position; the tolerance is the issue's 1 cm.
"""

from __future__ import annotations

import time

import pytest

from flexdigit.rig.recording import read_recording

from .live_helpers import stats, wait_for

LOCATE_TOL_M = 0.010  # the 1 cm
ROTATION_TOL_DEG = 2.0  # the controller's 2 % band is 0.6 deg; the page shows a 0.1 s average of a noisy estimate

pytestmark = pytest.mark.slow
#: The contact estimate's note and the text the panel shows, read at once.
SHOWN_NOTE = "() => [flexdigit.last.contact[0].note, document.querySelector('#c-note').innerText]"


def _click(page, s_m: float, mass_g: float = 25.0) -> None:
    page.select_option("#mass", f"{mass_g:g}")
    point = page.evaluate(f"() => flexdigit.pointFor({s_m})")
    assert point is not None
    page.mouse.click(point["x"], point["y"])


def _contact(s) -> dict:
    return s["last"]["contact"][0]


def test_page_streams_the_twin_and_the_slider_moves_the_digit(live_server, page, tmp_path):
    server = live_server("--record", str(tmp_path / "session.mcap"))
    page.goto(server.url)
    # a frame may carry the shape and no samples: wait for one that has both, so the traces' time can be compared
    first = wait_for(
        page,
        lambda s: s["samples"] > 20 and s["last"]["shape"] is not None and s["last"]["samples"],
        what="the first samples",
    )
    # 50 Hz: about 50 more a second; the traces advance (waited for, not timed: a loaded machine is slower)
    later = wait_for(page, lambda s: s["samples"] >= first["samples"] + 30, timeout_s=10, what="more samples")
    assert later["last"]["samples"] == [] or later["last"]["samples"][-1]["t"] > first["last"]["samples"][-1]["t"]
    tip_before = later["last"]["shape"]["tip_m"][1]
    assert page.evaluate("() => flexdigit.traces") == 3  # the thesis rig's three gauges, one trace each
    assert page.locator("#gauge-legend .gauge-key").count() == 3
    page.locator("#setpoint").fill("30")
    moved = wait_for(
        page,
        lambda s: s["last"]["samples"] and abs((s["last"]["samples"][-1]["y"] or 0) - 30) < ROTATION_TOL_DEG,
        timeout_s=30,
        what="the digit to reach 30 deg",
    )
    assert moved["last"]["state"]["engaged"]
    assert moved["last"]["state"]["setpoint"] == 30
    assert moved["last"]["shape"]["tip_m"][1] > tip_before + 0.04  # the tip rose by centimetres
    # a click hangs the weight on the twin; the contact panel reports it (placed only coarsely: taut cable)
    _click(page, 0.22)
    loaded = wait_for(page, lambda s: s["last"]["state"]["loads"] and _contact(s)["contact"], what="a contact")
    mass, position = loaded["last"]["state"]["loads"][0]
    assert mass == pytest.approx(0.025)
    assert abs(position - 0.22) < 0.006  # the click's arc position, 5 mm grid
    c = _contact(loaded)
    if c["located"]:
        assert abs(c["position_from_base_m"] - position) < LOCATE_TOL_M
    else:  # the page says it cannot place it to a centimetre here, and why (read once: the note updates live)
        note = page.inner_text("#c-note")
        assert "placed only" in note or "cannot place it" in note
    page.click("#clear")
    wait_for(page, lambda s: not s["last"]["state"]["loads"], what="the load removed")
    assert page.console_errors == []
    result = server.stop()
    assert result["status"] == "stopped"
    assert server.returncode == 0
    header, samples, footer = read_recording(tmp_path / "session.mcap")
    assert footer["stop"] == "stopped"
    assert samples[-1]["command"] == 8  # relaxed when the page went away
    assert len(samples) > 100


@pytest.mark.parametrize("position_m", [0.17, 0.22, 0.26])
def test_a_click_is_located_within_a_centimetre_where_the_gauges_see_it(live_server, page, position_m):
    # chapter 6's digit: horizontal, the cable detached, so no cable friction: two or three gauges bend beyond
    # gauge 2 and place a 25 g weight to a millimetre or two
    server = live_server("--backend", "sim?cable=false")
    page.goto(server.url)
    wait_for(page, lambda s: s["last"]["shape"] is not None, what="the shape")
    _click(page, position_m)
    hung = wait_for(page, lambda s: s["last"]["state"]["loads"], what="the weight hung")["last"]["state"]["loads"]
    # settled: the located estimate stays within 1 cm of the weight for a second (ten polls in a row)
    streak, deadline = 0, time.monotonic() + 20
    while streak < 10 and time.monotonic() < deadline:
        c = _contact(stats(page))
        near = c["located"] and abs(c["position_from_base_m"] - hung[0][1]) < LOCATE_TOL_M
        streak = streak + 1 if near else 0
        page.wait_for_timeout(100)
    assert streak >= 10, f"the estimate did not settle within 1 cm of {hung[0][1]} m: last {c}"
    assert abs(hung[0][1] - position_m) < 0.006  # the weight went where the click was (5 mm grid)
    assert page.console_errors == []
    server.stop()


def test_the_page_says_where_the_gauges_cannot_see_a_load(live_server, page):
    server = live_server("--backend", "sim?cable=false")
    page.goto(server.url)
    wait_for(page, lambda s: s["locMap"] is not None, timeout_s=40, what="the locatability map")
    loc = stats(page)["locMap"]
    blind = [s for s, sd in zip(loc["s_m"], loc["sd_m"], strict=True) if sd is None or sd > 0.005]
    assert min(blind) < 0.045
    assert max(blind) >= 0.13  # clamp to gauge 2: no gauge, or gauge 1 alone, bends
    _click(page, 0.03)  # between the clamp and gauge 1
    page.wait_for_timeout(3000)
    c = _contact(stats(page))
    assert not c["located"]
    assert c["note"] in ("no load found",) or "cannot" in c["note"]
    # the panel shows the estimate's note: read together until they agree (the note updates live, drawn a frame
    # after it arrives), bounded
    deadline = time.monotonic() + 20
    shown = page.evaluate(SHOWN_NOTE)
    while shown[0] != shown[1] and time.monotonic() < deadline:
        page.wait_for_timeout(100)
        shown = page.evaluate(SHOWN_NOTE)
    assert shown[0] == shown[1], shown
    server.stop()


def test_the_page_reconnects_after_a_server_restart(live_server, page):
    server = live_server("--backend", "sim?cable=false")
    page.goto(server.url)
    wait_for(page, lambda s: s["samples"] > 20, what="samples")
    port = server.port
    server.stop()
    wait_for(page, lambda s: not s["connected"], what="the page to notice the server left")
    assert page.inner_text("#conn") == "reconnecting"
    # what is still drawn is no longer the digit: the page says so and greys it out
    assert "unreachable" in page.inner_text("#status")
    assert page.evaluate("document.body.classList.contains('stale')")
    again = live_server("--backend", "sim?cable=false", port=port)
    before = stats(page)["samples"]
    wait_for(page, lambda s: s["connected"] and s["samples"] > before + 20, timeout_s=60, what="the reconnection")
    assert stats(page)["reconnects"] >= 1
    assert page.inner_text("#conn") == "live"
    assert not page.evaluate("document.body.classList.contains('stale')")
    assert page.console_errors == [] or all("WebSocket" in e for e in page.console_errors)
    again.stop()


def test_a_second_page_shows_the_servers_setpoint_and_pause(live_server, browser, page):
    # the controls show the server's state, not the page's own last gesture (a reconnection, another page)
    server = live_server()
    page.goto(server.url)
    wait_for(page, lambda s: s["last"]["shape"] is not None, what="the shape")
    page.locator("#setpoint").fill("30")
    wait_for(page, lambda s: s["last"]["state"]["setpoint"] == 30, what="the setpoint applied")
    page.click("#pause")
    wait_for(page, lambda s: s["last"]["state"]["paused"], what="the pause applied")
    other = browser.new_context(viewport={"width": 700, "height": 900}).new_page()
    other.goto(server.url)
    wait_for(other, lambda s: s["last"]["state"]["setpoint"] == 30, what="the second page's first frame")
    other.wait_for_timeout(300)
    assert float(other.input_value("#setpoint")) == 30.0
    assert other.inner_text("#sp-value") == "30.0"
    assert other.inner_text("#pause") == "resume"
    # a narrow window stacks the panels under the digit rather than squeezing the digit beside them
    shape, contact = other.locator("#shape").bounding_box(), other.locator("#contact").bounding_box()
    assert shape["width"] > 600
    assert contact["y"] > shape["y"] + shape["height"]
    other.context.close()
    server.stop()
