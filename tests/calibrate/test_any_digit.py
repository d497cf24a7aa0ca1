"""``flexdigit calibrate --params D`` on a digit's own simulated records gives its calibration back (issue 24).

Known answers: the records are simulated (seeded) from a twin whose calibration is the digit's derived default
(:func:`flexdigit.twin.digit_calibration.calibration_for`) perturbed by :data:`PERTURB`, so the fit must move away
from its starting point to find it. Tolerances, from the records' noise:

- a release test's wn is identified within ~0.1 % (the gauges of one record agree to 0.05 %, ``simulate release``);
  a mass from the bare wn (``wn^2 ~ 1/m``) to ~0.2 %, the housing's stiffness from the housed wn given the mass to
  ~0.5 %: :data:`STIFFNESS_RTOL` 2 % leaves the 20 mm release's amplitude (its nonlinearity against the linear
  modes the fit uses) its share;
- zeta scatters by ~2 % between gauges (a median over a digit's gauges): the dampings within :data:`DAMPING_RTOL`;
- a channel's gain to its slope's standard error from the sweep's scatter and drift (the fit reports it): within
  three of them, :data:`GAIN_SIGMAS`.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from flexdigit.calibrate.record_files import read_release
from flexdigit.cli import main
from flexdigit.cli.simulate import RELEASE_CYCLES, RELEASE_DECAY
from flexdigit.params import load_params
from flexdigit.twin.calibration import load_calibration, save_calibration
from flexdigit.twin.digit_calibration import calibration_for

HANDMADE = Path(__file__).resolve().parent.parent / "data" / "handmade_digits"
STIFFNESS_RTOL = 0.02
DAMPING_RTOL = 0.10
GAIN_SIGMAS = 3.0
#: The "rig"'s calibration against the digit's derived default: masses x1.15 (their ratios kept), housing x1.1,
#: dampings x1.3.
PERTURB = {"mass": 1.15, "housing": 1.1, "beta": 1.3}
#: A digit of this file's own: six 60 mm strips (0.37 m) whose bare strip rings at 7.4 rad/s with zeta ~0.0014
#: (PERTURB's dampings): 12 periods (11 s) lose 10 % of the swing.
LIGHT_DIGIT = """[geometry]
section_count = 6
section_length_m = [0.06, 0.06, 0.06, 0.06, 0.06, 0.06]
gauge_positions_m = [0.02, 0.16, 0.30]
cable_eccentricity_m = 0.008
[actuator]
operating_commands = [8, 50]
"""
#: The strip's damping from a bare record that loses RELEASE_DECAY of its swing: within 2.6 % on this digit (seeds
#: 0-2) and on seven_sections_450mm (seeds 0-3), whose 12-period record had left it +17.3 / +2.9 / -11.9 / -3.4 %.
DECAYED_DAMPING_RTOL = 0.05
#: The decay read back from the record's identified wn and zeta: zeta within DECAYED_DAMPING_RTOL, and margin.
DECAY_READ_RTOL = 0.1


def _truth(params, mass=PERTURB["mass"], strip=PERTURB["beta"], gains=None):
    cal = calibration_for(params)
    gains = (1.0,) * len(cal.channel_gain) if gains is None else gains
    return cal.replace(
        support_mass_kg=tuple(m * mass for m in cal.support_mass_kg),
        housing_ei_n_m2=tuple(ei * PERTURB["housing"] for ei in cal.housing_ei_n_m2),
        strip_beta_s=cal.strip_beta_s * strip,
        housing_beta_s=cal.housing_beta_s * PERTURB["beta"],
        channel_gain=tuple(g * f for g, f in zip(cal.channel_gain, gains, strict=True)),
    )


def _records(name, tmp_path, capsys, kinds=("bare", "housed"), sweep=(), **truth):
    """The digit's records simulated from its perturbed calibration (seed 1): ``(params file, truth, files)``;
    ``sweep`` more flags of ``simulate sweep``."""
    path = name if isinstance(name, Path) else HANDMADE / f"{name}.toml"
    truth = _truth(load_params(path), **truth)
    cal_file = save_calibration(truth, tmp_path / "truth.toml")
    files = {}
    for kind in kinds:
        out = tmp_path / f"{kind}.csv"
        extra = {"bare": ["release", "--no-housing"], "housed": ["release"], "sweep": ["sweep", *sweep]}[kind]
        argv = ["simulate", *extra, "--params", str(path), "--calibration", str(cal_file), "--seed", "1"]
        assert main([*argv, "--out", str(out)]) == 0
        files[kind] = out
    capsys.readouterr()
    return path, truth, files


def _calibrate(path, files, out, capsys):
    flags = {"bare": "--release-bare", "housed": "--release-housed", "sweep": "--sweep"}
    argv = ["calibrate", "--params", str(path), "--out", str(out), "--json"]
    for kind, f in files.items():
        argv += [flags[kind], str(f)]
    code = main(argv)
    captured = capsys.readouterr()
    return code, (json.loads(captured.out) if code == 0 else captured.err)


def test_bare_and_housed_together_converge_on_the_thesis_template(tmp_path, capsys):
    """Issue 24 trial 1: 4 mechanical values (mass, housing, two dampings) against the 4 figures of the two release
    tests; was 'did not converge (maximum number of function evaluations)'."""
    path, truth, files = _records("thesis_template", tmp_path, capsys)
    code, data = _calibrate(path, files, tmp_path / "c.toml", capsys)
    assert code == 0, data
    assert set(data["fitted"]) >= {"support_mass_kg", "housing_ei_n_m2", "strip_beta_s", "housing_beta_s"}
    got = load_calibration(tmp_path / "c.toml")
    np.testing.assert_allclose(got.support_mass_kg, truth.support_mass_kg, rtol=STIFFNESS_RTOL)
    np.testing.assert_allclose(got.housing_ei_n_m2, truth.housing_ei_n_m2, rtol=STIFFNESS_RTOL)
    np.testing.assert_allclose(got.strip_beta_s, truth.strip_beta_s, rtol=DAMPING_RTOL)
    np.testing.assert_allclose(got.housing_beta_s, truth.housing_beta_s, rtol=DAMPING_RTOL)


@pytest.mark.slow
def test_a_lightly_damped_strip_is_recorded_until_its_swing_decays(tmp_path, capsys):
    """Trial 3: seven_sections_450mm's strip damping came out +17.8 %: its 12-period bare record lost 7 % of its
    swing, too little to read zeta from. ``simulate release`` now records until the swing has lost RELEASE_DECAY
    (as the thesis rig's bare 8 s do), and the damping is told (a 12-period record loses 10 % here)."""
    digit = tmp_path / "light.toml"
    digit.write_text(LIGHT_DIGIT)
    path, truth, files = _records(digit, tmp_path, capsys)
    code, data = _calibrate(path, files, tmp_path / "c.toml", capsys)
    assert code == 0, data
    bare = data["release_tests"]["bare"]
    duration = read_release(files["bare"])[0].t_s[-1]
    assert duration > RELEASE_CYCLES * 2 * np.pi / bare["wn_rad_s"]  # longer than 12 periods
    decay = 1 - np.exp(-bare["zeta"] * bare["wn_rad_s"] * duration)
    assert decay >= RELEASE_DECAY * (1 - DECAY_READ_RTOL)
    got = load_calibration(tmp_path / "c.toml")
    np.testing.assert_allclose(got.strip_beta_s, truth.strip_beta_s, rtol=DECAYED_DAMPING_RTOL)


def test_unequal_supports_keep_their_ratios(tmp_path, capsys):
    """Issue 24 trial 2: supports of 12/10/8 mm weigh 7.9/6.6/5.3 g in the records, not 5.55 g each: one wn gives
    one scale on the description's per-support masses."""
    path, truth, files = _records("nitinol_unequal_supports", tmp_path, capsys)
    code, data = _calibrate(path, files, tmp_path / "c.toml", capsys)
    assert code == 0, data
    got = np.asarray(load_calibration(tmp_path / "c.toml").support_mass_kg)
    want = np.asarray(truth.support_mass_kg)
    assert np.ptp(want) / want.max() > 0.3  # the supports do differ
    np.testing.assert_allclose(got, want, rtol=STIFFNESS_RTOL)
    np.testing.assert_allclose(got / got[0], want / want[0], rtol=1e-9)  # ratios kept exactly


def test_housed_and_sweep_give_every_gain_within_its_reported_error_or_keep_it(tmp_path, capsys):
    """Issue 24 trial 3: four_sections_geared_eight's gauges 7 and 8 came out -19 / +17 %, its records made tip up
    where it buckles. Now hung, as simulate and run mount it. Its 3:1 servo's sweep over 8..43 turns the tip a third
    as far as the thesis rig's: gauges 1 and 2 read lines too shallow for the gauges' drift to leave their gains
    within 5 % (7 %, 1 sd; seeds 0-2 fitted them -0.3, -10.0; -8.5, +2.1; -15.3, -1.2 %): kept at their starting
    values and said, with the sweep that would tell them. The others within 3 of their standard errors. The
    supports' mass and the strip's damping are the description's (a housed test alone cannot tell them from the
    housing's: they are kept, and the notes say so); the gains +-10 % on alternate gauges."""
    gains = (1.1, 0.9) * 4
    path, truth, files = _records(
        "four_sections_geared_eight", tmp_path, capsys, ("housed", "sweep"), mass=1.0, strip=1.0, gains=gains
    )
    code, data = _calibrate(path, files, tmp_path / "c.toml", capsys)
    assert code == 0, data
    assert data["orientation"] == "hanging"
    notes = " ".join(data["notes"])
    assert "kept support_mass_kg" in notes  # housed alone: mass or housing?
    assert "--release-bare" in notes
    kept = {int(k) for k in re.findall(r"kept channel_gain of gauge (\d+)", notes)}
    assert kept == {1, 2}, notes
    assert "a sweep over 8..113 (as far in tip rotation as the thesis rig's 8..43)" in notes
    errors = dict(re.findall(r"gauge (\d+) \+-(\d+) %", notes.split("standard errors from the sweep")[-1]))
    got = load_calibration(tmp_path / "c.toml").channel_gain
    start = calibration_for(load_params(path)).channel_gain
    for k, (g, t) in enumerate(zip(got, truth.channel_gain, strict=True)):
        if k + 1 in kept:
            assert g == start[k]  # the prior, never a confident wrong value
            continue
        se = max(float(errors.get(str(k + 1), 2)), 1.0) / 100  # under 2 % it is not reported
        assert se <= 0.05
        assert abs(g / t - 1) < GAIN_SIGMAS * se, (k + 1, g, t, se)


def test_a_geared_digits_sweep_over_the_thesis_tip_range_tells_every_gain(tmp_path, capsys):
    """The same digit swept over 8..113 (the note's advice: 3 of its commands a thesis command): every gain fitted,
    each told to within 5 % (1 sd; the drift's tilt falls as the root of the commands swept), within 3 of its
    standard errors of the records' own."""
    gains = (1.1, 0.9) * 4
    path, truth, files = _records(
        "four_sections_geared_eight",
        tmp_path,
        capsys,
        ("housed", "sweep"),
        mass=1.0,
        strip=1.0,
        gains=gains,
        sweep=["--commands", "8..113"],
    )
    code, data = _calibrate(path, files, tmp_path / "c.toml", capsys)
    assert code == 0, data
    notes = " ".join(data["notes"])
    assert "kept channel_gain" not in notes
    errors = dict(re.findall(r"gauge (\d+) \+-(\d+) %", notes.split("standard errors from the sweep")[-1]))
    got = load_calibration(tmp_path / "c.toml").channel_gain
    for k, (g, t) in enumerate(zip(got, truth.channel_gain, strict=True)):
        se = max(float(errors.get(str(k + 1), 2)), 1.0) / 100
        assert se <= 0.05
        assert abs(g / t - 1) < GAIN_SIGMAS * se, (k + 1, g, t, se)
