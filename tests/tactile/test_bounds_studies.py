import numpy as np
import pytest

from flexdigit.errors import ParameterError
from flexdigit.tactile.bounds import ZONES, cramer_rao, protocol_limits
from flexdigit.tactile.estimators import BeamInversion, GPLocaliser
from flexdigit.tactile.localisation import localisation_study
from flexdigit.tactile.protocols import load_protocol
from flexdigit.tactile.runner import collect

NOISE = 0.002


class Cantilever:
    noise_v = np.full(3, NOISE)

    def __init__(self, model):
        self.model = model

    def gauges_v(self, a, m, command):
        return self.model(a, m)


def test_zones_follow_the_cantilever(cantilever_model):
    # no moment reaches a gauge beyond the load: clamp..gauge 1 invisible, gauge 1..2 one equation (confounded)
    b = cramer_rao(Cantilever(cantilever_model), [0.03, 0.10, 0.18, 0.26], 0.0125)
    assert b.zone.tolist() == [ZONES[0], ZONES[1], ZONES[2], ZONES[2]]
    assert np.isinf(b.crlb_m[:2]).all()
    assert np.isfinite(b.crlb_known_mass_m[1])


def test_crlb_matches_closed_form(cantilever_model):
    # beyond gauge 3, v_i = k_i m g (a - x_i): the 2x2 Fisher information has a closed form
    a, m = 0.25, 0.0125
    k = np.array([40.0, 45.0, 50.0]) * 9.81
    x = np.array([0.045, 0.135, 0.225])
    ja, jm = k * m, k * (a - x)
    f = np.array([[ja @ ja, ja @ jm], [ja @ jm, jm @ jm]]) / NOISE**2
    b = cramer_rao(Cantilever(cantilever_model), [a], m)
    assert b.crlb_m[0] == pytest.approx(np.sqrt(np.linalg.inv(f)[0, 0]), rel=1e-3)
    assert b.crlb_known_mass_m[0] == pytest.approx(1 / np.sqrt(f[0, 0]), rel=1e-3)


def test_beam_inversion_is_efficient_on_its_own_model(cantilever_model):
    # the maximum-likelihood inversion on the true model reaches the Cramer-Rao bound (within 15 %, 400 draws)
    model = Cantilever(cantilever_model)
    rng = np.random.default_rng(2)
    a = rng.uniform(0.235, 0.27, 400)
    m = rng.uniform(0.01, 0.03, 400)
    v = cantilever_model(a, m) + NOISE * rng.standard_normal((400, 3))
    est = BeamInversion(model, calibrate=False).fit(v[:1])
    err = est.predict(v)[:, 0] - (0.27 - a)
    bound = np.sqrt(np.mean(cramer_rao(model, a, m).crlb_m ** 2))
    assert np.sqrt(np.mean(err**2)) == pytest.approx(bound, rel=0.15)


def test_localisation_study_on_table_6_1(tmp_path, make_rig, cantilever_model):
    ds = collect(load_protocol("thesis-6.1"), make_rig(seed=0), tmp_path / "d.parquet")
    r = localisation_study(ds, Cantilever(cantilever_model), seed=0, epochs=10)
    # a load 24 cm from the tip (3 cm from the clamp) bends no gauge of a cantilever: every such reading is invisible
    far = ds["position_index"][r.test_rows] == 16
    assert set(r.zone[far]) == {ZONES[0]}
    inv = r.position_rmse_identifiable_m["beam inversion"]
    assert inv <= 1.25 * r.crlb_rms_identifiable_m
    assert r.contact_accuracy_visible["beam inversion"] >= 0.99
    assert r.magnitude_rel_rmse_identifiable["beam inversion"] < 0.10
    # the Bayes limit knows the protocol: no estimator beats it by more than the test set's sampling error
    best = min(r.position_rmse_identifiable_m.values())
    assert r.bayes["position_rmse_identifiable_m"] <= 1.1 * best  # 0 here: 2 mV noise separates every position
    assert r.bayes["contact_accuracy_visible"] >= max(r.contact_accuracy_visible.values()) - 0.01
    gp_mean, gp_std = GPLocaliser().fit(ds.gauges_v[:50], ds["load_kg"][:50]).predict(ds.gauges_v[:5], True)
    assert gp_std.shape == gp_mean.shape == (5, 1)


def test_tare_zeroes_each_test_on_its_no_load_readings(tmp_path, make_rig):
    from flexdigit.tactile.localisation import tare
    from flexdigit.tactile.protocols import Protocol

    p = Protocol("t", loads_kg=(0.01, 0.02), positions_from_tip_m=(0.0,), repetitions=3, no_load_repetitions=4)
    ds = collect(p, make_rig(seed=1), tmp_path / "t.parquet")
    ds.columns["gauge1_v"] = ds["gauge1_v"] + 0.5 * ds["test"]  # a different offset per test
    tared, since = tare(ds)
    for test in (0, 1):
        zero = (ds["test"] == test) & (ds["load_kg"] == 0)
        np.testing.assert_allclose(tared.gauges_v[zero].mean(axis=0), 0.0, atol=1e-12)
    assert np.all(since >= 0)
    assert since[ds["load_kg"] > 0].min() > 0


def test_known_load_set_inversion_recovers_the_load(cantilever_model):
    # noise-free readings of loads from a set of three: the set-restricted inversion returns the exact load
    model = Cantilever(cantilever_model)
    a = np.array([0.25, 0.20, 0.265, 0.15])
    m = np.array([0.0075, 0.025, 0.0125, 0.025])
    v = cantilever_model(a, m)
    y = np.column_stack([0.27 - a, m])
    est = BeamInversion(model, load_set=True, calibrate=False).fit(v, y)
    pred = est.predict(v)
    np.testing.assert_allclose(pred[:, 1], m)
    np.testing.assert_allclose(pred[:, 0], 0.27 - a, atol=2e-4)


class LoadDependentNoise:
    """One gauge reading ``k a m`` (two more that read nothing), with noise ``s0 + c a`` on the first gauge."""

    k, s0, c = 40.0, 0.002, 0.05

    def gauges_v(self, a, m, command):
        a, m = np.broadcast_arrays(np.atleast_1d(a), np.atleast_1d(m))
        out = np.zeros((a.size, 3))
        out[:, 0] = self.k * a * m
        out[:, 1:] = (a * m)[:, None] * [1e-3, 2e-3]  # tiny, so the zone is not "no gauge bends"
        return out

    noise_v = np.array([0.002, 1.0, 1.0])

    def noise_at(self, a, m, command):
        a = np.atleast_1d(a)
        return np.column_stack([self.s0 + self.c * a, np.ones(a.size), np.ones(a.size)])


def test_crlb_includes_load_dependent_noise_in_closed_form():
    # mass known, one parameter a: F = (dg/da)^2 / sigma^2 + 2 (dsigma/da)^2 / sigma^2 (Gaussian with a-dependent
    # variance), summed over gauges; gauges 2-3 add (1e-3 m)^2 + (2e-3 m)^2 with sigma 1
    model, a, m = LoadDependentNoise(), 0.2, 0.025
    sigma = model.s0 + model.c * a
    fisher = ((model.k * m) ** 2 + 2 * model.c**2) / sigma**2 + (1e-3 * m) ** 2 + (2e-3 * m) ** 2
    b = cramer_rao(model, [a], m, 20)
    assert b.crlb_known_mass_m[0] == pytest.approx(1 / np.sqrt(fisher), rel=1e-6)
    # a fixed noise override drops the spread's information: (dg/da)^2 / sigma^2 only
    fixed = cramer_rao(model, [a], m, 20, noise_v=[sigma, 1.0, 1.0])
    assert fixed.crlb_known_mass_m[0] == pytest.approx(
        1 / np.sqrt((model.k * m / sigma) ** 2 + (1e-3 * m) ** 2 + (2e-3 * m) ** 2), rel=1e-6
    )


def test_twin_gauge_model_noise_is_white_when_relaxed_and_adds_friction_when_taut():
    from flexdigit.tactile.bounds import TwinGaugeModel
    from flexdigit.twin.calibration import default_calibration
    from flexdigit.twin.twin import friction_sd_v, static_gauges_v

    cal = default_calibration()
    assert cal.cable_friction_ratio > 0
    model = TwinGaugeModel(calibration=cal)
    np.testing.assert_array_equal(model.noise_at([0.2], [0.025], [-1])[0], cal.noise_white_v)
    _, sol = static_gauges_v([0.025], [0.2], [40], calibration=cal, adc=False, return_solution=True)
    expected = np.sqrt(np.array(cal.noise_white_v) ** 2 + friction_sd_v(sol, calibration=cal)[0] ** 2)
    np.testing.assert_allclose(model.noise_at([0.2], [0.025], [40])[0], expected, rtol=1e-12)
    # the bound grows with the friction: twice the ratio, a looser bound at command 40
    looser = TwinGaugeModel(calibration=cal.replace(cable_friction_ratio=2 * cal.cable_friction_ratio))
    assert (
        cramer_rao(looser, [0.2], 0.025, 40).crlb_known_mass_m[0]
        > cramer_rao(model, [0.2], 0.025, 40).crlb_known_mass_m[0]
    )


def test_twin_gauge_model_solves_a_grid_once_for_its_voltages_and_noise(monkeypatch):
    # the inversion asks for a grid's voltages, then its noise, and tares on a grid of no-load cases: one solve each,
    # of the distinct cases only, with the numbers of a solve of every case (rounding: another batch size)
    import flexdigit.tactile.bounds as bounds
    import flexdigit.twin.twin as twin
    from flexdigit.tactile.bounds import TwinGaugeModel
    from flexdigit.twin.calibration import default_calibration

    cal = default_calibration()
    rng = np.random.default_rng(3)
    a, m = rng.uniform(0.0, 0.27, 40), rng.uniform(0.0, 0.05, 40)
    a[:10], m[:10] = 0.0, 0.0  # ten identical no-load cases
    c = np.full(40, 40)
    cases = []
    solve = twin.static_gauges_v
    monkeypatch.setattr(
        bounds,  # where TwinGaugeModel looks it up
        "static_gauges_v",
        lambda mass, pos, *args, **kw: cases.append(np.size(mass)) or solve(mass, pos, *args, **kw),
    )
    model = TwinGaugeModel(calibration=cal)
    volts, noise = model.gauges_v(a, m, c), model.noise_at(a, m, c)
    assert cases == [31]  # 30 loaded + 1 no-load case, solved once for both
    _, sol = solve(m, a, c, calibration=cal, adc=False, return_solution=True)
    np.testing.assert_allclose(volts, solve(m, a, c, calibration=cal, adc=False), rtol=1e-12, atol=1e-15)
    friction = twin.friction_sd_v(sol, calibration=cal)
    np.testing.assert_allclose(noise, np.sqrt(np.array(cal.noise_white_v) ** 2 + friction**2), rtol=1e-9)
    model.gauges_v(a, m, np.full(40, 50))  # another command: a solve of its own
    assert cases == [31, 31]
    model.calibration = cal.replace(cable_friction_ratio=2 * cal.cable_friction_ratio)  # other settings: solved anew
    model.noise_at(a, m, c)
    assert cases == [31, 31, 31]


class OneGauge:
    """Gauge 1 reads ``slope * m * a`` (V), the others nothing; constant noise ``sigma``."""

    def __init__(self, slope=1.0, sigma=0.01):
        self.slope, self.noise_v = slope, np.array([sigma, sigma, sigma])

    def gauges_v(self, a, m, command):
        a, m = np.broadcast_arrays(np.atleast_1d(np.asarray(a, float)), np.atleast_1d(np.asarray(m, float)))
        return np.column_stack([self.slope * m * a, 0 * a, 0 * a])


def test_bayes_contact_error_is_the_gaussian_tail():
    # load vs no load, equal priors, one gauge separated by d = 2 sigma: Bayes error Phi(-d / 2 sigma) = Phi(-1)
    from scipy.stats import norm

    model = OneGauge(slope=1.0, sigma=0.01)
    lim = protocol_limits(model, [0.0, 0.2], [0.0, 0.1], [-1, -1], samples=40000, seed=1)
    assert lim.contact_error == pytest.approx([norm.cdf(-1.0)] * 2, abs=0.006)
    assert np.isnan(lim.position_mse_m2[0])
    assert lim.position_mse_m2[1] == 0.0  # one loaded setting: no doubt


def test_bayes_position_error_matches_numerical_integration():
    # two equally likely positions a1, a2, same mass: the posterior mean errs by (a2 - a1) p_wrong, with
    # p_wrong = 1 / (1 + exp(D x)) for the reading x sigma from its own mean, D = (v2 - v1) / sigma
    from scipy.integrate import quad
    from scipy.stats import norm

    model, a1, a2, m = OneGauge(slope=1.0, sigma=0.01), 0.20, 0.22, 1.0
    d = (a2 - a1) * m / 0.01

    def p_wrong_sq(x):
        return norm.pdf(x) / (1 + np.exp(d * x + d * d / 2)) ** 2

    expected = (a2 - a1) ** 2 * quad(p_wrong_sq, -12, 12)[0]
    lim = protocol_limits(model, [a1, a2], [m, m], [-1, -1], samples=40000, seed=2)
    assert lim.position_mse_m2 == pytest.approx([expected, expected], rel=0.05)
    assert lim.contact_error.tolist() == [0.0, 0.0]  # no no-load setting: always a load


def test_bayes_limits_are_seeded_and_refuse_repeated_settings():
    model = OneGauge()
    one = protocol_limits(model, [0.1, 0.2], [0.02, 0.02], [-1, -1], samples=500, seed=3)
    two = protocol_limits(model, [0.1, 0.2], [0.02, 0.02], [-1, -1], samples=500, seed=3)
    np.testing.assert_array_equal(one.position_mse_m2, two.position_mse_m2)  # exact: one seed, one path, one machine
    with pytest.raises(ValueError, match="distinct settings"):
        protocol_limits(model, [0.1, 0.1], [0.02, 0.02], [-1, -1])


def test_bayes_contact_uses_the_no_load_noise_when_given():
    # no-load readings 10x quieter than loaded ones: a no-load reading is almost never mistaken for a load (it would
    # have to stray 1 sigma_loaded = 10 of its own sigmas), and a loaded one only when all three gauges land in the
    # no-load's narrow band: both errors fall far below the equal-noise Phi(-1) = 0.159
    from scipy.stats import norm

    model = OneGauge(slope=1.0, sigma=0.01)
    lim = protocol_limits(model, [0.0, 0.2], [0.0, 0.1], [-1, -1], samples=40000, seed=4, no_load_noise_v=[1e-3] * 3)
    assert lim.contact_error[0] < 1e-3
    assert lim.contact_error[1] < 0.1 * norm.cdf(-1.0)


def test_identifiability_map_zones_and_scaling_on_the_cantilever(cantilever_model):
    from flexdigit.tactile.localisation import identifiability_map
    from flexdigit.tactile.protocols import RELAXED

    gauges = np.array([0.045, 0.135, 0.225])  # table 3.5, the cantilever's gauges
    out = identifiability_map(Cantilever(cantilever_model), [0.0125, 0.025], [RELAXED], 0.27, points=109)
    a = out["position_from_base_m"]
    assert a[0] == 0.0
    assert a[-1] == pytest.approx(0.27)
    assert len(out["cases"]) == 2
    light, heavy = out["cases"]
    # zones change exactly at the gauges (closed form: a load bends only the gauges between it and the clamp)
    off = np.min(np.abs(a[:, None] - gauges[:2]), axis=1) > 0.003
    expected = np.where(a < gauges[0], ZONES[0], np.where(a < gauges[1], ZONES[1], ZONES[2]))
    assert (light["zone"][off] == expected[off]).all()
    assert (heavy["zone"][off] == expected[off]).all()
    # v_i = k_i m g (a - x_i): dv/da grows as m, so the known-mass bound halves when the mass doubles
    beyond = a > gauges[2] + 0.005
    np.testing.assert_allclose(heavy["crlb_known_m"][beyond], light["crlb_known_m"][beyond] / 2, rtol=1e-3)
    assert np.isinf(light["crlb_m"][a < gauges[1] - 0.003]).all()


def test_strategies_on_the_cantilever_err_only_where_no_gauge_bends(tmp_path, make_rig):
    # figures 6.2-6.4: with a 2 mV cantilever the visible loads are easy; a no-load reading and a load before gauge 1
    # read alike (zero moment at every gauge), so contact can be wrong on those test readings and nowhere else
    from flexdigit.tactile.pipeline import compare_strategies, thesis_split

    ds = collect(load_protocol("thesis-6.1"), make_rig(seed=0), tmp_path / "d.parquet")
    scores = compare_strategies(ds, seed=0, epochs=10)
    assert [s.strategy for s in scores] == ["parallel", "combined", "cascaded"]
    test = thesis_split(len(ds), 0).test
    ambiguous = np.sum((ds["load_kg"][test] == 0) | (ds["position_index"][test] == 16))
    best_possible = 1 - min(np.sum(ds["load_kg"][test] == 0), np.sum(ds["position_index"][test] == 16)) / len(test)
    for s in scores:
        assert 1 - ambiguous / len(test) <= s.contact_accuracy <= best_possible, s
    parallel = scores[0]
    assert parallel.position_corr2 > 0.99
    assert parallel.position_rmse_m < 0.005
    assert scores[2].position_corr2 > 0.99  # cascaded: the thesis feared compounding errors; none to compound here


class Gauges:
    """A cantilever's G gauges at ``places_m`` (1 V per N m of bending moment), noise ``NOISE`` each."""

    def __init__(self, places_m):
        self.places_m = np.asarray(places_m, dtype=float)
        self.noise_v = np.full(self.places_m.size, NOISE)

    def gauges_v(self, a, m, command):
        a, m = np.broadcast_arrays(np.atleast_1d(a), np.atleast_1d(m))
        return (9.81 * m)[:, None] * np.clip(a[:, None] - self.places_m, 0, None)


@pytest.mark.parametrize("places_m", [[0.05, 0.10], [0.02, 0.06, 0.10, 0.14, 0.18, 0.22, 0.26, 0.28]])
def test_beam_inversion_takes_the_models_gauge_count(places_m):
    # noise-free readings of a load beyond the last gauge (every gauge bends: position and mass identifiable)
    # give back the load; G + 1 columns carry the command; any other count is refused naming the expected one
    model = Gauges(places_m)
    a, m = np.array([0.29, 0.295]), np.array([0.02, 0.035])
    v = model.gauges_v(a, m, None)
    est = BeamInversion(model, digit_length_m=0.3, max_mass_kg=0.05, calibrate=False).fit(v)
    assert est.gain_.shape == (len(places_m),)
    np.testing.assert_allclose(est.predict(v), np.column_stack([0.3 - a, m]), atol=1e-5)
    with_command = np.column_stack([v, np.full(2, -1)])
    np.testing.assert_allclose(est.predict(with_command), est.predict(v), atol=1e-12)
    with pytest.raises(ParameterError, match=f"X must have {len(places_m)} gauge column"):
        est.predict(np.zeros((2, len(places_m) + 2)))
