"""Tapered sections in the design study (issue 24: the twin, the elastica oracle, shape and palpation take unequal
sections; the design study drew only equal ones): the taper's geometry against its definition, the shipped
thesis-design study unchanged, and a tapered design exported, checked, simulated and bent as its elastica."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math

import numpy as np
import pytest

from digits import DIGITS
from flexdigit.errors import ParameterError
from flexdigit.params import RigParams, digit_inconsistencies, load_params
from flexdigit.studies.design_study import (
    Candidate,
    DesignSettings,
    candidates,
    design_parameter_set,
    study_fingerprint,
    tapered,
)
from flexdigit.studies.spec import ParameterSet, load_spec, spec_from_toml
from flexdigit.twin.digit import build_digit
from flexdigit.twin.digit_calibration import calibration_for
from oracles import digit_contact_bvp, thesis_digit_segments

#: lengths summed from floats (m)
LENGTH_ATOL_M = 1e-12
#: issue 24: the twin's static deflection within 0.1 % of the elastica of the same geometry (as
#: tests/twin/test_digit_calibration.py holds every test digit to, with the same 27 cells and BVP tolerance)
ELASTICA_RTOL = 1e-3
CELLS = 27
BVP_TOL = 1e-8
#: The shipped thesis-design study as main c03479c (before tapers) computed it: the journal's fingerprint (so a
#: finished study resumes) and a hash of its 400 sampled candidates' options, in order.
THESIS_DESIGN_FINGERPRINT = "d7223240849e8632"
THESIS_DESIGN_CANDIDATES_SHA = "6ab478d4efb61cf8"


@pytest.mark.parametrize("digit", ["thesis", "five-sections-eight-gauges", "unequal-sections"])
@pytest.mark.parametrize("ratio", [0.5, 2.0, 0.2])
def test_a_taper_is_a_geometric_progression_of_the_same_strip(digit, ratio):
    params = RigParams.from_dict(DIGITS[digit])
    g, t = params.geometry, tapered(params, ratio).geometry
    lengths = np.array(t.section_lengths_m)
    n = g.section_count
    assert lengths[-1] / lengths[0] == pytest.approx(ratio, rel=1e-12)
    # each section the same factor longer than the one before it: ratio^(1 / (n - 1))
    assert np.allclose(lengths[1:] / lengths[:-1], ratio ** (1 / (n - 1)), rtol=1e-12, atol=0)
    assert math.fsum(lengths) == pytest.approx(g.strip_length_m, abs=LENGTH_ATOL_M)
    assert t.supports_m == pytest.approx(g.supports_m, abs=LENGTH_ATOL_M)
    assert t.digit_length_m == g.digit_length_m
    assert t.support_centres_m[-1] == pytest.approx(g.digit_length_m, abs=LENGTH_ATOL_M)  # the tip stays the tip

    # every gauge keeps its place within its section (its fraction of the section's strip)
    def fractions(geo):
        out = []
        for x in geo.gauge_positions_m:
            a, b = next((a, b) for a, b in geo.section_bounds_m if a <= x <= b)
            out.append((x - a) / (b - a))
        return out

    assert fractions(t) == pytest.approx(fractions(g), abs=1e-9)
    assert digit_inconsistencies(tapered(params, ratio)) == []


def test_the_thesis_rigs_tapered_gauges_stay_midway():
    g = tapered(RigParams(), 0.5).geometry
    mids = [(a + b) / 2 for a, b in g.section_bounds_m]
    assert g.gauge_positions_m == pytest.approx(mids, abs=LENGTH_ATOL_M)
    assert g.section_bounds_m[0][1] - g.section_bounds_m[0][0] > 0.1  # the base section the longest: 108.7 mm


def test_no_taper_is_the_baseline_itself():
    params = RigParams()
    assert tapered(params, 1.0) is params
    plain = Candidate(4, "equal", "full", 16, 219 / 508, 5.715e-3, 5.0, 1.25)
    assert design_parameter_set(ParameterSet(), plain) == design_parameter_set(
        ParameterSet(), dataclasses.replace(plain, section_taper=1.0)
    )
    assert plain.label() == "4 gauges equal, full bridge, 16 bit, 0.431 deg/cmd, e 5.71 mm, 2 cables 5 N, size x1.25"
    assert dataclasses.replace(plain, section_taper=2.0).label().endswith(", taper 2")


def test_the_shipped_thesis_design_study_is_unchanged():
    spec = load_spec("thesis-design")
    settings = DesignSettings.from_spec(spec)
    cands = candidates(settings, spec.seed)
    assert len(candidates(dataclasses.replace(settings, samples=0), spec.seed)) == 2916
    assert len(cands) == 400
    assert all(c.section_taper == 1.0 for c in cands)
    options = [dataclasses.astuple(c)[:-1] for c in cands]  # the options main had, in its order
    assert hashlib.sha256(repr(options).encode()).hexdigest()[:16] == THESIS_DESIGN_CANDIDATES_SHA
    assert study_fingerprint(spec, settings) == THESIS_DESIGN_FINGERPRINT
    # a taper is another study: its journal is not resumed as the untapered one's
    tapered_settings = dataclasses.replace(settings, section_taper=(1.0, 2.0))
    assert study_fingerprint(spec, tapered_settings) != THESIS_DESIGN_FINGERPRINT


def test_the_shipped_taper_study_reads():
    settings = DesignSettings.from_spec(load_spec("thesis-taper"))
    assert 1.0 in settings.section_taper
    assert min(settings.section_taper) < 1 < max(settings.section_taper)
    cands = candidates(settings, 0)
    assert sum(c.is_thesis for c in cands) == 1  # the thesis design (untapered) is marked on its front


@pytest.mark.parametrize("table", ["section_taper = [0.1]", "section_taper = [6.0]", "section_taper = ['x']"])
def test_bad_tapers_are_named(table):
    spec = spec_from_toml(f"[design]\n{table}\n", source="d.toml")
    with pytest.raises(ParameterError, match=r"d\.toml: \[design\] section_taper") as err:
        DesignSettings.from_spec(spec)
    assert "\n" not in str(err.value)


def test_a_one_section_digit_is_not_tapered():
    one = ParameterSet(RigParams.from_dict(DIGITS["one-section"]))
    c = Candidate(3, "equal", "half", 16, 219 / 254, 5.715e-3, 0.0, 1.0, 2.0)
    with pytest.raises(ParameterError, match="section_taper 2: the baseline digit has 1 section") as err:
        design_parameter_set(one, c)
    assert "\n" not in str(err.value)


def _elastica_tip_m(params, cal, force_n):
    segments, supports = thesis_digit_segments(params, cal)
    ref = digit_contact_bvp(
        segments,
        strip_mass_per_m=params.material.strip_density_kg_m3 * params.geometry.cross_section_m2,
        point_masses=dict(zip(supports, cal.support_mass_kg, strict=True)),
        gravity_ab=(9.80665, 0.0),  # hanging, tip down
        eccentricity_m=params.geometry.cable_eccentricity_m,
        cable_stiffness_n_m=cal.cable_stiffness_n_m,
        cable_pretension_m=params.cables.pretension_n / cal.cable_stiffness_n_m if params.cables.count == 2 else None,
        point_forces_b={params.geometry.digit_length_m: force_n},
        tol=BVP_TOL,
        max_nodes=100_000,
    )
    assert ref.converged, ref.message
    return ref.tip


def test_an_exported_tapered_design_runs_and_bends_as_its_elastica(tmp_path, capsys):
    from flexdigit.cli import main

    spec = tmp_path / "taper.toml"
    spec.write_text(
        """
[study]
seed = 4
[design]
gauge_counts = [4]
layouts = ["equal"]
bridges = ["full"]
adc_bits = [16]
servo_deg_per_command = [0.4311]
eccentricity_m = [0.005715]
pretension_n = [0.0]
size = [1.0]
section_taper = [0.5, 2.0]
bayes_samples = 50
"""
    )
    out = tmp_path / "out"
    base = ["study", "design", str(spec), "--out", str(out), "--workers", "0", "--no-progress"]
    assert main([*base, "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["candidates"] == 2
    assert {r["section_taper"] for r in summary["pareto_front"]} <= {0.5, 2.0}
    k = summary["pareto_front"][0]["row"]
    taper = summary["pareto_front"][0]["section_taper"]
    assert main([*base, "--export", str(k)]) == 0
    exported = out / f"design-{k}.toml"
    params = load_params(exported)
    lengths = params.geometry.section_lengths_m
    assert lengths[-1] / lengths[0] == pytest.approx(taper, rel=1e-9)  # unequal sections in the file
    assert main(["params", str(exported)]) == 0
    release = tmp_path / "release.parquet"
    argv = ["simulate", "release", "--params", str(exported), "--out", str(release), "--duration", "3"]
    assert main(argv) == 0
    assert release.exists()
    # its twin (the exported file's, calibration scaled to it) bends under a tip load as the elastica of its geometry
    cal = calibration_for(params)
    length = params.geometry.digit_length_m
    force = 1.0 * (params.bending_stiffness_n_m2 + min(cal.housing_ei_n_m2)) / length**2  # alpha^2 = 1
    tip = _elastica_tip_m(params, cal, force)
    twin = build_digit(params, cal, orientation="hanging", cells_per_section=CELLS).solve_static(
        tip_force_n=[[0.0, force]]
    )
    deflection = tip - np.array([length, 0.0])
    assert abs(deflection[1]) > 0.05 * length
    assert np.linalg.norm(twin.tip_m[0] - tip) < ELASTICA_RTOL * np.linalg.norm(deflection)
