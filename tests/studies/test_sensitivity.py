"""Sobol and Morris on the Ishigami function, whose indices are known in closed form (Ishigami & Homma 1990;
Saltelli et al. 2008, 'Global Sensitivity Analysis: The Primer', 4.7), through the whole study machinery."""

import json
import math

import numpy as np
import pyarrow.parquet as pq
import pytest

from flexdigit.errors import OutputExistsError
from flexdigit.studies import metrics as metrics_module
from flexdigit.studies.sensitivity import SensitivitySettings, run_sensitivity, sobol_indices, write_outputs
from flexdigit.studies.spec import spec_from_toml

# f = sin x1 + 7 sin^2 x2 + 0.1 x3^4 sin x1, x ~ U(-pi, pi)^3 (a = 7, b = 0.1)
A, B = 7.0, 0.1
_V1 = 0.5 * (1 + B * math.pi**4 / 5) ** 2
_V2 = A**2 / 8
_V13 = B**2 * math.pi**8 * (1 / 18 - 1 / 50)
_V = _V1 + _V2 + _V13
S1 = np.array([_V1 / _V, _V2 / _V, 0.0])
ST = np.array([(_V1 + _V13) / _V, _V2 / _V, _V13 / _V])
INDEX_ATOL = 0.05  # 2N = 1024 Saltelli samples: the estimators' error is ~0.02

FIELDS = {  # three real fields of the rig, each mapped linearly onto [-pi, pi]
    "material.youngs_modulus_pa": (1e11, 3e11),
    "material.strip_density_kg_m3": (7000.0, 9000.0),
    "sensors.gauge_factor": (0.5, 1.5),
}
SPEC = "\n".join(
    f"[parameters.{name}]\ndistribution = 'uniform'\nlow = {lo!r}\nhigh = {hi!r}\n" for name, (lo, hi) in FIELDS.items()
)


def _x(ps):
    values = [
        ps.params.material.youngs_modulus_pa,
        ps.params.material.strip_density_kg_m3,
        ps.params.sensors.gauge_factor,
    ]
    return [-math.pi + 2 * math.pi * (v - lo) / (hi - lo) for v, (lo, hi) in zip(values, FIELDS.values(), strict=True)]


def _ishigami(ps, ctx):
    x1, x2, x3 = _x(ps)
    return math.sin(x1) + A * math.sin(x2) ** 2 + B * x3**4 * math.sin(x1)


@pytest.fixture
def ishigami_metric():
    metrics_module.register_metric("ishigami", "", "Ishigami test function")(_ishigami)
    yield "ishigami"
    del metrics_module.METRICS["ishigami"]


def test_closed_form_values():
    # the textbook figures (Saltelli et al. 2008): S1 = 0.3139, 0.4424, 0; ST = 0.5576, 0.4424, 0.2437
    np.testing.assert_allclose(S1, [0.3139, 0.4424, 0.0], atol=1e-4)
    np.testing.assert_allclose(ST, [0.5576, 0.4424, 0.2437], atol=1e-4)


def test_ishigami_indices_converge_to_the_closed_form(ishigami_metric, tmp_path):
    spec = spec_from_toml(f"[study]\nmetrics = ['{ishigami_metric}']\nseed = 5\n" + SPEC)
    settings = SensitivitySettings(
        morris_trajectories=20, sobol_n=512, bootstrap=100, chunk_size=512, convergence_tol=0.05
    )
    result = run_sensitivity(spec, tmp_path, settings=settings, workers=0, progress=False)
    res = result.sobol[ishigami_metric][1024]
    np.testing.assert_allclose(res["S1"], S1, atol=INDEX_ATOL)
    np.testing.assert_allclose(res["ST"], ST, atol=INDEX_ATOL)
    # the intervals are real intervals: they cover the truth (at 95 %, allow a little slack for the bootstrap)
    assert np.all(np.abs(res["ST"] - ST) <= 2 * res["ST_conf"] + 0.01)
    assert result.convergence[ishigami_metric]["converged"]
    # Morris ranks x3 last by mu_star, as its elementary effects are only felt through x1 (Saltelli 2008, 3.8)
    mu = result.morris[ishigami_metric]["mu_star"]
    assert mu[2] < max(mu[0], mu[1])

    paths = write_outputs(result, tmp_path)
    table = pq.read_table(paths["indices"]).to_pandas()
    assert set(table.columns) == {"metric", "method", "index", "parameter", "parameter_2", "n_base", "value", "conf"}
    st = table.query("method == 'sobol' and index == 'ST' and n_base == 1024").set_index("parameter")["value"]
    np.testing.assert_allclose(st[list(spec.names)].to_numpy(), res["ST"])
    summary = json.loads(paths["summary"].read_text())
    assert summary["metrics"][ishigami_metric]["convergence"]["converged"]
    assert summary["sobol_estimator"].startswith("SALib.analyze.sobol")  # a first-order design: SALib's own
    assert (tmp_path / "figures" / f"sobol_{ishigami_metric}.png").stat().st_size > 1000
    with pytest.raises(OutputExistsError):
        write_outputs(result, tmp_path)


def test_too_few_samples_are_flagged_unconverged(ishigami_metric, tmp_path, capsys):
    spec = spec_from_toml(f"[study]\nmetrics = ['{ishigami_metric}']\n" + SPEC)
    settings = SensitivitySettings(morris_trajectories=0, sobol_n=8, convergence_tol=0.01, chunk_size=64)
    result = run_sensitivity(spec, tmp_path, settings=settings, workers=0, progress=False)
    assert not result.convergence[ishigami_metric]["converged"]
    assert "NOT converged" in capsys.readouterr().err


def test_second_order_finds_the_x1_x3_interaction():
    # S2 of Ishigami: only (x1, x3) interact, S13 = V13 / V = 0.2437
    from SALib.sample import sobol

    problem = {"num_vars": 3, "names": list("abc"), "bounds": [[-math.pi, math.pi]] * 3}
    x = sobol.sample(problem, 1024, calc_second_order=True, seed=3)
    y = np.sin(x[:, 0]) + A * np.sin(x[:, 1]) ** 2 + B * x[:, 2] ** 4 * np.sin(x[:, 0])
    res = sobol_indices(list("abc"), y, True, 100, 0.95, seed=0)
    assert res["S2"][0, 2] == pytest.approx(ST[2], abs=0.06)
    assert abs(res["S2"][0, 1]) < 0.06
    assert abs(res["S2"][1, 2]) < 0.06


def test_failed_rows_are_reported_with_their_parameters_and_block_the_indices(tmp_path, capsys):
    # each range passes on its own, but some draws put gauge 2 beyond gauge 3: those rows fail, the rest run
    spec = spec_from_toml(
        """
[study]
metrics = ["release_wn_rad_s"]
[parameters.geometry.gauge_positions_m.1]
distribution = "uniform"
low = 0.10
high = 0.20
[parameters.geometry.gauge_positions_m.2]
distribution = "uniform"
low = 0.15
high = 0.26
"""
    )
    settings = SensitivitySettings(morris_trajectories=0, sobol_n=8, chunk_size=4)
    result = run_sensitivity(spec, tmp_path, settings=settings, workers=0, progress=False)
    summary = result.summary()
    failed = summary["failed_rows"]
    assert failed
    assert len(failed) < result.values.shape[0]
    for row in failed:
        p = row["parameters"]
        assert p["geometry.gauge_positions_m[1]"] >= p["geometry.gauge_positions_m[2]"]
        assert "gauge_positions_m" in row["error"]
    assert "release_wn_rad_s" in result.refused
    assert "release_wn_rad_s" not in result.sobol
    assert "not finite" in capsys.readouterr().err


def _flags(*command):
    """The option strings of ``flexdigit COMMAND ...``."""
    import argparse

    from flexdigit.cli import build_parser

    parser = build_parser()
    for name in command:
        sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        parser = sub.choices[name]
    return {option for action in parser._actions for option in action.option_strings}


def test_unconverged_warning_names_a_command_and_flag_that_exist(ishigami_metric, tmp_path, capsys):
    # issue 27 item 5: `reproduce` printed "rerun with --n 64", a flag reproduce does not have
    spec = spec_from_toml(f"[study]\nmetrics = ['{ishigami_metric}']\n" + SPEC)
    settings = SensitivitySettings(morris_trajectories=0, sobol_n=8, convergence_tol=0.01, chunk_size=64)
    run_sensitivity(spec, tmp_path / "a", settings=settings, workers=0, progress=False)
    assert "rerun `flexdigit study sensitivity` with --n 32" in capsys.readouterr().err
    assert "--n" in _flags("study")  # `study sensitivity SPEC --n N`
    # the report's study (reproduce) names what reproduce has
    from flexdigit.report.ch8_studies import rerun_hint

    hint = rerun_hint(True, 16)
    assert "--n" not in hint
    assert "`flexdigit reproduce` without --fast" in hint
    assert "--fast" in _flags("reproduce")
    assert "--n" not in _flags("reproduce")
    assert "`flexdigit study sensitivity thesis-tolerances --n 512`" in rerun_hint(False, 128)
    run_sensitivity(spec, tmp_path / "b", settings=settings, workers=0, progress=False, rerun=hint)
    err = capsys.readouterr().err
    assert "NOT converged" in err
    assert hint in err
    assert "--n" not in err


def test_figures_carry_the_n_used_and_say_not_converged(ishigami_metric, tmp_path, monkeypatch):
    # issue 27 item 5: `study --n 8` titled its figures "N = 16" alone, and "not converged" was only on the terminal
    from flexdigit.studies import figures

    saved = {}
    monkeypatch.setattr(figures, "_save", lambda fig, path, force: saved.setdefault(path.name, fig) and path)
    spec = spec_from_toml(f"[study]\nmetrics = ['{ishigami_metric}']\n" + SPEC)
    settings = SensitivitySettings(morris_trajectories=0, sobol_n=8, convergence_tol=0.01, chunk_size=64)
    result = run_sensitivity(spec, tmp_path, settings=settings, workers=0, progress=False)
    assert not result.convergence[ishigami_metric]["converged"]
    figures.sensitivity_figures(result, tmp_path / "figures")
    bars = saved[f"sobol_{ishigami_metric}.png"].axes[0].get_title()
    assert "N = 16 (2 x 8: indices at 8 and 16 compared)" in bars
    assert "NOT converged: moved" in bars
    assert "between N = 8 and 16" in bars
    total = saved["sobol_total_map.png"].axes[0]
    assert "1 of 1 metrics NOT converged" in total.get_title()
    assert [t.get_text() for t in total.get_yticklabels()] == [f"{ishigami_metric} (NOT converged)"]
    # converged: no note
    converged = dict(result.convergence[ishigami_metric], converged=True)
    assert figures.convergence_note(converged) == ""
