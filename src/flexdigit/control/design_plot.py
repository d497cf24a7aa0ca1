"""The figures of a controller design (``flexdigit design ... --plot``): its step and its frequency response.

:func:`design_figure` (``design hinf|mixsyn``): left, the closed loop's step responses (thesis 4.5: the output to
a setpoint step, T_yw, and the command it takes, T_uw); right, the Bode plot of the loop gain L = G K with the
sensitivity S and complementary sensitivity T (the shapes 4.4 weights). :func:`twenty_ms_figure` (``design 20ms``):
the same four panels for the 20 ms discrete design (5.2-5.3), its step the tip's in degrees, its frequency response
up to the Nyquist frequency. :func:`sweep_figure` (``design sweep``): the filter sweep of 4.7, the additive
tolerance and ``||T_pq||`` against the error filter's cut-off. Computed by python-control here, drawn on the report's
figure style.
"""

from __future__ import annotations

import control as ct
import numpy as np

from flexdigit._plot import new_figure
from flexdigit.control.analysis import loop_maps
from flexdigit.control.design20ms import closed_loop

__all__ = ["design_figure", "twenty_ms_figure", "sweep_figure"]


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
    _bode(am, ap, w, resp, "L = G K", "Bode plot")
    if title:
        fig.suptitle(title, fontsize=9)
    return fig


def _bode(am, ap, w: np.ndarray, resp: dict, loop: str, title: str) -> None:
    """Magnitudes (dB) of ``resp`` (name -> complex response on ``w``) on ``am``, the phase of ``resp[loop]`` on
    ``ap``, against frequency in rad/s."""
    for name, h in resp.items():
        am.semilogx(w, 20 * np.log10(np.abs(h)), label=name)
    am.axhline(0.0, color="k", lw=0.5)
    am.set_ylabel("magnitude (dB)")
    am.set_title(title, fontsize=9)
    am.legend(fontsize=7)
    ap.semilogx(w, np.degrees(np.unwrap(np.angle(resp[loop]))), label=loop)
    ap.axhline(-180.0, color="k", ls=":", lw=0.8)
    ap.set_xlabel("frequency (rad/s)")
    ap.set_ylabel("phase of L (deg)")


def _step(sys, t: np.ndarray) -> np.ndarray:
    return np.squeeze(ct.step_response(sys, T=t).outputs)


def _freq(sys, w: np.ndarray) -> np.ndarray:
    return np.squeeze(ct.frequency_response(sys, w).complex)


def twenty_ms_figure(design, *, step_deg: float = 30.0, duration_s: float = 3.0, title: str = ""):
    """The 20 ms design's linear step and its loop's frequency response, as a matplotlib ``Figure`` of four axes:
    the tip's rotation (deg) after a ``step_deg`` setpoint step over ``duration_s`` (the step ``flexdigit design
    20ms`` scores, :func:`~flexdigit.control.design20ms.digit_design_20ms_summary`), the command it takes (servo
    commands from the equilibrium's, before the runtime rounds and saturates it), and the discrete loop's
    magnitude (dB: the loop gain L, the sensitivity S = 1/(1 + L), the setpoint to the tip T) and phase of L, up
    to the Nyquist frequency.

    Parameters
    ----------
    design : Digital20msDesign
        What :func:`~flexdigit.control.design20ms.digit_design_20ms` returned.

    Examples
    --------
    >>> from flexdigit.control.design20ms import design_20ms
    >>> fig = twenty_ms_figure(design_20ms())
    >>> fig.axes[0].get_ylabel(), fig.axes[3].get_xlabel()
    ('tip rotation (deg)', 'frequency (rad/s)')
    """
    plant, controller = ct.ss(design.plant_d), ct.ss(design.controller)
    to_tip = closed_loop(design.plant_d, design.controller, output=design.tip_plant_d)
    # the command u = K_r r + K_y y on the loop's states [plant; controller] (closed_loop's order)
    c_u = np.hstack([controller.D[:, 1:2] @ plant.C, controller.C])
    to_command = ct.ss(to_tip.A, to_tip.B, c_u, controller.D[:, 0:1], plant.dt)
    t = np.arange(0.0, duration_s + plant.dt / 2, plant.dt)
    setpoint = np.full(t.size, step_deg)
    fig, axes = new_figure(2, 2, figsize=(10.0, 5.6))
    (ay, am), (au, ap) = axes
    ay.plot(t, np.squeeze(ct.forced_response(to_tip, t, setpoint).outputs), label="tip rotation")
    ay.plot(t, setpoint, "k:", lw=0.8, label="setpoint")
    ay.set_ylabel("tip rotation (deg)")
    ay.set_title(f"linear {step_deg:g} deg step", fontsize=9)
    ay.legend(fontsize=7)
    au.step(t, np.squeeze(ct.forced_response(to_command, t, setpoint).outputs), where="post", color="C1",
            label="command (linear, unrounded)")  # fmt: skip
    au.set_xlabel("time (s)")
    au.set_ylabel("command change (servo commands)")
    au.legend(fontsize=7)
    w = np.logspace(-1, np.log10(np.pi / plant.dt), 600) * (1 - 1e-9)  # Nyquist's last sample, not above it
    loop = -_freq(controller[0, 1], w) * _freq(plant, w)  # L: the return ratio of the measured rotation's path
    resp = {"L (loop gain)": loop, "S = 1/(1 + L)": 1.0 / (1.0 + loop), "T (setpoint to tip)": _freq(to_tip, w)}
    _bode(am, ap, w, resp, "L (loop gain)", f"frequency response, up to Nyquist ({np.pi / plant.dt:.0f} rad/s)")
    if title:
        fig.suptitle(title, fontsize=9)
    return fig


def sweep_figure(filters_hz, tpq_peak_db, tolerance_percent, thesis_percent=None, thesis_arithmetic_percent=None,
                 *, title: str = ""):  # fmt: skip
    """The error-filter sweep of 4.7 (``flexdigit design sweep``) as a matplotlib ``Figure`` of two axes against
    the cut-off (Hz, log): ``||T_pq||`` (dB), and the additive tolerance (%, log) as ``1/||T_pq||`` of ``|G(0)|``
    beside the thesis's printed percentages and its arithmetic ``100/(||T_pq|| in dB)`` at the printed controllers'
    10x gain, each where there is one (None or NaN where not).

    Examples
    --------
    >>> fig = sweep_figure([0.5, 5.0], [10.0, 20.0], [5.0, 1.0], [None, 2.0])
    >>> [ax.get_ylabel() for ax in fig.axes]
    ['||T_pq|| (dB)', 'additive tolerance (%)']
    """
    f = np.asarray(filters_hz, float)
    order = np.argsort(f)
    fig, (top, bottom) = new_figure(2, 1, figsize=(7.0, 5.0), sharex=True)
    top.semilogx(f[order], np.asarray(tpq_peak_db, float)[order], "-o", ms=4, label="||T_pq||")
    top.set_ylabel("||T_pq|| (dB)")
    default = "H-inf designs on the thesis rig's printed plant, across the error filter's cut-off (thesis 4.7)"
    top.set_title(title or default, fontsize=9)
    series = {
        "1/||T_pq||, % of |G(0)| (flexdigit)": (tolerance_percent, "-o"),
        "thesis (as printed)": (thesis_percent, "s"),
        "thesis's arithmetic: 100/(dB + 20)": (thesis_arithmetic_percent, "x"),
    }
    for label, (values, style) in series.items():
        if values is None:
            continue
        y = np.array([np.nan if v is None else v for v in values], float)[order]
        if np.any(np.isfinite(y)):
            bottom.plot(f[order], y, style, ms=6 if style != "-o" else 4, mfc="none", label=label)
    bottom.set_xscale("log")
    bottom.set_yscale("log")
    bottom.set_xlabel("error filter cut-off (Hz)")
    bottom.set_ylabel("additive tolerance (%)")
    bottom.legend(fontsize=7)
    return fig
