"""The figure of a controller design (``flexdigit design hinf|mixsyn ... --plot``): its step and its Bode plot.

Left, the closed loop's step responses (thesis 4.5: the output to a setpoint step, T_yw, and the command it takes,
T_uw); right, the Bode plot of the loop gain L = G K with the sensitivity S and complementary sensitivity T (the
shapes 4.4 weights). Computed by python-control here, drawn on the report's figure style.
"""

from __future__ import annotations

import control as ct
import numpy as np

from flexdigit._plot import new_figure
from flexdigit.control.analysis import loop_maps

__all__ = ["design_figure"]


def design_figure(plant, controller, *, output_unit: str = "m", t_final_s: float = 3.0, title: str = ""):
    """Step responses of ``T_yw`` and ``T_uw`` over ``t_final_s`` and the Bode plot of ``L = G K``, ``S``, ``T``
    for ``u = K (w - y)``; a matplotlib ``Figure`` of four axes (step output, step command, magnitude in dB,
    phase in deg), ``output_unit`` naming the plant's output (per servo command).

    Examples
    --------
    >>> import control as ct
    >>> fig = design_figure(ct.tf([1.0], [1.0, 1.0]), ct.tf([2.0], [1.0]), output_unit="rad")
    >>> fig.axes[1].get_ylabel()
    'magnitude (dB)'
    """
    maps = loop_maps(plant, controller)
    t = np.linspace(0.0, t_final_s, 1500)
    fig, axes = new_figure(2, 2, figsize=(10.0, 5.6))
    (ay, am), (au, ap) = axes
    # no setpoint line at 1: the thesis's loops reach a small fraction of it (their T_yw is its own scale)
    ay.plot(t, _step(maps.T_yw, t), label="output y (T_yw)")
    ay.set_ylabel(f"y per unit step ({output_unit}/{output_unit})")
    ay.set_title("closed-loop step", fontsize=9)
    ay.legend(fontsize=7)
    au.plot(t, _step(maps.T_uw, t), color="C1", label="command u (T_uw)")
    au.set_xlabel("time (s)")
    au.set_ylabel(f"u per unit step (commands/{output_unit})")
    au.legend(fontsize=7)
    loop = ct.series(ct.ss(controller), ct.ss(plant))
    w = np.logspace(-1, 3, 600)
    resp = {
        "L = G K": _freq(loop, w),
        "S (T_zw)": _freq(maps.T_zw, w),
        "T (T_yw)": _freq(maps.T_yw, w),
    }
    for name, h in resp.items():
        am.semilogx(w, 20 * np.log10(np.abs(h)), label=name)
    am.axhline(0.0, color="k", lw=0.5)
    am.set_ylabel("magnitude (dB)")
    am.set_title("Bode plot", fontsize=9)
    am.legend(fontsize=7)
    ap.semilogx(w, np.degrees(np.unwrap(np.angle(resp["L = G K"]))), label="L = G K")
    ap.axhline(-180.0, color="k", ls=":", lw=0.8)
    ap.set_xlabel("frequency (rad/s)")
    ap.set_ylabel("phase of L (deg)")
    if title:
        fig.suptitle(title, fontsize=9)
    return fig


def _step(sys, t: np.ndarray) -> np.ndarray:
    return np.squeeze(ct.step_response(sys, T=t).outputs)


def _freq(sys, w: np.ndarray) -> np.ndarray:
    return np.squeeze(ct.frequency_response(sys, w).complex)
