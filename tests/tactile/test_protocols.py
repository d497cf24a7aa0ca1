import numpy as np
import pytest

from digits import write_digit
from flexdigit.errors import ParameterError
from flexdigit.params import RigParams, load_params
from flexdigit.reference import thesis_value
from flexdigit.tactile.protocols import RELAXED, load_protocol, protocol_from_toml


def test_table_6_1_counts_match_thesis():
    # table 6.1 / thesis-values [tactile.non_actuated]: 3 loads x 16 positions x 25 + 75 no-load = 1275
    p = load_protocol("thesis-6.1")
    assert p.sample_count == thesis_value("tactile.non_actuated.samples") == 1275
    assert [round(m * 1000, 3) for m in p.loads_kg] == thesis_value("tactile.non_actuated.loads_g")
    assert [round(x * 100, 6) for x in p.positions_from_tip_m] == thesis_value(
        "tactile.non_actuated.positions_from_tip_cm"
    )
    assert not p.actuated
    plan = p.plan(0.270)
    assert np.sum(plan["load_kg"] == 0) == 75  # a no-load reading set at the start of every test
    assert np.all(plan["command"] == RELAXED)
    # first test starts with its no-load readings, then position 1 (the tip, 270 mm from the base)
    assert plan["load_kg"][0] == 0
    assert plan["position_index"][25] == 1
    assert plan["position_from_base_m"][25] == pytest.approx(0.270)


def test_table_7_1_counts_match_thesis():
    # table 7.1: 2 x 10 x 3 x 25 = 1500 (as printed; no-load readings are not in that count)
    p = load_protocol("thesis-7.1")
    assert p.sample_count == thesis_value("tactile.actuated.samples") == 1500
    assert list(p.actuation_commands) == thesis_value("tactile.actuated.actuation_commands")
    assert load_protocol("thesis-7.1-no-load").sample_count == 1500 + 2 * 3 * 25
    plan = p.plan(0.270)
    assert sorted(set(plan["command"].tolist())) == [0, 20, 40]


def test_user_protocol_and_clear_errors(tmp_path):
    p = protocol_from_toml('name = "mine"\nloads_g = [10]\npositions_from_tip_cm = [0, 5]\nrepetitions = 2\n')
    assert p.sample_count == 2 * (25 + 2)  # the 25 no-load readings before each position (tare_each_position)
    once = protocol_from_toml(
        'name = "mine"\nloads_g = [10]\npositions_from_tip_cm = [0, 5]\nrepetitions = 2\ntare_each_position = false\n'
    )
    assert once.sample_count == 2 * 2 + 25  # at the start of the test only, as the thesis's (6.5, 7.2)
    with pytest.raises(ParameterError, match="missing key 'loads_g'"):
        protocol_from_toml('name = "x"\npositions_from_tip_cm = [1]\n')
    with pytest.raises(ParameterError, match="unknown key 'load_g'"):
        protocol_from_toml('name = "x"\nload_g = [1]\npositions_from_tip_cm = [1]\n')
    with pytest.raises(ParameterError, match="repetitions"):
        protocol_from_toml('name = "x"\nloads_g = [1]\npositions_from_tip_cm = [1]\nrepetitions = 0\n')
    with pytest.raises(ParameterError, match="expected_samples"):
        protocol_from_toml('name = "x"\nloads_g = [1]\npositions_from_tip_cm = [1]\nexpected_samples = 3\n')
    with pytest.raises(ParameterError, match="actuation_commands"):
        protocol_from_toml('name = "x"\nloads_g = [1]\npositions_from_tip_cm = [1]\nactuation_commands = [300]\n')
    with pytest.raises(ParameterError, match="no protocol"):
        load_protocol(tmp_path / "absent.toml")
    with pytest.raises(ParameterError, match="must lie on the digit"):
        protocol_from_toml('name = "x"\nloads_g = [1]\npositions_from_tip_cm = [30]\n').plan(0.27)
    # re-hanging before every repetition: the thesis protocols do (7.1), user protocols choose, with a bool
    assert load_protocol("thesis-7.1").rehang
    assert not p.rehang
    with pytest.raises(ParameterError, match="'rehang' parameter .* true or false. Got 'yes'"):
        protocol_from_toml('name = "x"\nloads_g = [1]\npositions_from_tip_cm = [1]\nrehang = "yes"\n')


def test_positions_in_mm_written_as_cm_name_the_slip():
    # table 7.1's positions (0..18 cm) written in mm under positions_from_tip_cm: 0..1.8 m on a 0.27 m digit
    text = 'name = "x"\nloads_g = [25]\npositions_from_tip_cm = [0, 20, 40, 60, 80, 100, 120, 140, 160, 180]\n'
    with pytest.raises(ParameterError, match=r"must lie on the digit .* did you mean mm written as cm .*0\.18 m\)\?"):
        protocol_from_toml(text).plan(0.27)
    # beyond the digit even at a tenth: no slip guessed, just the range
    with pytest.raises(ParameterError, match=r"must lie on the digit .* instead\.$"):
        protocol_from_toml('name = "x"\nloads_g = [25]\npositions_from_tip_cm = [0, 150, 190]\n').plan(0.1)


def test_a_protocol_for_a_digit_is_one_library_call(tmp_path):
    # issue 23: `flexdigit collect PROTOCOL --params FILE` scaled a built-in protocol to the digit in the command
    # line; load_protocol(name, params) is that call now, and the command makes it
    short = load_params(write_digit("short", tmp_path))  # 0.15 m long
    thesis = load_protocol("thesis-6.1")
    on_short = load_protocol("thesis-6.1", short)
    ratio = short.geometry.digit_length_m / RigParams().geometry.digit_length_m
    assert on_short.positions_from_tip_m == pytest.approx([x * ratio for x in thesis.positions_from_tip_m], abs=1e-9)
    assert on_short.loads_kg == thesis.loads_kg
    assert load_protocol("thesis-6.1", RigParams()) == thesis  # the thesis digit: as written
    user = tmp_path / "far.toml"
    user.write_text('name = "far"\nloads_g = [25]\npositions_from_tip_cm = [20]\n')
    assert load_protocol(user).positions_from_tip_m == (0.2,)  # no digit given: as written, unchecked
    with pytest.raises(ParameterError, match="must lie on the digit"):
        load_protocol(user, short)  # a user's protocol is checked, not scaled: 20 cm is off a 15 cm digit


def test_a_refined_protocol_cuts_each_step_and_keeps_its_readings():
    """``Protocol.refined`` (``collect --refine``): thesis-6.1's 1 cm run cut into K steps, the 24 cm position (10
    steps past the run: no step of the run) kept alone, the repetitions divided by K rounded up."""
    p = load_protocol("thesis-6.1")
    fine = p.refined(4)
    run_cm = [round(100 * x, 6) for x in fine.positions_from_tip_m[:-1]]
    assert run_cm == [round(0.25 * k, 6) for k in range(57)]  # 0 to 14 cm in 0.25 cm steps
    assert fine.positions_from_tip_m[-1] == pytest.approx(0.24)
    assert fine.repetitions == 7  # ceil(25 / 4)
    assert fine.sample_count == 3 * 25 + 3 * 58 * 7  # 1293, against thesis-6.1's 1275
    assert p.refined(1) is p


def test_a_refined_protocol_refuses_a_factor_by_name():
    with pytest.raises(ParameterError, match="'factor'"):
        load_protocol("thesis-6.1").refined(0)
