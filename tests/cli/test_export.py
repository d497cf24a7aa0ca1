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


def test_cli_export_a_digits_own_design(tmp_path, capsys, monkeypatch):
    """``--params`` (issue 24): the pair of cables' digit exports its own design, the controller ``flexdigit run
    --params`` builds on its twin (same matrices), its 4-gauge map, its straight command 127 and the dither."""
    import numpy as np

    import flexdigit.cli.export as export_command
    from digits import write_digit
    from flexdigit.cli import main
    from flexdigit.params import load_params
    from flexdigit.rig.base import open_rig
    from flexdigit.rig.controllers import make_controller
    from flexdigit.twin.digit_calibration import twin_calibration

    # the design the command exports, kept as it made it: computing it again took a third sweep of the twin (a
    # third of this test's time); the host's own sweep below is the independent one it is compared with
    designs, design_export = [], export_command._digit_export_design

    def keep(*args):
        designs.append(design_export(*args))
        return designs[-1]

    monkeypatch.setattr(export_command, "_digit_export_design", keep)
    path = write_digit("four-sections-two-cables", tmp_path)
    out = tmp_path / "pair.c"
    assert main(["export", "controller", "--out", str(out), "--params", str(path), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert (doc["gauges"], doc["straight_command"], doc["dither"]) == (4, 127, True)
    assert doc["analysis"]["closed_loop_stable"] is True
    header = out.with_suffix(".h").read_text()
    assert "#define FD_CTRL_GAUGES 4" in header
    assert "#define FD_CTRL_COMMAND_EQ 127" in header
    params = load_params(path)
    with open_rig("sim", params, calibration=twin_calibration(params)) as rig:
        host = make_controller("digital20", rig).runtime  # what run --params closes the loop with
    ((exported, _, rotation, _, _),) = designs  # the 20 ms design (--period-s's default) the file holds
    assert exported.dither
    assert host.dither
    # the map the command reports is the one it designed with; the host's sweep on the same seed's twin measured
    # the same rotation per command: the same design
    np.testing.assert_allclose(rotation.coef, doc["rotation_map"]["coef"], rtol=1e-9)
    for a, b in zip(
        (exported.sys.A, exported.sys.B, exported.sys.C, exported.sys.D),
        (host.sys.A, host.sys.B, host.sys.C, host.sys.D),
        strict=True,
    ):
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-12)


def test_cli_export_params_refusals_are_one_line(tmp_path, capsys):
    from digits import write_digit
    from flexdigit.cli import main

    path = write_digit("two-sections", tmp_path)
    out = str(tmp_path / "x.c")
    assert main(["export", "controller", "--out", out, "--params", str(path), "--design", "thesis39-tustin"]) == 2
    err = capsys.readouterr().err.strip()
    assert "--design thesis39-tustin" in err
    assert "\n" not in err
    assert main(["export", "controller", "--out", out, "--calibration", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert "--params" in err
    assert "\n" not in err
    assert not (tmp_path / "x.c").exists()
