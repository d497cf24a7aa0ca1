"""Error lines a user reads (trial 2 of hand-made digits, 2026-11-27): a nested command named whole, a byte-order
mark skipped, a huge echoed value cut to a readable line."""

from __future__ import annotations

from pathlib import Path

import pytest

from flexdigit.cli import MESSAGE_LIMIT, main
from flexdigit.params import RigParams, load_params


@pytest.mark.parametrize(
    ("argv", "prefix"),
    [
        (["design", "20ms", "--params", "MISSING"], "flexdigit design 20ms: error: no such file"),
        (["simulate", "release", "--params", "MISSING", "--out", "x.csv"], "flexdigit simulate release: error:"),
        (["tdcr", "statics", "MISSING", "--tension-n", "1"], "flexdigit tdcr statics: error:"),
    ],
)
def test_a_sub_command_reports_under_its_whole_name(argv, prefix, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith(prefix), err
    assert err.count("\n") == 1


def test_a_description_saved_with_a_byte_order_mark_loads(tmp_path, capsys):
    plain = tmp_path / "plain.toml"
    assert main(["params", "--write", str(plain)]) == 0
    marked = tmp_path / "marked.toml"
    marked.write_bytes(b"\xef\xbb\xbf" + plain.read_bytes())  # as Notepad saves "UTF-8 with BOM"
    capsys.readouterr()
    assert main(["params", str(marked)]) == 0
    assert load_params(marked) == load_params(plain) == RigParams()


def test_a_huge_value_echoed_in_an_error_is_cut_to_one_readable_line(tmp_path, capsys):
    n = 200_000  # 1.4 MB of positions: the refusal names the key, the line stays short
    path = tmp_path / "p.toml"
    positions = ", ".join(f"{0.01 + 0.001 * (i % 100):.3f}" for i in range(n))
    path.write_text(f"[geometry]\ngauge_positions_m = [{positions}]\n")
    assert main(["params", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert len(err) < MESSAGE_LIMIT + 200
    assert "gauge_positions_m" in err
    assert "characters left out" in err


def test_params_writes_the_calibration_every_command_uses_for_the_digit(tmp_path, capsys):
    """What the twin of a digit nobody measured runs on, printable and editable (trial 2: it was not)."""
    from flexdigit.twin.calibration import load_calibration
    from flexdigit.twin.digit_calibration import calibration_for, twin_calibration

    path = Path(__file__).parents[1] / "data" / "handmade_digits2" / "quarter_single_150mm.toml"  # 1 section
    digit = load_params(path)
    out = tmp_path / "cal.toml"
    assert main(["params", str(path), "--write-calibration", str(out)]) == 0
    written = load_calibration(out)
    assert written == twin_calibration(digit) == calibration_for(digit)
    assert len(written.housing_ei_n_m2) == 1
    assert "scaled to this digit" in out.read_text().splitlines()[0]
    assert main(["params", str(path), "--write-calibration", str(out)]) == 2  # never over a file without --force
    assert "exists" in capsys.readouterr().err
    thesis = tmp_path / "thesis.toml"
    assert main(["params", "--write-calibration", str(thesis)]) == 0
    assert load_calibration(thesis) == twin_calibration(RigParams())
