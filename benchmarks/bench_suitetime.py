"""The longer trainings of ``flexdigit train`` (50, 100 ... 800 epochs of one network) resumed, not restarted.

:func:`flexdigit.tactile.localisation.train_network` trains the kept network again at twice the epochs up to 800;
the compiled training (:mod:`flexdigit.tactile._scg_kernel`) goes on from the last one (the same numbers,
tests/tactile/test_scg_kernel.py). Timed on 600 readings of three inputs (a smooth target and noise), a 10-node
network at tolerance 1e-7: the five trainings from the start each time (the kept runs cleared before each) and
each going on from the last; best of 3.

``python -m benchmarks suitetime``
"""

from __future__ import annotations

from benchmarks._common import best_of

EPOCHS = (50, 100, 200, 400, 800)


def run() -> list[dict]:
    import numpy as np

    from flexdigit.tactile import _scg_kernel
    from flexdigit.tactile.netlab import MLP

    rng = np.random.default_rng(0)
    x = rng.normal(size=(600, 3))
    y = np.tanh(x @ [1.0, -2.0, 0.5]) + 0.05 * rng.normal(size=600)

    def trainings(restart: bool) -> None:
        _scg_kernel._runs.clear()
        for epochs in EPOCHS:
            if restart:
                _scg_kernel._runs.clear()
            MLP(hidden=10, tol=1e-7, epochs=epochs, random_state=0).fit(x[:300], y[:300], x[300:], y[300:])

    rows = []
    for restart, how in ((True, "each from the start"), (False, "each going on from the last")):
        seconds = best_of(lambda restart=restart: trainings(restart))
        rows.append(
            {
                "name": f"one network at 50..800 epochs, {how}",
                "value": seconds,
                "unit": "s",
                "goal": "",
                "note": f"{sum(EPOCHS) if restart else max(EPOCHS)} epochs trained",
            }
        )
    return rows


if __name__ == "__main__":
    for row in run():
        print(f"{row['name']}: {row['value']:.4f} {row['unit']} {row['note']}")
