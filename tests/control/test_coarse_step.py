"""A command step too coarse for issue 24's 2 % band is said, not run silently (the campaign's seed 3: 3.1 deg a
command). One frame of one command moves the tip about 0.2 of a command's rotation at its peak (the servo's
impulse response, 3.2.4), whatever the digit: 0.36 deg at the thesis rig's 1.7 deg, 0.62 deg at 3.1 deg, which is
the whole 2 % band of a 30 deg step (0.6 deg). The design is the search's all the same (the same controller);
its choice says the figure (``meets`` False, ``failing``), a ``DesignWarning`` says it, and ``run`` says it on stderr
in one line and in ``--json``'s ``design_warnings``."""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path

import numpy as np
import pytest

from digit_campaign import campaign_digit
from digits import DIGITS
from flexdigit.cli import main
from flexdigit.control import design20ms as dz
from flexdigit.errors import DesignWarning
from flexdigit.params import RigParams

#: The servo as identified (3.2.4) and the thesis rig's serial frame (5.2).
SERVO_WN, SERVO_ZETA, FRAME_S = 20.53, 0.5629, 0.020
#: The closed form's grid against the design's exact matrix exponentials on a 1 ms grid: the peak of a smooth
#: response between two grid points differs by at most ~(1 ms x wn)^2 / 8 of it.
PEAK_RTOL = 1e-3

#: tests/digit_campaign.py's campaign_digit(3): 3 x 140.1 mm of phosphor bronze, 0.444 m, a pair at 3.05 mm
#: eccentricity: a command turns the tip 3.1 deg (its sweep on the twin: 3.0995).
COARSE = campaign_digit(3)


def _servo_pulse_peak(per_command: float, frame_s: float) -> float:
    """The closed form: the second-order servo's unit step response ``s(t) = 1 - e^(-zeta wn t) (cos wd t +
    zeta / sqrt(1 - zeta^2) sin wd t)`` and a frame's pulse ``s(t) - s(t - T)``, its peak on a 10 us grid."""
    wd = SERVO_WN * math.sqrt(1 - SERVO_ZETA**2)

    def step(t):
        t = np.maximum(t, 0.0)
        decay = np.exp(-SERVO_ZETA * SERVO_WN * t)
        return 1 - decay * (np.cos(wd * t) + SERVO_ZETA / math.sqrt(1 - SERVO_ZETA**2) * np.sin(wd * t))

    t = np.arange(0.0, 1.0, 1e-5)
    return per_command * float(np.max(step(t) - step(t - frame_s)))


def test_one_frame_of_one_command_is_the_servos_pulse_response():
    """On 5.3's model (the servo times the rotation per command) the tip's peak after one frame is the closed form's,
    0.21 of a command at 20 ms; a short frame's is its impulse response's peak ``0.5155 wn`` times the frame."""
    plant = dz.design_plant()
    per_command = float(np.real(plant.dcgain()))
    assert dz.frame_pulse_deg(plant, FRAME_S) == pytest.approx(_servo_pulse_peak(per_command, FRAME_S), rel=PEAK_RTOL)
    assert dz.frame_pulse_deg(plant, FRAME_S) / per_command == pytest.approx(0.21, abs=0.005)
    wd_t = math.atan(math.sqrt(1 - SERVO_ZETA**2) / SERVO_ZETA)  # the impulse response's peak
    impulse_peak = SERVO_WN * math.exp(-SERVO_ZETA / math.sqrt(1 - SERVO_ZETA**2) * wd_t)
    assert impulse_peak / SERVO_WN == pytest.approx(0.5155, abs=1e-4)
    short = dz.frame_pulse_deg(plant, 1e-3) / per_command
    assert short == pytest.approx(1e-3 * impulse_peak, rel=0.02)


def test_a_digit_of_the_thesis_rigs_step_is_designed_without_a_word():
    """The one-section digit (1.67 deg a command): one frame moves its tip 0.37 deg, under the band; no warning."""
    params = RigParams.from_dict(DIGITS["one-section"])
    with warnings.catch_warnings():
        warnings.simplefilter("error", DesignWarning)
        design = dz.digit_design_20ms(params)
    assert design.choice.meets, design.choice.failing


#: The second hand-made set (tests/data/handmade_digits2): the two whose command turns the tip over 3 deg missed
#: the step on the twin (+30 deg, seeds 0-1: not settled in 2.5 s, or 1.06 and 1.67 s), those at 1.9-2.0 deg a
#: command settled in 0.19-0.28 s (measured at 6627992 with ``run --params D --setpoint-deg 30 --seed S``).
HANDMADE_2 = {
    "coarse_step_big_pulley": True,
    "thin_shim_three": True,
    "pair_tiny_pretension_tiny_e": False,
    "quarter_single_150mm": False,
}


@pytest.mark.parametrize("name", list(HANDMADE_2))
def test_the_hand_made_digits_too_coarse_for_the_band_are_the_ones_that_missed(name):
    from pathlib import Path

    from flexdigit.control.digit_model import digit_model
    from flexdigit.params import load_params

    params = load_params(Path(__file__).parents[1] / "data" / "handmade_digits2" / f"{name}.toml")
    model = digit_model(params, orientation=dz.digit_mount(params))
    pulse = dz.frame_pulse_deg(model.plant, params.actuator.serial_period_s)
    assert pulse / model.deg_per_command == pytest.approx(0.21, abs=0.02)  # the servo's share, as on 5.3's model
    assert (pulse >= dz.STEP_BAND_DEG) is HANDMADE_2[name]


@pytest.mark.slow
def test_a_coarse_command_step_is_said_in_one_line(tmp_path, capsys, monkeypatch):
    """The campaign's seed 3: one frame of one command moves its tip 0.62 deg (0.2 of its 3.12 deg); the design is
    the search's (the controller unchanged against a design that would not check), said in its choice, a
    ``DesignWarning``, and by ``run`` on stderr in one line and in ``--json``."""
    import tomli_w

    params = RigParams.from_dict(COARSE)
    with pytest.warns(DesignWarning) as caught:
        design = dz.digit_design_20ms(params)
    assert not design.choice.meets
    assert design.deg_per_command == pytest.approx(3.1, rel=0.02)
    pulse = 0.2 * design.deg_per_command  # the servo's share: 0.195-0.214 over the test digits' chains
    message = str(caught[0].message)
    assert "\n" not in message
    assert message == f"design: {design.choice.failing}"
    assert f"moves the tip {pulse:.1f}" in message
    assert "a finer command step" in message
    monkeypatch.setattr(dz, "STEP_BAND_DEG", math.inf)  # no check: the same controller, chosen as meeting
    unchecked = dz.digit_design_20ms(params)
    assert unchecked.choice.meets
    assert unchecked.weights == design.weights
    assert np.array_equal(unchecked.controller.A, design.controller.A)
    monkeypatch.undo()
    path = tmp_path / "coarse.toml"
    path.write_text(tomli_w.dumps(COARSE))
    with warnings.catch_warnings():
        warnings.simplefilter("error", DesignWarning)  # the CLI says it in its report: never a Python warning
        code = main(["design", "20ms", "--params", str(path), "--json"])
    captured = capsys.readouterr()
    assert code == 0
    assert captured.err == ""
    search = json.loads(captured.out)["search"]
    assert not search["meets"]
    assert "one frame of one command moves the tip" in search["failing"]


BIG_PULLEY = Path(__file__).parents[1] / "data" / "handmade_digits2" / "coarse_step_big_pulley.toml"


@pytest.mark.slow
def test_a_coarse_digit_whose_search_finds_none_runs_the_quietest_design_in_time(monkeypatch):
    """coarse_step_big_pulley (3.65 deg a command): the dither's rounding alone puts ~0.17 deg at the tip, over the
    search's noise limit whatever the weights, so none qualifies; the fastest (what a digit of a fine step gets
    then) passes the gauges' noise too. The coarse digit runs the quietest that still settles in time."""
    from flexdigit.params import load_params

    params = load_params(BIG_PULLEY)
    with pytest.warns(DesignWarning):
        quiet = dz.digit_design_20ms(params).choice
    monkeypatch.setattr(dz, "STEP_BAND_DEG", math.inf)  # not coarse to the design: the fastest of the stable
    fastest = dz.digit_design_20ms(params).choice
    assert not fastest.meets
    assert fastest.failing.startswith("noise")
    assert fastest.noise_sd_deg > dz.NOISE_LIMIT_DEG
    assert quiet.settling_time_s < dz.QUIET_SETTLING_S
    assert quiet.overshoot_percent < dz.OVERSHOOT_LIMIT_PERCENT
    assert quiet.noise_sd_deg < fastest.noise_sd_deg - 0.05  # 0.18 against 0.26 deg on the model


@pytest.mark.slow
def test_a_coarse_digit_driven_by_the_boards_own_timer_holds_the_band(capsys):
    """The same digit's step with the servo pulsed by the board's own timer (the reference firmware's drive): the
    dithered command's toggles reach the servo one per frame, and the tip settles within 2 % in 1 s (0.58 s, seed
    0). On the serial board, which reads one frame in 25 twice, the dither counts the board's pulses
    (tests/rig/test_board_pulses.py)."""
    code = main(
        ["run", "--backend", "sim?servo_drive=timer", "--params", str(BIG_PULLEY), "--setpoint-deg", "30", "--seed",
         "0", "--json"]
    )  # fmt: skip
    run = json.loads(capsys.readouterr().out)
    assert code == 0, run
    true = run["step_metrics"]["true"]
    assert true["settling_time_s"] is not None
    assert true["settling_time_s"] < 1.0
    assert true["overshoot_percent"] < 2.0
    assert abs(run["true_final_rotation_deg"] - 30.0) < 0.02 * 30.0
