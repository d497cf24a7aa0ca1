"""Error lines a user reads (trial 2 of hand-made digits, 2026-11-27): a nested command named whole, a byte-order
mark skipped, a huge echoed value cut to a readable line."""

from __future__ import annotations

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
