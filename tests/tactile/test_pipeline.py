import numpy as np
import pytest
from sklearn.exceptions import NotFittedError

from flexdigit.errors import DataFileError
from flexdigit.tactile.accuracy import corr2, percentage_error
from flexdigit.tactile.model_io import load_model, save_model
from flexdigit.tactile.netlab import MLP, scg
from flexdigit.tactile.pipeline import Normaliser, ThesisNetwork, run_pipeline, thesis_split

# Tolerances, each with the reason for its size
EXACT_RTOL = 1e-12  # the same quantity computed two ways (numpy's corrcoef, E 6.1 written out, a saved model)
EXACT_ATOL = 1e-12  # ... where it is zero
SCG_QUADRATIC_RTOL = 1e-6  # SCG run to its 1e-10 step tolerance on a well-conditioned 6-D quadratic
LEARNABLE_CORR2 = 0.99  # the cantilever's position follows from two gauges in closed form: a near-perfect fit


def test_corr2_is_pearson_over_all_elements():
    # MATLAB corr2 (thesis 6.9, ref [27]) equals Pearson's r of the flattened arrays (numpy.corrcoef)
    rng = np.random.default_rng(3)
    a, b = rng.normal(size=(5, 4)), rng.normal(size=(5, 4))
    assert corr2(a, b) == pytest.approx(np.corrcoef(a.ravel(), b.ravel())[0, 1], rel=EXACT_RTOL)
    assert np.isnan(percentage_error([1.0], [0.0])[0])
    assert percentage_error([11.0], [10.0])[0] == pytest.approx(10.0)


def test_scg_solves_a_quadratic_to_its_closed_form():
    # f = 0.5 x'Ax - b'x has its minimum at A^-1 b; SCG (Moller 1993) reaches it in ~n iterations
    rng = np.random.default_rng(0)
    q = rng.normal(size=(6, 6))
    a = q @ q.T + 6 * np.eye(6)
    b = rng.normal(size=6)
    x, converged = scg(lambda x: 0.5 * x @ a @ x - b @ x, lambda x: a @ x - b, np.zeros(6), 200, 1e-10, 1e-14)
    assert converged
    np.testing.assert_allclose(x, np.linalg.solve(a, b), rtol=SCG_QUADRATIC_RTOL)


def test_split_and_normaliser_follow_e_6_1():
    s = thesis_split(1275, seed=4)
    assert (len(s.train), len(s.val), len(s.test)) == (638, 425, 212)  # 1/2, 1/3, 1/6 of table 6.1's 1275
    assert len(set(np.concatenate([s.train, s.val, s.test]).tolist())) == 1275
    x = np.random.default_rng(1).normal(3.0, 2.0, size=(100, 3))
    z = Normaliser().fit(x).transform(x)
    np.testing.assert_allclose(z.mean(axis=0), 0, atol=EXACT_ATOL)
    np.testing.assert_allclose(z.std(axis=0, ddof=1), 1, rtol=EXACT_RTOL)


def _cantilever_xy(model, n=300, seed=0):
    rng = np.random.default_rng(seed)
    a = rng.choice(np.linspace(0.14, 0.27, 14), n)
    m = rng.choice([0.0075, 0.0125, 0.025], n)
    x = model(a, m) + 0.002 * rng.standard_normal((n, 3))
    return x, 0.27 - a


def test_same_seed_same_numbers(cantilever_model):
    x, y = _cantilever_xy(cantilever_model)
    kw = dict(coarse=(5, 10), fine_halfwidth=1, gradients=(1e-3, 1e-7), epochs=4, curve_hidden=5)
    r1 = run_pipeline(x, y, seed=5, **kw)
    r2 = run_pipeline(x, y, seed=5, **kw)
    r3 = run_pipeline(x, y, seed=6, **kw)
    assert r1.corr2 == r2.corr2
    assert np.array_equal(r1.y_pred, r2.y_pred)
    assert [p.val_mse for p in r1.coarse] == [p.val_mse for p in r2.coarse]
    assert r1.corr2 != r3.corr2
    # the sweep picks the size with the lowest validation error among those it tried
    tried = r1.coarse + r1.fine
    assert r1.best_hidden == min(tried, key=lambda p: p.val_mse).hidden
    # early stopping keeps the epoch with the lowest validation error
    assert r1.model.net_.best_epoch_ == int(np.argmin(r1.model.net_.val_error_))


def test_network_learns_cantilever_position(cantilever_model):
    # the position of a load beyond gauge 2 follows from two gauge readings in closed form: a good fit is possible
    x, y = _cantilever_xy(cantilever_model, n=400)
    r = run_pipeline(x, y, seed=0, fixed_hidden=10, fixed_tol=1e-7, epochs=10)
    assert r.corr2 > LEARNABLE_CORR2
    assert r.model.val_error_[r.model.net_.best_epoch_] < r.model.val_error_[0]


def test_model_file_round_trip_and_errors(tmp_path, cantilever_model):
    x, y = _cantilever_xy(cantilever_model, n=100)
    net = ThesisNetwork(hidden=4, epochs=2).fit(x, y)
    path = save_model(tmp_path / "m.json", net, target="position", inputs=["gauge1_v", "gauge2_v", "gauge3_v"])
    np.testing.assert_allclose(load_model(path).network.predict(x), net.predict(x), rtol=EXACT_RTOL)
    text = path.read_text()
    (tmp_path / "v.json").write_text(text.replace('"version": 1', '"version": 99'))
    with pytest.raises(DataFileError, match="version 99"):
        load_model(tmp_path / "v.json")
    (tmp_path / "t.json").write_text(text.replace('"hidden": 4', '"hidden": 5'))
    with pytest.raises(DataFileError, match="'weights' has"):
        load_model(tmp_path / "t.json")
    (tmp_path / "b.json").write_bytes(b"\x80\x04pickle")
    with pytest.raises(DataFileError, match="not a model file"):
        load_model(tmp_path / "b.json")
    with pytest.raises(NotFittedError, match="not fitted"):  # scikit-learn's contract (a ValueError)
        MLP().predict(x)


def test_target_scores_are_in_the_units_train_reports():
    from types import SimpleNamespace

    from flexdigit.tactile.pipeline import target_scores

    y_test = np.array([0.010, 0.020, 0.030, 0.040])
    result = SimpleNamespace(target="position", y_test=y_test, y_pred=y_test + 0.002, corr2=0.9, best_hidden=7,
                             best_tol=1e-5)  # fmt: skip
    # a constant 2 mm error: its RMS is 2 mm
    assert target_scores(result) == pytest.approx(
        {"corr2": 0.9, "hidden": 7, "learning_gradient": 1e-5, "rmse_mm": 2.0}, rel=1e-9
    )
    result.target, result.y_pred = "magnitude", y_test - 0.003  # kg: 3 g off
    assert target_scores(result)["rmse_g"] == pytest.approx(3.0, rel=1e-9)
