"""The design study: layouts, candidates, the D-criterion and the Pareto front against independent checks."""

import dataclasses
import itertools

import numpy as np
import pytest

from flexdigit.errors import ParameterError
from flexdigit.params import RigParams, description_notes
from flexdigit.studies.design_study import (
    Candidate,
    DesignSettings,
    _information,
    _with_supports,
    candidates,
    d_criterion,
    d_optimal_positions,
    design_parameter_set,
    equal_positions,
    exchange_search,
    pareto_front,
    run_design,
)
from flexdigit.studies.metrics import METRICS, MetricContext, bayes_limits_by_prior
from flexdigit.studies.spec import ParameterSet, load_spec, spec_from_toml
from flexdigit.twin.digit_calibration import twin_calibration

THESIS = Candidate(3, "thesis", "half", 16, 219 / 254, 5.715e-3, 0.0, 1.0)


def test_pareto_front_against_brute_force():
    rng = np.random.default_rng(0)
    y = rng.random((60, 3))
    y[7] = np.nan  # a failed design is never on the front
    front = set(pareto_front(y).tolist())
    for i in range(60):
        dominated = any(
            np.all(y[j] <= y[i]) and np.any(y[j] < y[i]) for j in range(60) if j != i and np.all(np.isfinite(y[j]))
        )
        assert (i in front) == (np.all(np.isfinite(y[i])) and not dominated)


def test_equal_spacing_of_three_is_the_thesis_layout_and_stays_on_the_strip():
    p = RigParams()
    assert equal_positions(3, p) == pytest.approx(p.geometry.gauge_positions_m)  # table 3.5: midway (2.3.2)
    for n in range(3, 7):
        for x in equal_positions(n, p):  # never on a nylon support (90, 180 mm +- 5 mm)
            assert all(abs(x - s) > 0.005 for s in (0.09, 0.18))


def test_thesis_candidate_rebuilds_the_thesis_rig():
    ps = design_parameter_set(ParameterSet(), THESIS)
    base = RigParams()
    assert ps.params.geometry == base.geometry
    assert ps.params.sensors == base.sensors
    assert ps.params.actuator.deg_per_command == pytest.approx(base.actuator.deg_per_command)
    assert ps.antagonist_pretension_n is None


def test_finer_servo_second_cable_and_size_change_the_rig_as_asked():
    c = Candidate(6, "equal", "full", 12, 219 / 1016, 8e-3, 5.0, 1.25)
    ps = design_parameter_set(ParameterSet(), c)
    assert ps.params.geometry.digit_length_m == pytest.approx(1.25 * 0.27)
    assert len(ps.params.geometry.gauge_positions_m) == 6 == len(ps.calibration.channel_gain)
    assert ps.params.actuator.deg_per_command == pytest.approx(219 / 1016)
    # the operating range still reaches 30 deg of tip rotation (3.4.1) with the finer step
    gain = METRICS["rotation_gain_deg_per_command"](ps)
    lo, hi = ps.params.actuator.operating_commands
    assert (hi - lo) * gain >= 29.0
    # the pair of cables stiffens the tip (2.1: 'rigidity of the member')
    single = design_parameter_set(ParameterSet(), Candidate(6, "equal", "full", 12, 219 / 1016, 8e-3, 0.0, 1.25))
    assert METRICS["tip_stiffness_nm_per_rad"](ps) > 1.5 * METRICS["tip_stiffness_nm_per_rad"](single)


def test_full_bridge_and_more_bits_localise_better():
    ctx = MetricContext(redesign=True, bayes_samples=100)
    limit = {
        (b, bits): METRICS["bayes_position_limit_mm"](
            design_parameter_set(ParameterSet(), Candidate(3, "equal", b, bits, 219 / 254, 5.715e-3, 0.0, 1.0)), ctx
        )
        for b, bits in itertools.product(("half", "full"), (8, 16))
    }
    # E 2.3 vs E 2.4: the full bridge doubles the signal over the same amplifier noise
    assert limit["full", 16] < limit["half", 16]
    # an 8-bit card's 39 mV step adds 11 mV rms of quantisation noise to the 2 mV white noise
    assert limit["half", 8] > 2 * limit["half", 16]


def test_d_optimal_beats_every_pair_on_a_coarse_grid():
    # exchange search against exhaustive search for 2 gauges on a 10 mm grid
    ps = ParameterSet()
    from flexdigit.tactile.protocols import load_protocol

    jac, grid = _information(ps.params, ps.calibration, 0.01, tuple(load_protocol("thesis-6.1").loads_kg))
    best = max(d_criterion(jac, pair) for pair in itertools.combinations(range(grid.size), 2))
    positions, value, equal_value = d_optimal_positions(2, ps, step_m=0.01, seed=0)
    assert value == pytest.approx(best, abs=1e-9)
    assert value >= equal_value


def test_d_optimal_crowding_at_the_clamp_is_the_cantilevers_not_the_twins():
    # Closed form (Euler-Bernoulli cantilever, no cells): a load m at a bends a gauge at x < a by m g (a - x) / EI
    # and leaves one beyond it straight, so d/d(a/L) = m g L and d/d(m / 25 g) = 0.025 g (a - x) behind the load,
    # 0 ahead of it. Scaled onto the twin's gradients (one factor: volts per moment over the noise, which the
    # criterion's ridge makes matter), the same exchange search from the same starts puts 3 gauges where the
    # twin's information does, the first at the grid's edge by the clamp: the crowding is the physics of the
    # criterion (a mass is read best where its moment arm is longest; a load behind every gauge is not seen),
    # not the twin's 3 cells per section (the information uses 9).
    from flexdigit.tactile.protocols import load_protocol

    ps = ParameterSet()
    masses = tuple(load_protocol("thesis-6.1").loads_kg)
    jac, grid = _information(ps.params, ps.calibration, 0.0025, masses)
    length = ps.params.geometry.digit_length_m
    a, m = (x.ravel() for x in np.meshgrid(np.linspace(0.05 * length, length, 24), masses))
    behind = grid[None, :] < a[:, None]
    closed = np.stack(
        [np.where(behind, m[:, None] * 9.81 * length, 0.0), np.where(behind, 0.025 * 9.81 * (a[:, None] - grid), 0.0)],
        axis=-1,
    )
    closed *= np.sum(jac * closed) / np.sum(closed**2)
    assert np.linalg.norm(jac - closed) / np.linalg.norm(jac) < 0.25  # the twin is a cantilever, nearly
    positions, _, _ = d_optimal_positions(3, ps, step_m=0.0025, seed=0)
    rng = np.random.default_rng([0, 3, 23])  # d_optimal_positions' starts
    equal = [int(np.argmin(np.abs(grid - x))) for x in equal_positions(3, ps.params)]
    starts = [equal] + [sorted(rng.choice(grid.size, 3, replace=False).tolist()) for _ in range(3)]
    chosen, _ = exchange_search(closed, starts)
    np.testing.assert_allclose(grid[chosen], positions, atol=0.0025 + 1e-12)  # within one grid step
    assert positions[0] == pytest.approx(grid[0])
    assert positions[2] < 0.5 * length


def test_candidates_sample_keeps_the_thesis_design():
    settings = DesignSettings(samples=25)
    got = candidates(settings, seed=3)
    assert len(got) == 25
    assert any(c.is_thesis for c in got)
    # and the thesis design's equal-spacing twins, the designs the front is read against
    assert {
        c.gauge_count
        for c in got
        if c.layout == "equal"
        and c.bridge == "half"
        and c.size == 1.0
        and c.adc_bits == 16
        and c.pretension_n == 0
        and c.eccentricity_m == 5.715e-3
        and abs(c.servo_deg_per_command - 219 / 254) < 1e-9
    } == {3, 4, 5, 6}
    assert got == candidates(settings, seed=3) != candidates(settings, seed=4)
    assert all(c.gauge_count == 3 for c in candidates(DesignSettings(), 0) if c.layout == "thesis")


@pytest.mark.parametrize(
    "table, expected",
    [
        ("bridges = ['half', 'triple']", "bridges"),
        ("gauge_counts = [0, 3]", "gauge_counts"),
        ("size = []", "size"),
        ("pretension_n = [-1.0]", "pretension_n"),
        ("objectives = ['bayes_position_limit_mm']", "objectives"),
        ("gauges = [3]", "unknown key 'gauges'"),
    ],
)
def test_bad_design_tables_are_named(table, expected):
    spec = spec_from_toml(f"[design]\n{table}\n", source="d.toml")
    with pytest.raises(ParameterError) as err:
        DesignSettings.from_spec(spec)
    assert expected in str(err.value)
    assert "d.toml" in str(err.value)


def test_small_design_study_marks_the_thesis_on_its_front(tmp_path):
    spec = spec_from_toml(
        """
[study]
seed = 2
[design]
gauge_counts = [3]
layouts = ["thesis", "equal"]
bridges = ["half", "full"]
adc_bits = [16]
servo_deg_per_command = [0.8622]
eccentricity_m = [0.005715]
pretension_n = [0.0]
size = [1.0, 1.25]
bayes_samples = 50
"""
    )
    result = run_design(spec, tmp_path, workers=0, progress=False)
    marks = result.marked()
    assert "thesis layout" in marks
    assert "equal spacing, 3 gauges" in marks
    obj = result.objective_matrix()
    # the front is exactly the non-dominated designs, and the full bridge dominates the thesis's half bridge
    assert set(result.front.tolist()) == set(pareto_front(obj).tolist())
    assert marks["thesis layout"] not in set(result.front.tolist())
    assert np.all(np.isfinite(obj[marks["thesis layout"]]))


def test_shipped_design_spec_reads():
    settings = DesignSettings.from_spec(load_spec("thesis-design"))
    assert settings.samples > 0
    assert 3 in settings.gauge_counts
    assert "full" in settings.bridges


def test_a_front_design_exports_a_params_file_the_commands_take(tmp_path, capsys):
    # issue 24 item 6: design K on the front -> params TOML -> `flexdigit params` and `flexdigit simulate` take it
    from flexdigit.cli import main
    from flexdigit.params import load_params

    spec = tmp_path / "d.toml"
    spec.write_text(
        """
[study]
seed = 3
[design]
gauge_counts = [4]
layouts = ["equal"]
bridges = ["full"]
adc_bits = [16]
servo_deg_per_command = [0.4311]
eccentricity_m = [0.005715]
pretension_n = [0.0, 5.0]
size = [1.0, 1.25]
bayes_samples = 50
chunk_size = 2
"""
    )
    out = tmp_path / "out"
    base = ["study", "design", str(spec), "--out", str(out), "--workers", "0", "--no-progress"]
    assert main([*base, "--json"]) == 0
    summary = __import__("json").loads(capsys.readouterr().out)
    front = [row["row"] for row in summary["pareto_front"]]
    off = sorted(set(range(summary["candidates"])) - set(front))
    k = front[0]
    assert main([*base, "--export", str(k)]) == 0  # the finished study is read, not refused or rerun
    exported = out / f"design-{k}.toml"
    result = run_design(spec_from_toml(spec.read_text(), str(spec)), out, workers=0, progress=False)
    expected = design_parameter_set(ParameterSet(), result.candidates[k], seed=3).description()
    if expected.cables.count == 2:  # a pair is exported straight mid-range, its 30 deg either side (issue 24)
        a = expected.actuator
        span = a.operating_commands[1] - a.equilibrium_command
        expected = expected.replace(
            actuator=dataclasses.replace(a, equilibrium_command=127, operating_commands=(127 - span, 127 + span))
        )
    # a resized design's supports written out (not derived with a note that they are not 10 mm)
    expected = _with_supports(expected)
    assert load_params(exported) == expected  # the design's own rig: 4 gauges, geared servo, its cables and size
    assert len(load_params(exported).geometry.gauge_positions_m) == 4
    assert description_notes(load_params(exported)) == []
    text = exported.read_text().splitlines()
    # the template's notes tell the thesis rig's values: a key whose value differs says so (trial: "Half bridge"
    # written above bridge = "full")
    above_bridge = text[text.index('bridge = "full"') - 1]
    assert above_bridge.startswith("# (This digit's differs.) On the thesis rig: Half bridge")
    assert any(line.startswith("# Its servo step, 0.4311 deg a command") for line in text)
    # the limits of the file's own twin, by prior, as train computes them (trial 2: 0.131 mm scored, 1.47 trained)
    limits = bayes_limits_by_prior(
        ParameterSet(expected, twin_calibration(expected)), MetricContext(seed=3, bayes_samples=50)
    )
    said = [line for line in text if line.startswith("# Bayes limits of this file's twin")]
    assert len(said) == 1, said
    assert f"on its 'baseline' one): {limits['settings']:.3g} mm with" in said[0]
    assert f"{limits['span']:.3g} mm anywhere on their stretch" in said[0]
    capsys.readouterr()
    assert main(["params", str(exported)]) == 0
    assert "note:" not in capsys.readouterr().out
    assert main(["simulate", "release", "--params", str(exported), "--out", str(tmp_path / "r.parquet")]) == 0
    capsys.readouterr()
    assert main([*base, "--export", str(k)]) != 0  # never overwritten without --force
    assert "exists" in capsys.readouterr().err
    # a design off the front is refused in one line listing the front's rows
    assert main([*base, "--export", str(off[0]), "--export-to", str(tmp_path / "x.toml")]) == 2
    err = capsys.readouterr().err.strip()
    assert "not on the Pareto front" in err
    assert "\n" not in err


@pytest.mark.parametrize("kind", ["file", "directory", "no parent"])
def test_an_export_target_that_cannot_be_written_is_refused_before_the_study_runs(tmp_path, capsys, kind):
    # hostile review: '--export K --export-to EXISTING' ran the whole study, then refused the file and advised
    # --force, which would run the study again from its start
    from flexdigit.cli import main

    target = {"file": tmp_path / "taken.toml", "directory": tmp_path, "no parent": tmp_path / "no" / "x.toml"}[kind]
    if kind == "file":
        target.write_text("# someone's rig\n")
    out = tmp_path / "out"
    argv = ["study", "design", "thesis-design", "--out", str(out), "--workers", "0", "--export", "0"]
    assert main([*argv, "--export-to", str(target), "--no-progress"]) != 0
    err = capsys.readouterr().err.strip()
    assert str(target) in err
    assert "\n" not in err
    assert not out.exists()  # no journal: nothing ran
    if kind == "file":
        assert "runs the study again" in err
        assert target.read_text() == "# someone's rig\n"


def test_a_pair_design_is_exported_bending_both_ways():
    """Regression (issue-24 campaign, the study's front): a pair design was exported straight at the single
    cable's command 8, so `run --setpoint-deg -30` on it was refused (the servo reached -3.5 deg at most). It is
    exported straight mid-range (127, as a pair described without a straight command) with the design's span of
    commands either side; a single cable's design is exported as it was."""
    from flexdigit.params import Actuator, Cables, RigParams
    from flexdigit.studies.design_study import _bends_both_ways

    design = RigParams(actuator=Actuator(operating_commands=(8, 78)), cables=Cables(count=2, pretension_n=5.0))
    exported = _bends_both_ways(design).actuator
    assert (exported.equilibrium_command, exported.operating_commands) == (127, (57, 197))
    single = RigParams(actuator=Actuator(operating_commands=(8, 78)))
    assert _bends_both_ways(single) == single
