"""A user's own metric: a spec's ``[metrics.NAME]`` names ``module:function`` of a parameter set; it is validated
when the spec is read (one line naming the key) and run like the built-in metrics, in process and on workers."""

import zlib

import numpy as np
import pytest

from flexdigit.errors import ParameterError
from flexdigit.studies.metrics import MetricContext, evaluate, evaluate_many
from flexdigit.studies.spec import spec_from_toml

# the strip's mass (g): density x thickness x width x length; a closed form of the parameters, so a value that is
# the wrong row's, or the baseline's, fails the comparison below
MODULE = """
def strip_mass_g(ps):
    g, m = ps.params.geometry, ps.params.material
    return 1e3 * m.strip_density_kg_m3 * g.strip_thickness_m * g.strip_width_m * g.digit_length_m

def words(ps):
    return "heavy"

NOT_A_FUNCTION = 3.0
"""

SPEC = """
[study]
name = "user-metric"
seed = 1
metrics = ["release_wn_rad_s"]
[sensitivity]
morris_trajectories = 0
sobol_n = 4
chunk_size = 4
[parameters.material.strip_density_kg_m3]
distribution = "uniform"
low = 7000.0
high = 9000.0
[parameters.geometry.strip_thickness_m]
distribution = "uniform"
relative = 0.1
[metrics.{name}]
function = "{function}"
unit = "g"
"""


def _strip_mass_g(ps):
    g, m = ps.params.geometry, ps.params.material
    return 1e3 * m.strip_density_kg_m3 * g.strip_thickness_m * g.strip_width_m * g.digit_length_m


@pytest.fixture
def user_module(tmp_path, monkeypatch, request):
    """A module of user metrics in a directory on the path, named per test (imports are cached)."""
    name = f"fd_user_metrics_{zlib.crc32(request.node.nodeid.encode()):08x}"
    (tmp_path / f"{name}.py").write_text(MODULE)
    monkeypatch.syspath_prepend(str(tmp_path))
    return name


def test_a_user_metric_runs_like_the_built_in_ones(user_module, tmp_path):
    from flexdigit.studies.sensitivity import run_sensitivity

    spec = spec_from_toml(SPEC.format(name="strip_mass_g", function=f"{user_module}:strip_mass_g"), "user.toml")
    assert spec.study_metrics(()) == ("release_wn_rad_s", "strip_mass_g")
    ctx = MetricContext(user_metrics=spec.user_metrics)
    ps = spec.parameter_set([8000.0, 0.4e-3])
    assert evaluate(ps, ["strip_mass_g"], ctx)["strip_mass_g"] == pytest.approx(_strip_mass_g(ps), rel=1e-15)
    result = run_sensitivity(spec, tmp_path / "out", workers=0, progress=False)
    rows = [spec.parameter_set(v) for v in result.values]
    np.testing.assert_allclose(result.outputs["strip_mass_g"], [_strip_mass_g(p) for p in rows], rtol=1e-15)
    assert np.ptp(result.outputs["strip_mass_g"]) > 0.05  # the rows' masses differ (g)
    assert result.summary()["metrics"]["strip_mass_g"]["unit"] == "g"
    # a row whose value is not a number is that row's error, naming the spec key
    bad = MetricContext(user_metrics=(spec.user_metrics[0].__class__("w", f"{user_module}:words", "g", "", "x"),))
    (out,) = evaluate_many([ps], ["w"], bad)
    assert isinstance(out, ParameterError)
    assert "x function:" in str(out)
    assert "'heavy'" in str(out)


@pytest.mark.parametrize(
    "name, function, expected",
    [
        ("m_g", "no_such_module_fd27:f", r"user.toml: \[metrics.m_g\] function: no module 'no_such_module_fd27'"),
        ("m_g", "{module}:NOT_A_FUNCTION", r"user.toml: \[metrics.m_g\] function: .*NOT_A_FUNCTION is a float"),
        ("m_g", "{module}:missing", r"user.toml: \[metrics.m_g\] function: module '.*' has no 'missing'"),
        ("m_g", "{module}:words", r"user.toml: \[metrics.m_g\] function: .*:words returned 'heavy' \(str\)"),
        ("m_g", "no colon", r"user.toml: \[metrics.m_g\] function: expected 'module:function'"),
        ("release_wn_rad_s", "{module}:strip_mass_g", r"user.toml: \[metrics.release_wn_rad_s\]: .*new identifier"),
    ],
)
def test_a_bad_user_metric_is_one_line_naming_its_key(user_module, name, function, expected):
    text = SPEC.format(name=name, function=function.format(module=user_module))
    with pytest.raises(ParameterError, match=expected) as info:
        spec_from_toml(text, "user.toml")
    assert "\n" not in str(info.value)
