"""Short, complete reprs (issue 23): a plant, a design, a loop's result, an identification, a parameter set or a
robot prints what it is and its key figures in a few lines, never pages of arrays (``flexdigit._repr``).

Each test checks the line count and that the figure a reader looks for is there, with the value computed here
independently of the object's own properties where one can be.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from flexdigit._repr import differences, summary
from flexdigit.calibrate.twin_fit import CalibrationResult
from flexdigit.control import design_20ms, mixsyn_on_the_digit, thesis_design
from flexdigit.control.analysis import StepFigures
from flexdigit.identify import TimeSeries, identify
from flexdigit.models.plant import build_plant
from flexdigit.params import RigParams, Sensors
from flexdigit.rig import open_rig
from flexdigit.rig.step_test import step_test
from flexdigit.studies import load_spec
from flexdigit.studies.parameter_set import ParameterSet
from flexdigit.tdcr import Robot, Segment, Tendon, solve_statics
from flexdigit.tdcr.dynamics import simulate
from flexdigit.twin import release_test
from flexdigit.twin.calibration import Calibration, default_calibration
from flexdigit.twin.digit import Chain
from oracles import DIGIT, release_record

#: A repr is a few lines at most.
MAX_LINES = 3
#: A parameter object lists every field, so may take a few more (the twin's Calibration: 12 fields, 5 lines).
MAX_FIELD_LINES = 6
#: Characters of the longest repr a user meets here; before issue 23's audit a Calibration printed 620 (17-digit
#: floats), a TwinRecord 3,300 (pyarrow's dump), a StudySpec 5,700 (every parameter's source).
MAX_CHARS = 600


def _lines(obj) -> list[str]:
    return repr(obj).splitlines()


def test_summary_wraps_long_figures_and_shows_large_arrays_by_shape():
    text = summary("Thing", big=np.zeros((40, 3)), small=np.array([1.5, 2.0]), **{f"k{i}": 1.0 for i in range(30)})
    assert text.startswith("Thing(big=<float64 array 40x3>, small=[1.5, 2], k0=1")
    assert max(len(line) for line in text.splitlines()) <= 110
    assert text.endswith("k29=1)")


def test_summary_puts_the_unit_after_the_value():
    assert summary("Fit", wn=(12.3456, "rad/s")) == "Fit(wn=12.35 rad/s)"


def test_differences_names_the_nested_field_that_changed():
    params = RigParams().replace(sensors=Sensors(bridge="full", excitation_v=2.0))
    assert differences(params, RigParams()) == {"sensors.bridge": "full", "sensors.excitation_v": 2.0}


def test_plant_repr_names_order_dc_gain_with_unit_and_poles():
    plant = build_plant()
    num, den = plant.poly.num, plant.poly.den
    assert len(_lines(plant)) <= MAX_LINES
    assert "array" not in repr(plant)  # the dataclass repr printed A, B, C, D: 11 lines
    assert "order=4" in repr(plant)
    assert f"dc_gain={num[-1] / den[-1]:.4g} m/command" in repr(plant)
    assert "rad/s" in repr(plant)


def test_rig_params_repr_is_what_differs_from_the_thesis():
    assert repr(RigParams()) == "RigParams(thesis_defaults=True)"
    assert repr(RigParams().replace(sensors=Sensors(bridge="full"))) == "RigParams(sensors.bridge='full')"


def test_parameter_set_repr_names_the_antagonist_and_the_changes():
    text = repr(ParameterSet(params=RigParams().replace(sensors=Sensors(bridge="full")), antagonist_pretension_n=5))
    assert text == "ParameterSet(antagonist_pretension_n=5, sensors.bridge='full')"


def test_robot_and_its_solutions_print_their_figures():
    robot = Robot(name="rod", segments=(Segment(0.2, 5), Segment(0.1, 5)), tendons=(Tendon(disk=10),))
    assert repr(robot).startswith("Robot(name='rod', length_m=0.3, segments=2, disks=10, tendons=1,")
    assert len(_lines(robot)) <= MAX_LINES
    static = solve_statics(robot, [0.0])
    assert len(_lines(static)) <= MAX_LINES
    assert "converged=True" in repr(static)
    assert "tip_m=[0, 0, 0.3]" in repr(static)  # no tension, no gravity: straight up the z axis
    motion = simulate(robot, static, 0.01, dt_s=0.005)
    assert len(_lines(motion)) <= MAX_LINES
    assert "steps=3" in repr(motion)


def test_identification_and_time_series_print_wn_zeta_and_size():
    t, y = release_record(0, noise=0.02)
    series = TimeSeries.from_arrays(t, y)
    assert repr(series).startswith(f"TimeSeries(channel='y', unit='', samples={len(t)}, duration_s=")
    result = identify(series, "release", method="lsq")
    assert len(_lines(result)) <= MAX_LINES
    assert f"wn_rad_s={result.wn_rad_s:.4g}" in repr(result)
    assert result.wn_rad_s == pytest.approx(DIGIT["wn_rad_s"], rel=0.02)


def test_designs_print_gamma_orders_and_poles():
    hinf = thesis_design(5)
    assert len(_lines(hinf)) <= MAX_LINES
    assert f"gamma={hinf.gamma:.4g}" in repr(hinf)
    assert f"controller_order={hinf.controller.nstates}" in repr(hinf)
    digital = design_20ms()
    assert len(_lines(digital)) <= MAX_LINES
    assert "period_s=0.02" in repr(digital)
    assert f"largest_pole_radius={max(abs(digital.closed_loop_poles)):.4g}" in repr(digital)


def test_step_test_and_loop_result_print_status_and_figures():
    with open_rig("sim", seed=0) as rig:
        test = step_test(rig, duration_s=0.6)
    assert len(_lines(test)) <= MAX_LINES
    assert len(_lines(test.result)) <= MAX_LINES
    assert "status='completed'" in repr(test.result)
    assert f"samples={len(test.result.time_s)}" in repr(test.result)
    assert f"overshoot_percent={test.metrics.overshoot_percent:.4g}" in repr(test)


def test_fields_summary_lists_every_field_short():
    text = repr(StepFigures(0.1234567, 0.5, 0.6, 12.345678, 1.1, 0.2, 1.0, 0.0, 0.05, True))
    assert text.startswith("StepFigures(rise_time_s=0.1235, settling_time_s=0.5, settling_to_final_s=0.6,")
    assert "overshoot_percent=12.35" in text
    assert text.endswith("iae=0.05, bounded=True)")


def test_a_twin_static_solution_prints_its_arrays_by_shape():
    solution = Chain.uniform(length_m=0.2, ei_n_m2=0.01, n_cells=40).solve_static(tip_force_n=[[0.0, 1e-4]])
    assert len(_lines(solution)) <= MAX_LINES
    assert "converged=True" in repr(solution)
    assert "array" in repr(solution)


def test_calibration_result_names_success_cost_and_fitted_fields():
    result = CalibrationResult(Calibration(), cost=0.25, fitted=["strip_beta_s"], message="converged")
    assert repr(result) == (
        "CalibrationResult(success=True, cost=0.25, fitted=['strip_beta_s'], targets=0, message='converged')"
    )


def test_the_twin_calibration_prints_every_field_to_four_digits():
    cal = default_calibration()
    text = repr(cal)
    assert len(text.splitlines()) <= MAX_FIELD_LINES
    assert len(text) <= MAX_CHARS
    assert f"cable_stiffness_n_m={cal.cable_stiffness_n_m:.4g}" in text
    assert f"strip_beta_s={cal.strip_beta_s:.4g}," in text
    assert text.count("=") == len(dataclasses.fields(cal))  # complete: every field named once


def test_a_twin_record_prints_its_experiment_and_size_not_its_table():
    record = release_test(seed=0, duration_s=1.0)
    text = repr(record)
    assert len(_lines(record)) <= MAX_LINES
    assert text.startswith("TwinRecord(experiment='release_test', seed=0, rows=")
    assert f"rows={record.table.num_rows}," in text
    assert "'gauge1_v'" in text


@pytest.mark.filterwarnings("ignore::UserWarning")  # python-control's warnings on the weights, beside the point
def test_a_mixsyn_design_prints_its_order_and_gamma_not_its_coefficients():
    design = mixsyn_on_the_digit()[0]
    text = repr(design)
    assert len(_lines(design)) <= MAX_LINES
    assert "array" not in text  # the generated repr printed the controller's coefficient arrays over 6 lines
    assert f"controller_order={len(design.controller.den[0][0]) - 1}" in text
    assert f"gamma={design.hinf.gamma:.4g}" in text


def test_a_study_spec_prints_its_name_and_parameter_count():
    spec = load_spec("thesis-tolerances")
    text = repr(spec)
    assert len(_lines(spec)) <= MAX_LINES
    assert len(text) <= MAX_CHARS
    assert f"parameters=<{len(spec.parameters)} items>" in text
    assert "settings=['sensitivity']" in text


def test_a_twin_chain_prints_its_links_and_mass_not_the_object_address():
    chain = Chain.uniform(length_m=0.2, ei_n_m2=0.01, n_cells=40)
    text = repr(chain)
    assert len(_lines(chain)) <= MAX_LINES
    assert text.startswith("Chain(links=40, length_m=0.2,")  # was <flexdigit.twin.digit.Chain object at 0x...>
    assert f"total_mass_kg={chain.mass_kg.sum():.4g}" in text
