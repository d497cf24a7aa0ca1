"""The live page on digits other than the thesis rig's (issue 24, item 3's ``live --params``), in a real browser:
one trace and one legend entry per gauge of the digit (1 and 5 here, 3 on the thesis page), the digit drawn with
its own sections and length, and, with an antagonistic pair, a slider that runs below zero and a digit that
follows it there. References: the digit's parameter file (its gauge count, sections, length), the setpoint asked.
"""

from __future__ import annotations

import pytest

from digits import write_digit

from .live_helpers import stats, wait_for

pytestmark = pytest.mark.slow

#: The held rotation's band on the page, deg: one servo command is 1.735 deg (E 3.15), the page shows a 0.1 s
#: average of a noisy estimate (test_page's band for the thesis rig).
ROTATION_TOL_DEG = 2.0

FIVE_GAUGES = {  # the 0.5 m, five-section digit with one gauge per section instead of two
    "geometry": {"gauge_positions_m": [0.03, 0.13, 0.23, 0.33, 0.43]},
    "sensors": {"adc_channels": [0, 1, 2, 3, 4]},
}


@pytest.mark.parametrize(
    ("name", "changes", "gauges", "sections", "length_m"),
    [("one-section", {}, 1, 1, 0.16), ("five-sections-eight-gauges", FIVE_GAUGES, 5, 5, 0.50)],
    ids=["1-gauge", "5-gauges"],
)
def test_the_page_draws_one_trace_per_gauge_of_the_digit(
    live_server, page, tmp_path, name, changes, gauges, sections, length_m
):
    path = write_digit(name, tmp_path, **changes)
    server = live_server("--params", str(path))
    page.goto(server.url)
    s = wait_for(page, lambda s: s["draws"] > 3 and s["last"]["shape"] is not None, timeout_s=40, what="drawing")
    assert page.evaluate("() => flexdigit.traces") == gauges
    keys = page.locator("#gauge-legend .gauge-key")
    assert keys.count() == gauges
    assert keys.nth(gauges - 1).inner_text().startswith(f"gauge {gauges} at ")
    assert all(len(smp["gauges_v"]) == gauges for smp in s["last"]["samples"])
    hello = s["hello"]
    assert (hello["section_count"], len(hello["supports_m"]), len(hello["gauges_m"])) == (sections, sections, gauges)
    assert hello["digit_length_m"] == pytest.approx(length_m)
    assert hello["supports_m"][-1] == pytest.approx(length_m)  # the last support is the tip
    assert f"{sections} section" in page.inner_text("#backend")
    # the estimated centre line is the digit's length (arc length), drawn inside the view
    assert s["last"]["shape"]["s_m"][-1] == pytest.approx(length_m, abs=0.005)
    point = page.evaluate(f"() => flexdigit.pointFor({length_m})")
    box = page.locator("#shape").bounding_box()
    assert box["x"] < point["x"] < box["x"] + box["width"]
    assert box["y"] < point["y"] < box["y"] + box["height"]
    assert page.console_errors == []
    result = server.stop()
    assert result["status"] == "stopped"
    assert result["params"] == str(path)


def test_a_two_cable_digit_bends_below_straight_from_the_slider(live_server, page, tmp_path):
    path = write_digit("four-sections-two-cables", tmp_path)
    server = live_server("--params", str(path))
    page.goto(server.url)
    wait_for(page, lambda s: s["last"]["shape"] is not None, timeout_s=40, what="the shape")
    assert float(page.locator("#setpoint").get_attribute("min")) < -20
    assert page.evaluate("() => flexdigit.traces") == 4
    assert "two cables" in page.inner_text("#backend")
    page.locator("#setpoint").fill("-20")
    held = wait_for(
        page,
        lambda s: s["last"]["samples"] and abs((s["last"]["samples"][-1]["y"] or 0) + 20) < ROTATION_TOL_DEG,
        timeout_s=40,
        what="the digit to reach -20 deg",
    )
    assert held["last"]["state"]["setpoint"] == -20
    assert held["last"]["samples"][-1]["command"] < 127  # the second cable pulls: below the straight command
    # the tip went down, towards the second cable (the first cable's side is +y)
    page.wait_for_timeout(1000)
    assert stats(page)["last"]["shape"]["tip_m"][1] < -0.03
    assert page.console_errors == []
    server.stop()
