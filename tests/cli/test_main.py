"""The ``flexdigit`` command: sub-commands, --json, and one-line errors instead of tracebacks."""

import json

import pytest

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
    assert "gauge_factor" in err
    assert "Traceback" not in err
    assert main(["params", str(tmp_path / "missing.toml")]) == 2
    assert "no such file" in capsys.readouterr().err


def pytest_approx(x):
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


@pytest.mark.parametrize(
    "argv",
    [
        ["model"],
        ["model", "--json"],
        ["model", "--variant", "consistent", "--output", "tip_rotation_rad", "--json"],
        ["model", "--explain"],
        ["model", "--variant", "consistent", "--output", "gauge_v_sg2", "--gains", "measured", "--explain"],
    ],
)
def test_model_command_imports_no_heavy_library(argv):
    # start-up (issue 15 item 6): the plant is numpy polynomials (flexdigit.models.polytf), so `flexdigit model`
    # runs without python-control (2 s of imports: scipy.signal, scipy.stats, matplotlib.pyplot)
    loaded = _imported_after(f"from flexdigit.cli import main; assert main({argv!r}) == 0")
    assert not loaded & set(HEAVY), loaded & set(HEAVY)


# -- errors as JSON under --json (issue 16): a client always gets one JSON object on stdout, exit 2 ---------------
@pytest.mark.parametrize(
    "argv, error_type, needle",
    [
        (["params", "--seed", "1", "--json"], "UsageError", "unrecognized arguments: --seed"),
        (["collect", "thesis-6.1", "--out", "x.parquet", "--seed", "abc", "--json"], "UsageError", "an integer"),
        (["simulate", "release", "--json"], "UsageError", "required: --out"),
        (["params", "missing.toml", "--json"], "FileNotFoundError", "no such file: missing.toml"),
        (["run", "--backend", "nosuch://x", "--json"], "ParameterError", "nosuch://x"),
    ],
)
def test_errors_are_json_on_stdout_under_json(argv, error_type, needle, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    captured = capsys.readouterr()
    doc = json.loads(captured.out)  # stdout holds exactly one JSON object
    assert doc["exit_code"] == 2
    assert doc["error_type"] == error_type
    assert needle in doc["error"]
    assert doc["command"] == argv[0] or (argv[0] == "simulate" and doc["command"] == "simulate release")
    assert "Traceback" not in captured.err
    assert len(captured.err.strip().splitlines()) == 1


def test_errors_without_json_stay_one_line_on_stderr(capsys):
    assert main(["params", "--seed", "1"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith("flexdigit params: error: unrecognized arguments")


def test_an_internal_error_is_one_line_not_a_traceback(monkeypatch, capsys):
    import flexdigit.cli.params_file as pc

    def broken(args):
        raise RuntimeError("boom")

    monkeypatch.setattr(pc, "_params", broken)
    assert main(["params", "--json"]) == 2
    doc = json.loads(capsys.readouterr().out)
    assert doc["error_type"] == "RuntimeError"
    assert "internal error" in doc["error"]
    assert "boom" in doc["error"]


def test_collect_json_keeps_progress_off_stdout(tmp_path, capsys):
    """The progress bar goes to stderr; before issue 16 it went into stdout and broke the JSON."""
    protocol = tmp_path / "p.toml"
    protocol.write_text(
        'name = "tiny"\nloads_g = [25.0]\npositions_from_tip_cm = [0, 5]\nrepetitions = 2\n'
        "no_load_repetitions = 1\nsettle_s = 0.5\n"
    )
    out = tmp_path / "d.parquet"
    assert main(["collect", str(protocol), "--out", str(out), "--json"]) == 0
    captured = capsys.readouterr()
    doc = json.loads(captured.out)
    assert doc["samples"] == 2 * (1 + 2)  # a protocol file tares before each position (docs/tactile): no-load + 2 each
    assert doc["protocol"] == "tiny"
    assert "tiny" in captured.err  # the bar was drawn, on stderr


def test_only_the_program_leaves_its_heap_to_the_exit(tmp_path, capsys):
    """``flexdigit`` as a program freezes its heap as it returns (the exit then frees nothing one by one) and its
    file is written whole; :func:`main` called in a caller's process leaves that process's collector alone."""
    import gc
    import subprocess
    import sys

    frozen = gc.get_freeze_count()
    assert main(["params", "--json"]) == 0
    capsys.readouterr()
    assert gc.get_freeze_count() == frozen
    out = tmp_path / "rig.toml"
    code = (
        "import atexit, gc, sys\n"
        "atexit.register(lambda: print('frozen', gc.get_freeze_count(), file=sys.stderr))\n"
        "from flexdigit.cli import main\n"
        f"sys.argv = ['flexdigit', 'params', '--write', {str(out)!r}]\n"
        "raise SystemExit(main())\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert int(done.stderr.split("frozen")[-1]) > 10_000  # the heap: numpy and the domains' objects
    assert "[geometry]" in out.read_text()
