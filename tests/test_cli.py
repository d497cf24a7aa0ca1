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


#: Libraries a sub-command may import when it runs, never to build the parser (``flexdigit --help``).
HEAVY = ("scipy", "control", "sklearn", "cvxpy", "matplotlib", "pyarrow", "slycot")


def _imported_after(code: str) -> set[str]:
    import subprocess
    import sys

    probe = code + "\nimport sys; print(' '.join(sorted({m.split('.')[0] for m in sys.modules})))"
    out = subprocess.run([sys.executable, "-c", probe], check=True, capture_output=True, text=True).stdout
    return set(out.split())


def test_parser_and_light_commands_import_no_heavy_library():
    # start-up (issue 15): the parser loads every sub-command's options and nothing they compute with, so
    # `flexdigit --help` does not pay for python-control, scipy, cvxpy...; `params` needs numpy only
    assert not _imported_after("from flexdigit.cli import build_parser; build_parser()") & set(HEAVY)
    loaded = _imported_after("from flexdigit.cli import main; main(['params', '--json'])")
    assert not loaded & set(HEAVY), loaded & set(HEAVY)
