"""A description's ``[twin]`` table (issue 24: the twin's static deflection within 0.1 % of the elastica).

The default resolution (cells <= 27 mm) leaves the twin 0.1-0.6 % from the elastica under the issue's tip load:
the chain's mid-point lumping, ``h^2``. ``[twin] max_cell_length_m`` or ``cells_per_section`` asks for a finer
chain, and every builder of the chain from a description takes it; left out, nothing changes.

References: the ``scipy.integrate.solve_bvp`` elastica of the same geometry (``tests/oracles.py``, as
``tests/twin/test_campaign_digits.py``: supports rigid, their masses and the strip's weight, hanging), never the
twin. The settings are docs/digits.md's table (``resolution_for``'s, to 0.5 mm).
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import numpy as np
import pytest

from digit_campaign import campaign_digit, to_toml
from digits import DIGITS
from flexdigit.errors import ParameterError
from flexdigit.params import RigParams, TwinResolution, load_params, twin_cells
from flexdigit.twin.digit import build_digit, default_cells
from flexdigit.twin.resolution import CABLE_TIP_DEG, STATIC_RTOL, TIP_LOAD_ALPHA2, resolution_advice, static_error
from flexdigit.twin.twin import Twin
from oracles import digit_contact_bvp, thesis_digit_segments

DATA = Path(__file__).resolve().parents[1] / "data"
#: The BVP's tolerance (as tests/twin/test_campaign_digits.py): its error is 1e-5 of the twin's at worst.
BVP_TOL = 1e-8
#: The BVP's tolerance where only the 0.1 % bound is asked (every described digit's default twin): at 1e-6 the
#: measured errors (0.03-0.07 %) moved by at most 2e-6 of the deflection against 1e-8 (five_unequal_bronze_full's
#: tip load 0.0405 -> 0.0403 %; five-sections-eight-gauges and one-section < 3e-7), for 25-45 % less time.
BOUND_BVP_TOL = 1e-6
#: How closely the Richardson estimate (twin.resolution) tells the twin's error against the elastica, relative
#: to that error: measured < 0.05 % on these digits (the h^4 term and the BVP's own 1e-8), 2026-11-27.
ESTIMATE_RTOL = 0.01
#: (name, description, [twin] max_cell_length_m meeting 0.1 %): the thesis rig, the shortest sections (one
#: 0.15 m section of 7 cells), one long section of 15 cells (campaign seed 2) and an antagonistic pair.
DIGITS_FOR_ELASTICA = [
    ("thesis", {}, 0.014),
    ("one-section", DIGITS["one-section"], 0.009),
    ("campaign-2", campaign_digit(2), 0.018),
    ("four-sections-two-cables", DIGITS["four-sections-two-cables"], 0.0165),  # a pair, pretensioned
]


def _with_twin(data: dict, **twin) -> dict:
    doc = {k: dict(v) for k, v in data.items()}
    doc["twin"] = twin
    return doc


def _load(tmp_path, data: dict, name="digit.toml") -> RigParams:
    path = tmp_path / name
    path.write_text(to_toml(data) if data else "")
    return load_params(path)


def _elastica_error(params, chain, cal, tol: float = BVP_TOL) -> tuple[float, float]:
    """The chain's tip error over the tip deflection against the solve_bvp elastica (at ``tol``): (tip load,
    cable)."""
    length = params.geometry.digit_length_m
    force = TIP_LOAD_ALPHA2 * (params.bending_stiffness_n_m2 + min(cal.housing_ei_n_m2)) / length**2
    shortening = params.geometry.cable_eccentricity_m * math.radians(CABLE_TIP_DEG)
    twin_tips = (
        chain.solve_static(tip_force_n=[[0.0, force]]).tip_m[0],
        chain.solve_static(cable_shortening_m=[shortening]).tip_m[0],
    )
    references = _elastica_tips(params.digit_only(), cal, tol)
    errors = [
        float(np.linalg.norm(tip - ref) / deflection)
        for tip, (ref, deflection) in zip(twin_tips, references, strict=True)
    ]
    return errors[0], errors[1]


@functools.cache
def _elastica_tips(params, cal, tol: float) -> tuple[tuple[np.ndarray, float], tuple[np.ndarray, float]]:
    """The solve_bvp elastica's tip and tip deflection under the tip load and under the cable, of the digit
    ``params`` (without its ``[twin]`` table: the elastica is the digit's, not its twin's) on ``cal``, at ``tol``.
    Solved once per digit, calibration and tolerance in a run: the default twin and the one a ``[twin]`` table
    refines (the same digit, the same calibration) are compared with the same elastica, as are a hand-made digit's
    suggested setting and its default twin."""
    length = params.geometry.digit_length_m
    pair = params.cables.count == 2
    segments, supports = thesis_digit_segments(params, cal)
    force = TIP_LOAD_ALPHA2 * (params.bending_stiffness_n_m2 + min(cal.housing_ei_n_m2)) / length**2
    shortening = params.geometry.cable_eccentricity_m * math.radians(CABLE_TIP_DEG)
    tips = []
    for loads in ({"point_forces_b": {length: force}}, {"cable_shortening_m": shortening}):
        ref = digit_contact_bvp(
            segments,
            strip_mass_per_m=params.material.strip_density_kg_m3 * params.geometry.cross_section_m2,
            point_masses=dict(zip(supports, cal.support_mass_kg, strict=True)),
            gravity_ab=(9.80665, 0.0),  # hanging
            eccentricity_m=params.geometry.cable_eccentricity_m,
            cable_stiffness_n_m=cal.cable_stiffness_n_m,
            cable_pretension_m=params.cables.pretension_n / cal.cable_stiffness_n_m if pair else None,
            tol=tol,
            max_nodes=100_000,
            **loads,
        )
        assert ref.converged, ref.message
        deflection = np.linalg.norm(ref.tip - np.array([length, 0.0]))
        assert deflection > 0.05 * length  # a large deflection, not a linear one
        tips.append((ref.tip.copy(), float(deflection)))
    return tips[0], tips[1]


@pytest.mark.parametrize(("name", "data", "max_cell_m"), DIGITS_FOR_ELASTICA, ids=[d[0] for d in DIGITS_FOR_ELASTICA])
def test_a_twin_table_brings_the_statics_within_0_1_percent_of_the_elastica(name, data, max_cell_m, tmp_path):
    """Through the public path: a file with ``[twin] max_cell_length_m``, ``load_params``, ``Twin(params)``."""
    default = _load(tmp_path, data, "default.toml")
    fine = _load(tmp_path, _with_twin(data, max_cell_length_m=max_cell_m), "fine.toml")
    # the 27 mm cells a [twin] table replaces (a derived digit's own default is finer already: below)
    twin_default = Twin(default, orientation="hanging", cells_per_section=twin_cells(default))
    twin_fine = Twin(fine, orientation="hanging")
    assert twin_fine.calibration == twin_default.calibration  # the same digit: its resolution is not its physics
    assert twin_fine.chain.n > twin_default.chain.n
    coarse = _elastica_error(default, twin_default.chain, twin_default.calibration)
    refined = _elastica_error(fine, twin_fine.chain, twin_fine.calibration)
    assert coarse[0] > STATIC_RTOL  # 27 mm cells miss the 0.1 % under the tip load ...
    assert max(refined) < STATIC_RTOL  # ... the setting meets it under both
    # the estimate `params FILE` prints tells the measured error (h^2 Richardson, no BVP)
    for params, measured in ((default, coarse), (fine, refined)):
        estimate = static_error(params, cells=twin_cells(params))
        assert estimate.tip_load == pytest.approx(measured[0], rel=ESTIMATE_RTOL)
        assert estimate.cable == pytest.approx(measured[1], rel=ESTIMATE_RTOL)


def test_the_estimate_follows_the_h_squared_law():
    """Three times the cells, a ninth of the error (the mid-point rule's order): the estimate is no constant."""
    params = RigParams()
    errors = [static_error(params, cells=n) for n in (3, 9)]
    assert errors[0].tip_load / errors[1].tip_load == pytest.approx(9.0, rel=0.05)
    assert errors[0].cable / errors[1].cable == pytest.approx(9.0, rel=0.05)


def test_no_table_is_todays_twin_to_the_bit(tmp_path):
    """Left out, the twin is the one the 509 report entries rest on: the same chain, the same file."""
    params = _load(tmp_path, {"geometry": {"section_count": 3}})
    assert params == RigParams()
    assert params.twin.is_default
    assert "twin" not in params.to_dict()  # a written file, a record's metadata, a fingerprint: unchanged
    for data in ({}, DIGITS["unequal-sections"], campaign_digit(2)):
        p = RigParams.from_dict(data)
        cal = Twin(p).calibration
        assert twin_cells(p) == default_cells(p.geometry)
        ours = build_digit(p, cal)
        before = build_digit(p, cal, cells_per_section=default_cells(p.geometry))
        for name in ("joint_s_m", "stiffness", "damping", "cell_length_m", "mass_kg", "k_psi", "a_mass"):
            np.testing.assert_array_equal(getattr(ours, name), getattr(before, name))


def test_the_thesis_rig_with_a_finer_twin_keeps_its_packaged_calibration():
    from flexdigit.twin.calibration import packaged_calibration
    from flexdigit.twin.digit_calibration import twin_calibration

    fine = RigParams(twin=TwinResolution(cells_per_section=9))
    assert fine != RigParams()
    assert fine.digit_only() == RigParams()
    assert twin_calibration(fine) == packaged_calibration()
    other = RigParams.from_dict(_with_twin(DIGITS["two-sections"], cells_per_section=[9, 9]))
    assert twin_calibration(other) == twin_calibration(other.digit_only())


def test_the_thesis_rig_is_named_whatever_its_twin():
    """``RigParams.is_thesis_rig``: the thesis rig at any ``[twin]`` resolution is it, another digit is not."""
    assert RigParams(twin=TwinResolution(cells_per_section=9)).is_thesis_rig()
    assert RigParams(twin=TwinResolution(max_cell_length_m=0.01)).is_thesis_rig()
    assert not RigParams.from_dict(DIGITS["two-sections"]).is_thesis_rig()


def test_the_advice_suggests_a_setting_only_where_the_twin_misses():
    """``resolution_advice`` (what ``params FILE`` prints): the default thesis twin misses 0.1 % and docs/digits.md's
    0.014 m meets it; a twin at that setting is acceptable and gets no suggestion."""
    default = resolution_advice(RigParams())
    assert not default.acceptable
    assert default.max_cell_length_m == 0.014
    assert default.suggested_error.worst <= STATIC_RTOL
    fine = resolution_advice(RigParams(twin=TwinResolution(max_cell_length_m=0.014)))
    assert fine.acceptable
    assert fine.max_cell_length_m is None
    assert fine.suggested_error is None


def test_every_builder_of_the_chain_takes_the_table():
    """Scalar and batched twins, static readings, records, shape, the contact and gauge models, the design model
    and calibrate's fit: the table's 27 springs, not the default's 9, without being told."""
    from flexdigit.calibrate.twin_fit import model_response
    from flexdigit.control.digit_model import digit_model
    from flexdigit.palpation.contact_estimation import ContactGaugeModel
    from flexdigit.twin.batched import BatchedChains, BatchedTwin, batch_cells
    from flexdigit.twin.twin import static_gauges_v

    fine = RigParams(twin=TwinResolution(cells_per_section=9))
    cal = Twin(fine).calibration
    assert Twin(fine).chain.n == 27
    assert BatchedTwin(fine).chains.n == 27
    assert BatchedChains.from_rigs([fine, fine], [cal, cal]).n == 27
    assert batch_cells([fine, RigParams(twin=TwinResolution(cells_per_section=(5, 7, 9)))]) == (9, 9, 9)
    assert ContactGaugeModel(fine, cal).chain.n == 27
    # readings: the table's chain's, i.e. the default description's asked for 9 cells explicitly, to the bit
    loads = ([0.0, 0.01], [0.0, 0.27])
    np.testing.assert_array_equal(
        static_gauges_v(*loads, params=fine, calibration=cal, adc=False),
        static_gauges_v(*loads, params=RigParams(), calibration=cal, adc=False, cells_per_section=9),
    )
    assert not np.array_equal(
        static_gauges_v(*loads, params=fine, calibration=cal, adc=False),
        static_gauges_v(*loads, params=RigParams(), calibration=cal, adc=False),
    )
    wn = [digit_model(p, cal).modes_wn_rad_s[0] for p in (fine, RigParams())]
    assert wn[0] == digit_model(RigParams(), cal, cells_per_section=9).modes_wn_rad_s[0] != wn[1]
    # calibrate's fit compares the twin's modes and sweep: the table's chain's
    from flexdigit.calibrate.targets import CalibrationTargets

    ours = model_response(fine, cal, CalibrationTargets())
    told = model_response(RigParams(), cal, CalibrationTargets(), cells_per_section=9)
    default = model_response(RigParams(), cal, CalibrationTargets())
    for key in ("housing_wn", "bare_wn"):
        np.testing.assert_array_equal(ours[key], told[key])
    assert ours["housing_wn"] != default["housing_wn"]


def test_records_take_the_table():
    from flexdigit.twin import records

    fine = RigParams(twin=TwinResolution(cells_per_section=9))
    kwargs = {"duration_s": 1.0, "sample_rate_hz": 100, "seed": 1}
    ours = records.release_test(params=fine, **kwargs).column("gauge1_v")
    told = records.release_test(params=RigParams(), calibration=Twin(fine).calibration, **kwargs)
    default = told.column("gauge1_v")
    assert not np.array_equal(ours, default)  # the table's finer chain rings otherwise
    assert records.release_test(params=fine, **kwargs).metadata["params"]["twin"] == {"cells_per_section": 9}


@pytest.mark.parametrize(
    ("twin", "match"),
    [
        ({"cells_per_section": [9, 9]}, r"\[twin\] cells_per_section has 2 counts for 3 sections"),
        ({"cells_per_section": 0}, r"'cells_per_section' parameter .* inside \[1, 81\]"),
        ({"cells_per_section": [9, 2.5, 9]}, r"'cells_per_section\[1\]' .* whole number"),
        ({"cells_per_section": "9"}, r"'cells_per_section'"),
        ({"max_cell_length_m": 1e-5}, r"'max_cell_length_m' .* inside \[0.001, 0.5\] m"),
        ({"max_cell_length_m": 0.01, "cells_per_section": 9}, r"'cells_per_section' .*one or the other"),
        ({"cells_per_section": 81, "colour": 1}, r"unknown key 'colour' in \[twin\]"),
    ],
)
def test_a_bad_twin_table_is_refused_in_one_line_naming_its_key(twin, match, tmp_path):
    path = tmp_path / "digit.toml"
    path.write_text(to_toml({"twin": twin}))
    with pytest.raises(ParameterError, match=match) as info:
        load_params(path)
    assert "\n" not in str(info.value)
    assert str(path) in str(info.value)


def test_a_twin_too_fine_to_step_in_real_time_is_refused(tmp_path):
    data = _with_twin(DIGITS["four-sections-two-cables"], max_cell_length_m=0.001)
    path = tmp_path / "digit.toml"
    path.write_text(to_toml(data))
    with pytest.raises(ParameterError, match=r"\[twin\] max_cell_length_m = 0.001 makes 324 springs .* at most 243"):
        load_params(path)
    RigParams.from_dict(_with_twin({}, max_cell_length_m=0.001))  # the thesis rig's 243: the limit


def test_simulate_load_and_params_run_a_finer_twin_end_to_end(tmp_path, capsys):
    """The commands: ``params FILE`` prints the table's springs and its error, ``simulate load`` records the
    finer twin's gauges (another record than the default's, said in its metadata)."""
    import json

    from flexdigit.cli import main
    from flexdigit.twin.records import TwinRecord

    fine = tmp_path / "fine.toml"
    fine.write_text(to_toml({"twin": {"max_cell_length_m": 0.014}}))
    assert main(["params", str(fine), "--json"]) == 0
    twin = json.loads(capsys.readouterr().out)["twin"]
    assert twin["cells_per_section"] == [7, 7, 7]
    assert twin["static_error_tip_load"] < STATIC_RTOL
    assert twin["static_error_cable"] < STATIC_RTOL
    thesis = tmp_path / "thesis.toml"
    assert main(["params", "--write", str(thesis)]) == 0
    capsys.readouterr()
    assert main(["params", str(thesis), "--json"]) == 0  # the default: 0.37 %, and the setting that meets 0.1 %
    default = json.loads(capsys.readouterr().out)["twin"]
    assert default["static_error_tip_load"] > STATIC_RTOL
    assert default["max_cell_length_m_for_0.1_percent"] == 0.014
    outs = []
    for name, extra in (("fine", ["--params", str(fine)]), ("default", [])):
        out = tmp_path / f"{name}.parquet"
        assert main(["simulate", "load", *extra, "--out", str(out), "--seed", "1"]) == 0
        outs.append(TwinRecord.load(out))
    assert outs[0].metadata["params"]["twin"] == {"max_cell_length_m": 0.014}
    assert "twin" not in outs[1].metadata["params"]
    assert outs[0].metadata["calibration"] == outs[1].metadata["calibration"]  # the thesis rig's packaged fit
    gauges = [r.column("gauge1_v") for r in outs]
    assert gauges[0].shape == gauges[1].shape
    assert not np.array_equal(*gauges)  # the finer chain's readings
    assert np.abs(gauges[0] - gauges[1]).max() < 0.05 * np.abs(gauges[1]).max()  # the same digit, a few % apart


def test_the_template_documents_the_table_commented_out(tmp_path):
    from flexdigit.params import params_template

    text = params_template()
    twin = text[text.index("[twin]") :]
    assert "# max_cell_length_m = 0.014" in twin
    assert "# cells_per_section = 7" in twin
    thesis = static_error(RigParams())  # the table's row is the estimate, which the elastica test checks
    row = f"thesis rig (3 x 0.27)         3 a section     {100 * thesis.tip_load:.3f} | {100 * thesis.cable:.3f}"
    assert row in twin
    path = tmp_path / "template.toml"
    path.write_text(text)
    assert load_params(path) == RigParams()
    path.write_text(text.replace("# cells_per_section = 7", "cells_per_section = 7"))
    assert twin_cells(load_params(path)) == (7, 7, 7)


def test_the_thesis_rig_with_a_finer_twin_is_still_the_thesis_rig_to_its_commands():
    """What asks "is this the thesis rig?" reads the digit, not its twin's resolution: the rotation map's
    protocol, the thesis's printed tables, the palpation tolerance (the control, tactile and report layers'
    own checks are their owners', noted in docs/digits.md)."""
    from flexdigit.models.chapter3_tables import table_3_4_printed
    from flexdigit.rig.rotation import sweep_protocol

    fine = RigParams(twin=TwinResolution(cells_per_section=9))
    assert sweep_protocol(fine, reference="twin") == sweep_protocol(RigParams(), reference="twin") == "plain"
    assert table_3_4_printed("y_max_mm", fine, 17)[1] == 3.26  # table 3.4, printed


def test_the_sim_rig_runs_the_table_and_records_it_only_when_given():
    from flexdigit.rig import open_rig
    from flexdigit.rig.recording import rig_metadata

    fine = open_rig("sim", RigParams(twin=TwinResolution(cells_per_section=5)))
    assert fine.twin.chain.n == 15
    assert rig_metadata(fine)["flexdigit.rig"]["params"]["twin"]["cells_per_section"] == 5
    assert "twin" not in rig_metadata(open_rig("sim", RigParams()))["flexdigit.rig"]["params"]  # as before


HANDMADE = sorted(p for folder in ("handmade_digits", "handmade_digits2") for p in (DATA / folder).glob("*.toml"))


@pytest.mark.slow
@pytest.mark.parametrize("path", HANDMADE, ids=[p.stem for p in HANDMADE])
def test_the_setting_params_suggests_meets_0_1_percent_on_the_hand_made_digits(path, tmp_path):
    """Digits written by hand from the template (the stand-ins for the hidden ones): the ``max_cell_length_m``
    that ``params FILE`` suggests (``resolution_for``), written into the file, puts the twin within 0.1 % of the
    elastica under both loads."""
    from flexdigit.twin.resolution import resolution_for

    params = load_params(path)
    cell_m, _ = resolution_for(params)
    text = path.read_text() + f"\n[twin]\nmax_cell_length_m = {cell_m!r}\n"
    fine = tmp_path / path.name
    fine.write_text(text)
    params = load_params(fine)
    twin = Twin(params, orientation="hanging")
    assert max(_elastica_error(params, twin.chain, twin.calibration)) < STATIC_RTOL


#: Every described digit but the thesis rig's: the test digits of tests/digits.py and the three hand-made sets.
DESCRIBED = [(f"digits-{name}", RigParams.from_dict(data)) for name, data in DIGITS.items() if data] + [
    (f"{p.parent.name}-{p.stem}", load_params(p))
    for folder in ("handmade_digits", "handmade_digits2", "handmade_digits3")
    for p in sorted((DATA / folder).glob("*.toml"))
]
DESCRIBED = [(name, params) for name, params in DESCRIBED if params.digit_only() != RigParams()]
#: The hand-made digits whose elastica the test above solved at BVP_TOL: the test below compares their default
#: twin with that one (a tighter reference than BOUND_BVP_TOL's, solved once for both tests in a run)
SOLVED_AT_BVP_TOL = {f"{p.parent.name}-{p.stem}" for p in HANDMADE}


@pytest.mark.slow
@pytest.mark.parametrize(("name", "params"), DESCRIBED, ids=[d[0] for d in DESCRIBED])
def test_every_described_digit_s_default_twin_is_within_0_1_percent_of_the_elastica(name, params):
    """No ``[twin]`` table: the twin of a digit on its derived calibration, as every command builds it
    (``Twin(params)``), within the issue's 0.1 % of the solve_bvp elastica under the tip load and the cable. The
    thesis rig keeps the 3 cells a section its packaged calibration was fitted at (0.37 %, docs/digits.md)."""
    twin = Twin(params, orientation="hanging")
    tol = BVP_TOL if name in SOLVED_AT_BVP_TOL else BOUND_BVP_TOL
    tip_load, cable = _elastica_error(params, twin.chain, twin.calibration, tol)
    assert tip_load < STATIC_RTOL, f"{name}: {100 * tip_load:.3f} % under the tip load at {twin.chain.n} springs"
    assert cable < STATIC_RTOL, f"{name}: {100 * cable:.3f} % under the cable at {twin.chain.n} springs"


def test_the_thesis_rig_keeps_the_cells_its_calibration_was_fitted_at():
    """The packaged fit is the thesis rig's at 3 cells a section (its report's 509 entries rest on them); a
    fitted or user calibration keeps the 27 mm default too; only a derived one is refined."""
    from flexdigit.twin.calibration import packaged_calibration
    from flexdigit.twin.resolution import DERIVED_RTOL, twin_default_cells

    assert Twin(RigParams()).chain.n == 9
    one = RigParams.from_dict(DIGITS["one-section"])
    derived = Twin(one).calibration
    fitted = derived.replace(strip_beta_s=derived.strip_beta_s * 1.01)  # e.g. calibrate's result
    assert twin_default_cells(one, fitted) == twin_cells(one) == (7,)
    assert Twin(one, calibration=fitted).chain.n == 7
    cells = twin_default_cells(one, derived)
    assert static_error(one, derived, cells).worst <= DERIVED_RTOL
    fewer = tuple(n - 2 for n in cells)  # the fewest odd cells that meet it
    assert static_error(one, derived, fewer).worst > DERIVED_RTOL
    assert twin_default_cells(RigParams(), packaged_calibration()) == (3, 3, 3)
