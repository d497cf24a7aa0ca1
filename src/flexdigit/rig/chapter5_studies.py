"""The studies of thesis chapter 5, one call each: what report chapter 5 shows, as numbers.

- :func:`sample_period_table`: the printed 39 Hz controller digitised by Tustin and forward Euler at the periods
  of 5.1, closed around the printed plant (figures 5.3-5.7): stability and error per period.
- :func:`twenty_ms_study`: control at the rig's 20 ms serial period on the nonlinear twin: the direct discrete
  design at plant gain x0.7, x1 and x1.3 (the robustness cases) beside the thesis's controller digitised by
  forward Euler and Tustin, each a 0 -> 30 deg step (5.2).
- :func:`chapter5_study`: both, and the closed-loop bandwidth, the Euler stability limit and the step halving of
  5.1.

Examples
--------
>>> t = sample_period_table([0.001, 0.02])
>>> [round(r[1], 4) < 1 for r in t.rows]            # Tustin keeps the loop stable at 1 and 20 ms
[True, True]
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexdigit._repr import fields_summary
from flexdigit._result_table import ResultTable
from flexdigit.control.design20ms import design_20ms, digit_mount
from flexdigit.control.discretise import forward_euler_stability_limit_s, halve_step, sample_period_study, sampled_loop
from flexdigit.control.thesis_designs import printed_controller, thesis_plant
from flexdigit.params import RigParams
from flexdigit.rig.base import open_rig
from flexdigit.rig.rotation import calibrate_rotation, sweep_commands
from flexdigit.rig.step_test import step_test

__all__ = [
    "PERIODS_S",
    "TWENTY_MS_CASES",
    "sample_period_table",
    "TwentyMsStudy",
    "twenty_ms_study",
    "Chapter5Study",
    "chapter5_study",
]

#: Sample periods of the study of 5.1 (s); the fast report uses fewer.
PERIODS_S = (0.0006, 0.001, 0.002, 0.005, 0.010, 0.020)
#: The 20 ms step tests: (controller, plant gain). Gains x0.7 and x1.3 are the robustness cases.
TWENTY_MS_CASES = (
    ("digital20", 1.0),
    ("digital20", 0.7),
    ("digital20", 1.3),
    ("thesis39-euler", 1.0),
    ("thesis39-tustin", 1.0),
)


def _printed_loop():
    return thesis_plant("printed"), printed_controller("39hz")


def sample_period_table(periods_s=PERIODS_S, *, study: dict | None = None) -> ResultTable:
    """``rig.sample_period_study``: per period, each method's spectral radius and error (figures 5.3-5.7).

    Error: max |y - y_continuous| / max |y_continuous| of the closed-loop step (NaN where the loop is unstable);
    the Euler zero miss is how far forward Euler moves the controller zeros off the plant poles they cancel.
    """
    if study is None:
        G, K = _printed_loop()
        study = sample_period_study(G, K, list(periods_s), methods=("tustin", "forward_euler"), t_final_s=2.0)
    rows = []
    for tu, fe in zip(study["tustin"], study["forward_euler"], strict=True):
        rows.append(
            (
                1000 * tu.period_s,
                tu.spectral_radius,
                tu.error,
                fe.spectral_radius,
                fe.error if fe.stable else float("nan"),
                fe.cancellation_error,
            )
        )
    return ResultTable(
        "rig.sample_period_study",
        "Sample-period study on the printed plant (error: max |y - y_continuous| / max |y_continuous|; NaN: "
        "the loop is unstable)",
        ("period_ms", "tustin_max_abs_pole", "tustin_error", "euler_max_abs_pole", "euler_error", "euler_zero_miss"),
        tuple(rows),
    )


@dataclass(frozen=True)
class TwentyMsStudy:
    """Step tests at 20 ms on the twin (:func:`twenty_ms_study`).

    Attributes
    ----------
    runs : dict
        ``(controller, plant gain)`` -> :class:`~flexdigit.rig.step_test.StepTest`.
    table : ResultTable
        ``rig.twenty_ms_steps``: per run, settling (s), overshoot (%), final error (deg and command quanta), peak
        (deg) and whether it stayed bounded.
    deg_per_command : float
        Beam rotation per command of the design (deg): one quantum.
    """

    runs: dict
    table: ResultTable
    deg_per_command: float

    __repr__ = fields_summary


def twenty_ms_study(params: RigParams | None = None, *, seed: int = 0, fast: bool = False) -> TwentyMsStudy:
    """0 -> 30 deg steps at the serial board's 20 ms on the nonlinear twin (:data:`TWENTY_MS_CASES`).

    The rotation is estimated from the gauges by a map calibrated on a static sweep of the twin seeded ``seed``
    (:func:`~flexdigit.rig.rotation.calibrate_rotation`); every step runs on a fresh twin seeded ``seed + 1``
    and is scored on its true tip rotation. ``fast`` calibrates on 5 commands instead of 9. The twin stands tip up
    as the thesis's, or hangs when the digit buckles so (as ``flexdigit run --params`` mounts it).
    """
    params = params or RigParams()
    mount = digit_mount(params)
    if params.is_thesis_rig():
        commands = (8, 14, 20, 26, 32) if fast else (8, 11, 14, 17, 20, 23, 26, 29, 32)
    else:  # the digit's own sweep, as `run --params` maps it (a pair straight at 127 swept both ways)
        commands = sweep_commands(params)[:: 2 if fast else 1]
    rig = open_rig("sim", params, seed=seed, orientation=mount)
    est = calibrate_rotation(rig, commands, settle_s=1.5 if fast else 2.0)
    runs = {
        # unguarded: the chapter shows the thesis's forward-Euler design failing on the twin (5.1.2), not stopped
        (name, gain): step_test(
            open_rig("sim", params, seed=seed + 1, orientation=mount), name, estimator=est, gain=gain, guard=False
        )
        for name, gain in TWENTY_MS_CASES
    }
    rows = []
    for (name, gain), st in runs.items():
        m = st.metrics
        rows.append(
            (
                name,
                gain,
                m.settling_time_s,
                m.overshoot_percent,
                m.final_error_deg,
                m.final_error_quanta,
                m.peak_deg,
                bool(m.bounded),
            )
        )
    table = ResultTable(
        "rig.twenty_ms_steps",
        "0 -> 30 deg beam-rotation step at 20 ms on the twin (true tip rotation)",
        (
            "controller",
            "plant_gain",
            "settling_s",
            "overshoot_percent",
            "final_error_deg",
            "final_error_quanta",
            "peak_deg",
            "bounded",
        ),
        tuple(rows),
    )
    return TwentyMsStudy(runs, table, design_20ms(params).deg_per_command)


@dataclass(frozen=True)
class Chapter5Study:
    """Everything report chapter 5 shows; tables in :attr:`tables`.

    Attributes
    ----------
    bandwidth_rad_s : float
        -3 dB bandwidth of K G/(1 + K G) (5.1.1), and ``dc_gain`` of that loop.
    loops : dict
        ``{"tustin": [SampledLoop, ...], "forward_euler": [...]}`` at :attr:`periods_s`.
    euler_limit_s, euler_zero_limit_s : float
        The periods above which forward Euler puts the controller's poles, and its zeros, outside the unit circle.
    euler_20ms_spectral_radius : float
        Of the 20 ms loop with the forward-Euler controller (figure 5.7).
    halving : StepHalving
        Step halving from 20 ms with a 5 % agreement criterion (5.1.2).
    """

    bandwidth_rad_s: float
    dc_gain: float
    periods_s: tuple[float, ...]
    loops: dict
    sample_periods: ResultTable
    euler_limit_s: float
    euler_zero_limit_s: float
    euler_20ms_spectral_radius: float
    halving: object
    twenty_ms: TwentyMsStudy

    @property
    def tables(self) -> tuple[ResultTable, ...]:
        return (self.sample_periods, self.twenty_ms.table)

    __repr__ = fields_summary


def chapter5_study(params: RigParams | None = None, *, seed: int = 0, fast: bool = False) -> Chapter5Study:
    """Thesis chapter 5 on the printed plant, and the 20 ms loop on the twin (see :class:`Chapter5Study`).

    ``seed`` seeds the twin of the 20 ms study; ``fast`` uses 4 periods and a shorter calibration (tests).
    """
    import control as ct

    G, K = _printed_loop()
    Tc = ct.feedback(ct.series(K, G), 1)
    periods = (0.001, 0.005, 0.010, 0.020) if fast else PERIODS_S
    loops = sample_period_study(G, K, list(periods), methods=("tustin", "forward_euler"), t_final_s=2.0)

    def fe_response(alpha):
        loop = sampled_loop(G, K, alpha, "forward_euler", t_final_s=2.0)
        return loop.t_s, loop.y

    return Chapter5Study(
        bandwidth_rad_s=float(ct.bandwidth(Tc)),
        dc_gain=float(np.real(ct.dcgain(Tc))),
        periods_s=tuple(periods),
        loops=loops,
        sample_periods=sample_period_table(periods, study=loops),
        euler_limit_s=forward_euler_stability_limit_s(K.poles()),
        euler_zero_limit_s=forward_euler_stability_limit_s(K.zeros()),
        euler_20ms_spectral_radius=sampled_loop(G, K, 0.020, "forward_euler", t_final_s=1.0).spectral_radius,
        halving=halve_step(fe_response, 0.020, tolerance=0.05),
        twenty_ms=twenty_ms_study(params, seed=seed, fast=fast),
    )
