"""The twin's stepping API (what the ``sim`` rig backend drives) and a batched static solver for load studies.

:class:`Twin` holds the digit (:mod:`flexdigit.twin.digit`), the servo (:mod:`flexdigit.twin.actuator`) and the
sensor chain (:mod:`flexdigit.twin.sensors`) on one clock. It integrates on a fixed grid (``dt_s``, a divisor of the
20 ms serial period) and answers :meth:`Twin.read` at any time in between by cubic Hermite interpolation of the
grid states, so a caller sampling at 1 kHz costs no more than one at 50 Hz.

The cable is just taut with the digit straight at the equilibrium command (8, table 3.4 note): the cable
shortening is ``r_M (theta_M - theta_M(8))`` (E 3.11); below command 8 it is slack. With an antagonistic pair
(``[cables] count = 2``) both cables keep their pretension at the equilibrium command, and below it the second
cable bends the digit the other way (:class:`~flexdigit.twin.digit.Chain`).

Examples
--------
>>> twin = Twin(seed=1)
>>> twin.command(20)
>>> twin.advance(1.0)
>>> gauges_v, pot_v = twin.read()
>>> gauges_v.shape, round(twin.time_s, 3)
((3,), 1.0)
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import NamedTuple

import numpy as np

from flexdigit._validation import check_array, check_choice, check_int, check_real, check_values
from flexdigit.errors import DesignError, ParameterError
from flexdigit.models.servo import command_to_angle_rad
from flexdigit.params import DigitDynamics, RigParams
from flexdigit.twin.actuator import Servo
from flexdigit.twin.calibration import Calibration
from flexdigit.twin.contact import Tissue, TissueContact, check_point_force, check_pressure, quadrature
from flexdigit.twin.digit import ORIENTATIONS, Chain, DynamicState, build_digit
from flexdigit.twin.digit_calibration import twin_calibration
from flexdigit.twin.resolution import twin_default_cells
from flexdigit.twin.sensors import SensorChain
from flexdigit.twin.sensors import adc as quantise

__all__ = [
    "DEFAULT_DT_S",
    "DEFAULT_CELLS_PER_SECTION",
    "FRICTION_STREAM",
    "cached_digit",
    "cable_shortening_m",
    "ReadSeries",
    "Twin",
    "check_load",
    "static_gauges_v",
    "friction_sd_v",
    "release_dynamics",
]

DEFAULT_DT_S = 0.020
#: None: the description's own resolution, :func:`flexdigit.params.twin_cells` (its ``[twin]`` table, else
#: :func:`flexdigit.twin.digit.default_cells`: cells no longer than ``MAX_CELL_LENGTH_M``, the thesis rig's 3 per
#: section); an int or a per-section tuple passed instead is honoured.
DEFAULT_CELLS_PER_SECTION = None
#: Second word of the seed of the cable-guide friction's generator, ``default_rng([seed, FRICTION_STREAM])``.
FRICTION_STREAM = 1


def cached_digit(params: RigParams, calibration: Calibration, housing: bool, orientation: str, cells=None) -> Chain:
    """:func:`build_digit`, cached (parameters are frozen and hashable; ``cells`` a count or one per section, None
    the twin's own: :func:`~flexdigit.twin.resolution.twin_default_cells`, finer on a derived calibration)."""
    if cells is None:
        cells = twin_default_cells(params, calibration)
    if np.ndim(cells) > 0:
        cells = tuple(cells)
    return _cached_digit(params, calibration, housing, orientation, cells)


@lru_cache(maxsize=32)
def _cached_digit(params: RigParams, calibration: Calibration, housing: bool, orientation: str, cells) -> Chain:
    return build_digit(params, calibration, housing=housing, orientation=orientation, cells_per_section=cells)


def cable_shortening_m(command_or_angle, params: RigParams, *, is_angle: bool = False):
    """Cable shortening (m) for a command (or a servo angle, rad): ``r_M (theta_M - theta_M(8))`` (E 3.11)."""
    a = params.actuator
    angle = np.asarray(command_or_angle, dtype=float)
    if not is_angle:
        angle = command_to_angle_rad(angle, params)
    return a.cable_m_per_servo_rad * (angle - command_to_angle_rad(a.equilibrium_command, params))


class ReadSeries(NamedTuple):
    """What :meth:`Twin.read_at` returns: one row per read."""

    gauges_v: np.ndarray  #: (N, 3) gauge voltages (V), gauges 1..3 from the base
    pot_v: np.ndarray  #: (N,) potentiometer voltage (V)
    command: np.ndarray  #: (N,) the servo command in force (0..254)
    servo_angle_rad: np.ndarray  #: (N,) servo shaft angle (rad)
    tip_m: np.ndarray  #: (N, 2) tip position in the (along-digit, towards-cable) axes (m)


def _hermite(t, t0, h, psi0, om0, psi1, om1, th0, w0, th1, w1):
    """:meth:`Twin._interpolate` for arrays of reads (rows), the same operations in the same order."""
    with np.errstate(divide="ignore", invalid="ignore"):
        x = np.where(h > 0, np.minimum(np.maximum((t - t0) / h, 0.0), 1.0), 1.0)
    x2, x3 = x * x, x * x * x
    h00, h10, h01, h11 = 2 * x3 - 3 * x2 + 1, x3 - 2 * x2 + x, -2 * x3 + 3 * x2, x3 - x2
    theta = h00 * th0 + h10 * h * w0 + h01 * th1 + h11 * h * w1
    psi = (h00[:, None] * psi0 + (h10 * h)[:, None] * om0) + h01[:, None] * psi1 + (h11 * h)[:, None] * om1
    return psi, theta


class Twin:
    """The simulated rig: integer commands in, three gauge voltages and a potentiometer voltage out.

    Parameters
    ----------
    params : RigParams, optional
        The rig; the thesis rig by default.
    calibration : Calibration, optional
        Fitted parameters; by default :func:`~flexdigit.twin.digit_calibration.twin_calibration` of ``params``
        (the CLI's: the packaged thesis fit for the thesis rig, else the thesis's scaled to the digit).
    seed : int
        Seed of the noise generator: same seed and same calls, same numbers.
    orientation : {"vertical", "hanging", "horizontal"}
        "vertical": tip up (the designed mounting, 2.2.4); "horizontal": cable side up (chapters 6-7).
    housing : bool
        With the elastomer housing (the operating rig) or the bare strip.
    cable : bool
        Cable attached (False: the release-test set-up of 3.1.2, cable removed).
    dt_s : float
        Integration step (s), rounded to a divisor of the serial period.
    cells_per_section : int, sequence of int or None
        Springs per section of the digit model (None: the description's, :func:`~flexdigit.params.twin_cells`).
    command : int, optional
        Initial command (default the equilibrium command, 8); the twin starts at rest in equilibrium there.
    compiled : bool, optional
        Step the digit with the compiled kernel (:meth:`~flexdigit.twin.digit.DynamicState.use_compiled`): ~5 x
        less CPU per simulated second, within 1e-9 rad of the numpy path but not bit for bit. Default (None):
        compiled for a digit other than the thesis rig, numpy for the thesis rig (the report's numbers come from
        its numpy path); False keeps numpy for any digit. Either path is deterministic on one machine (same seed
        and calls, same numbers: numba's machine code runs the same operations in the same order every time).
    servo_drive : {"serial", "timer"}
        How commands reach the servo (:mod:`flexdigit.twin.actuator`): the thesis's serial board, or a pulse the
        controller's own timer generates (the reference firmware's: the loop on the board's timing).
    """

    def __init__(
        self,
        params: RigParams | None = None,
        calibration: Calibration | None = None,
        *,
        seed: int = 0,
        orientation: str = "vertical",
        housing: bool = True,
        cable: bool = True,
        dt_s: float = DEFAULT_DT_S,
        cells_per_section: int = DEFAULT_CELLS_PER_SECTION,
        command: int | None = None,
        compiled: bool | None = None,
        servo_drive: str = "serial",
    ):
        self.params = params or RigParams()
        self.calibration = calibration or twin_calibration(self.params)
        self.seed = check_int(seed, "seed", "Twin", low=0)
        self.orientation = check_choice(orientation, "orientation", tuple(ORIENTATIONS), "Twin")
        self.housing = bool(housing)
        self.cable = bool(cable)
        period = self.params.actuator.serial_period_s
        dt = check_real(dt_s, "dt_s", "Twin", low=1e-5, high=period)
        self.dt_s = period / max(1, round(period / dt))
        self.chain = cached_digit(self.params, self.calibration, self.housing, self.orientation, cells_per_section)
        self.rng = np.random.default_rng(self.seed)
        self.sensors = SensorChain(self.params, self.calibration, self.rng)
        # cable-guide friction draws from its own stream: the white noise and drift stay the same numbers
        self.friction_rng = np.random.default_rng([self.seed, FRICTION_STREAM])
        self._curvature_per_moment = self.chain.gauge_curvature_per_moment
        # the cable-guide friction's state (standard-normal, per gauge section): zero until something jolts the
        # cable (a servo pulling it slides it one way, a repeatable state the calibration absorbs)
        self._friction_xi = np.zeros(len(self.params.geometry.gauge_positions_m))
        start = self.params.actuator.equilibrium_command if command is None else command
        self.servo = Servo(self.params, start, drive=servo_drive)
        self._pulley_m = self.params.actuator.cable_m_per_servo_rad
        self._angle_taut = float(command_to_angle_rad(self.params.actuator.equilibrium_command, self.params))
        self._loads: list[tuple[float, float]] = []
        self._presses: list = []  # PointForce / Pressure (flexdigit.twin.contact)
        self.tissue = None
        self.dynamics = DynamicState(self.chain)
        if compiled or (compiled is None and not self.params.is_thesis_rig()):
            self.dynamics.use_compiled()
        self._settle()
        self.time_s = 0.0
        self._t_grid = 0.0
        self._prev = self._snapshot()

    # ------------------------------------------------------------------------------------------------ state
    def _shortening(self, servo_angle: float) -> float:
        if not self.cable:
            return -math.inf
        return self._pulley_m * (servo_angle - self._angle_taut)

    def _settle(self) -> None:
        """Put the digit at rest in static equilibrium under the current loads and servo angle."""
        self.dynamics.psi = self._static().psi_rad[0].copy()
        self.dynamics.omega = np.zeros(self.chain.n)

    def _static(self, tip_force_n=None):
        """The static equilibrium under the hung weights, presses, the body beside it and the servo angle now."""
        s_arr, m_arr = self._load_arrays()
        forces_s, forces_ab = self._press_arrays()
        weights_ab = m_arr[:, None] * self.chain.gravity[None, :]
        load_s = np.concatenate([s_arr, forces_s])
        load_f = np.concatenate([weights_ab, forces_ab])
        return self.chain.solve_static(
            load_s[None, :] if load_s.size else None,
            load_f[None] if load_s.size else None,
            tip_force_n=None if tip_force_n is None else [[0.0, tip_force_n]],
            cable_shortening_m=[self._shortening(self.servo.angle)] if self.cable else None,
            contact=self.dynamics.contact,
            max_iter=200 if self.dynamics.contact is not None else 80,
        )

    def _press_arrays(self):
        return quadrature(self.chain, self._presses)

    def _load_arrays(self):
        if not self._loads:
            return np.zeros(0), np.zeros(0)
        s, m = zip(*self._loads, strict=True)
        return np.array(s), np.array(m)

    def _snapshot(self):
        return (
            self._t_grid,
            self.dynamics.psi.copy(),
            self.dynamics.omega.copy(),
            self.servo.angle,
            self.servo.rate,
        )

    # -------------------------------------------------------------------------------------------------- API
    def command(self, value: int) -> None:
        """Send a servo command (integer ``command_min..command_max``); it takes effect on the next serial frame.

        Raises
        ------
        ParameterError
            If ``value`` is not an integer in range (255, the board's sync byte, is never a position).
        """
        self.servo.schedule(value, self.time_s, self.dt_s)

    def advance(self, duration_s: float) -> None:
        """Let ``duration_s`` seconds of rig time pass (integrates the digit and the servo)."""
        duration = check_real(duration_s, "duration_s", "Twin.advance", low=0)
        target = self.time_s + duration
        if self.dynamics.compiled and self.dynamics.contact is None:
            self._advance_compiled(target)
            self.time_s = target
            return
        h = self.dt_s
        while self._t_grid < target - 1e-12:
            self._prev = self._snapshot()
            self.servo.update_command(self._t_grid)
            t_next = (math.floor(self._t_grid / h + 1e-9) + 1) * h  # back on the grid after deflect()
            step = t_next - self._t_grid
            if abs(step - h) < 1e-9:  # keep the step bit-identical so the servo's transition matrix stays cached
                step = h
            a0 = self.servo.angle
            self.servo.step(step)
            self.dynamics.step(step, self._shortening(a0), self._shortening(self.servo.angle))
            self._t_grid = t_next
        self.time_s = target

    def _advance_compiled(self, target: float) -> None:
        """:meth:`advance`'s loop with the digit's steps handed to the compiled kernel a run at a time (one call
        per run of equal steps, not one per step: most of a compiled step's cost is the call). The servo does not
        depend on the digit, so it runs first; the digit then takes all steps but the last, the snapshot the
        reads interpolate from is taken, and the last step."""
        h = self.dt_s
        runs: list[tuple[float, list[float]]] = []  # (step, shortenings at its boundaries)
        before_last = None
        while self._t_grid < target - 1e-12:
            before_last = (self._t_grid, self.servo.angle, self.servo.rate)
            self.servo.update_command(self._t_grid)
            t_next = (math.floor(self._t_grid / h + 1e-9) + 1) * h
            step = t_next - self._t_grid
            if abs(step - h) < 1e-9:
                step = h
            a0 = self.servo.angle
            self.servo.step(step)
            if runs and runs[-1][0] == step:
                runs[-1][1].append(self._shortening(self.servo.angle))
            else:
                runs.append((step, [self._shortening(a0), self._shortening(self.servo.angle)]))
            self._t_grid = t_next
        if before_last is None:
            return
        step, last = runs[-1]
        runs[-1] = (step, last[:-1])
        for h_run, shortenings in runs:
            if len(shortenings) > 1:
                self.dynamics.step_run(h_run, shortenings)
        t_prev, angle, rate = before_last
        self._prev = (t_prev, self.dynamics.psi.copy(), self.dynamics.omega.copy(), angle, rate)
        self.dynamics.step_run(step, last[-2:])

    def state(self, time_s: float | None = None):
        """Interpolated ``(psi, servo_angle)`` at ``time_s`` (default now), between the last two grid points."""
        return self._interpolate(self.time_s if time_s is None else time_s, True)

    def _interpolate(self, t: float, want_psi: bool):
        t0, psi0, om0, th0, w0 = self._prev
        t1 = self._t_grid
        psi1, om1, th1, w1 = self.dynamics.psi, self.dynamics.omega, self.servo.angle, self.servo.rate
        h = t1 - t0
        if h <= 0:
            return (psi1.copy() if want_psi else None), th1
        x = min(max((t - t0) / h, 0.0), 1.0)
        x2, x3 = x * x, x * x * x
        h00, h10, h01, h11 = 2 * x3 - 3 * x2 + 1, x3 - 2 * x2 + x, -2 * x3 + 3 * x2, x3 - x2
        theta = h00 * th0 + h10 * h * w0 + h01 * th1 + h11 * h * w1
        if not want_psi:
            return None, theta
        psi = h00 * psi0 + (h10 * h) * om0 + h01 * psi1 + (h11 * h) * om1
        return psi, theta

    def _gauge_state(self, t: float):
        """Curvature and axial force at the gauges, cable tension (a group delay ago) and the servo angle now."""
        psi, theta = self._interpolate(t - self.sensors.delay_s, True)
        kappa = self.chain.curvature_at_gauges(psi)
        if self.cable and self.chain.antagonist:
            tension = float(self.chain.cable_tension(psi[-1], self._shortening(theta))[0])
        elif self.cable:
            stretch = self._shortening(theta) - self.chain.eccentricity * psi[-1]
            tension = self.chain.cable_stiffness * stretch if stretch > 0 else 0.0
        else:
            tension = 0.0
        axial = self.chain.axial_force(psi, self.dynamics.beyond(psi), tension)
        _, theta_now = self._interpolate(t, False)
        return kappa, axial, tension, theta_now

    def clean_read(self, time_s: float | None = None):
        """Noise-free ``(gauges_v, pot_v)`` at ``time_s`` (default now), before the ADC.

        The gauges see the state a low-pass group delay ago (:mod:`flexdigit.twin.sensors`); the pot is read now.
        """
        kappa, axial, _, theta_now = self._gauge_state(self.time_s if time_s is None else time_s)
        return self.sensors.clean_v(kappa, axial), self.servo.pot_v(theta_now)

    def cable_tension_n(self) -> float:
        """Cable tension now (N; 0 when slack or detached), as the gauges see it (a group delay ago)."""
        return float(self._gauge_state(self.time_s)[2])

    def read(self) -> tuple[np.ndarray, float]:
        """Sample the three gauge channels and the potentiometer through the sensor chain (with noise).

        With a taut cable each reading also carries the cable-guide friction's current state
        (``Calibration.cable_friction_ratio``, :mod:`flexdigit.twin.sensors`), drawn afresh by :meth:`disturb`.

        Returns
        -------
        gauges_v : ndarray, shape (3,)
            Gauge voltages (V), gauges 1..3 from the base.
        pot_v : float
            Potentiometer voltage (V).
        """
        kappa, axial, tension, theta_now = self._gauge_state(self.time_s)
        if tension > 0 and self.sensors.friction_ratio > 0 and self._friction_xi.any():  # none until a jolt
            sd = self.sensors.friction_curvature_sd_1_m(tension, self._curvature_per_moment)
            kappa = kappa + sd * self._friction_xi
        clean = self.sensors.clean_v(kappa, axial)
        return self.sensors.sample(clean, self.time_s), self.sensors.sample_pot(self.servo.pot_v(theta_now))

    def read_at(self, times_s) -> ReadSeries:
        """Advance through increasing times and read at each: ``advance(t - time_s)`` then :meth:`read`, bit for bit.

        The same numbers as that loop (the same random draws in the same order), for less CPU: the digit is
        stepped as the loop would step it, and the reads between two grid points, which only interpolate between
        them, are taken together. Times before ``time_s`` read at ``time_s``, as ``advance(0)`` would.

        Parameters
        ----------
        times_s : array_like, shape (N,)
            Sample times (s of rig time), non-decreasing.

        Returns
        -------
        ReadSeries
            Gauge and pot voltages, the command in force, the servo angle and the tip position at each time.

        Examples
        --------
        >>> twin = Twin(seed=1)
        >>> twin.command(20)
        >>> series = twin.read_at([0.5, 0.75, 1.0])
        >>> series.gauges_v.shape, round(twin.time_s, 3)
        ((3, 3), 1.0)
        """
        times = check_array(times_s, "times_s", "Twin.read_at", ndim=1)
        if times.size > 1 and np.any(np.diff(times) < 0):
            raise ParameterError("The 'times_s' parameter of Twin.read_at must be non-decreasing.")
        if self.dynamics.contact is not None:  # the contact's share of the axial force is per state: one by one
            return self._read_each(times)
        n = times.size
        at = np.empty(n)  # the rig time of each read, as advance() computes it
        group = np.empty(n, dtype=np.int64)
        snaps: list[tuple] = []
        commands: list[int] = []
        for k, t in enumerate(times.tolist()):
            duration = max(t - self.time_s, 0.0)
            target = self.time_s + duration  # as advance() computes it
            if not snaps or self._t_grid < target - 1e-12:  # advance() would step: a new interval
                self.advance(duration)
                snaps.append(self._snapshot_pair())
                commands.append(self.servo.command)
            self.time_s = target
            at[k] = target
            group[k] = len(snaps) - 1
        if n == 0:
            return ReadSeries(np.empty((0, 3)), np.empty(0), np.empty(0, dtype=np.int64), np.empty(0), np.empty((0, 2)))
        kappa, axial, tension, theta_now, psi_now = self._gauge_states(at, group, snaps)
        if self.sensors.friction_ratio > 0 and self._friction_xi.any():
            sd = self.sensors.friction_curvature_sd_1_m(tension, self._curvature_per_moment)
            kappa = np.where((tension > 0)[:, None], kappa + sd * self._friction_xi, kappa)
        gauges, pot = self.sensors.sample_series(self.sensors.clean_v(kappa, axial), at, self.servo.pot_v(theta_now))
        return ReadSeries(gauges, pot, np.asarray(commands, dtype=np.int64)[group], theta_now, self.chain.tip(psi_now))

    def _read_each(self, times: np.ndarray) -> ReadSeries:
        """:meth:`read_at` one read at a time (the reference the batched path is tested against)."""
        out = ([], [], [], [], [])
        for t in times.tolist():
            self.advance(max(t - self.time_s, 0.0))
            gauges, pot = self.read()
            psi, theta = self.state()
            for column, value in zip(out, (gauges, pot, self.servo.command, theta, self.chain.tip(psi)), strict=True):
                column.append(value)
        shapes = ((0, 3), (0,), (0,), (0,), (0, 2))
        gauges, pot, cmd, theta, tip = (np.array(c) if c else np.empty(sh) for c, sh in zip(out, shapes, strict=True))
        return ReadSeries(gauges, pot, cmd.astype(np.int64), theta, tip)

    def _snapshot_pair(self):
        """The two grid states a read interpolates between (the last snapshot and now)."""
        return self._prev, (
            self._t_grid,
            self.dynamics.psi.copy(),
            self.dynamics.omega.copy(),
            self.servo.angle,
            self.servo.rate,
        )

    def _gauge_states(self, at: np.ndarray, group: np.ndarray, snaps: list[tuple]):
        """:meth:`_gauge_state` for many reads at once (``at`` their times, ``group`` the index of their
        interval in ``snaps``), and the angles now (for the tip). Elementwise the same operations."""
        (t0, psi0, om0, th0, w0), (t1, psi1, om1, th1, w1) = (
            [np.array(v)[group] for v in zip(*side, strict=True)] for side in zip(*snaps, strict=True)
        )
        h = t1 - t0
        psi_d, theta_d = _hermite(at - self.sensors.delay_s, t0, h, psi0, om0, psi1, om1, th0, w0, th1, w1)
        psi_now, theta_now = _hermite(at, t0, h, psi0, om0, psi1, om1, th0, w0, th1, w1)
        kappa = self.chain.curvature_at_gauges(psi_d)
        if self.cable and self.chain.antagonist:
            tension = self.chain.cable_tension(psi_d[:, -1], self._pulley_m * (theta_d - self._angle_taut))[0]
        elif self.cable:
            stretch = self._pulley_m * (theta_d - self._angle_taut) - self.chain.eccentricity * psi_d[:, -1]
            tension = np.where(stretch > 0, self.chain.cable_stiffness * stretch, 0.0)
        else:
            tension = np.zeros(at.size)
        axial = self.chain.axial_force(psi_d, self.dynamics.beyond(), tension)
        return kappa, axial, tension, theta_now, psi_now

    def deflect(self, tip_force_n: float) -> None:
        """Hold the digit at rest under an extra sideways tip force (N, towards the cable side), as a hand does
        before a release test (3.1.2); the next :meth:`advance` releases it."""
        force = check_real(tip_force_n, "tip_force_n", "Twin.deflect")
        sol = self._static(tip_force_n=force)
        self.dynamics.psi = sol.psi_rad[0].copy()
        self.dynamics.omega = np.zeros(self.chain.n)
        self.servo.rate = 0.0
        self._t_grid = self.time_s
        self._prev = self._snapshot()

    def tip_position_m(self) -> np.ndarray:
        """Tip position now in the (along-digit, towards-cable) axes (m)."""
        return self.chain.tip(self.state()[0])

    def deflection_m(self, s_m) -> np.ndarray:
        """Sideways deflection (towards the cable, m) now at arc positions ``s_m`` from the base."""
        return self.chain.positions(self.state()[0], np.atleast_1d(np.asarray(s_m, dtype=float)))[:, 1]

    def place_load(self, mass_kg: float, position_from_base_m: float) -> None:
        """Hang a weight (kg) at a position along the digit (m from the base); it stays until :meth:`clear_loads`.

        Hanging it jolts the cable in its guides: the friction is drawn afresh (:meth:`disturb`).
        """
        m, s = check_load(mass_kg, position_from_base_m, self.params)
        self._loads.append((float(s), float(m)))
        self._apply_loads()
        self.disturb()

    def _apply_loads(self) -> None:
        s_arr, m_arr = self._load_arrays()
        self.dynamics.set_loads(s_arr, m_arr, *self._press_arrays())

    def clear_loads(self) -> None:
        """Remove every hung weight (a jolt, like hanging one: :meth:`disturb`)."""
        self._loads.clear()
        self._apply_loads()
        self.disturb()

    # ------------------------------------------------------------------------------------------------ contact
    def press(self, force_n: float, position_from_base_m: float) -> None:
        """Add a world-fixed sideways point force (N, + towards the cable side) at a position along the digit (m
        from the base); it stays (with any others) until :meth:`clear_presses`. The digit is not jolted: it moves
        from where it is (the next :meth:`advance` integrates the motion)."""
        self._presses.append(check_point_force(position_from_base_m, force_n, self.chain.length_m, "Twin.press"))
        self._apply_loads()

    def apply_pressure(self, total_n: float, start_m: float, end_m: float) -> None:
        """Add a world-fixed sideways line load: ``total_n`` (N, + towards the cable side) spread evenly over the
        stretch ``start_m..end_m`` (m from the base). Stays until :meth:`clear_presses`."""
        self._presses.append(check_pressure(start_m, end_m, total_n, self.chain.length_m, "Twin.apply_pressure"))
        self._apply_loads()

    def clear_presses(self) -> None:
        """Remove every point force and line load added by :meth:`press` and :meth:`apply_pressure`."""
        self._presses.clear()
        self._apply_loads()

    @property
    def presses(self) -> list:
        """The point forces and line loads acting now (:mod:`flexdigit.twin.contact`)."""
        return list(self._presses)

    def set_tissue(self, tissue=None, *, settle: bool = False) -> None:
        """Put a compliant body beside the digit (:class:`flexdigit.twin.contact.Tissue`), or take it away (None).

        The digit meets it where it is: with ``settle`` it is put at rest in the new static equilibrium instead
        (a body placed before the run, the digit already pressing on it).
        """
        if tissue is not None and not isinstance(tissue, Tissue):
            raise ParameterError(f"The 'tissue' parameter of Twin.set_tissue must be a Tissue or None. Got {tissue!r}.")
        self.tissue = tissue
        self.dynamics.contact = TissueContact(self.chain, tissue) if tissue is not None else None
        if settle:
            self._settle()
            self._prev = self._snapshot()

    def contact_state(self):
        """The body's force on the digit now (N, + towards the cable side), its centroid (m of arc from the base)
        and the stretch in contact ``(first, last)`` (m; NaN without contact): the truth the gauges are read for."""
        if self.dynamics.contact is None:
            return 0.0, math.nan, (math.nan, math.nan)
        psi, _ = self.state()
        force, centroid, (first, last), _ = self.dynamics.contact.resultant(psi[None], self.dynamics.omega[None])
        return float(force[0]), float(centroid[0]), (float(first[0]), float(last[0]))

    def disturb(self) -> None:
        """Jolt the cable in its guides (a weight hung, lifted or re-hung by hand): the cable-guide friction
        settles in a new random state, held until the next jolt (:mod:`flexdigit.twin.sensors`).

        The mechanics are untouched: re-hanging a weight at the same place leaves the settled shape as it was.
        Draws from the friction's own stream, so the white noise and drift are the same numbers.
        """
        self._friction_xi = self.friction_rng.standard_normal(self._friction_xi.size)

    @property
    def loads(self) -> list[tuple[float, float]]:
        """Hung weights as ``(mass_kg, position_from_base_m)``."""
        return [(m, s) for s, m in self._loads]

    def __repr__(self) -> str:
        return (
            f"Twin(seed={self.seed}, orientation={self.orientation!r}, housing={self.housing}, cable={self.cable}, "
            f"dt_s={self.dt_s:g}, time_s={self.time_s:g}, command={self.servo.command}, loads={self.loads}"
            + (", compiled=True" if self.dynamics.compiled else "")
            + (f", presses={self.presses}" if self._presses else "")
            + (f", tissue={self.tissue!r}" if self.tissue is not None else "")
            + ")"
        )


def check_load(mass_kg, position_from_base_m, params: RigParams):
    """Validate one hung weight: mass > 0 (kg), position in (0, digit_length] (m)."""
    m = check_real(mass_kg, "mass_kg", "load", low=0, low_open=True)
    length = params.geometry.digit_length_m
    s = check_real(position_from_base_m, "position_from_base_m", "load", low=0, high=length)
    return m, s


def static_gauges_v(
    loads_mass_kg,
    positions_from_base_m,
    commands=None,
    *,
    params: RigParams | None = None,
    calibration: Calibration | None = None,
    orientation: str = "horizontal",
    housing: bool = True,
    cells_per_section: int = DEFAULT_CELLS_PER_SECTION,
    seed: int | None = None,
    adc: bool = True,
    return_solution: bool = False,
    friction_draws=None,
    servo_offset_rad=None,
):
    """Steady gauge voltages for many static load cases at once (one batched Newton solve).

    Parameters
    ----------
    loads_mass_kg : array_like, shape (B,) or (B, K)
        Hung weights (kg, >= 0; 0 means no weight). ``K`` weights per case when 2-D.
    positions_from_base_m : array_like, same shape
        Their positions along the digit from the base (m), in [0, digit_length].
    commands : int or array_like of int, shape (B,), optional
        Servo command per case (0..254); None: cable detached (the non-actuated digit of chapter 6).
    params, calibration : optional
        Rig and calibration (thesis defaults).
    orientation : {"horizontal", "vertical", "hanging"}
        Horizontal by default: the weights hang off a horizontal digit, cable side up (chapters 6-7).
    housing : bool
    cells_per_section : int, sequence of int or None
        Springs per section (None: the description's, :func:`~flexdigit.params.twin_cells`).
    seed : int, optional
        With a seed, add the calibration's white noise and, where the cable is taut, one draw of the cable-guide
        friction per case (drift is a slow process, not per case). The same seed gives the same white noise as
        without friction (the friction has its own stream, ``default_rng([seed, FRICTION_STREAM])``).
    adc : bool
        Clip and quantise like the 16-bit card.
    return_solution : bool
        Also return the :class:`~flexdigit.twin.digit.StaticSolution`.
    friction_draws : array_like, shape (B, 3), optional
        Standard-normal draws of the cable-guide friction to use instead of fresh ones (with ``seed``): lets a
        caller share one draw between readings of the same hang.
    servo_offset_rad : array_like, shape (B,), optional
        Servo shaft angle away from the command's (rad), e.g. where a servo stopped inside its deadband; used by
        the report to show that such a disturbance alone is not what costs the actuated experiment its corr2.

    Returns
    -------
    ndarray, shape (B, 3)
        Gauge voltages (V), gauges 1..3.

    Examples
    --------
    >>> v = static_gauges_v([0.0, 0.025], [0.27, 0.27], [8, 8])
    >>> v.shape, bool(abs(v[1, 0] - v[0, 0]) > 0.01)
    ((2, 3), True)
    """
    params = params or RigParams()
    calibration = calibration or twin_calibration(params)
    masses, pos = _static_load_cases(loads_mass_kg, positions_from_base_m, params)
    b = masses.shape[0]
    chain = cached_digit(params, calibration, bool(housing), orientation, cells_per_section)
    shortening = _static_cable_shortening(commands, servo_offset_rad, b, params)
    forces = masses[..., None] * chain.gravity
    sol = chain.solve_static(pos, forces, cable_shortening_m=shortening)
    rng = np.random.default_rng(seed) if seed is not None else None
    sensors = SensorChain(params, calibration, rng if rng is not None else np.random.default_rng(0))
    kappa = sol.curvature_1_m
    if rng is not None and shortening is not None and sensors.friction_ratio > 0:
        kappa = _with_guide_friction(kappa, sol, sensors, chain, seed, friction_draws)
    volts = sensors.clean_v(kappa, sol.axial_force_n)
    if rng is not None:
        volts = volts + np.asarray(calibration.noise_white_v) * rng.standard_normal(volts.shape)
    if adc:
        volts = quantise(volts, params.sensors)
    return (volts, sol) if return_solution else volts


def _static_load_cases(loads_mass_kg, positions_from_base_m, params: RigParams):
    """Checked ``(masses, positions)`` of :func:`static_gauges_v`'s load cases, both shape (B, K)."""
    owner = "static_gauges_v"
    masses = check_values(loads_mass_kg, "loads_mass_kg", owner, low=0, unit="kg")
    if masses.ndim == 1:
        masses = masses[:, None]
    if masses.ndim != 2:
        raise ParameterError(
            f"The 'loads_mass_kg' parameter of static_gauges_v must be 1-D or 2-D. Got shape {masses.shape}."
        )
    length = params.geometry.digit_length_m
    pos = check_values(
        positions_from_base_m, "positions_from_base_m", owner, low=0, high=length, unit="m from the base"
    )
    pos = pos.reshape(masses.shape) if pos.size == masses.size else None
    if pos is None:
        raise ParameterError(
            "The 'positions_from_base_m' parameter of static_gauges_v must have the shape of 'loads_mass_kg' "
            f"{masses.shape}. Got {np.shape(positions_from_base_m)} instead."
        )
    return masses, pos


def _static_cable_shortening(commands, servo_offset_rad, b: int, params: RigParams):
    """Cable shortening (m) per load case of :func:`static_gauges_v`: its servo commands plus any shaft offset.

    None when ``commands`` is None (cable detached).
    """
    if commands is None:
        return None
    owner = "static_gauges_v"
    a = params.actuator
    cmd = check_values(commands, "commands", owner, low=a.command_min, high=a.command_max, integer=True)
    if cmd.ndim and cmd.size not in (1, b):
        raise ParameterError(
            f"The 'commands' parameter of {owner} must be one command or one per load case ({b}). "
            f"Got {cmd.size} commands instead."
        )
    cmd = np.broadcast_to(cmd.reshape(-1) if cmd.ndim else cmd, (b,))
    shortening = cable_shortening_m(cmd, params)
    if servo_offset_rad is not None:
        offset = check_values(servo_offset_rad, "servo_offset_rad", owner, unit="rad")
        shortening = shortening + params.actuator.cable_m_per_servo_rad * np.broadcast_to(offset.reshape(-1), (b,))
    return shortening


def _with_guide_friction(kappa, sol, sensors: SensorChain, chain: Chain, seed: int, friction_draws):
    """Gauge curvatures plus one cable-guide friction draw per case (fresh from ``seed``'s stream, or given)."""
    owner = "static_gauges_v"
    c_moment = chain.gauge_curvature_per_moment
    if friction_draws is None:
        friction_rng = np.random.default_rng([seed, FRICTION_STREAM])
        return sensors.friction_draw(kappa, sol.tension_n, c_moment, friction_rng)
    xi = check_values(friction_draws, "friction_draws", owner)
    if xi.shape != kappa.shape:
        raise ParameterError(
            f"The 'friction_draws' parameter of {owner} must have shape {kappa.shape} (load cases, gauges). "
            f"Got shape {xi.shape} instead."
        )
    return kappa + sensors.friction_curvature_sd_1_m(sol.tension_n, c_moment) * xi


def friction_sd_v(
    solution,
    params: RigParams | None = None,
    calibration: Calibration | None = None,
    *,
    orientation: str = "horizontal",
    housing: bool = True,
    cells_per_section: int = DEFAULT_CELLS_PER_SECTION,
) -> np.ndarray:
    """Standard deviation (V) of the cable-guide friction in one reading, per case and gauge, shape (B, 3).

    ``solution`` a :class:`~flexdigit.twin.digit.StaticSolution` (e.g. from :func:`static_gauges_v` with
    ``return_solution=True``); zero where the cable is slack. The same model the twin draws from
    (:mod:`flexdigit.twin.sensors`), for the Cramer-Rao bound and the calibration.

    Examples
    --------
    >>> from flexdigit.twin.calibration import default_calibration
    >>> cal = default_calibration().replace(cable_friction_ratio=0.1)
    >>> _, sol = static_gauges_v([0.0, 0.0], [0.0, 0.0], [0, 40], calibration=cal, adc=False, return_solution=True)
    >>> sd = friction_sd_v(sol, calibration=cal)
    >>> sd.shape, bool(np.all(sd[1] > sd[0]))      # more tension at command 40, more friction
    ((2, 3), True)
    """
    params = params or RigParams()
    calibration = calibration or twin_calibration(params)
    chain = cached_digit(params, calibration, bool(housing), orientation, cells_per_section)
    sensors = SensorChain(params, calibration, np.random.default_rng(0))
    return sensors.friction_sd_v(
        solution.curvature_1_m, solution.axial_force_n, solution.tension_n, chain.gauge_curvature_per_moment
    )


def release_dynamics(params: RigParams, calibration: Calibration | None = None, *, orientation: str = "vertical"):
    """The digit's release-test dynamics (3.1.2) from its twin: the first mode of the chain about straight with the
    cable removed, housed (table 3.2's E(s)) and bare (table 3.1), as a :class:`~flexdigit.params.DigitDynamics`.

    What a digit nobody has identified puts where the thesis rig has its tables' averages; on the thesis rig the
    housed mode is its table 3.2 values to 0.01 % (13.1 rad/s, zeta 0.0679), the calibration having been fitted
    to them.
    """

    cal = calibration if calibration is not None else twin_calibration(params)
    modes = {}
    for housed in (True, False):
        chain = cached_digit(params, cal, housed, orientation, DEFAULT_CELLS_PER_SECTION)
        stiffness = chain.tangent_stiffness(np.zeros(chain.n), chain.g_gravity, False)
        if np.min(np.linalg.eigvalsh(0.5 * (stiffness + stiffness.T))) <= 0:
            raise DesignError(
                f"the straight digit ({params.geometry.section_count} sections, {params.geometry.digit_length_m:g} m)"
                f" is not stable {orientation} without its cable (it buckles under its own weight): no release "
                "mode, no plant; mount it hanging or horizontal"
            )
        wn, zeta = chain.linear_modes()
        modes[housed] = (float(wn[0]), float(zeta[0]))
    return DigitDynamics(
        wn_housing_rad_s=modes[True][0],
        zeta_housing=modes[True][1],
        wn_bare_rad_s=modes[False][0],
        zeta_bare=modes[False][1],
    )
