"""Sobol indices of a tendon robot through the studies machinery, against closed forms.

- A pure tendon moment bends a one-segment robot's tip by ``theta = T d L / EI`` (issue 26), so with ``d`` and
  ``E`` independent and uniform on ``x0 (1 +- a)``, ``theta = c g(d) h(E)`` with ``g = d``, ``h = 1 / E``: the
  first-order indices of a product are ``S_d = Var(g) E[h]^2 / V`` and ``S_E = E[g]^2 Var(h) / V`` with
  ``V = E[g^2] E[h^2] - E[g]^2 E[h]^2``, and the moments of ``1 / E`` uniform are ``E[h] = ln((1+a)/(1-a)) /
  (2 a E0)``, ``E[h^2] = 1 / (E0^2 (1 - a^2))``. The density moves nothing: its indices are 0 exactly.
- The straight backbone's first frequency is ``~ sqrt(E / rho)`` (Euler-Bernoulli): a product of ``sqrt(E)`` and
  ``1 / sqrt(rho)``, whose uniform moments are closed forms too.

``SOBOL_ATOL``: the study's own convergence tolerance (0.05); the estimates at 2N = 128 are measured within 0.004
of the closed forms (tip angle) and 0.003 (frequency).
"""

import json
import math

import numpy as np
import pytest

from flexdigit.cli import main
from flexdigit.errors import ParameterError
from flexdigit.studies.robot_study import load_robot_spec, robot_spec_from_toml, run_robot_sensitivity, tip_angle_deg
from flexdigit.studies.sensitivity import SensitivitySettings

SOBOL_ATOL = 0.05
SPREAD = 0.1

ROD = """name = "one-tendon"
[[segments]]
length_m = 0.2
disk_count = 10
[[tendons]]
offset_m = 0.01
angle_deg = 90.0
disk = 10
"""


def _spec(tmp_path, body, robot=ROD):
    (tmp_path / "rod.toml").write_text(robot)
    path = tmp_path / "spec.toml"
    path.write_text(body)
    return path


def _uniform_moments(power, a=SPREAD):
    """E[x^p] of x uniform on (1 - a, 1 + a)."""
    lo, hi = 1 - a, 1 + a
    if power == -1:
        return math.log(hi / lo) / (hi - lo)
    return (hi ** (power + 1) - lo ** (power + 1)) / ((power + 1) * (hi - lo))


def _product_indices(p, q):
    """First-order indices of x^p y^q, x and y independent uniform on 1 +- SPREAD."""
    gx, gx2, hy, hy2 = _uniform_moments(p), _uniform_moments(2 * p), _uniform_moments(q), _uniform_moments(2 * q)
    total = gx2 * hy2 - gx**2 * hy**2
    return (gx2 - gx**2) * hy**2 / total, gx**2 * (hy2 - hy**2) / total


def _run(path, tmp_path, n):
    settings = SensitivitySettings(morris_trajectories=0, sobol_n=n, bootstrap=50)
    return run_robot_sensitivity(path, tmp_path / "out", settings=settings, workers=0, progress=False)


def test_tip_angle_indices_of_a_pure_tendon_moment(tmp_path):
    path = _spec(
        tmp_path,
        f"""[study]
robot = "rod.toml"
tensions_n = [0.5]
metrics = ["tip_angle_deg"]
[parameters.backbone.youngs_modulus_pa]
distribution = "uniform"
relative = {SPREAD}
[parameters.backbone.density_kg_m3]
distribution = "uniform"
relative = {SPREAD}
[parameters.tendons.offset_m]
distribution = "uniform"
relative = {SPREAD}
""",
    )
    result = _run(path, tmp_path, 64)
    s_d, s_e = _product_indices(1, -1)
    res = result.sobol["tip_angle_deg"][128]
    names = result.spec.names
    assert names == ["backbone.youngs_modulus_pa", "backbone.density_kg_m3", "tendons.offset_m[*]"]
    np.testing.assert_allclose(res["S1"][[0, 2]], [s_e, s_d], atol=SOBOL_ATOL)
    np.testing.assert_allclose(res["ST"][[0, 2]], [1 - s_d, 1 - s_e], atol=SOBOL_ATOL)
    assert res["S1"][1] == 0.0
    assert res["ST"][1] == 0.0
    # the angle itself: T d L / EI at the nominal robot (the Cosserat rod's extension couples at ~1e-4)
    case = result.spec.baseline
    ei = case.robot.backbone.bending_torsion_stiffness[0]
    assert tip_angle_deg(case) == pytest.approx(math.degrees(0.5 * 0.01 * 0.2 / ei), rel=1e-3)


def test_first_frequency_indices_of_modulus_and_density(tmp_path):
    path = _spec(
        tmp_path,
        f"""[study]
robot = "rod.toml"
metrics = ["first_frequency_hz"]
[parameters.backbone.youngs_modulus_pa]
distribution = "uniform"
relative = {SPREAD}
[parameters.backbone.density_kg_m3]
distribution = "uniform"
relative = {SPREAD}
""",
    )
    result = _run(path, tmp_path, 32)
    s_e, s_rho = _product_indices(0.5, -0.5)
    res = result.sobol["first_frequency_hz"][64]
    np.testing.assert_allclose(res["S1"], [s_e, s_rho], atol=SOBOL_ATOL)


@pytest.mark.parametrize(
    ("body", "needle"),
    [
        ('[study]\nrobot = "nope"\n', "[study] robot: unknown robot 'nope'"),
        ('[study]\nrobot = "rod.toml"\n[parameters.arm.x]\ndistribution = "uniform"\n', "unknown section 'arm'"),
        ('[study]\nrobot = "rod.toml"\n[parameters.backbone.mass]\n', "unknown field 'mass'"),
        ('[study]\nrobot = "rod.toml"\n', "nothing is uncertain"),
        ('[study]\nrobot = "rod.toml"\ntensions_n = [1, 2]\n', "[study] tensions_n must list one tension"),
        ('[study]\nrobot = "rod.toml"\nmetrics = ["wn"]\n', "unknown robot metric 'wn'"),
        ('[study]\nrobot = "rod.toml"\nflavour = 1\n', "unknown key 'flavour' in [study]"),
        (
            '[study]\nrobot = "rod.toml"\n[parameters.backbone.radius_m]\ndistribution = "uniform"\nrelative = 1.5\n',
            "radius_m",
        ),
        (
            '[study]\nrobot = "rod.toml"\n[parameters.loads.tensions_n.0]\ndistribution = "normal"\nsd = 0.1\n',
            "tendon tensions must be finite and >= 0 N",
        ),
        (
            '[study]\nrobot = "rod.toml"\n[parameters.tendons.offset_m.3]\ndistribution = "uniform"\ndelta = 1e-3\n',
            "element tables 0..0",
        ),
    ],
)
def test_bad_robot_specs_are_refused_in_one_line(tmp_path, body, needle):
    with pytest.raises(ParameterError) as info:
        load_robot_spec(_spec(tmp_path, body))
    assert needle in str(info.value)
    assert "spec.toml" in str(info.value)
    assert "\n" not in str(info.value)


def test_the_shipped_rao2021_spec_reads():
    spec = load_robot_spec("rao2021-tolerances")
    assert spec.baseline.robot.name == "rao2021"
    assert len(spec.parameters) == 5
    assert spec.parameter_set(np.ones(5) * [54e9, 0.7e-3, 1.0, 4.0, 2.0]).tensions_n == (4.0, 0, 0, 0, 2.0, 0)
    assert robot_spec_from_toml(
        '[study]\nrobot = "rao2021"\n[parameters.loads.tensions_n]\ndistribution = "uniform"\nrelative = 0.1\n'
    ).names == ["loads.tensions_n[*]"]


def test_study_sensitivity_runs_a_robot_spec(tmp_path, capsys):
    path = _spec(
        tmp_path,
        """[study]
robot = "rod.toml"
tensions_n = [0.5]
metrics = ["tip_angle_deg", "tip_z_m"]
[sensitivity]
morris_trajectories = 2
[parameters.backbone.youngs_modulus_pa]
distribution = "uniform"
relative = 0.1
[parameters.tendons.offset_m]
distribution = "uniform"
relative = 0.1
""",
    )
    out = tmp_path / "out"
    argv = ["study", "sensitivity", str(path), "--out", str(out), "--workers", "0", "--n", "8", "--no-progress"]
    assert main([*argv, "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert set(summary["metrics"]) == {"tip_angle_deg", "tip_z_m"}
    assert summary["metrics"]["tip_angle_deg"]["unit"] == "deg"
    assert (out / "indices.parquet").exists()
    assert (out / "summary.json").exists()
    assert main([*argv, "--json"]) == 2  # finished: refused without --force
    assert "pass --force" in json.loads(capsys.readouterr().out)["error"]
    assert main(["study", "design", str(path), "--out", str(tmp_path / "d"), "--json"]) == 2
    assert "sensitivity study only" in json.loads(capsys.readouterr().out)["error"]
