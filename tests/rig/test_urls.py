"""One URL parser for every backend (issue 16): options declared once per backend, unknown ones refused by name,
values typed and range-checked from the declarations (0 is a value), a seed given twice must agree."""

from __future__ import annotations

import json

import pytest

from flexdigit.cli import main
from flexdigit.errors import ParameterError, RigError
from flexdigit.rig.backends import (
    board_backend,
    daq_backend,
    hil_backend,
    replay_backend,
    serial_backend,
    sim_backend,
    stream_backend,
)
from flexdigit.rig.base import BACKENDS, UrlOption, console_operator, open_rig, parse_rig_url, rig_url_options

MODULES = {
    "sim": sim_backend,
    "serial": serial_backend,
    "daq": daq_backend,
    "replay": replay_backend,
    "stream": stream_backend,
    "hil": hil_backend,
    "board": board_backend,
}
LOCATION = {
    "sim": "sim",
    "serial": "serial://loop://",
    "daq": "daq://0",
    "replay": "replay://run.jsonl",
    "stream": "stream:///dev/null",
    "hil": "hil://image.elf",
    "board": "board:///dev/ttyACM0",
}


# -- the reproductions of issue 16: unknown options reached the constructors (TypeError tracebacks) ---------------
@pytest.mark.parametrize(
    "url, culprit",
    [
        ("replay://run.jsonl?speed=2", "unknown option 'speed'; a replay URL takes run"),
        ("replay://run.jsonl?clock=2", "unknown option 'clock'"),  # a Python-only keyword is not URL text
        ("serial://loop://?sensor=1", "unknown option 'sensor'; a serial URL takes baud, channel"),
        ("sim?bogus=1", "sim: unknown option 'bogus'; a sim URL takes seed, orientation"),
        ("sim?seed=1&seed=2", "option 'seed' is given twice ('1' and '2')"),
        ("sim://here", "the twin takes no location"),
        ("replay://", "replay:// needs the recorded log"),
        ("daq://first", "the board must be a number"),
    ],
)
def test_bad_urls_are_refused_naming_the_option(url, culprit):
    with pytest.raises(ParameterError, match=culprit.replace("(", r"\(").replace(")", r"\)")):
        open_rig(url)


@pytest.mark.parametrize("url", ["replay://run.jsonl?speed=2", "serial://loop://?sensor=1", "sim?bogus=1"])
def test_the_cli_gives_one_line_for_a_bad_url(url, capsys):
    assert main(["run", "--backend", url]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "unknown option" in err
    assert "Traceback" not in err


# -- declarations drive the checks: every declared option, just inside and just outside its range ---------------
def _cases():
    for scheme, module in MODULES.items():
        for opt in module.URL_OPTIONS:
            yield scheme, opt


@pytest.mark.parametrize("scheme, opt", list(_cases()), ids=lambda v: getattr(v, "name", v))
def test_every_declared_option_is_typed_and_range_checked(scheme, opt: UrlOption):
    url = LOCATION[scheme]
    if opt.kind in ("int", "float"):
        if opt.low is not None:
            low_ok = opt.low if not opt.low_open else opt.low + 1e-9
            assert rig_url_options(f"{url}?{opt.name}={low_ok!r}")[1][opt.name] == pytest.approx(low_ok)
            below = opt.low - (1 if opt.kind == "int" else 1e-6)
            with pytest.raises(ParameterError, match=f"option {opt.name}="):
                rig_url_options(f"{url}?{opt.name}={below!r}")
        if opt.high is not None:
            above = opt.high + (1 if opt.kind == "int" else 1e-6)
            with pytest.raises(ParameterError, match=f"option {opt.name}="):
                rig_url_options(f"{url}?{opt.name}={above!r}")
        for bad in ("x", "nan", "inf", "1e999"):
            with pytest.raises(ParameterError, match=f"option {opt.name}='{bad}' must be"):
                rig_url_options(f"{url}?{opt.name}={bad}")
        if opt.kind == "int":
            with pytest.raises(ParameterError, match="must be an integer"):
                rig_url_options(f"{url}?{opt.name}=2.5")
    elif opt.kind == "bool":
        assert rig_url_options(f"{url}?{opt.name}=0")[1][opt.name] is False  # 0 is a value: false, not "absent"
        assert rig_url_options(f"{url}?{opt.name}=yes")[1][opt.name] is True
        with pytest.raises(ParameterError, match="must be a boolean"):
            rig_url_options(f"{url}?{opt.name}=maybe")
    elif opt.kind == "choice":
        assert rig_url_options(f"{url}?{opt.name}={opt.choices[0]}")[1][opt.name] == opt.choices[0]
        with pytest.raises(ParameterError, match="must be one of"):
            rig_url_options(f"{url}?{opt.name}=sideways")
    if not opt.none:  # an empty value is not "not given"
        with pytest.raises(ParameterError, match=f"option {opt.name}='' must be"):
            rig_url_options(f"{url}?{opt.name}=")


def test_every_backend_declares_its_options():
    assert set(MODULES) | {"sim+paced"} == set(BACKENDS)
    for module in MODULES.values():
        assert all(isinstance(opt, UrlOption) for opt in module.URL_OPTIONS)
        assert not {o.name for o in module.URL_OPTIONS} & set(module.PYTHON_OPTIONS)


def test_zero_is_a_value_not_absent():
    # seed=0 in the URL conflicts with seed=1 from Python: 0 was read as a value (a falsy 0 once meant "absent")
    with pytest.raises(ParameterError, match="option seed is 0 in the URL but 1 was also asked for"):
        open_rig("sim?seed=0", seed=1)
    assert open_rig("sim?seed=0", seed=0).settings()["seed"] == 0
    assert rig_url_options("serial://loop://?channel=0&pot=0&daq=0")[1] == {"channel": 0, "pot": 0, "daq": "0"}
    assert rig_url_options("serial://loop://?sync=0xFE")[1]["sync"] == 254  # hexadecimal for bytes
    assert rig_url_options("daq://0?pot=none")[1]["pot"] is None


def test_python_keywords_are_checked_by_the_same_declarations():
    with pytest.raises(ParameterError, match="option seed=-1 must be an integer inside"):
        open_rig("sim", seed=-1)
    with pytest.raises(ParameterError, match="option dt_s=0 must be a finite number inside"):
        open_rig("sim", dt_s=0)
    with pytest.raises(ParameterError, match="unknown option 'speed'"):
        open_rig("sim", speed=2)


def test_parse_keeps_text_for_callers_that_only_look():
    parsed = parse_rig_url("serial:///dev/ttyUSB0?baud=9600&pot=3")
    assert parsed.options == {"baud": "9600", "pot": "3"}
    assert parsed.where == "serial:///dev/ttyUSB0"


# -- the seed: the URL's, or --seed, never a default over an explicit URL option; what was used is recorded -------
@pytest.mark.slow
def test_run_uses_and_reports_the_urls_seed(capsys):
    assert main(["run", "--backend", "sim?seed=5", "--duration", "0.2", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["rig"]["seed"] == 5
    assert main(["run", "--backend", "sim?seed=5", "--seed", "0", "--duration", "0.2", "--json"]) == 2
    assert "seed is 5 in the URL but 0" in json.loads(capsys.readouterr().out)["error"]
    assert main(["run", "--backend", "serial://loop://", "--seed", "3"]) == 2
    assert "no random noise to seed" in capsys.readouterr().err


def test_collect_records_the_seed_it_used(tmp_path, capsys):
    protocol = tmp_path / "p.toml"
    protocol.write_text(
        'name = "tiny"\nloads_g = [25.0]\npositions_from_tip_cm = [0]\nrepetitions = 1\nsettle_s = 0.2\n'
    )
    out = tmp_path / "d.parquet"
    argv = ["collect", str(protocol), "--backend", "sim?seed=5", "--out", str(out), "--no-progress"]
    assert main(argv) == 0
    from flexdigit.tactile.dataset import load_dataset

    assert load_dataset(out).meta["rig"]["settings"]["seed"] == 5


# -- replay where an operator is needed; no operator to ask ------------------------------------------------------
def test_collect_on_a_replay_is_refused_before_any_reading(tmp_path, capsys):
    log = tmp_path / "rec.jsonl"
    log.write_text('{"format": "flexdigit-loop-log/1"}\n{"k": 0, "t": 0.0, "gauges_v": [0, 0, 0], "command": 8}\n')
    out = tmp_path / "d.parquet"
    assert main(["collect", "thesis-6.1", "--backend", f"replay://{log}", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "cannot collect a load protocol on it" in err
    assert "EOFError" not in err
    assert list(tmp_path.iterdir()) == [log]  # no journal, no dataset


def test_console_operator_without_a_terminal_is_a_rig_error(monkeypatch):
    import io

    monkeypatch.setattr("sys.stdin", io.StringIO(""))  # closed: end of file at once
    with pytest.raises(RigError, match=r"no operator to ask \(Hang 25 g"):
        console_operator("Hang 25 g at 200 mm from the base.")


def test_console_operator_asks_on_stderr_and_waits_for_enter(monkeypatch, capsys):
    import io

    monkeypatch.setattr("sys.stdin", io.StringIO("\n"))
    console_operator("Hang 25 g at 200 mm from the base.")
    out, err = capsys.readouterr()
    assert out == ""  # stdout carries a command's result (--json) and nothing else
    assert err == "Hang 25 g at 200 mm from the base. Press Enter when done. "


def test_a_board_with_no_gauge_source_says_so():
    rig = open_rig("serial://loop://")
    with pytest.raises(RigError, match="no gauge source configured"):
        rig.read()
    rig.close()


def test_run_on_a_board_with_no_gauge_source_says_so(tmp_path, capsys):
    """Issue 16: it said "gauge 1 read nan"; the controller's tare is the first read, before the loop starts."""
    cal = tmp_path / "map.json"
    cal.write_text(json.dumps({"method": "x", "coef": [1, 0, 0], "intercept": 0, "gauge_v_per_deg": [1, 0, 0]}))
    argv = ["run", "--backend", "serial://loop://", "--rotation-map", str(cal), "--json"]
    assert main(argv) == 2
    doc = json.loads(capsys.readouterr().out)
    assert doc["error_type"] == "RigError"
    assert "no gauge source configured" in doc["error"]
