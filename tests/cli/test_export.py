"""``flexdigit export controller``: writes the C pair atomically, refuses to overwrite without --force, --json."""

from __future__ import annotations

import json


def test_cli_export_controller(tmp_path):
    from flexdigit.cli import main

    out = tmp_path / "c.c"
    assert main(["export", "controller", "--out", str(out), "--format", "fixed", "--no-rotation-map"]) == 0
    assert main(["export", "controller", "--out", str(out), "--no-rotation-map"]) == 2  # exists: refused
    code = main(
        ["export", "controller", "--out", str(out), "--force", "--json", "--period-s", "0.005", "--no-rotation-map"]
    )
    assert code == 0
    assert "5000UL" in (tmp_path / "c.h").read_text()


def test_cli_export_json(tmp_path, capsys):
    from flexdigit.cli import main

    out = tmp_path / "c.c"
    assert main(["export", "controller", "--out", str(out), "--json", "--no-rotation-map"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc["analysis"]["closed_loop_stable"] is True
    assert doc["format"] == "float"
