"""The figures of a palpation (``flexdigit palpate ... --plot``): force against indentation, a scan's stiffness
map, a force hold over time.

- :func:`indentation_figure`: per sweep plateau the contact force from the gauges (with its standard deviation)
  against the indentation of the fitted tissue (a cross on the axis where the gauges read no force), the fitted
  tissue's force and, on the twin, the true contact force (thesis 8: stiffness from the digit's gauges alone);
- :func:`scan_figure`: the local modulus along the tissue, the fitted inclusion and, on the twin, the true one;
- :func:`hold_figure`: the force held under force control, estimated and (twin) true, and the command.
"""

from __future__ import annotations

import numpy as np

from flexdigit._plot import new_figure

__all__ = ["indentation_figure", "scan_figure", "hold_figure"]


def indentation_figure(result, *, true_modulus_n_m2: float | None = None, title: str = ""):
    """Force (N) against indentation (mm) of a :class:`~flexdigit.palpation.palpation.PalpationResult`; a
    matplotlib ``Figure``. ``true_modulus_n_m2`` (the twin's tissue) is written beside the estimate."""
    c = result.curve
    depth_mm = 1e3 * np.asarray(c["indentation_m"], float)
    order = np.argsort(depth_mm)
    fig, ax = new_figure(figsize=(6.5, 4.0))
    read = np.asarray(c.get("force_read", np.isfinite(c["force_n"])), bool)
    ax.errorbar(depth_mm[read], np.asarray(c["force_n"])[read], yerr=np.asarray(c["force_sd_n"])[read], fmt="o", ms=4,
                capsize=2, label="from the gauges")  # fmt: skip
    if not np.all(read):  # a marker on the axis, not a force: the gauges read none there
        label = f"no force read ({np.count_nonzero(~read)} plateaus: no contact seen, or sd over the value)"
        ax.plot(depth_mm[~read], np.zeros(np.count_nonzero(~read)), "x", color="0.4", ms=6, clip_on=False,
                transform=ax.get_xaxis_transform(), label=label)  # fmt: skip
    ax.plot(depth_mm[order], np.asarray(c["model_force_n"])[order], color="C1", label="fitted tissue")
    if "true_force_n" in c:
        ax.plot(depth_mm[order], np.asarray(c["true_force_n"])[order], "s--", ms=3, color="C3", lw=1.0,
                label="true contact force (twin)")  # fmt: skip
    ax.set_xlabel("indentation (mm)")
    ax.set_ylabel("contact force (N)")
    f = result.fit
    unit = "N/m^2" if result.protocol.model == "linear" else f"N/m^{1 + f.exponent:.2f}"
    estimate = f"modulus {f.modulus_n_m2:.4g} +- {f.modulus_sd_n_m2:.2g} {unit}"
    truth = f" (true {true_modulus_n_m2:.4g} N/m^2, twin)" if true_modulus_n_m2 is not None else ""
    ax.set_title((f"{title}\n" if title else "") + estimate + truth, fontsize=9)
    ax.legend(fontsize=7)
    return fig


def scan_figure(result, *, true_centre_mm: float | None = None, title: str = ""):
    """The local modulus (N/m^2) along the tissue (mm) of a :class:`~flexdigit.palpation.palpation.ScanResult`,
    the fitted inclusion's centre and, on the twin, the true one; a matplotlib ``Figure``."""
    fig, ax = new_figure(figsize=(6.5, 4.0))
    ax.errorbar(1e3 * result.map_position_m, result.map_modulus_n_m2, yerr=result.map_modulus_sd_n_m2, fmt="o-",
                ms=4, capsize=2, label="local modulus")  # fmt: skip
    ax.axvline(1e3 * result.inclusion["centre_m"], color="C1", label="inclusion (fitted)")
    if true_centre_mm is not None:
        ax.axvline(true_centre_mm, color="C3", ls="--", label="inclusion (true, twin)")
    ax.set_xlabel("position in the tissue (mm)")
    ax.set_ylabel("modulus (N/m^2)")
    if title:
        ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7)
    return fig


def hold_figure(held, title: str = ""):
    """A :class:`~flexdigit.palpation.palpation.ForceHold`: force (N) and command over time (s); a ``Figure``."""
    fig, (top, bottom) = new_figure(2, 1, figsize=(8.0, 5.0), sharex=True, height_ratios=(3, 2))
    top.axhline(held.setpoint_n, color="k", ls=":", lw=1.0, label="setpoint")
    top.plot(held.time_s, held.force_n, color="C0", label="estimated force")
    if held.true_force_n is not None:
        top.plot(held.time_s, held.true_force_n, color="C3", lw=1.0, label="true force (twin)")
    top.set_ylabel("contact force (N)")
    top.legend(fontsize=7)
    if title:
        top.set_title(title, fontsize=9)
    bottom.step(held.time_s, held.command, where="post", color="C2", label="command")
    bottom.set_xlabel("time (s)")
    bottom.set_ylabel("servo command")
    return fig
