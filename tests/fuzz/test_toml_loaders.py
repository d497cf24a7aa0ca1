"""Fuzz the TOML loaders (rig parameters, protocols, twin calibration, tissue and palpation protocol files, study
specs): every generated file loads or gives the project's one-line error naming the file (issue 16). Valid seeds:
the thesis defaults written by tomli_w, the packaged thesis-6.1 protocol and twin calibration, the shipped
nodule phantom, the shipped sweep, scan and hold palpation protocols in one file, and the shipped
thesis-tolerances study, the rao2021 tendon robot written by tomli_w, the shipped rao2021-tolerances robot study."""

from __future__ import annotations

import tomllib
from importlib import resources

import pytest
import tomli_w
from hypothesis import given

from digits import DIGITS
from flexdigit.errors import FlexdigitError
from flexdigit.palpation.palpation_files import load_palpation_protocol, load_tissue
from flexdigit.params import RigParams, load_params, params_template
from flexdigit.studies.design_study import DesignSettings
from flexdigit.studies.robot_study import load_robot_spec
from flexdigit.studies.sensitivity import SensitivitySettings
from flexdigit.studies.spec import load_spec
from flexdigit.tactile.importer import ColumnMap
from flexdigit.tactile.protocols import load_protocol
from flexdigit.tdcr.description import ROBOTS, load_robot
from flexdigit.twin.calibration import load_calibration

from .strategies import assert_loader_contract, edited_document, mutated_bytes, toml_values

PARAMS = tomli_w.dumps(RigParams().to_dict()).encode()
PROTOCOL = resources.files("flexdigit.tactile").joinpath("protocols", "thesis-6.1.toml").read_bytes()
CALIBRATION = resources.files("flexdigit.twin").joinpath("default_calibration.toml").read_bytes()
_PALPATION = resources.files("flexdigit.palpation").joinpath("palpation_data")
TISSUE = _PALPATION.joinpath("nodule-phantom.toml").read_bytes()
PALPATION = _PALPATION.joinpath("scan.toml").read_bytes() + b"\n" + _PALPATION.joinpath("hold.toml").read_bytes()
SPEC = resources.files("flexdigit.studies").joinpath("specs", "thesis-tolerances.toml").read_bytes()
DESIGN = resources.files("flexdigit.studies").joinpath("specs", "thesis-design.toml").read_bytes()
ROBOT = tomli_w.dumps(ROBOTS["rao2021"].to_dict()).encode()
ROBOT_SPEC = resources.files("flexdigit.studies").joinpath("specs", "rao2021-tolerances.toml").read_bytes()
COLUMN_MAP = b'gauges = ["sg_a", "sg_b", "sg_c"]\ngauge_unit = "mV"\nload = "mass_g"\nposition = "x_mm"\n'

LOADERS = {
    "params": (load_params, PARAMS),
    # issue 24: the annotated template, and a digit of 5 sections and 8 gauges (tests/digits.py)
    "params template": (load_params, params_template().encode()),
    "digit": (load_params, tomli_w.dumps(DIGITS["five-sections-eight-gauges"]).encode()),
    "protocol": (load_protocol, PROTOCOL),
    "calibration": (load_calibration, CALIBRATION),
    "tissue": (load_tissue, TISSUE),
    "palpation": (load_palpation_protocol, PALPATION),
    "spec": (load_spec, SPEC),
    "robot": (load_robot, ROBOT),
    "robot spec": (load_robot_spec, ROBOT_SPEC),
}


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("toml")


def _dumps(doc) -> bytes:
    try:
        return tomli_w.dumps(doc).encode()
    except (TypeError, ValueError):  # not representable in TOML (a NaN key...): write its repr instead
        return repr(doc).encode("utf-8", "surrogatepass")


@pytest.mark.parametrize("name", LOADERS)
def test_the_seeds_load(name, folder):
    load, valid = LOADERS[name]
    path = folder / f"{name}.toml"
    path.write_bytes(valid)
    assert not isinstance(assert_loader_contract(load, path), Exception)


def _fuzz_bytes(name):
    load, valid = LOADERS[name]

    @given(data=mutated_bytes(valid))
    def test(folder, data):
        path = folder / f"{name}-bytes.toml"
        path.write_bytes(data)
        assert_loader_contract(load, path)

    return test


def _fuzz_values(name):
    load, valid = LOADERS[name]

    @given(doc=edited_document(tomllib.loads(valid.decode()), toml_values))
    def test(folder, doc):
        path = folder / f"{name}-values.toml"
        path.write_bytes(_dumps(doc))
        assert_loader_contract(load, path)

    return test


test_params_bytes = _fuzz_bytes("params")
test_params_values = _fuzz_values("params")
test_params_template_bytes = _fuzz_bytes("params template")
test_digit_bytes = _fuzz_bytes("digit")
test_digit_values = _fuzz_values("digit")
test_protocol_bytes = _fuzz_bytes("protocol")
test_protocol_values = _fuzz_values("protocol")
test_calibration_bytes = _fuzz_bytes("calibration")
test_calibration_values = _fuzz_values("calibration")
test_tissue_bytes = _fuzz_bytes("tissue")
test_tissue_values = _fuzz_values("tissue")
test_palpation_bytes = _fuzz_bytes("palpation")
test_palpation_values = _fuzz_values("palpation")
test_spec_bytes = _fuzz_bytes("spec")
test_spec_values = _fuzz_values("spec")
test_robot_bytes = _fuzz_bytes("robot")
test_robot_values = _fuzz_values("robot")
test_robot_spec_bytes = _fuzz_bytes("robot spec")
test_robot_spec_values = _fuzz_values("robot spec")


#: A key with a newline in it, as ``make fuzz`` (seed 0) generated it for the protocol, calibration and spec files:
#: echoed as it was, it broke the one-line message in two. Every loader that names an unknown key quotes it.
NEWLINE_KEY = "\n"


def _spec_settings(path):
    spec = load_spec(path)
    return DesignSettings.from_spec(spec), SensitivitySettings.from_spec(spec)


_NEWLINE_CASES = {  # where the key goes: the top level, or a table
    "params [geometry]": (load_params, PARAMS, ("geometry",)),
    "protocol": (load_protocol, PROTOCOL, ()),
    "calibration": (load_calibration, CALIBRATION, ()),
    "calibration [calibration]": (load_calibration, CALIBRATION, ("calibration",)),
    "tissue [tissue]": (load_tissue, TISSUE, ("tissue",)),
    "spec": (load_spec, SPEC, ()),
    "spec [study]": (load_spec, SPEC, ("study",)),
    "spec [parameters.geometry]": (load_spec, SPEC, ("parameters", "geometry")),
    "spec [sensitivity]": (_spec_settings, SPEC, ("sensitivity",)),
    "spec [design]": (_spec_settings, DESIGN, ("design",)),
    "column map": (ColumnMap.from_toml, COLUMN_MAP, ()),
    "robot": (load_robot, ROBOT, ()),
    "robot [backbone]": (load_robot, ROBOT, ("backbone",)),
}


@pytest.mark.parametrize("case", _NEWLINE_CASES)
def test_an_unknown_key_with_a_newline_is_named_on_one_line(case, folder):
    load, valid, table = _NEWLINE_CASES[case]
    doc = tomllib.loads(valid.decode())
    parent = doc
    for key in table:
        parent = parent[key]
    parent[NEWLINE_KEY] = False
    path = folder / "newline-key.toml"
    path.write_bytes(tomli_w.dumps(doc).encode())
    error = assert_loader_contract(load, path)
    assert isinstance(error, FlexdigitError)
    assert "\\n" in str(error)  # the key, escaped
