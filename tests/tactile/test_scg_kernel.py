"""The compiled NETLAB training (tactile/_scg_kernel.py) against the numpy reference (netlab.py) and closed forms."""

import numpy as np
import pytest

from flexdigit.tactile import _scg_kernel
from flexdigit.tactile.netlab import MLP, mlp_error, mlp_forward, mlp_grad, mlp_init, scg
from flexdigit.tactile.pipeline import _sweep, _train, thesis_split

# Tolerances, each with the reason for its size
TANH_ULP = 3  # the kernel's tanh (expm1 on a reduced argument, one division) against glibc's (np.tanh)
SAME_SUM_RTOL = 1e-12  # one error or gradient summed in another order (~n * eps)
FD_RTOL = 1e-6  # central differences with h = 1e-6 on an O(1) error: truncation ~h^2, rounding ~eps/h
SHORT_TRAINING_RTOL = 1e-8  # 40 SCG iterations from the same start: rounding grows, no branch has parted yet


def _ulps(ours, ref):
    return np.abs(ours - ref) / np.spacing(np.maximum(np.abs(ref), np.finfo(float).tiny))


def test_tanh_is_glibcs_to_a_few_ulp():
    x = np.concatenate(
        [
            np.linspace(-25.0, 25.0, 400_001),  # every branch of the reduction, saturation at +-19.1
            np.geomspace(1e-300, 1.0, 2001),  # tiny arguments: tanh(x) = x to the last bit matters
            -np.geomspace(1e-300, 1.0, 2001),
            [0.0, -0.0, 19.05, 19.1, 19.2, 700.0, -700.0, 1e308, -1e308],
        ]
    )
    ours = _scg_kernel.tanh(x)
    assert _ulps(ours, np.tanh(x)).max() <= TANH_ULP
    assert np.all(np.abs(ours) <= 1.0)
    assert np.array_equal(np.signbit(ours), np.signbit(np.tanh(x)))  # odd, -0.0 included


@pytest.mark.parametrize(
    ("nin", "hidden", "nout", "n"), [(3, 1, 1, 7), (3, 18, 1, 300), (5, 40, 3, 111), (4, 60, 2, 2)]
)
def test_error_and_gradient_are_netlabs(nin, hidden, nout, n):
    rng = np.random.default_rng(hidden)
    x, t = rng.normal(size=(n, nin)), rng.normal(size=(n, nout))
    w = 2.0 * mlp_init(nin, hidden, nout, rng)  # larger weights: tanh's saturated branch is used too
    xt, tt = np.ascontiguousarray(x.T), np.ascontiguousarray(t.T)
    z, d, g = np.empty((hidden, n)), np.empty((nout, n)), np.empty(w.size)
    err = _scg_kernel._forward(w, xt, tt, nin, hidden, nout, z, d)
    _scg_kernel._backward(w, xt, nin, hidden, nout, z, d, g)
    assert err == pytest.approx(mlp_error(w, x, t, hidden), rel=SAME_SUM_RTOL)
    np.testing.assert_allclose(g, mlp_grad(w, x, t, hidden), rtol=SAME_SUM_RTOL, atol=SAME_SUM_RTOL * np.abs(g).max())
    np.testing.assert_allclose(z.T, mlp_forward(w, x, hidden, nout)[1], rtol=0, atol=4 * np.finfo(float).eps)
    # and the gradient is the error's derivative (central differences: an oracle independent of both codes)
    h = 1e-6
    fd = np.array(
        [(mlp_error(w + h * e, x, t, hidden) - mlp_error(w - h * e, x, t, hidden)) / (2 * h) for e in np.eye(w.size)]
    )
    np.testing.assert_allclose(g, fd, rtol=FD_RTOL, atol=FD_RTOL * np.abs(fd).max())


def _reference_fit(x, t, xv, tv, hidden, tol, epochs, per_epoch, seed):
    """MLP.fit as it was in numpy: NETLAB's scg on mlp_error/mlp_grad, epochs, early stopping on (xv, tv)."""
    w = mlp_init(x.shape[1], hidden, t.shape[1], np.random.default_rng(seed))
    mse = lambda v, a, b: float(np.mean((mlp_forward(v, a, hidden, b.shape[1])[0] - b) ** 2))  # noqa: E731
    train, val, best, best_epoch = [mse(w, x, t)], [mse(w, xv, tv)], w, 0
    for epoch in range(1, epochs + 1):
        w, converged = scg(
            lambda v: mlp_error(v, x, t, hidden), lambda v: mlp_grad(v, x, t, hidden), w, per_epoch, tol, tol
        )
        train.append(mse(w, x, t))
        val.append(mse(w, xv, tv))
        if val[-1] < val[best_epoch]:
            best, best_epoch = w, epoch
        if converged:
            break
    return best, best_epoch, np.array(train), np.array(val), converged


def _data(n, seed):
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(n, 3))
    return x, np.tanh(x @ [1.0, -2.0, 0.5])[:, None] + 0.05 * rng.normal(size=(n, 1))


@pytest.mark.parametrize(("hidden", "tol", "epochs"), [(4, 1e-7, 3), (9, 1e-3, 3), (25, 1e-1, 2)])
def test_short_training_follows_the_reference_step_by_step(hidden, tol, epochs):
    x, t = _data(120, 2)
    xv, tv = _data(60, 3)
    net = MLP(hidden=hidden, tol=tol, epochs=epochs, iterations_per_epoch=13, random_state=hidden).fit(x, t, xv, tv)
    best, best_epoch, train, val, converged = _reference_fit(x, t, xv, tv, hidden, tol, epochs, 13, hidden)
    assert net.best_epoch_ == best_epoch
    assert net.converged_ == converged
    np.testing.assert_allclose(net.weights_, best, rtol=SHORT_TRAINING_RTOL, atol=SHORT_TRAINING_RTOL)
    np.testing.assert_allclose(net.train_error_, train, rtol=SHORT_TRAINING_RTOL)
    np.testing.assert_allclose(net.val_error_, val, rtol=SHORT_TRAINING_RTOL)


def test_a_large_tolerance_stops_training_early_as_netlab_does():
    # tol 1e-1 is met within the first epoch (the thesis's largest "learning gradient"): one epoch, converged
    x, t = _data(200, 5)
    net = MLP(hidden=5, tol=1e-1, epochs=50, iterations_per_epoch=50, random_state=0).fit(x, t)
    best, best_epoch, train, _, converged = _reference_fit(x, t, x, t, 5, 1e-1, 50, 50, 0)
    assert net.converged_
    assert converged
    assert len(net.train_error_) == len(train) < 51
    assert net.n_iter_ == 50 * (len(train) - 1)


def test_full_training_learns_as_the_reference_does():
    # 50 epochs of 50 iterations: SCG's accept/reject branches part after many iterations (rounding), so the two
    # trainings are compared by what they learn: both fit the smooth target to its noise floor (0.05^2)
    x, t = _data(400, 7)
    xv, tv = _data(200, 8)
    net = MLP(hidden=10, tol=1e-7, random_state=1).fit(x, t, xv, tv)
    *_, train, val, _ = _reference_fit(x, t, xv, tv, 10, 1e-7, 50, 50, 1)
    noise_floor = 0.05**2
    assert net.val_error_[net.best_epoch_] < 1.5 * noise_floor
    assert val.min() < 1.5 * noise_floor
    assert net.val_error_[net.best_epoch_] == pytest.approx(val.min(), rel=0.1)


def test_a_sweep_trained_together_is_the_networks_trained_one_by_one():
    x, t = _data(150, 11)
    y = t[:, 0]
    split = thesis_split(len(y), 0)
    configs = [(3, 1e-7, 11), (8, 1e-3, 12), (5, 1e-7, 13), (12, 1e-5, 14)]
    together = _sweep(x, y, split, configs, epochs=3)
    one_by_one = [_train(x, y, split, h, tol, seed, 3)[1] for h, tol, seed in configs]
    assert together == one_by_one  # dataclass equality: every float to the bit, in order


def _fit(x, t, xv, tv, epochs, tol=1e-7):
    net = MLP(hidden=6, tol=tol, epochs=epochs, iterations_per_epoch=13, random_state=4).fit(x, t, xv, tv)
    return net.weights_, net.best_epoch_, net.n_iter_, net.train_error_, net.val_error_, net.converged_


def _same(a, b):
    # the same compiled epochs on the same numbers, one after another: every float to the bit
    for u, v in zip(a, b, strict=True):
        np.testing.assert_array_equal(u, v)


def test_a_longer_training_goes_on_from_the_shorter_one_number_for_number(monkeypatch):
    """train's 50, 100 ... 800 epochs of one network (tactile.localisation.train_network): each longer training
    resumes the last one; its result is that of training from the start."""
    x, t = _data(150, 21)
    xv, tv = _data(60, 22)
    monkeypatch.setattr(_scg_kernel, "_runs", type(_scg_kernel._runs)())
    from_start = _fit(x, t, xv, tv, 12)
    assert from_start[2] == 12 * 13  # ran every epoch: a resumed one has epochs to add
    assert not from_start[5]
    _scg_kernel._runs.clear()
    epochs_run = []
    real = _scg_kernel._train

    def counted(w, best_w, train, val, start, *args):
        epochs_run.append(train.size - 1 - start)
        return real(w, best_w, train, val, start, *args)

    monkeypatch.setattr(_scg_kernel, "_train", counted)
    steps = [_fit(x, t, xv, tv, e) for e in (3, 6, 12)]
    _same(steps[-1], from_start)
    assert epochs_run == [3, 3, 6]  # each went on from the last
    _same(_fit(x, t, xv, tv, 12), from_start)  # asked again: kept, none run
    assert epochs_run == [3, 3, 6]
    _same(_fit(x, t, xv, tv, 3), steps[0])  # a shorter one starts over
    assert epochs_run == [3, 3, 6, 3]
    steps[-1][0][:] = 0.0  # what was returned is the caller's: the kept run is untouched
    _same(_fit(x, t, xv, tv, 6), steps[1])


def test_a_converged_training_asked_for_more_epochs_is_the_same(monkeypatch):
    x, t = _data(200, 5)
    monkeypatch.setattr(_scg_kernel, "_runs", type(_scg_kernel._runs)())
    from_start = _fit(x, t, x, t, 40, tol=1e-1)
    assert from_start[5]  # tol 1e-1 is met in the first epoch
    assert len(from_start[3]) < 5
    _scg_kernel._runs.clear()
    _fit(x, t, x, t, 4, tol=1e-1)
    _same(_fit(x, t, x, t, 40, tol=1e-1), from_start)  # kept: it would stop where it stopped
