"""`flexdigit palpate --protocol hold --params D.toml --json` on the digits whose force hung on the contact's place
(issue 24: the short digit held -29 %, the one-gauge digit had no contact place to stand on), from the command line.

References: the twin's true contact force and centroid, logged beside every sample (``true_force_n``,
``contact_place.true_steady_mm``). Tolerances: ``HOLD = 0.10``, the issue's 10 % of the setpoint over the hold's
last 3 s; ``PLACE_MM = 15``: the estimate's median place against the twin's centroid over the same 3 s (the point
model reads a 20-30 mm stretch of contact; 9 mm apart on the short digit, its Cramer-Rao sd 6.7 mm over 3 s).
"""

from __future__ import annotations

import json

import pytest

from digits import DIGITS, write_digit
from flexdigit.cli import main

HOLD = 0.10
PLACE_MM = 15.0


def _digit_and_block(name: str, tmp_path):
    """The digit's description and a 1000 N/m^2 block beside its outer 45 % (from 0.55 L to 80 mm past the tip,
    0.1 L away), as files."""
    digit = write_digit(name, tmp_path)
    length_mm = 1000 * DIGITS[name]["geometry"]["digit_length_m"]
    tissue = tmp_path / "tissue.toml"
    tissue.write_text(
        f'[tissue]\nname = "block"\nside = "cable"\nstart_mm = {0.55 * length_mm:.1f}\nend_mm = {length_mm + 80:.1f}'
        f"\ngap_mm = {0.1 * length_mm:.1f}\nmodulus_n_m2 = 1000.0\n"
    )
    return digit, tissue


def _hold(name: str, tmp_path, capsys) -> dict:
    digit, tissue = _digit_and_block(name, tmp_path)
    argv = ["palpate", "--params", str(digit), "--tissue", str(tissue), "--protocol", "hold", "--json"]
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


def test_the_short_digit_holds_its_force_and_tells_the_place(tmp_path, capsys):
    held = _hold("short", tmp_path, capsys)
    assert held["scored_on"] == "true contact force (twin)"
    assert abs(held["steady_error"]) < HOLD, held["steady_error"]
    place = held["contact_place"]
    assert place["told"]
    assert place["narrowed"]
    assert place["searched_mm"][0] > 120.0  # from its outer gauge (125 mm) on, not from the tissue's 82.5 mm
    assert abs(place["error_mm"]) < PLACE_MM, place
    assert "estimate_note" not in held
    assert held["estimate_sd_n"] < HOLD * held["setpoint_n"]


def _hold_at(name: str, setpoint_n: float, tmp_path, capsys) -> tuple[int, dict, str]:
    """``palpate --protocol FILE`` holding ``setpoint_n`` for 10 s beside the block of :func:`_digit_and_block`: exit
    code, JSON and stderr."""
    digit, tissue = _digit_and_block(name, tmp_path)
    protocol = tmp_path / "hold.toml"
    protocol.write_text(f"[force]\nsetpoint_n = {setpoint_n}\nduration_s = 10.0\n")
    argv = ["palpate", "--params", str(digit), "--tissue", str(tissue), "--protocol", str(protocol), "--json"]
    code = main(argv)
    captured = capsys.readouterr()
    return code, json.loads(captured.out), captured.err


def test_a_one_gauge_digit_refuses_a_force_it_cannot_read_within_10_percent(tmp_path, capsys):
    """Its one gauge reads 36 mN a reading and drifts 3.6 mN/sqrt(s), which it cannot tell from force: over a 10 s
    hold its force read is uncertain by 12 mN (1 sd), 12 % of 0.1 N. Its twin held -25, -27 and -22 % on seeds 1, 2
    and 4 and said "completed"; now refused before the digit moves, in one line naming the least force it holds
    (0.34 N: a larger force tares on fewer readings, palpation._least_held)."""
    code, out, err = _hold_at("one-section", 0.1, tmp_path, capsys)
    assert code == 2
    assert err.count("\n") == 1
    assert "cannot hold 0.1 N within 10 %" in err
    assert "uncertain by 12 mN" in err
    assert "it holds 0.34 N or more within 10 %" in err
    assert "not moved" in out["error"]


def test_a_one_gauge_digit_holds_the_least_force_it_names(tmp_path, capsys):
    """At the 0.34 N the refusal names, the one-gauge digit holds within 10 % of the twin's true force; its place is
    refused (one gauge reads one number, the force times its lever)."""
    code, held, _ = _hold_at("one-section", 0.34, tmp_path, capsys)
    assert code == 0, held
    assert abs(held["steady_error"]) < HOLD, held["steady_error"]
    place = held["contact_place"]
    assert place["steady_mm"] is None
    assert not place["told"]
    assert "one gauge" in place["reason"]
    assert place["true_steady_mm"] is not None  # the twin's contact was there: the place is refused, not missed
    assert held["estimate_sd_n"] <= 0.05 * held["setpoint_n"]
    # a contact read (a point, or at this force the line load its reference press reads better) over the window
    assert held["decisions"]["none"] < 0.1 * sum(held["decisions"].values())


@pytest.mark.parametrize(
    ("setpoint_n", "code", "said"),
    [(0.1, 0, None), (1.0, 2, "hold: never reached 1 N: pressing at its last command 254")],
)
def test_a_fine_step_digit_presses_over_its_range_or_says_why_not(setpoint_n, code, said, tmp_path, capsys):
    """A design-front digit (6 gauges, a pretensioned pair: straight at 127; 0.31 deg of tip a command) beside a
    body 27 mm away. Within 52 commands past straight its statics pressed at most 0.07 N: after 10 s it was still
    approaching ("no contact seen", -99.6 %). Its range is now the thesis rig's in tip rotation (127..254,
    palpation._press_commands): 0.1 N holds; 1 N, more than its 254 presses (0.6 N), ends in one line, exit 2."""
    from pathlib import Path

    digit = Path(__file__).parents[1] / "data" / "handmade_digits" / "design_front_30_six_gauges_pair.toml"
    tissue = tmp_path / "tissue.toml"
    tissue.write_text(
        '[tissue]\nname = "block"\nside = "cable"\nstart_mm = 148.5\nend_mm = 350.0\ngap_mm = 27.0\n'
        "modulus_n_m2 = 1000.0\n"
    )
    protocol = tmp_path / "hold.toml"
    protocol.write_text(f"[force]\nsetpoint_n = {setpoint_n}\nduration_s = 10.0\n")
    argv = ["palpate", "--params", str(digit), "--tissue", str(tissue), "--protocol", str(protocol), "--json"]
    assert main(argv) == code
    out = json.loads(capsys.readouterr().out)
    if said is None:
        assert abs(out["steady_error"]) < HOLD
        assert "limit_note" not in out
    else:
        assert out["error"].startswith(said), out


def test_a_hold_that_holds_says_nothing_of_limits(tmp_path, capsys):
    assert "limit_note" not in _hold("short", tmp_path, capsys)
