"""The figure of a simulated experiment's record (``flexdigit simulate ... --plot``): what the thesis plotted of it.

Release and step tests over time (figures 3.6 and 3.11), the actuation sweep against the command (figure 3.17),
the static load test against the load's position (figures 6.4-6.5).
"""

from __future__ import annotations

from flexdigit._plot import new_figure
from flexdigit.twin.records import TwinRecord

__all__ = ["record_figure"]


def _gauges(record: TwinRecord) -> list[str]:
    return [c for c in record.table.column_names if c.startswith("gauge") and c.endswith("_v")]


def record_figure(record: TwinRecord, *, digit: str | None = None):
    """The record's figure as a matplotlib ``Figure``: gauges (and the potentiometer) in V against time (s), the
    command or the load's position (cm from the tip), by the record's experiment; titled with ``digit``'s name
    (a ``--params`` file's stem) when it is not the thesis rig's.

    Examples
    --------
    >>> from flexdigit.twin.records import actuation_sweep
    >>> fig = record_figure(actuation_sweep([8, 43], settle_s=0.5, samples=2, seed=0))
    >>> fig.axes[0].get_xlabel()
    'servo command'
    """
    experiment = record.metadata.get("experiment", "")
    gauges = _gauges(record)
    if experiment == "servo_step_test":
        fig, (top, bottom) = new_figure(2, 1, figsize=(8.0, 5.0), sharex=True)
        t = record.column("time_s")
        top.plot(t, record.column("command"), label="command")
        top.set_ylabel("servo command")
        bottom.plot(t, record.column("pot_v"), label="potentiometer")
        for name in gauges:
            bottom.plot(t, record.column(name), label=_label(name))
        bottom.set_xlabel("time (s)")
        bottom.set_ylabel("voltage (V)")
        bottom.legend(fontsize=7)
        top.set_title(_title("servo step", "3.2.4, figure 3.11", digit), fontsize=9)
        return fig
    fig, ax = new_figure()
    if experiment == "actuation_sweep":
        x, xlabel, style = record.column("command"), "servo command", "o"
        title = _title("actuation sweep", "3.4.3, figure 3.17", digit)
    elif experiment == "static_load_test":
        x, xlabel, style = record.column("position_from_tip_m") * 1e2, "load position from the tip (cm)", "o"
        title = _title("static load test", "6.4-6.5", digit)
    else:
        x, xlabel, style = record.column("time_s"), "time (s)", "-"
        title = _title("release test", "3.1.2, figure 3.6", digit)
    for name in gauges:
        ax.plot(x, record.column(name), style, ms=3, label=_label(name))
    ax.set_xlabel(xlabel)
    ax.set_ylabel("gauge voltage (V)")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7)
    return fig


def _title(experiment: str, thesis: str, digit: str | None) -> str:
    """``release test on the twin (thesis 3.1.2, figure 3.6)``; another digit's: ``release test on the twin of
    digit mine (as thesis 3.1.2)``."""
    if digit is None:
        return f"{experiment} on the twin (thesis {thesis})"
    return f"{experiment} on the twin of digit {digit} (as thesis {thesis.split(',')[0]})"


def _label(column: str) -> str:
    """``gauge1_v`` -> ``gauge 1``."""
    stem = column.removesuffix("_v")
    digits = "".join(ch for ch in stem if ch.isdigit())
    return f"gauge {digits}" if digits else stem
