"""Controllers by name, as ``flexdigit run --controller NAME`` knows them, adapted to the real-time loop.

``digital20`` is the discrete design of :mod:`flexdigit.control.design20ms` on the beam rotation estimated from the
gauges (:mod:`flexdigit.rig.rotation`); ``thesis39-euler`` and ``thesis39-tustin`` are the printed 39 Hz controller
digitised as 5.2 and 5.1.1 did, on gauge-1 deflection in metres.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from flexdigit._validation import Plausible, check_choice, check_param, check_positive
from flexdigit.models.conversion import k3_printed_mm_per_v
from flexdigit.params import RigParams
from flexdigit.rig.base import Reading, Rig
from flexdigit.rig.rotation import RotationEstimator, calibrate_rotation, tare_at_rest
from flexdigit.twin.digit_calibration import twin_calibration

__all__ = ["CONTROLLERS", "make_controller"]


def _gauge1_deflection_m(params: RigParams, tare_v: float) -> Callable[[Reading], float]:
    """Gauge-1 deflection (m) from its voltage through the printed K3 (E 3.23, 6.5698 mm/V)."""
    k3_m_per_v = k3_printed_mm_per_v()[0] / 1000.0
    return lambda reading: (float(reading.gauges_v[0]) - tare_v) * k3_m_per_v


class _Wrapped:
    """Adapts a :class:`RuntimeController` to the loop: measurement, setpoint units, optional actuator gain error."""

    def __init__(
        self, runtime, measure, setpoint_scale: float = 1.0, gain: float = 1.0, equilibrium: int = 8, pulses=None
    ):
        self.runtime, self.measure = runtime, measure
        # the rig's count of the servo pulses a command gets (Rig.command_pulses), for the dither
        self.pulses = pulses
        self.setpoint_scale, self.gain, self.equilibrium = setpoint_scale, gain, equilibrium
        self.name = runtime.name

    def reset(self, command: int) -> None:
        self.runtime.reset(command)

    def step(self, setpoint: float, reading: Reading) -> float:
        pulses = self.pulses() if self.pulses is not None else None
        u = self.runtime.update(setpoint * self.setpoint_scale, self.measure(reading), pulses or 1)
        # a plant gain error, emulated at the actuator: the servo gets gain x the asked deviation
        return self.equilibrium + self.gain * (u - self.equilibrium) if self.gain != 1.0 else u


CONTROLLERS = ("digital20", "thesis39-euler", "thesis39-tustin")


#: An actuator gain error to emulate (robustness runs): the servo gets gain x the asked deviation.
ACTUATOR_GAIN = Plausible("", 0.1, 10.0, "an actuator gain error: a tenth to ten times the rig's own")


def make_controller(
    name: str,
    rig: Rig,
    *,
    period_s: float = 0.020,
    estimator: RotationEstimator | None = None,
    gain: float = 1.0,
    calibration=None,
    kept=None,
) -> _Wrapped:
    """Build controller ``name`` for ``rig``; its setpoint is beam rotation in degrees for all of them.

    The thesis controllers work on gauge-1 deflection (m): the setpoint in degrees is converted with the sweep's
    gauge-1 volts per degree times the printed K3 (6.5698 mm/V, E 3.23).

    ``digital20`` is designed for the rig's digit (:func:`flexdigit.control.design20ms.digit_design_20ms`: the
    thesis rig's chapter-5 design, or another digit's from its own components); ``calibration`` is the twin
    calibration of that digit when it is not the one its twin would get by default. ``kept``: a
    :class:`~flexdigit.control.kept_design.KeptDesign` of ``digital20`` for this digit (``flexdigit design 20ms
    --out``): checked against the rig's digit, calibration, mount and ``period_s`` (refused in one line), and its
    weights used instead of searching them again.
    """
    from flexdigit.control.design20ms import digit_design_20ms, thesis_controller

    check_choice(name, "controller", CONTROLLERS, "make_controller")
    check_positive(period_s, "period_s", "make_controller")
    gain = check_param(gain, ACTUATOR_GAIN, "gain", "make_controller")
    params = rig.params
    twin = getattr(rig, "twin", None)  # on the twin: its own calibration and orientation
    calibration = calibration if calibration is not None or twin is None else _own_calibration(twin)
    orientation = twin.orientation if twin is not None else "vertical"
    if estimator is None:
        estimator = calibrate_rotation(rig)
    rest_v = tare_at_rest(estimator, rig)  # the digit at rest at its straight command reads 0 deg
    eq = int(params.actuator.equilibrium_command)
    if name == "digital20":
        measured = getattr(estimator, "deg_per_command_", None)  # the sweep's rotation per command, if it has one
        measured = measured if isinstance(measured, float) and math.isfinite(measured) and measured > 0 else None
        weights = None
        if kept is not None:
            kept.check(params, calibration, orientation=orientation, period_s=period_s, source=kept.source)
            weights = kept.weights
        design = digit_design_20ms(
            params,
            period_s=period_s,
            calibration=calibration,
            orientation=orientation,
            deg_per_command=measured,
            weights=weights,
        )
        # another digit than the thesis rig's is held between quanta (dithered: RuntimeController's ``dither``)
        runtime = design.runtime(params, name=name, dither=not params.is_thesis_rig())
        return _Wrapped(runtime, estimator, 1.0, gain, eq, pulses=rig.command_pulses if runtime.dither else None)
    method = "forward_euler" if name.endswith("euler") else "tustin"
    measure = _gauge1_deflection_m(params, float(rest_v[0]))
    # metres of gauge-1 deflection per degree: K3 (m/V) x the sweep's gauge-1 volts per degree
    scale = k3_printed_mm_per_v()[0] / 1000.0 * float(estimator.gauge_v_per_deg_[0])
    return _Wrapped(thesis_controller(method, period_s, params), measure, scale, gain, eq)


def _own_calibration(twin):
    """The twin's calibration, or None when it is the one its digit gets by default (so the thesis rig keeps its
    chapter-5 design)."""

    return None if twin.calibration == twin_calibration(twin.params) else twin.calibration
