"""The 20 ms loop run on the batched twin: against the scalar loop (run_loop on SimRig), the scalar runtime
controller, and the linear-model metrics where the two should agree."""

import dataclasses

import control as ct
import numpy as np
import pytest

from flexdigit.control.analysis import step_figures
from flexdigit.control.design20ms import closed_loop, design_20ms
from flexdigit.control.runtime import RuntimeController
from flexdigit.params import RigParams, twin_cells
from flexdigit.studies.batched_loop import BatchedRuntime, StepSchedule, step_figures_batch, step_responses
from flexdigit.studies.metrics import METRICS, MetricContext, loop_design, loop_plant, twin_figures
from flexdigit.studies.spec import ParameterSet

ROTATION_ATOL_DEG = 1e-6  # the batched and the scalar twin: the same arithmetic in another order (1e-9 rad)
STATE_ATOL = 1e-9

CTX = MetricContext()
ECCENTRIC = ParameterSet(
    params=dataclasses.replace(
        RigParams(), geometry=dataclasses.replace(RigParams().geometry, cable_eccentricity_m=5e-3)
    )
)


def test_batched_runtime_gives_the_scalar_runtimes_commands():
    # the 20 ms design's runtime (back-calculation fed the integer command) and a PI without anti-windup, driven
    # hard enough to saturate and quantise: the same integers and states as RuntimeController.update
    design = design_20ms(RigParams())
    pi = ct.ss(ct.tf([3.0, -2.5], [1.0, -1.0], 0.02))
    rng = np.random.default_rng(7)
    for make in (lambda: design.runtime(RigParams()), lambda: RuntimeController(pi)):
        scalar = [make() for _ in range(3)]
        batch = BatchedRuntime([make() for _ in range(3)])
        r = rng.uniform(-20, 120, (200, 3))
        y = r + rng.normal(0, 15, (200, 3))
        for k in range(200):
            got = batch.update(r[k], y[k])
            want = [c.update(r[k, i], y[k, i]) for i, c in enumerate(scalar)]
            np.testing.assert_array_equal(got, want)
        np.testing.assert_allclose(batch.x, [c.state for c in scalar], atol=STATE_ATOL, rtol=1e-12)


def test_batched_loop_is_run_loop_on_the_scalar_twin():
    # the same controller on SimRig (the scalar twin at 2 ms) through flexdigit.rig.loop.run_loop, measuring the
    # twin's true tip rotation: the same commands and rotations sample for sample
    from flexdigit.rig.backends.sim_backend import SimRig
    from flexdigit.rig.loop import run_loop

    schedule = StepSchedule(step_deg=20.0, hold_s=0.6, after_s=0.6)
    sets = [ParameterSet(), ECCENTRIC]
    mid = twin_figures(sets)["_mid_rotation_deg"]
    run = step_responses(
        [p.params for p in sets],
        [p.calibration for p in sets],
        [loop_design(p, CTX).runtime(p.params) for p in sets],
        mid,
        schedule,
    )
    for i, ps in enumerate(sets):
        # at the batch's resolution, the description's: a scalar twin on a derived calibration runs finer
        rig = SimRig(ps.params, calibration=ps.calibration, cells_per_section=twin_cells(ps.params))
        rest = rig.tip_rotation_deg()
        ctl = loop_design(ps, CTX).runtime(
            ps.params, measure=lambda reading, rig=rig, rest=rest: rig.tip_rotation_deg() - rest
        )
        rotation = []
        result = run_loop(
            rig,
            ctl,
            setpoint=lambda t, i=i: run.low_deg[i] if t < schedule.hold_s - 1e-9 else run.high_deg[i],
            duration_s=schedule.hold_s + schedule.after_s,
            on_sample=lambda k, t, y, command, rotation=rotation: rotation.append(y),
            check_sensors=False,
        )
        assert result.status == "completed"
        np.testing.assert_array_equal(result.command, run.command[i])
        np.testing.assert_allclose(rotation, run.rotation_deg[i], atol=ROTATION_ATOL_DEG, rtol=0)


def test_twin_run_agrees_with_the_linear_loop_on_the_thesis_rig():
    # where they should agree: the rig the controller was designed for, at the linearisation point (a step
    # centred on the mid-range rotation). The twin's command is an integer latched within 0-19 ms (the linear
    # model: continuous, one whole sample late), so the figures agree to a few percent of the step and a sample
    ps = ParameterSet()
    run = step_responses(
        [ps.params],
        [ps.calibration],
        [loop_design(ps, CTX).runtime(ps.params)],
        twin_figures([ps])["_mid_rotation_deg"],
    )
    loop = closed_loop(loop_plant(ps, 0.02, 1), loop_design(ps, CTX).controller)
    t = np.arange(0.0, 10.0, 0.02)
    linear = np.squeeze(ct.step_response(loop, T=t).outputs)
    for band in (0.05, 0.10):  # 2 %: the digit's lightly damped actuated mode rings at the band's edge
        lin = step_figures(t, linear, target=linear[-1], band=band)
        lin_settling, lin_overshoot = lin.settling_time_s, lin.overshoot_percent
        twin = step_figures_batch(run, band)
        assert twin["settling_time_s"][0] == pytest.approx(lin_settling, abs=0.04)  # two samples
        assert twin["overshoot_percent"][0] == pytest.approx(lin_overshoot, abs=1.0)
    # the registry's linear figure is that same 2 % computation
    assert METRICS["overshoot_percent"](ps, CTX) == pytest.approx(
        step_figures(t, linear, target=linear[-1]).overshoot_percent, rel=1e-9
    )
    # the design holds the integer command's offset within half a quantum (design20ms, point 4)
    half_quantum = 0.5 * METRICS["rotation_gain_deg_per_command"](ps, CTX)
    assert 0 <= METRICS["twin_steady_state_error_deg"](ps, CTX) <= half_quantum


def test_twin_run_metrics_batched_equal_single():
    sets = [ParameterSet(), ECCENTRIC]
    for name in ("twin_settling_time_s", "twin_overshoot_percent", "twin_steady_state_error_deg"):
        batched = METRICS[name].batched(sets, CTX)
        single = [METRICS[name](ps, CTX) for ps in sets]
        np.testing.assert_allclose(batched, single, rtol=1e-12)
    # a cable nearer the strip (5 mm, not 5.7) turns the tip more per command (E 3.15, r_M / e): the baseline
    # controller, tuned for less, overshoots more
    assert METRICS["twin_overshoot_percent"](ECCENTRIC, CTX) > METRICS["twin_overshoot_percent"](ParameterSet(), CTX)


def test_step_schedule_refuses_bad_numbers():
    with pytest.raises(ValueError, match="step_deg"):
        StepSchedule(step_deg=0.0)
    with pytest.raises(ValueError, match="tail_s"):
        StepSchedule(after_s=0.4, tail_s=0.5)
