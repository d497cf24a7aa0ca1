"""The figure of a tactile dataset (``flexdigit collect ... --plot``): its gauge voltages against where the load hung
and over the run.

Top, each gauge's voltage against the load's position from the tip (the thesis's figures 6.4-6.5: the signal a
network localises from), one colour a gauge; bottom, every reading's gauge
voltages against time (the order the protocol read them in: tares, drift, settling), or against the reading's
number when the dataset has no times (an imported one).
"""

from __future__ import annotations

import numpy as np

from flexdigit._plot import new_figure

__all__ = ["dataset_figure"]


def dataset_figure(dataset, title: str = ""):
    """A dataset (:class:`~flexdigit.tactile.dataset.Dataset`) as a matplotlib ``Figure`` of two axes: gauge
    voltages (V) against the load's position from the tip (mm), loaded readings only, and against time (s).

    Examples
    --------
    >>> import numpy as np
    >>> from flexdigit.tactile.dataset import COLUMNS, Dataset
    >>> columns = {c: np.zeros(2, dtype=d) for c, d in COLUMNS.items()}
    >>> columns["load_kg"][:] = 0.02
    >>> fig = dataset_figure(Dataset(columns, {"protocol": {"name": "x"}}))
    >>> fig.axes[0].get_xlabel(), fig.axes[1].get_ylabel()
    ('load position from the tip (mm)', 'gauge voltage (V)')
    """
    loaded = dataset["load_kg"] > 0
    gauges = dataset.gauge_columns
    fig, (by_place, by_time) = new_figure(2, 1, figsize=(8.0, 6.0))
    at_mm = dataset["position_from_tip_m"][loaded] * 1e3
    for k, name in enumerate(gauges):
        by_place.plot(at_mm, dataset[name][loaded], "o", ms=3, color=f"C{k}", label=f"gauge {k + 1}")
    by_place.set_xlabel("load position from the tip (mm)")
    by_place.set_ylabel("gauge voltage (V)")
    masses_g = sorted({round(float(m) * 1e3, 6) for m in dataset["load_kg"][loaded]})
    what = ", ".join(f"{m:g}" for m in masses_g) + " g" if masses_g else "no load hung"
    by_place.set_title(f"{int(loaded.sum())} loaded readings ({what})", fontsize=9)
    by_place.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.0, 0.5))  # beside: never over a reading
    t = dataset["time_s"]
    timed = bool(np.all(np.isfinite(t))) and np.ptp(t) > 0 if t.size else False
    x = t if timed else dataset["sample"]
    for k, name in enumerate(gauges):
        by_time.plot(x, dataset[name], "o", ms=2.5, color=f"C{k}", label=f"gauge {k + 1}")
    if (~loaded).any():
        by_time.plot(x[~loaded], dataset[gauges[0]][~loaded], "kx", ms=4, label="no load hung (gauge 1)")
    by_time.set_xlabel("time (s)" if timed else "reading")
    by_time.set_ylabel("gauge voltage (V)")
    by_time.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.0, 0.5))
    name = dataset.meta.get("protocol", {}).get("name", "")
    fig.suptitle(title or f"dataset of protocol {name}", fontsize=9)
    return fig
