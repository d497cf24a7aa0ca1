"""A metric with no value on a row is refused in words, never an infinity; the digits' report pieces stay quiet.

Issue 24's follow-up: on the 5-section, 8-gauge test digit, ``tip_stiffness_nm_per_rad`` was ``moment / 0 = inf``
on 8 of 500 rows of the report's sensitivity study (the probe moment's static solve came back to the same angles),
and ``equivalent_servo_angle`` divided 0 by 0 on short digits whose cable is slack at some of the protocol's
settings (a RuntimeWarning with an internal path on the console).
"""

import dataclasses
import warnings

import numpy as np
import pytest

from digits import write_digit
from flexdigit.params import RigParams, load_params, twin_cells
from flexdigit.report.ch8_studies import REPORT_PARAMETERS
from flexdigit.studies import metrics
from flexdigit.studies.metrics import METRICS, UNDEFINED, twin_figures
from flexdigit.studies.parameter_set import ParameterSet
from flexdigit.studies.sensitivity import twin_sensitivity
from flexdigit.studies.spec import load_spec
from flexdigit.tactile.thesis_experiments import _digit_protocol, equivalent_servo_angle
from flexdigit.twin.batched import BatchedChains
from flexdigit.twin.calibration import default_calibration, use_calibration
from flexdigit.twin.digit_calibration import calibration_for
from flexdigit.twin.records import release_orientation
from flexdigit.twin.twin import cached_digit, static_gauges_v

STIFFNESS = "tip_stiffness_nm_per_rad"
STUCK_ROW = 3  # the design row whose probe solve is made to return its starting angles


@pytest.fixture
def stuck_probe(monkeypatch):
    """The batched static solve with a tip moment returns row STUCK_ROW's starting angles: its tip does not turn
    (what the 5-section digit's rows 15, 16, 39, ... did), every other row as solved."""
    solve = BatchedChains.solve_static

    def stuck(self, shortening_m, *, tip_moment_nm=None, psi0=None, **kw):
        psi = solve(self, shortening_m, tip_moment_nm=tip_moment_nm, psi0=psi0, **kw)
        if tip_moment_nm is not None and psi0 is not None and self.size > STUCK_ROW:
            psi[STUCK_ROW] = psi0[STUCK_ROW]
        return psi

    monkeypatch.setattr(BatchedChains, "solve_static", stuck)


def _report_spec(baseline=None):
    """The report's sensitivity spec (chapter 8: ``ch8_studies._sensitivity``) about ``baseline``."""
    spec = load_spec(
        "thesis-tolerances", baseline=baseline, fields=tuple({name.split("[")[0] for name in REPORT_PARAMETERS})
    )
    return dataclasses.replace(spec, parameters=tuple(p for p in spec.parameters if p.name in REPORT_PARAMETERS))


def test_a_row_whose_tip_does_not_turn_has_no_stiffness_not_an_infinity(stuck_probe):
    sets = [ParameterSet(RigParams(), default_calibration()) for _ in range(STUCK_ROW + 2)]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no "divide by zero" RuntimeWarning either
        figures = twin_figures(sets, keep=False)
    stiffness = figures[STIFFNESS]
    assert np.isnan(stiffness[STUCK_ROW])
    others = np.delete(stiffness, STUCK_ROW)
    # the other rows keep the unpatched one-row value (the same rig): the refusal touches the stuck row only
    metrics._new_block()
    alone = twin_figures([ParameterSet()], keep=False)[STIFFNESS][0]
    np.testing.assert_allclose(others, alone, rtol=1e-9)  # batched vs one row: rounding of the batch only
    assert alone > 0  # a rigidity (the thesis rig: ~1.9 N m/rad, its cable taut mid-range)
    # the row's other metrics are untouched
    assert all(np.isfinite(figures[name][STUCK_ROW]) for name in ("release_wn_rad_s", "actuated_wn_rad_s"))


def test_the_study_refuses_the_metric_naming_it_the_row_and_why(stuck_probe):
    result = twin_sensitivity(4, seed=0, spec=_report_spec())
    assert not np.isinf(result.outputs[STIFFNESS]).any()
    assert np.flatnonzero(np.isnan(result.outputs[STIFFNESS])).tolist() == [STUCK_ROW]
    refusal = result.refused[STIFFNESS]
    assert f"row {STUCK_ROW}: {STIFFNESS} undefined: {UNDEFINED[STIFFNESS]}" in refusal
    assert "not finite on 1 of" in refusal
    assert not result.failed_rows  # the row ran: only the metric it cannot give is refused
    assert set(result.refused) == {STIFFNESS}  # the other metrics keep their indices


def test_the_eight_gauge_digit_is_hung_not_scored_about_a_shape_it_cannot_hold(tmp_path):
    """The 5-section, 8-gauge digit (0.5 m, derived calibration) buckles under its weight tip up: its tangent
    stiffness at rest has a negative eigenvalue, and its figures were of an equilibrium that does not hold (tip
    stiffness -294..0.014 N m/rad, inf on 8 rows). Its rows are hung tip down, as release_orientation and
    ``run --params`` mount it: every figure finite, the stiffness positive, the release mode the scalar twin's."""
    params = load_params(write_digit("five-sections-eight-gauges", tmp_path))
    with use_calibration(calibration_for(params), source="test"), warnings.catch_warnings():
        warnings.simplefilter("error")
        baseline = ParameterSet(params, default_calibration())
        result = twin_sensitivity(4, seed=0, spec=_report_spec(baseline))
        assert release_orientation(params) == "hanging"
        chains = BatchedChains.from_rigs([params], [baseline.calibration], housing=True, orientation="vertical")
        metrics._new_block()
        wn = METRICS["release_wn_rad_s"](baseline)
        # at the study's resolution, the description's (a scalar twin on the derived calibration runs finer)
        hung = cached_digit(params, baseline.calibration, True, "hanging", twin_cells(params))
    at_rest = chains.linearised(np.zeros((1, chains.n)), np.array([-np.inf]))[2][0]
    assert np.linalg.eigvalsh(at_rest)[0] < 0  # the cause, on the batched twin's own matrices
    assert not result.refused
    for name in result.metrics:
        assert np.all(np.isfinite(result.outputs[name])), name
    assert np.all(result.outputs[STIFFNESS] > 0)
    # the scalar twin's linear modal analysis of the hung digit (another implementation of the chain)
    np.testing.assert_allclose(wn, hung.linear_modes()[0][0], rtol=1e-6)  # one arithmetic, two codes


def test_the_thesis_rig_stands_and_keeps_every_twin_metric():
    result = twin_sensitivity(4, seed=0, spec=_report_spec())
    assert not result.refused
    assert np.all(result.outputs[STIFFNESS] > 0)


@pytest.mark.parametrize("digit", ["one-section", "short"])
def test_slack_settings_are_left_out_of_the_servo_equivalent(tmp_path, digit):
    params = load_params(write_digit(digit, tmp_path))
    with use_calibration(calibration_for(params), source="test"), warnings.catch_warnings():
        warnings.simplefilter("error")  # was: "invalid value encountered in divide" (0 / 0 on a slack cable)
        eq = equivalent_servo_angle(params)
        cal = default_calibration()
    # independent count: the protocol's settings whose cable carries tension, from the static twin directly
    plan = _digit_protocol("thesis-7.1-no-load", params).plan(params.geometry.digit_length_m)
    keys = np.unique(
        np.column_stack([plan["load_kg"], np.nan_to_num(plan["position_from_base_m"]), plan["command"]]), axis=0
    )
    _, sol = static_gauges_v(
        keys[:, 0], keys[:, 1], keys[:, 2].astype(int), params=params, calibration=cal, return_solution=True
    )
    taut = int(np.sum(sol.tension_n > 0))
    assert eq["settings"] == len(keys)
    assert 0 < eq["taut"] == taut < len(keys)  # these short digits' cable is slack under some loads
    assert 0 < eq["min_deg"] <= eq["median_deg"] <= eq["max_deg"] < 90  # a slack cable's 0 deg is not counted
    assert eq["median_us"] == pytest.approx(eq["median_deg"] * eq["us_per_command"] / params.actuator.deg_per_command)


def test_two_cables_servo_equivalent_is_a_magnitude(tmp_path):
    params = load_params(write_digit("four-sections-two-cables", tmp_path))
    with use_calibration(calibration_for(params), source="test"):
        eq = equivalent_servo_angle(params)
    # the actuated protocol reads a pair at its own commands both ways (tactile.protocols.digit_commands): bent
    # against it, one cable can go slack, so not every setting is counted; those counted are magnitudes
    assert 0 < eq["taut"] <= eq["settings"]
    assert eq["min_deg"] > 0  # was -5.7..-2.5 deg: the pair's tension falls as the servo turns
