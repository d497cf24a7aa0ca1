"""The figure of a shape estimate (``flexdigit shape ... --plot``): the digit's centre line from its gauges.

The estimated centre line from the clamp to the tip with its two-standard-deviation band normal to it, the tip,
and the load where one was found (thesis 8's shape sensing; the live page draws the same line).
"""

from __future__ import annotations

import numpy as np

from flexdigit._plot import new_figure

__all__ = ["shape_figure"]


def shape_figure(estimate, i: int = 0, title: str = ""):
    """Reading ``i`` of a :class:`~flexdigit.shape.shape.ShapeEstimate`: the centre line in mm, along the digit
    from the clamp (x) and towards the cable (y), equal scales; a matplotlib ``Figure``."""
    line = 1e3 * np.asarray(estimate.centre_line_m[i], float)
    angle = np.asarray(estimate.angle_rad[i], float)
    sd = 1e3 * np.nan_to_num(np.asarray(estimate.sd_normal_m[i], float), posinf=0.0)
    normal = np.column_stack([-np.sin(angle), np.cos(angle)])
    upper, lower = line + 2 * sd[:, None] * normal, line - 2 * sd[:, None] * normal
    fig, ax = new_figure(figsize=(7.0, 4.2))
    ax.fill(np.r_[upper[:, 0], lower[::-1, 0]], np.r_[upper[:, 1], lower[::-1, 1]], color="C0", alpha=0.2,
            lw=0, label="2 sd band")  # fmt: skip
    ax.plot(line[:, 0], line[:, 1], color="C0", label="centre line")
    ax.plot(line[-1, 0], line[-1, 1], "o", color="C0", label="tip")
    ax.plot([0.0], [0.0], "ks", label="clamp")
    if bool(estimate.contact[i]) and np.isfinite(estimate.load_position_from_base_m[i]):
        s_mm = 1e3 * estimate.load_position_from_base_m[i]
        s = 1e3 * np.asarray(estimate.s_m, float)
        at = (np.interp(s_mm, s, line[:, 0]), np.interp(s_mm, s, line[:, 1]))
        ax.plot(*at, "v", color="C3", ms=8, label=f"{estimate.load_kind} at {s_mm:.0f} mm from the clamp")
    ax.set_xlabel("along the digit from the clamp (mm)")
    ax.set_ylabel("towards the cable (mm)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(fontsize=7)
    if title:
        ax.set_title(title, fontsize=9)
    return fig
