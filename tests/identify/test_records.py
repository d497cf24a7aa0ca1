"""The record generator (the oracle of the step-finding tests) checked against independent solvers.

Its closed forms are checked against python-control's simulation of ``wn^2 / (s^2 + 2 zeta wn s + wn^2)``
(step and initial-condition responses), and its CSV layouts against the standard library's ``csv`` reader, so a
mistake in the generator cannot hide a mistake in the identification (and vice versa).
"""

import csv
import math

import control
import numpy as np
import pytest

from .records import LAYOUTS, bad_records, free_response, good_records, make_signal, step_shape, write_record

#: python-control integrates the ODE; 1e-9 relative is far below any tolerance the identification is held to.
RTOL = 1e-9


@pytest.mark.parametrize(("wn", "zeta"), [(20.53, 0.5629), (13.0995, 0.06791), (10.2, 0.0025), (8.0, 1.5)])
def test_step_shape_is_the_second_order_step_response(wn, zeta):
    t = np.linspace(0, 3, 3001)
    sys = control.tf([wn**2], [1, 2 * zeta * wn, wn**2])
    expected = control.step_response(sys, t).outputs
    np.testing.assert_allclose(step_shape(t, wn, zeta), expected, rtol=RTOL, atol=1e-9)


@pytest.mark.parametrize(("wn", "zeta"), [(13.0995, 0.06791), (10.2, 0.0025), (8.0, 1.5), (13.1, -0.03)])
def test_free_response_is_the_release_from_rest(wn, zeta):
    # x'' + 2 zeta wn x' + wn^2 x = 0 from x(0) = 1, x'(0) = 0, as a state-space initial-condition response
    t = np.linspace(0, 3, 3001)
    sys = control.ss([[0, 1], [-(wn**2), -2 * zeta * wn]], [[0], [0]], [[1, 0]], [[0]])
    expected = control.initial_response(sys, t, X0=[1.0, 0.0]).outputs
    np.testing.assert_allclose(free_response(t, wn, zeta), expected, rtol=1e-7, atol=1e-9)


def test_signal_holds_its_baseline_then_responds_and_carries_its_disturbances():
    rng = np.random.default_rng(0)
    t, y, t0 = make_signal(
        rng, "step", wn=20.0, zeta=0.5, rate_hz=1000.0, duration_s=2.0, baseline_s=0.25, amplitude=-0.4,
        offset=1.0, noise=0.0, spikes=3, hum_hz=None, drift=0.0, start_s=3.0,
    )  # fmt: skip
    assert t0 == pytest.approx(3.25)
    assert t[0] == 3.0
    before = y[t < t0]
    assert np.sum(np.abs(before - 1.0) > 1e-12) <= 3  # the baseline, but for the spikes
    clean = 1.0 - 0.4 * step_shape(t - t0, 20.0, 0.5)
    assert np.sum(np.abs(y - clean) > 1e-12) == 3  # exactly the three spikes


@pytest.mark.parametrize("layout", list(LAYOUTS))
def test_every_layout_reads_back_with_the_csv_module(tmp_path, layout):
    t = np.arange(0, 0.05, 0.001)
    y = np.sin(40 * t)
    p = tmp_path / "r.csv"
    write_record(p, t, y, layout=layout, time_unit="ms", unit="mv", command=np.full(t.size, 7))
    spec = LAYOUTS[layout]
    lines = [line for line in p.read_text().splitlines() if not line.startswith("#")]
    if spec["delim"] == " ":
        rows = [line.split() for line in lines]
    else:
        rows = list(csv.reader(lines, delimiter=spec["delim"]))
    header, body = rows[0], rows[1:]
    tcol = header.index(spec["time"]["ms"])
    cells = [[c.replace(",", ".") for c in row] for row in body]
    np.testing.assert_allclose([float(r[tcol]) for r in cells], 1000 * t, rtol=1e-9)
    np.testing.assert_allclose([float(r[tcol + 1]) for r in cells], 1000 * y, rtol=1e-7)


def test_the_generated_set_covers_every_case_of_issue_11(tmp_path):
    good = good_records(tmp_path)
    assert len(good) >= 20
    assert {r.kind for r in good} == {"step", "release"}
    assert {r.direction for r in good} == {1, -1}
    assert any(r.baseline_s == 0 for r in good)
    assert any(0.1 <= r.baseline_s <= 0.4 for r in good)
    assert {r.hum_hz for r in good} == {None, 50.0, 60.0}
    assert any(r.spikes for r in good)
    assert any(r.drift for r in good)
    assert min(r.rate_hz for r in good) == 200
    assert max(r.rate_hz for r in good) == 2000
    assert {r.time_unit for r in good} == {"s", "ms"}
    assert {r.command for r in good if r.kind == "step"} == {True, False}
    assert {r.layout for r in good} == set(LAYOUTS)
    problems = {r.expect for r in bad_records(tmp_path)}
    assert problems >= {
        "no step",
        "two steps",
        "constant",
        "too short",
        "saturated",
        "no undershoot",
        "overdamped",
        "growing",
    }
    assert all(math.isfinite(r.wn_rad_s) and r.wn_rad_s > 0 for r in good)
