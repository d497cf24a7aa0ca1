"""The figure of an identification (``flexdigit identify ... --plot``): the fitted model over the record.

The record, the second-order model from its step or release instant (thesis 3.1.2, 3.2.4; figures 3.6 and 3.11
show the same comparison) and the residual below, so a fit nobody would trust is seen at a glance.
"""

from __future__ import annotations

import numpy as np

from flexdigit._plot import new_figure
from flexdigit.identify.identification import Identification
from flexdigit.identify.timeseries import TimeSeries

__all__ = ["fit_figure"]


def fit_figure(series: TimeSeries, result: Identification):
    """The record and the model ``result.predict`` over it from the instant ``result.t0_s`` (top), the residual
    (bottom); a matplotlib ``Figure``, the record's unit on the y axes, time in s.

    Examples
    --------
    >>> import numpy as np
    >>> from flexdigit.identify import identify, TimeSeries
    >>> t = np.arange(0, 3, 1e-3)
    >>> y = 1 - np.exp(-1.0 * t) * np.cos(13 * t)
    >>> fig = fit_figure(TimeSeries(t, y, "pot", "V"), identify(TimeSeries(t, y, "pot", "V"), "step", t0_s=0.0))
    >>> [line.get_label() for line in fig.axes[0].lines][:2]
    ['record', 'model']
    """
    t, y = np.asarray(series.t_s, float), np.asarray(series.y, float)
    after = t >= result.t0_s
    model = result.predict(t[after])
    unit = f" ({series.unit})" if series.unit else ""
    fig, (top, bottom) = new_figure(2, 1, figsize=(8.0, 5.0), sharex=True, height_ratios=(3, 1))
    top.plot(t, y, color="0.6", lw=0.8, label="record")
    top.plot(t[after], model, color="C3", lw=1.4, label="model")
    top.axvline(result.t0_s, color="k", ls=":", lw=0.8, label=f"{result.kind} instant")
    top.set_ylabel(f"{series.channel}{unit}")
    top.set_title(
        f"{result.kind} test {series.source}: wn {result.wn_rad_s:.4g} rad/s, zeta {result.zeta:.4g}, "
        f"fit {result.fit_percent:.1f} % ({result.method})",
        fontsize=9,
    )
    top.legend(fontsize=7)
    bottom.plot(t[after], y[after] - model, color="C0", lw=0.6, label="residual")
    bottom.axhline(0.0, color="k", lw=0.5)
    bottom.set_xlabel("time (s)")
    bottom.set_ylabel(f"residual{unit}")
    return fig
