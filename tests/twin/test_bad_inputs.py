"""Bad inputs to the twin's public entry points give one clear error naming the culprit and the expected range.

Issue 3 ("Bad inputs (load beyond the tip, negative mass, command out of range, NaN) give clear errors"). The
expected ranges come from the default rig parameters (flexdigit.params, the thesis rig): commands 0..254 (255 is
the servo board's sync byte), the digit 0.27 m long (three 90 mm sections). Each message must quote the offending
value once, however many load cases repeat it, and say what was expected.
"""

import re

import numpy as np
import pytest

from flexdigit._validation import describe_values
from flexdigit.cli import main
from flexdigit.errors import ParameterError
from flexdigit.twin import records as ex
from flexdigit.twin.digit import Chain
from flexdigit.twin.twin import static_gauges_v


def _message(call) -> str:
    with pytest.raises(ParameterError) as info:
        call()
    return str(info.value)


# ------------------------------------------------------------------------------------------ static_load_test
def test_out_of_range_command_is_named_once_with_the_range():
    # 25 repetitions of 3 loads at 2 positions: 175 cases would carry the bad command
    msg = _message(lambda: ex.static_load_test([0.0125, 0.025, 0.0075], [0.01, 0.05], commands=[300]))
    assert "'commands' parameter of static_load_test" in msg
    assert "integers inside [0, 254]" in msg
    assert msg.endswith("Got 300 instead.")
    assert "static_gauges_v" not in msg


def test_several_bad_commands_are_listed_distinct_and_capped():
    msg = _message(lambda: ex.static_load_test([0.025], [0.01], commands=[8, 300, 300, 8.5, 255, 400, -1]))
    assert "inside [0, 254]" in msg
    assert "Got [-1, 8.5, 255, ...] (5 distinct values) instead." in msg


def test_load_position_beyond_the_tip_or_behind_the_clamp():
    msg = _message(lambda: ex.static_load_test([0.025], [0.05, -0.02]))
    assert "'positions_from_tip_m'" in msg
    assert "inside [0, 0.27) m from the tip" in msg
    assert "beyond the tip" in msg
    assert msg.endswith("Got -0.02 instead.")
    msg = _message(lambda: ex.static_load_test([0.025], [0.30]))
    assert msg.endswith("Got 0.3 instead.")


@pytest.mark.parametrize(("loads", "shown"), [([0.025, -0.01], "-0.01"), ([float("nan"), 0.025], "nan")])
def test_negative_or_nan_mass(loads, shown):
    msg = _message(lambda: ex.static_load_test(loads, [0.05]))
    assert "'loads_kg'" in msg
    assert "inside (0, inf) kg" in msg
    assert msg.endswith(f"Got {shown} instead.")


def test_static_gauges_v_quotes_a_repeated_bad_command_once():
    msg = _message(lambda: static_gauges_v(np.full(500, 0.01), np.full(500, 0.1), np.full(500, 300)))
    assert "inside [0, 254]" in msg
    assert msg.endswith("Got 300 instead.")


# ------------------------------------------------------------------------------------------------------ CLI
def test_cli_out_of_range_command_is_one_short_line(tmp_path, capsys):
    assert main(["simulate", "load", "--commands", "300", "--out", str(tmp_path / "x.parquet")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "Traceback" not in err
    assert "'--commands'" in err
    assert "integer inside [0, 254]" in err
    assert "Got 300 instead." in err
    assert "static_gauges_v" not in err
    assert err.count("300") == 1
    assert not (tmp_path / "x.parquet").exists()


@pytest.mark.parametrize(
    ("option", "value", "expected", "shown"),
    [
        ("--positions-cm", "30,5", "inside [0, 27) cm from the tip", "30"),
        ("--loads-g", "25,nan", "a finite real number inside [0.1, 2000] g", "nan"),
        ("--commands", "8..300", "inside [0, 254]", "300"),  # the range's end, refused before the range is built
    ],
)
def test_cli_load_options_are_checked_in_the_users_units(tmp_path, capsys, option, value, expected, shown):
    assert main(["simulate", "load", option, value, "--out", str(tmp_path / "x.parquet")]) == 2
    err = capsys.readouterr().err.strip()
    assert f"'{option}'" in err
    assert expected in err
    assert f"Got {shown} instead." in err


def test_cli_empty_command_range(tmp_path, capsys):
    assert main(["simulate", "sweep", "--commands", "43..8", "--out", str(tmp_path / "x.csv")]) == 2
    assert "low <= high" in capsys.readouterr().err


# ------------------------------------------------------------------------------------------ Chain.solve_static
@pytest.fixture(scope="module")
def chain():
    return Chain.uniform(length_m=0.24, ei_n_m2=0.01, n_cells=12)


def test_solve_static_rejects_a_load_beyond_the_tip(chain):
    msg = _message(lambda: chain.solve_static([[0.30]], [[[0.0, 1e-3]]]))
    assert "'load_s_m' parameter of Chain.solve_static" in msg
    assert "inside [0, 0.24] m" in msg
    assert "beyond the tip" in msg
    assert msg.endswith("Got 0.3 instead.")
    # a batch: only the culprit is quoted
    s = np.full((1000, 1), 0.1)
    s[17] = -0.01
    msg = _message(lambda: chain.solve_static(s, np.zeros((1000, 1, 2))))
    assert msg.endswith("Got -0.01 instead.")


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        (dict(tip_force_n=[[0.0, float("nan")]]), "tip_force_n"),
        (dict(tip_moment_nm=float("inf")), "tip_moment_nm"),
        (dict(load_s_m=[[0.1]], load_force_ab_n=[[[float("nan"), 1e-3]]]), "load_force_ab_n"),
        (dict(cable_shortening_m=[0.0, float("nan")]), "cable_shortening_m"),
        (dict(psi0=np.full(12, np.nan)), "psi0"),
    ],
)
def test_solve_static_rejects_non_finite_loads(chain, kwargs, name):
    msg = _message(lambda: chain.solve_static(**kwargs))
    assert f"'{name}' parameter of Chain.solve_static must be finite" in msg
    assert re.search(r"Got (nan|inf) instead\.$", msg)


def test_solve_static_rejects_mismatched_batches(chain):
    msg = _message(lambda: chain.solve_static(tip_force_n=[[0.0, 1e-3]] * 3, tip_moment_nm=[0.0, 1e-4]))
    assert "3 in 'tip_force_n', 2 in 'tip_moment_nm'" in msg
    msg = _message(lambda: chain.solve_static(load_s_m=[[0.1]]))
    assert "go together" in msg
    assert "'load_s_m'" in msg


def test_solve_static_still_broadcasts_one_case_against_many(chain):
    # one load case against two moments: both cases carry the load (the 1-D form is one load per case)
    one = chain.solve_static([[0.1]], [[[0.0, 1e-3]]], tip_moment_nm=[0.0, 1e-4])
    each = [chain.solve_static([[0.1]], [[[0.0, 1e-3]]], tip_moment_nm=m).tip_m[0] for m in (0.0, 1e-4)]
    np.testing.assert_allclose(one.tip_m, each, rtol=1e-9, atol=1e-15)


def test_describe_values_puts_non_finite_first():
    assert describe_values([300.0] * 400) == "300"
    assert describe_values([5.0, np.nan, 1.0, 2.0, 3.0]) == "[nan, 1, 2, ...] (5 distinct values)"
