"""Tissue and protocol files, and ``flexdigit palpate`` (issue 13 item 5): one-line errors naming file and key."""

import json
import re

import pytest

from flexdigit.cli import main
from flexdigit.errors import DataFileError
from flexdigit.palpation.palpation_files import PROTOCOLS, TISSUES, load_palpation_protocol, load_tissue

QUICK_SWEEP = """
[sweep]
commands = { from = 8, to = 26, step = 3 }
settle_s = 2.5
readings = 10
"""

TISSUE = """
[tissue]
name = "test block"
side = "cable"
start_mm = 150
end_mm = 350
gap_mm = 30
modulus_n_m2 = 800
"""


@pytest.mark.parametrize("name", TISSUES)
def test_builtin_tissues_load(name):
    tissue, info = load_tissue(name)
    assert info.placed_on_twin
    assert tissue.start_m < tissue.end_m


def test_builtin_protocols_load():
    plans = {name: load_palpation_protocol(name) for name in PROTOCOLS}
    assert plans["sweep"].sweep.commands == tuple(range(8, 31))
    assert plans["scan"].scan["offsets_m"] == (-0.04, -0.03, -0.02, -0.01, 0.0, 0.01, 0.02, 0.03, 0.04)
    assert plans["hold"].force["setpoint_n"] == 0.1


def test_units_are_converted(tmp_path):
    path = tmp_path / "t.toml"
    path.write_text(TISSUE + "\n[[tissue.inclusions]]\ncentre_mm = 250\nwidth_mm = 8\nratio = 2.5\n")
    tissue, info = load_tissue(path)
    assert (tissue.start_m, tissue.end_m, tissue.gap_m, tissue.modulus_n_m2) == (0.15, 0.35, 0.03, 800.0)
    assert (tissue.inclusions[0].centre_m, tissue.inclusions[0].width_m, tissue.inclusions[0].ratio) == (
        0.25,
        0.008,
        2.5,
    )
    assert info.name == "test block"


BAD_TISSUES = [
    ("[tissue]\nstart_mm = 150\n", "key 'tissue.end_mm' is missing"),
    (TISSUE.replace("gap_mm = 30", 'gap_mm = "far"'), "key 'tissue.gap_mm' must be a real number"),
    (TISSUE.replace("end_mm = 350", "end_mm = 100"), "key 'tissue.end_mm' must be beyond 'start_mm'"),
    (TISSUE.replace("modulus_n_m2 = 800", "modulus_n_m2 = -1"), "key 'tissue.modulus_n_m2' must be inside"),
    (TISSUE + "colour = 'red'\n", "unknown key 'tissue.colour'"),
    (TISSUE.replace('side = "cable"', 'side = "left"'), "key 'tissue.side' must be one of 'cable', 'opposite'"),
    (TISSUE + "\n[[tissue.inclusions]]\ncentre_mm = 250\nwidth_mm = 0\nratio = 3\n", "'tissue.inclusions[0].width_mm'"),
    (TISSUE + "\n[[tissue.inclusions]]\ncentre_mm = 250\nratio = 3\n", "'tissue.inclusions[0].width_mm' is missing"),
    # an inclusion outside the body would change nothing: refused, not ignored
    (
        TISSUE + "\n[[tissue.inclusions]]\ncentre_mm = 400\nwidth_mm = 8\nratio = 3\n",
        "centre_mm' must lie in the tissue",
    ),
    (TISSUE + "\n[extra]\nx = 1\n", "unknown table 'extra'"),
    ("[tissue\nstart_mm = 1", "not valid TOML"),
]


@pytest.mark.parametrize("text, message", BAD_TISSUES)
def test_bad_tissue_files_give_one_line_naming_the_key(tmp_path, text, message):
    path = tmp_path / "tissue.toml"
    path.write_text(text)
    with pytest.raises(DataFileError, match=re.escape(message)) as err:
        load_tissue(path)
    assert str(path) in str(err.value)
    assert "\n" not in str(err.value)


BAD_PROTOCOLS = [
    ("[sweep]\ncommands = [8, 9]\n", "at least 3 commands"),
    ("[sweep]\ncommands = [8, 9, 300]\n", "'commands'"),
    ("[sweep]\ncommands = { from = 20, to = 8, step = 1 }\n", "'to' must not be below 'from'"),
    ("[sweep]\nreadings = 0\n", "key 'sweep.readings' must be an integer"),
    ("[sweep]\nmodel = 'spring'\n", "key 'sweep.model' must be one of"),
    ("[scan]\noffsets_mm = [0, 10]\n", "key 'scan.offsets_mm' must give at least 3 offsets"),
    ("[force]\nsetpoint_n = -0.1\n", "key 'force.setpoint_n' must be inside"),
    ("[sweep]\nspeed = 3\n", "unknown key 'sweep.speed'"),
    ("[palpate]\n", "unknown table 'palpate'"),
]


@pytest.mark.parametrize("text, message", BAD_PROTOCOLS)
def test_bad_protocol_files_give_one_line_naming_the_key(tmp_path, text, message):
    path = tmp_path / "protocol.toml"
    path.write_text(text)
    with pytest.raises(DataFileError, match=re.escape(message)):
        load_palpation_protocol(path)


def test_cli_refuses_a_bad_tissue_file_in_one_line(tmp_path, capsys):
    path = tmp_path / "tissue.toml"
    path.write_text(TISSUE.replace("gap_mm = 30", "gap_mm = nan"))
    assert main(["palpate", "--tissue", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0
    assert "tissue.gap_mm" in err
    assert str(path) in err


def test_cli_needs_gap_and_modulus_on_the_twin(tmp_path, capsys):
    path = tmp_path / "tissue.toml"
    path.write_text(TISSUE.replace("gap_mm = 30\n", ""))
    assert main(["palpate", "--tissue", str(path)]) == 2
    assert "'tissue.gap_mm' and 'tissue.modulus_n_m2' are needed on the twin" in capsys.readouterr().err


@pytest.mark.slow
def test_cli_palpates_on_the_twin_and_never_clobbers(tmp_path, capsys):
    tissue, protocol, out = tmp_path / "t.toml", tmp_path / "p.toml", tmp_path / "r.json"
    tissue.write_text(TISSUE)
    protocol.write_text(QUICK_SWEEP)
    args = ["palpate", "--tissue", str(tissue), "--protocol", str(protocol), "--out", str(out), "--json"]
    assert main(args) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["result"]["modulus_n_m2"] == pytest.approx(800.0, rel=0.1)
    assert data["truth"]["modulus_n_m2"] == 800.0
    assert json.loads(out.read_text())["kind"] == "sweep"
    assert main(args) == 2  # --out exists: refused before any work
    assert "pass --force" in capsys.readouterr().err


# Issue 22: plausible ranges. A value 1e308 or a thousand times off is refused in one line naming the file, the key
# and, where a unit slip lands inside the range, the slip.
IMPLAUSIBLE_TISSUES = [
    (TISSUE.replace("modulus_n_m2 = 800", "modulus_n_m2 = 1e308"), "key 'tissue.modulus_n_m2' must be inside [1"),
    (TISSUE.replace("modulus_n_m2 = 800", "modulus_n_m2 = 0.8"), "did you mean kN/m^2 (kPa) (800 N/m^2)?"),
    (TISSUE.replace("gap_mm = 30", "gap_mm = 30000"), "key 'tissue.gap_mm' must be inside [-2000, 2000] mm"),
    (TISSUE.replace("start_mm = 150", "start_mm = 0.15").replace("end_mm = 350", "end_mm = 0.35"), "did you mean m"),
    (TISSUE + "\n[[tissue.inclusions]]\ncentre_mm = 250\nwidth_mm = 0.01\nratio = 3\n", "did you mean m (10 mm)?"),
    (TISSUE + "\n[[tissue.inclusions]]\ncentre_mm = 250\nwidth_mm = 8\nratio = 1e308\n", "inclusions[0].ratio"),
    (TISSUE + "damping_s_m = 1e308\n", "key 'tissue.damping_s_m' must be inside [0, 100] s/m"),
]


@pytest.mark.parametrize("text, message", IMPLAUSIBLE_TISSUES)
def test_implausible_tissue_values_are_refused_naming_the_slip(tmp_path, text, message):
    path = tmp_path / "tissue.toml"
    path.write_text(text)
    with pytest.raises(DataFileError, match=re.escape(message)) as err:
        load_tissue(path)
    assert str(path) in str(err.value)
    assert "\n" not in str(err.value)


IMPLAUSIBLE_PROTOCOLS = [
    ("[sweep]\nsettle_s = 1e308\n", "key 'sweep.settle_s' must be inside [0, 3600] s"),
    ("[sweep]\nperiod_s = 20\n", "key 'sweep.period_s' must be inside [0.0001, 1] s"),
    ("[sweep]\nperiod_s = 20\n", "did you mean ms (0.02 s)?"),
    ("[scan]\noffsets_mm = [-0.04, 0, 0.04]\n", "did you mean m (80 mm)?"),
    ("[scan]\noffsets_mm = [0, 10, 1e308]\n", "key 'scan.offsets_mm'[2] must be inside"),
    ("[scan]\noffsets_mm = [0, 10, 20]\ninclusion_width_mm = 0.01\n", "did you mean m (10 mm)?"),
    ("[force]\nsetpoint_n = 1e308\n", "key 'force.setpoint_n' must be inside"),
    ("[force]\nsetpoint_n = 0.1\ngain = 5e-324\n", "key 'force.gain' must be inside"),
    ("[force]\nsetpoint_n = 0.1\nduration_s = 1e308\n", "key 'force.duration_s' must be inside"),
    ("[force]\nsetpoint_n = 0.1\napproach_rate = 1e308\n", "key 'force.approach_rate' must be inside"),
]


@pytest.mark.parametrize("text, message", IMPLAUSIBLE_PROTOCOLS)
def test_implausible_protocol_values_are_refused_naming_the_slip(tmp_path, text, message):
    path = tmp_path / "protocol.toml"
    path.write_text(text)
    with pytest.raises(DataFileError, match=re.escape(message)) as err:
        load_palpation_protocol(path)
    assert str(path) in str(err.value)
    assert "\n" not in str(err.value)
