"""Issue 11, item 1: `flexdigit identify` finds its own step on records flexdigit did not make, and refuses the
records it cannot identify with confidence (issue 16's reproductions among them).

The records come from tests/identify/records.py, a generator written independently of flexdigit (closed-form
second-order responses, checked against python-control in test_records.py), in several CSV layouts. Tolerances
are the issue's: wn within 3 %, zeta within 5 %, on every record.
"""

import json

import numpy as np
import pytest

from flexdigit.cli import main

from .records import (
    bad_records,
    good_records,
    light_release_records,
    make_signal,
    motivating_records,
    pushed_release_records,
    write_record,
)

#: Issue 11's "Done when": default identify within 3 % on wn and 5 % on zeta.
WN_RTOL, ZETA_RTOL = 0.03, 0.05


def _run(capsys, argv):
    code = main(argv)
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.fixture(scope="module")
def records_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("records")


@pytest.mark.slow  # ~10 s: 29 records, up to 18,000 samples each
def test_default_identify_finds_the_step_within_3_and_5_percent(records_dir, capsys):
    rows, covered = [], 0
    pushed = pushed_release_records(records_dir)
    for rec in good_records(records_dir) + motivating_records(records_dir) + pushed:
        code, out, err = _run(capsys, rec.cli("--json"))
        assert code == 0, f"{rec.name}: {err}"
        res = json.loads(out)
        wn_err, zeta_err = res["wn_rad_s"] / rec.wn_rad_s - 1, res["zeta"] / rec.zeta - 1
        rows.append((rec.name, rec.layout, rec.rate_hz, 100 * wn_err, 100 * zeta_err, res["t0_s"] - rec.t0_s))
        assert abs(wn_err) < WN_RTOL, rows[-1]
        assert abs(zeta_err) < ZETA_RTOL, rows[-1]
        # the instant is reported, found from the record (the command column when there is one)
        dt = 1.0 / rec.rate_hz
        assert res["t0_s"] == pytest.approx(rec.t0_s, abs=max(2 * dt, 0.003)), rows[-1]
        assert res["instant"]["found_from"] == ("command" if rec.command else "signal")
        if rec.kind == "step":
            assert res["instant"]["direction"] == ("up" if rec.direction > 0 else "down")
        # every fit reports its quality
        q = res["quality"]
        assert q["fit_percent"] > 80
        assert q["misfit_percent"] < 5
        assert q["whiteness"]["test"] == "Ljung-Box"
        assert res["record"]["spikes"] == rec.spikes
        assert (res["record"]["hum_hz"] is None) == (rec.hum_hz is None)
        if rec.hum_hz:
            assert res["record"]["hum_hz"] == pytest.approx(rec.hum_hz, abs=0.05)
        if rec in pushed:  # recorded from rest: the push before the hold is left out, and the user told so
            assert any("left out of the fit" in w for w in res["warnings"])
        lo, hi = res["confidence_intervals"]["wn_rad_s"]
        covered += lo <= rec.wn_rad_s <= hi
    worst_wn = max(abs(r[3]) for r in rows)
    worst_zeta = max(abs(r[4]) for r in rows)
    print(
        f"\n{len(rows)} records: worst |wn error| {worst_wn:.2f} %, worst |zeta error| {worst_zeta:.2f} %, "
        f"worst |t0 error| {1e3 * max(abs(r[5]) for r in rows):.2f} ms, {covered} wn intervals cover the truth"
    )
    for r in rows:
        print("  {:<18} {:<16} {:6.0f} Hz  wn {:+6.2f} %  zeta {:+6.2f} %  t0 {:+.4f} s".format(*r))
    # the 95 % intervals are honest: with 29 records, fewer than 25 covering the truth has probability < 1.5 %
    assert covered >= 25


def test_issue_11_reproduction_step_down_in_ms_without_command(records_dir, capsys):
    # the issue's case: no command column, 0.1-0.4 s of baseline, spikes, one a step down with time in ms; wn came
    # out 51-79 % low with exit 0 when the step was taken at t = 0
    rec = motivating_records(records_dir)[1]
    assert rec.direction == -1
    assert rec.time_unit == "ms"
    assert 0.1 <= rec.baseline_s <= 0.4
    code, out, _ = _run(capsys, rec.cli())
    assert code == 0
    reported = float(out.split("step at t = ")[1].split(" s")[0])
    assert reported == pytest.approx(rec.t0_s, abs=0.004)
    assert "found from the signal" in out
    assert "step down" in out
    assert "ms on the file's clock" in out
    code, out, _ = _run(capsys, rec.cli("--json"))
    res = json.loads(out)
    assert res["wn_rad_s"] == pytest.approx(rec.wn_rad_s, rel=WN_RTOL)
    assert res["zeta"] == pytest.approx(rec.zeta, rel=ZETA_RTOL)
    assert res["instant"]["baseline_s"] == pytest.approx(rec.baseline_s, abs=0.02)


def test_a_lightly_damped_release_with_an_uneven_first_swing_is_identified(records_dir, capsys):
    # the bare digit (zeta 0.0025) read by a gauge near the tip: a higher mode and the gauge's nonlinearity make the
    # first undershoot smaller than the swing after it; the release-instant finder took that for noise and refused
    # the record as "no undershoot", even noise-free (one gauge of three identified in the twin's 30 s record)
    for rec in light_release_records(records_dir):
        code, out, err = _run(capsys, rec.cli("--json"))
        assert code == 0, f"{rec.name}: {err}"
        res = json.loads(out)
        assert res["wn_rad_s"] == pytest.approx(rec.wn_rad_s, rel=0.001), rec.name
        assert res["zeta"] == pytest.approx(rec.zeta, rel=0.02), rec.name
        assert res["t0_s"] == pytest.approx(0.0, abs=0.002), rec.name


#: Every record of records.bad_records (the test below checks the list is complete).
BAD = [
    "no-step", "no-release", "two-steps", "pulse", "two-steps-command", "constant-command", "constant",
    "constant-release", "too-short", "saturated", "saturated-release", "overdamped-release", "overdamped-step",
    "growing-release",
    "growing-step", "exponential", "exponential-release",
]  # fmt: skip


def test_the_bad_records_are_all_tested(records_dir):
    assert sorted(r.name for r in bad_records(records_dir)) == sorted(BAD)


@pytest.mark.parametrize("name", BAD)
def test_records_that_cannot_be_identified_exit_non_zero_saying_why(records_dir, capsys, name):
    rec = next(r for r in bad_records(records_dir) if r.name == name)
    code, out, err = _run(capsys, rec.cli())
    assert code == 2
    assert out == ""
    assert err.count("\n") == 1
    assert "Traceback" not in err
    assert rec.expect in err, err
    assert rec.path in err  # names the file


@pytest.mark.parametrize("name", ["two-steps", "saturated", "too-short", "no-step", "growing-release"])
def test_force_prints_the_fit_with_the_warning(records_dir, capsys, name):
    rec = next(r for r in bad_records(records_dir) if r.name == name)
    code, out, _ = _run(capsys, rec.cli("--force"))
    assert code == 0
    assert "wn   =" in out
    assert f"warning: {rec.expect}" in out
    code, out, _ = _run(capsys, rec.cli("--force", "--json"))
    assert code == 0
    assert any(w.startswith(rec.expect) for w in json.loads(out)["warnings"])


def test_constant_record_is_refused_even_with_force(records_dir, capsys):
    rec = next(r for r in bad_records(records_dir) if r.name == "constant")
    code, _, err = _run(capsys, rec.cli("--force"))
    assert code == 2
    assert "the signal is constant (0.731 V) over the whole record: no step to identify" in err


@pytest.mark.parametrize("name", ["constant-release", "growing-release", "exponential-release"])
def test_constant_or_growing_release_is_refused_with_allow_overdamped(records_dir, capsys, name):
    # issue 16: "a constant or growing signal 'fits' with --allow-overdamped"
    rec = next(r for r in bad_records(records_dir) if r.name == name)
    code, _, err = _run(capsys, rec.cli("--allow-overdamped"))
    assert code == 2
    assert rec.expect in err


def test_overdamped_release_is_identified_with_allow_overdamped(tmp_path, capsys):
    # zeta 1.5: poles at 5.0 and 34 rad/s; the fast one hides in the noise, so wn needs a quiet record (0.3 %)
    t, y, _ = make_signal(
        np.random.default_rng(4), "release", wn=13.1, zeta=1.5, rate_hz=1000.0, duration_s=3.0, baseline_s=0.2,
        amplitude=0.8, offset=0.1, noise=0.003,
    )  # fmt: skip
    p = tmp_path / "overdamped.csv"
    write_record(p, t, y, layout="comma", time_unit="s", unit="v")
    code, _, err = _run(capsys, ["identify", "release", str(p)])
    assert code == 2
    assert "no undershoot" in err
    code, out, _ = _run(capsys, ["identify", "release", str(p), "--allow-overdamped", "--json"])
    assert code == 0
    res = json.loads(out)
    assert res["zeta"] == pytest.approx(1.5, rel=0.05)
    assert res["wn_rad_s"] == pytest.approx(13.1, rel=0.05)
    # the noisier generated one (2 %) is refused even so, as too uncertain: wn is known to only about +-11 %
    rec = next(r for r in bad_records(tmp_path) if r.name == "overdamped-release")
    code, _, err = _run(capsys, rec.cli("--allow-overdamped"))
    assert code == 2
    assert "not identified with confidence: the 95 % interval of wn" in err


def test_a_long_record_at_2_khz_is_identified(tmp_path, capsys):
    # 30 s at 2 kHz (60,000 samples) with spikes, hum and drift: the case the benchmark times
    t, y, t0 = make_signal(
        np.random.default_rng(3), "step", wn=20.53, zeta=0.5629, rate_hz=2000.0, duration_s=30.0,
        baseline_s=0.3, amplitude=0.4, offset=0.9, noise=0.01, spikes=20, hum_hz=50.0, hum=0.05, drift=0.02,
    )  # fmt: skip
    p = tmp_path / "long.csv"
    write_record(p, t, y, layout="comma", time_unit="s", unit="v")
    code, out, _ = _run(capsys, ["identify", "step", str(p), "--json"])
    assert code == 0
    res = json.loads(out)
    assert res["wn_rad_s"] == pytest.approx(20.53, rel=0.01)
    assert res["zeta"] == pytest.approx(0.5629, rel=0.02)
    assert res["t0_s"] == pytest.approx(0.3, abs=1e-3)
    assert res["record"]["spikes"] == 20


@pytest.mark.parametrize("late_s", [0.06, 0.2, 0.45])
def test_a_release_record_that_starts_in_mid_swing(tmp_path, capsys, late_s):
    # the recording started after the release (a gauge near the clamp also reads this way, its higher modes
    # moving it away from rest first): the instant lies before the record, and the fit finds it there
    t, y, t0 = make_signal(
        np.random.default_rng(9), "release", wn=13.1, zeta=0.068, rate_hz=500.0, duration_s=5.0,
        baseline_s=-late_s, amplitude=0.8, offset=0.1, noise=0.01,
    )  # fmt: skip
    p = tmp_path / "late.csv"
    write_record(p, t, y, layout="comma", time_unit="s", unit="v")
    code, out, err = _run(capsys, ["identify", "release", str(p), "--json"])
    assert code == 0, err
    res = json.loads(out)
    assert res["wn_rad_s"] == pytest.approx(13.1, rel=0.01)
    assert res["zeta"] == pytest.approx(0.068, rel=0.03)
    assert res["instant"]["baseline_s"] < 0.05  # no hold: at most the approach to the record's first extreme
    # the fitted instant, modulo half a period (only the phase is seen, and a release from the next extreme is the
    # same curve with the deflection's sign flipped): within 5 ms of the true one
    half = np.pi / (13.1 * np.sqrt(1 - 0.068**2))
    offset = (res["t0_s"] - t0 + half / 2) % half - half / 2
    assert abs(offset) < 0.005
