"""The ``flexdigit`` command: sub-commands, --json, and one-line errors instead of tracebacks."""

import json

from flexdigit.cli import main


def test_params_json_and_write(tmp_path, capsys):
    out = tmp_path / "rig.toml"
    assert main(["params", "--write", str(out), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["params"]["actuator"]["equilibrium_command"] == 8
    assert data["derived"]["second_moment_m4"] == pytest_approx(5.8532e-14)
    assert "[geometry]" in out.read_text()


def test_bad_file_gives_one_line_error(tmp_path, capsys):
    bad = tmp_path / "rig.toml"
    bad.write_text("[sensors]\ngauge_factor = 'big'\n")
    assert main(["params", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "gauge_factor" in err and "Traceback" not in err
    assert main(["params", str(tmp_path / "missing.toml")]) == 2
    assert "no such file" in capsys.readouterr().err


def pytest_approx(x):
    import pytest

    return pytest.approx(x, rel=1e-4)
