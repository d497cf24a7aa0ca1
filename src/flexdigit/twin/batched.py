"""N parameter sets of the twin stepped together: one vectorised state for the statics and the dynamics.

Studies (:mod:`flexdigit.studies`) evaluate thousands of rigs; stepping them one :class:`~flexdigit.twin.Twin` at a
time costs Python overhead per rig and per step. :class:`BatchedTwin` stacks the rigs' chains (same number of
springs; every other number may differ: stiffness, damping, masses, lengths, gauges, cable, servo) and advances
them with the scalar twin's integrator (:class:`~flexdigit.twin.digit.DynamicState`: two-stage L-stable Rosenbrock,
exact Jacobian, the step halved while a link would turn more than 0.1 rad), compiled
(:mod:`flexdigit.twin._batched_kernel`: eight rigs abreast, blocks of rigs on separate cores); a rig that needs a
halved step gets it alone, the others keep the full step. The servo is the scalar twin's
(:mod:`flexdigit.twin.actuator`: second order, exact transition, commands latched on the 20 ms serial frame and the
52 Hz PWM pulse, hard stops). Same inputs, same numbers as N scalar twins (tested to 1e-9 rad), and the same bits
for a rig whatever its batch or the number of threads.

The batched twin also gains the thesis's **second, antagonistic cable** (2.1: "future designs should incorporate
two cable system to ensure rigidity of the member and ultimately its stability"; 2.5 mentions one fitted for
stiffness): a cable on the far side (eccentricity ``-e``), wound on the same pulley the other way, both cables
pretensioned by ``pretension_n``. The tip link then carries ``e (T1 - T2)`` with ``T1 = k_c max(0, p + s - e psi)``
and ``T2 = k_c max(0, p - s + e psi)`` (``s`` the shortening of the main cable, E 3.11, ``p = pretension / k_c``):
near the equilibrium both are taut and the tip gains ``2 k_c e^2`` of stiffness instead of ``k_c e^2``, and
commands below the equilibrium bend the digit the other way instead of slackening the cable.

Reads are at the integration grid's points (the scalar twin interpolates between them) and noise-free: studies
want the mechanics; the sensor chain's noise models are in :mod:`flexdigit.twin.sensors` and the tactile bounds.

Examples
--------
>>> from flexdigit.params import RigParams
>>> from flexdigit.twin.calibration import default_calibration
>>> cal = default_calibration()
>>> twins = BatchedTwin([RigParams()] * 2, [cal, cal.replace(cable_stiffness_n_m=2e4)])
>>> twins.command([30, 30]); twins.advance(2.0)
>>> bool(twins.tip_rotation_deg()[0] > twins.tip_rotation_deg()[1] > 30)    # the stiffer cable turns it further
True
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import scipy.linalg

from flexdigit._validation import check_array, check_choice, check_int, check_real
from flexdigit.errors import ParameterError
from flexdigit.models.servo import command_to_angle_rad
from flexdigit.params import RigParams, twin_cells
from flexdigit.twin.calibration import Calibration
from flexdigit.twin.digit import (
    ORIENTATIONS,
    Chain,
    DynamicState,
    chain_matrices,
    digit_arrays,
    section_cells,
)
from flexdigit.twin.digit_calibration import twin_calibration
from flexdigit.twin.twin import DEFAULT_CELLS_PER_SECTION, DEFAULT_DT_S, cached_digit

__all__ = ["BatchedChains", "BatchedTwin", "batch_cells"]


class BatchedChains:
    """The matrices of N chains with the same number of springs, stacked on a leading axis.

    Parameters
    ----------
    chains : sequence of Chain
    pretension_n : array_like, shape (N,), optional
        With a second, antagonistic cable: both cables' pretension (N); None: each chain's own cables (its
        description's ``[cables]``: the pair and its pretension, or the thesis's single cable).
    antagonist : array_like of bool, shape (N,), optional
        Which chains have the second cable (default: all of them when ``pretension_n`` is given).
    """

    def __init__(self, chains: Sequence[Chain], pretension_n=None, antagonist=None) -> None:
        if not chains:
            raise ParameterError("BatchedChains needs at least one chain")
        n, g = chains[0].n, chains[0].gauge_s_m.size
        for i, ch in enumerate(chains):
            if ch.n != n or ch.gauge_s_m.size != g:
                raise ParameterError(
                    f"BatchedChains: chain {i} has {ch.n} springs and {ch.gauge_s_m.size} gauges; chain 0 has {n} "
                    f"and {g} (same section count, cells per section and gauge count across the batch)"
                )
        self.chains = list(chains)
        if pretension_n is None:  # the chains' own cables (a pair described in [cables] keeps its pretension)
            pretension_n, antagonist = _described_cables(
                [ch.cable_pretension_m * ch.cable_stiffness for ch in chains], [ch.antagonist for ch in chains]
            )
        g_grav = np.stack([ch.g_gravity for ch in chains])
        self._setup(
            np.stack([ch.k_psi for ch in chains]),
            np.stack([ch.c_psi for ch in chains]),
            np.stack([ch.a_mass for ch in chains]),
            g_grav,
            np.array([ch.eccentricity for ch in chains]),
            np.array([ch.cable_stiffness for ch in chains]),
            np.stack([ch._psi_to_gauge_curvature for ch in chains]),
            np.stack([ch.link_length_m for ch in chains]),
            np.array([ch.joint_s_m[0] for ch in chains]),
            np.stack([ch.stiffness for ch in chains]),
            pretension_n,
            antagonist,
        )

    @classmethod
    def from_rigs(
        cls,
        params,
        calibrations,
        *,
        housing: bool = True,
        orientation: str = "vertical",
        cells_per_section: int = DEFAULT_CELLS_PER_SECTION,
        pretension_n=None,
        antagonist=None,
    ) -> BatchedChains:
        """``BatchedChains([build_digit(p, c, ...) for p, c in zip(params, calibrations)], ...)`` without a
        :class:`~flexdigit.twin.digit.Chain` per rig: rigs whose springs, masses and gauges sit at the same places
        (a study of stiffnesses, masses, damping, cables) share one chain's geometry, and their matrices are
        assembled stacked (:func:`~flexdigit.twin.digit.chain_matrices`); the same numbers (tested), a tenth of the
        time for thousands of rigs."""
        params, calibrations = list(params), list(calibrations)
        if not params or len(params) != len(calibrations):
            raise ParameterError(
                f"BatchedChains.from_rigs needs one calibration per rig (at least one). Got {len(params)} rigs and "
                f"{len(calibrations)} calibrations instead."
            )
        cells = batch_cells(params, cells_per_section, "BatchedChains.from_rigs")
        rows = [
            digit_arrays(p, c, housing=housing, orientation=orientation, cells_per_section=cells)
            for p, c in zip(params, calibrations, strict=True)
        ]
        if pretension_n is None:  # the rigs' own cables, as build_digit gives each chain
            pretension_n, antagonist = _described_cables(
                [r["cable_pretension_n"] for r in rows], [r["antagonist"] for r in rows]
            )
        first = Chain(**rows[0])
        k, c, a, g_grav, to_curvature, link, s0 = _stacked_chain_matrices(rows, first)
        out = cls.__new__(cls)
        out.chains = None
        out._setup(
            k,
            c,
            a,
            g_grav,
            check_array([r["cable_eccentricity_m"] for r in rows], "cable_eccentricity_m", "Chain", low=0),
            check_array([r["cable_stiffness_n_m"] for r in rows], "cable_stiffness_n_m", "Chain", low=0),
            to_curvature,
            link,
            s0,
            np.array([r["joint_stiffness_nm_rad"] for r in rows]),
            pretension_n,
            antagonist,
        )
        return out

    def _setup(self, k, c, a, g_grav, e, kc, to_curvature, link, s0, stiffness, pretension_n, antagonist) -> None:
        self.size, self.n = k.shape[0], k.shape[1]
        self.k, self.c, self.a = k, c, a
        self.ga, self.gb = g_grav[..., 0].copy(), g_grav[..., 1].copy()
        self.e, self.kc = e, kc
        self.to_curvature, self.link, self.s0, self.stiffness = to_curvature, link, s0, stiffness
        # springs and dampers join neighbouring links: K and C are banded (the dynamics kernel skips the zeros)
        rows, cols = np.nonzero(np.any(self.k != 0, axis=0) | np.any(self.c != 0, axis=0))
        self.bandwidth = int(np.max(np.abs(rows - cols))) if rows.size else 0
        if pretension_n is None:
            self.antagonist = np.zeros(self.size, dtype=bool)
            self.pre = np.zeros(self.size)
        else:
            pre = check_array(pretension_n, "pretension_n", "BatchedChains", shape=(self.size,), low=0)
            self.antagonist = np.ones(self.size, dtype=bool) if antagonist is None else np.asarray(antagonist, bool)
            if self.antagonist.shape != (self.size,):
                raise ParameterError(
                    f"The 'antagonist' parameter of BatchedChains must be {self.size} booleans, one per chain. "
                    f"Got shape {self.antagonist.shape} instead."
                )
            with np.errstate(divide="ignore", invalid="ignore"):
                self.pre = np.where(self.antagonist & (self.kc > 0), pre / np.where(self.kc > 0, self.kc, 1.0), 0.0)

    # ---------------------------------------------------------------------------------------------- cable
    def tensions(self, psi_tip, shortening):
        """``(T1, T2, taut1, taut2)``: main and antagonistic cable tension (N) and whether each is taut."""
        s1 = shortening + self.pre - self.e * psi_tip
        t1 = self.kc * np.maximum(s1, 0.0)
        s2 = np.where(self.antagonist, self.pre - shortening + self.e * psi_tip, -np.inf)
        t2 = self.kc * np.maximum(s2, 0.0)
        return t1, t2, s1 > 0, s2 > 0

    def tip_rad(self, psi) -> np.ndarray:
        """Absolute tip-link angle (rad)."""
        return psi[:, -1]

    def tip_m(self, psi) -> np.ndarray:
        """Tip positions (N, 2) in the (a, b) axes."""
        a = self.s0 + np.sum(self.link * np.cos(psi), axis=1)
        b = np.sum(self.link * np.sin(psi), axis=1)
        return np.column_stack([a, b])

    def curvature(self, psi) -> np.ndarray:
        """Strip curvature at the gauges (N, G), 1/m."""
        return np.einsum("bgn,bn->bg", self.to_curvature, psi)

    # ---------------------------------------------------------------------------------------------- statics
    def solve_static(self, shortening_m, *, tip_moment_nm=None, psi0=None, tol=1e-11, max_iter=80, max_step_rad=0.35):
        """Equilibrium of every chain under self-weight, the cable(s) and an optional tip moment; (N, n) angles.

        ``shortening_m`` (N,): the main cable's shortening, ``-inf`` for a detached cable (the antagonist then
        carries nothing either). The scalar :meth:`Chain.solve_static`'s damped Newton, batched over chains.
        """
        short = np.broadcast_to(np.asarray(shortening_m, dtype=float), (self.size,))
        moment = np.zeros(self.size) if tip_moment_nm is None else np.broadcast_to(tip_moment_nm, (self.size,))
        attached = np.isfinite(short)
        sh = np.where(attached, short, 0.0)
        psi = np.zeros((self.size, self.n)) if psi0 is None else np.array(psi0, dtype=float)
        idx = np.arange(self.n)
        scale = float(np.max(self.stiffness))
        for _ in range(max_iter):
            s, c = np.sin(psi), np.cos(psi)
            res = np.einsum("bij,bj->bi", self.k, psi) + s * self.ga - c * self.gb
            res[:, -1] -= moment
            jac = self.k.copy()
            jac[:, idx, idx] += c * self.ga + s * self.gb
            t1, t2, taut1, taut2 = self.tensions(psi[:, -1], sh)
            res[:, -1] -= np.where(attached, self.e * (t1 - t2), 0.0)
            jac[:, -1, -1] += np.where(attached, self.kc * self.e**2 * (taut1.astype(float) + taut2), 0.0)
            step = np.linalg.solve(jac, res[..., None])[..., 0]
            biggest = np.max(np.abs(step), axis=1, keepdims=True)
            step *= np.minimum(1.0, max_step_rad / np.maximum(biggest, 1e-300))
            psi -= step
            if np.max(np.abs(res)) < tol * scale and np.max(biggest) < 1e-9:
                break
        if not np.all(np.isfinite(psi)):
            raise ArithmeticError("batched static solve diverged (non-finite angles)")
        return psi

    def linear_modes(self, psi_eq=None, shortening_m=None):
        """First-mode natural frequency (rad/s) and damping ratio of every chain, linearised about ``psi_eq``.

        The cables count as taut where their stretch at ``psi_eq`` and ``shortening_m`` is positive (None: cable
        removed, the release test of 3.1.2).
        """
        psi = np.zeros((self.size, self.n)) if psi_eq is None else np.asarray(psi_eq, dtype=float)
        n = self.n
        idx = np.arange(n)
        m = self.a * np.cos(psi[:, :, None] - psi[:, None, :])
        k = self.k.copy()
        k[:, idx, idx] += np.cos(psi) * self.ga + np.sin(psi) * self.gb
        if shortening_m is not None:
            _, _, taut1, taut2 = self.tensions(psi[:, -1], np.asarray(shortening_m, dtype=float))
            k[:, -1, -1] += self.kc * self.e**2 * (taut1.astype(float) + taut2)
        minv_k = np.linalg.solve(m, k)
        minv_c = np.linalg.solve(m, self.c)
        top = np.concatenate([np.zeros_like(m), np.broadcast_to(np.eye(n), m.shape)], axis=2)
        bottom = np.concatenate([-minv_k, -minv_c], axis=2)
        lam = np.linalg.eigvals(np.concatenate([top, bottom], axis=1))
        lam = np.where(lam.imag > 0, lam, np.nan)  # one of each conjugate pair (the digit's modes are underdamped)
        wn = np.abs(lam)
        first = np.nanargmin(wn, axis=1)
        rows = np.arange(self.size)
        return wn[rows, first], -lam.real[rows, first] / wn[rows, first]

    def linearised(self, psi_eq, shortening_m):
        """``(M, C, K, b)`` of every chain about ``psi_eq`` (N, n): mass, damping and tangent stiffness matrices
        (N, n, n) and the generalised force per metre of cable shortening (N, n), ``k_c e`` on the tip link per
        taut cable (E 3.11)."""
        psi = np.asarray(psi_eq, dtype=float)
        idx = np.arange(self.n)
        m = self.a * np.cos(psi[:, :, None] - psi[:, None, :])
        k = self.k.copy()
        k[:, idx, idx] += np.cos(psi) * self.ga + np.sin(psi) * self.gb
        _, _, taut1, taut2 = self.tensions(psi[:, -1], np.asarray(shortening_m, dtype=float))
        taut = taut1.astype(float) + taut2
        k[:, -1, -1] += self.kc * self.e**2 * taut
        b = np.zeros_like(psi)
        b[:, -1] = self.kc * self.e * taut
        return m, self.c.copy(), k, b


def _described_cables(pretension_n, antagonist):
    """``(pretension_n, antagonist)`` for :meth:`BatchedChains._setup` from each rig's own cables (its
    description's ``[cables]``, as :func:`~flexdigit.twin.digit.digit_arrays` reads it): ``(None, None)`` when no
    rig has the antagonistic pair (the single cable of the thesis)."""
    antagonist = [bool(a) for a in antagonist]
    if not any(antagonist):
        return None, None
    return [float(p) if a else 0.0 for p, a in zip(pretension_n, antagonist, strict=True)], antagonist


class BatchedTwin:
    """N rigs on one clock: integer commands in (one per rig), tip rotations and gauge curvatures out.

    Parameters
    ----------
    params : RigParams or sequence of RigParams
        One per rig (or one for all); the serial period and PWM frequency must agree (one clock).
    calibrations : Calibration or sequence of Calibration, optional
        One per rig, or one for all; left out, each rig's own default
        (:func:`~flexdigit.twin.digit_calibration.twin_calibration`), as :class:`~flexdigit.twin.twin.Twin` takes it.
    orientation : {"vertical", "hanging", "horizontal"}
    housing, cable : bool
    dt_s : float
        Integration step (s), rounded to a divisor of the serial period.
    cells_per_section : int, sequence of int or None
        Springs per section; None: :func:`batch_cells`, the finest of the rigs' default resolutions.
    pretension_n : array_like, shape (N,), optional
        A second, antagonistic cable with this pretension on both cables (N); None: each rig's own ``cables``
        (an antagonistic pair with its ``pretension_n``, as the scalar twin runs it, or the single cable).
    antagonist : array_like of bool, shape (N,), optional
        Which rigs have the second cable when ``pretension_n`` is given (default: all of them).
    command : int or array_like, optional
        Initial commands (default the equilibrium command); every rig starts at rest in equilibrium there.
    """

    MAX_ROTATION_PER_STEP_RAD = DynamicState.MAX_ROTATION_PER_STEP_RAD

    def __init__(
        self,
        params,
        calibrations=None,
        *,
        orientation: str = "vertical",
        housing: bool = True,
        cable: bool = True,
        dt_s: float = DEFAULT_DT_S,
        cells_per_section: int = DEFAULT_CELLS_PER_SECTION,
        pretension_n=None,
        antagonist=None,
        command=None,
    ) -> None:
        params_list = [params] if isinstance(params, RigParams) else list(params)
        if calibrations is None:  # each rig's own default (twin_calibration), as Twin(params) takes it
            cal_list = [twin_calibration(p) for p in params_list]
        elif isinstance(calibrations, Calibration):
            cal_list = [calibrations] * len(params_list)
        else:
            cal_list = list(calibrations)
        if len(params_list) == 1 and len(cal_list) > 1:
            params_list = params_list * len(cal_list)
        if len(params_list) != len(cal_list) or not params_list:
            raise ParameterError(
                f"BatchedTwin: {len(params_list)} parameter sets and {len(cal_list)} calibrations; give one of each "
                "per rig (or one for all)"
            )
        check_choice(orientation, "orientation", tuple(ORIENTATIONS), "BatchedTwin")
        cells = batch_cells(params_list, cells_per_section, "BatchedTwin")
        self.params, self.calibrations = params_list, cal_list
        self.size = len(params_list)
        self.cable = bool(cable)
        clocks = {(p.actuator.serial_period_s, p.actuator.pwm_frequency_hz) for p in params_list}
        if len(clocks) != 1:
            raise ParameterError(
                "BatchedTwin: the rigs must share one serial period and PWM frequency (one clock). "
                f"Got {sorted(clocks)}."
            )
        (period, self._pwm_hz) = clocks.pop()
        self._period = period
        dt = check_real(dt_s, "dt_s", "BatchedTwin", low=1e-5, high=period)
        self.dt_s = period / max(1, round(period / dt))
        # each rig at its description's resolution (twin_cells), never the finer twin of a derived calibration
        # (twin.resolution): a study scores every design at one resolution, as BatchedChains.from_rigs stacks them
        chains = [
            cached_digit(p, c, bool(housing), orientation, twin_cells(p) if cells is None else cells)
            for p, c in zip(params_list, cal_list, strict=True)
        ]
        if not self.cable:  # detached: no cable pulls, neither the pair's second one
            pretension_n, antagonist = np.zeros(self.size), np.zeros(self.size, dtype=bool)
        self.chains = BatchedChains(chains, pretension_n, antagonist)
        act = [p.actuator for p in params_list]
        self._cmd_lo = np.array([a.command_min for a in act])
        self._cmd_hi = np.array([a.command_max for a in act])
        self._rad_per_command = np.array([a.rad_per_command for a in act])
        self._angle0 = np.array([math.radians(a.angle_min_deg) for a in act])
        self._angle_min = self._angle0.copy()
        self._angle_max = np.array([math.radians(a.angle_max_deg) for a in act])
        self._wn = np.array([a.servo_wn_rad_s for a in act])
        self._zeta = np.array([a.servo_zeta for a in act])
        self._pulley = np.array([a.cable_m_per_servo_rad for a in act])
        self._angle_taut = np.array(
            [float(command_to_angle_rad(a.equilibrium_command, p)) for a, p in zip(act, params_list, strict=True)]
        )
        start = np.array([a.equilibrium_command for a in act]) if command is None else command
        self.commands = self._check_commands(start)
        self.angle = self._target(self.commands)
        self.rate = np.zeros(self.size)
        self._pending: list[tuple[float, np.ndarray]] = []
        self._transitions: dict[float, np.ndarray] = {}
        self._psi = np.ascontiguousarray(self.chains.solve_static(self._shortening(self.angle)))
        self._omega = np.zeros_like(self._psi)
        self.time_s = 0.0
        #: ROS2 steps each rig has taken (halved steps included): a rig in a violent transient takes more
        self.substeps = np.zeros(self.size, dtype=np.int64)
        #: None: one thread per core (up to 8) for batches of 2 x THREAD_MIN_RIGS rigs or more; 1: no threads
        self.threads = None

    # ---------------------------------------------------------------------------------------------- servo
    def _check_commands(self, values) -> np.ndarray:
        v = np.broadcast_to(np.asarray(values), (self.size,))
        if not np.all(np.isfinite(v.astype(float))) or np.any(v != np.round(v)):
            raise ParameterError(f"The 'command' parameter of BatchedTwin must be integers. Got {v!r} instead.")
        v = v.astype(int)
        bad = np.flatnonzero((v < self._cmd_lo) | (v > self._cmd_hi))
        if bad.size:
            i = int(bad[0])
            raise ParameterError(
                f"The 'command' parameter of BatchedTwin must be an integer in [{self._cmd_lo[i]}, {self._cmd_hi[i]}]. "
                f"Got {int(v[i])} for rig {i} instead."
            )
        return v.copy()

    def _target(self, commands) -> np.ndarray:
        return self._angle0 + (commands - self._cmd_lo) * self._rad_per_command

    def _shortening(self, angle) -> np.ndarray:
        if not self.cable:
            return np.full(self.size, -np.inf)
        return self._pulley * (angle - self._angle_taut)

    def _transition(self, h: float) -> np.ndarray:
        """The servo's exact transition over ``h`` for every rig (N, 3, 3), one matrix exponential per distinct
        servo (studies mostly vary other things)."""
        phi = self._transitions.get(h)
        if phi is None:
            servos, which = np.unique(np.column_stack([self._wn, self._zeta]), axis=0, return_inverse=True)
            wn, zeta = servos[:, 0], servos[:, 1]
            a = np.zeros((len(servos), 3, 3))
            a[:, 0, 1] = 1.0
            a[:, 1, 0] = -(wn**2)
            a[:, 1, 1] = -2.0 * zeta * wn
            a[:, 1, 2] = wn**2
            phi = self._transitions[h] = scipy.linalg.expm(a * h)[which.reshape(-1)]
        return phi

    def command(self, values) -> None:
        """Send one command per rig (integers); they take effect on the next serial frame and PWM pulse, as on the
        scalar twin (:meth:`flexdigit.twin.actuator.Servo.schedule`)."""
        v = self._check_commands(values)
        frame = math.ceil(self.time_s / self._period - 1e-9) * self._period
        pwm = 1.0 / self._pwm_hz
        pulse = math.ceil(frame / pwm - 1e-9) * pwm
        apply = math.ceil(pulse / self.dt_s - 1e-9) * self.dt_s
        self._pending.append((apply, v))
        self._pending.sort(key=lambda item: item[0])

    # ---------------------------------------------------------------------------------------------- stepping
    def advance(self, duration_s: float) -> None:
        """Let ``duration_s`` of rig time pass (a whole number of integration steps, rounded up).

        The servo (independent of the digit) runs first over the whole interval, in numpy; then every rig's digit
        follows its cable through the compiled kernel (:mod:`flexdigit.twin._batched_kernel`), blocks of rigs on
        separate cores.
        """
        duration = check_real(duration_s, "duration_s", "BatchedTwin.advance", low=0)
        target = self.time_s + duration
        h = self.dt_s
        shortening = [self._shortening(self.angle)]
        times = []
        while (times[-1] if times else self.time_s) < target - 1e-12:
            now = times[-1] if times else self.time_s
            while self._pending and self._pending[0][0] <= now + 1e-12:
                self.commands = self._pending.pop(0)[1]
            self._servo_step(h)
            shortening.append(self._shortening(self.angle))
            times.append((round(now / h) + 1) * h)
        if not times:
            return
        self._step_digits(np.array(shortening), h)
        self.time_s = times[-1]

    #: Below this many rigs a batch steps in one thread (the threads' overhead outweighs a second core).
    THREAD_MIN_RIGS = 64

    def _blocks(self) -> list[tuple[int, int]]:
        """Contiguous blocks of rigs ``(lo, hi)``, one per core when the batch is large enough. A rig's arithmetic
        is its own (the kernel steps one rig at a time): any blocks, any threads, the same bits."""
        import os

        cores = min(os.cpu_count() or 1, 8)
        if self.threads is not None:
            cores = self.threads
        from flexdigit.twin._batched_kernel import LANES

        count = max(1, min(cores, self.size // self.THREAD_MIN_RIGS))
        groups = -(-self.size // LANES)  # blocks of whole groups of LANES rigs
        edges = np.minimum(LANES * np.linspace(0, groups, count + 1).round().astype(int), self.size)
        return [(int(lo), int(hi)) for lo, hi in zip(edges[:-1], edges[1:], strict=True) if hi > lo]

    def _step_digits(self, shortening: np.ndarray, h: float) -> None:
        from flexdigit.twin._batched_kernel import advance_rigs

        ch = self.chains
        args = (self._psi, self._omega, np.ascontiguousarray(shortening), h, ch.a, ch.k, ch.c, ch.bandwidth)
        args += (ch.ga, ch.gb, ch.e)
        args += (ch.kc, ch.pre, ch.antagonist, self.MAX_ROTATION_PER_STEP_RAD)
        blocks = self._blocks()
        if len(blocks) == 1:
            failed = [advance_rigs(*args, 0, self.size, self.substeps)]
        else:  # the kernel releases the GIL: the blocks step on separate cores
            from concurrent.futures import ThreadPoolExecutor

            with ThreadPoolExecutor(len(blocks)) as pool:
                failed = list(pool.map(lambda b: advance_rigs(*args, b[0], b[1], self.substeps), blocks))
        bad = [f for f in failed if f >= 0]
        if bad:
            raise ArithmeticError(
                f"the batched digit dynamics diverged for rig {bad[0]} (a singular mass or iteration matrix, or "
                "non-finite angles): its parameters are not a physical digit"
            )

    def _servo_step(self, h: float) -> None:
        phi = self._transition(h)
        target = self._target(self.commands)
        angle = phi[:, 0, 0] * self.angle + phi[:, 0, 1] * self.rate + phi[:, 0, 2] * target
        rate = phi[:, 1, 0] * self.angle + phi[:, 1, 1] * self.rate + phi[:, 1, 2] * target
        stop = (angle > self._angle_max) | (angle < self._angle_min)
        self.angle = np.clip(angle, self._angle_min, self._angle_max)
        self.rate = np.where(stop, 0.0, rate)

    @property
    def psi(self) -> np.ndarray:
        """Link angles of every rig (N, n), rad."""
        return self._psi

    @property
    def omega(self) -> np.ndarray:
        """Link rates of every rig (N, n), rad/s."""
        return self._omega

    # ---------------------------------------------------------------------------------------------- reading
    def tip_rotation_deg(self) -> np.ndarray:
        """Tip rotation of every rig (deg, towards the cable side)."""
        return np.degrees(self.psi[:, -1])

    def gauge_curvature_1_m(self) -> np.ndarray:
        """Strip curvature at every rig's gauges (N, G), 1/m."""
        return self.chains.curvature(self.psi)

    def tensions_n(self) -> tuple[np.ndarray, np.ndarray]:
        """Main and antagonistic cable tensions now (N each; 0 when slack, absent or detached)."""
        short = self._shortening(self.angle)
        if not self.cable:
            return np.zeros(self.size), np.zeros(self.size)
        t1, t2, _, _ = self.chains.tensions(self.psi[:, -1], short)
        return t1, t2

    def __repr__(self) -> str:
        return (
            f"BatchedTwin(size={self.size}, dt_s={self.dt_s:g}, time_s={self.time_s:g}, cable={self.cable}, "
            f"antagonist={bool(self.chains.antagonist.any())})"
        )


def _shared_layouts(rows: list[dict]) -> list[list[int]]:
    """Indices of the rigs whose springs, masses and gauges sit at the same places, one list per layout."""
    layouts: dict[tuple, list[int]] = {}
    for i, r in enumerate(rows):
        key = tuple(
            np.asarray(r[name], dtype=float).tobytes()
            for name in ("length_m", "joint_s_m", "cell_length_m", "mass_s_m", "gauge_s_m", "gravity_ab_m_s2")
        )
        layouts.setdefault(key, []).append(i)
    return list(layouts.values())


def batch_cells(params, cells_per_section=None, owner: str = "BatchedTwin"):
    """The cells per section of a batch: an explicit count as given; None: section by section the most any rig's
    resolution asks for (:func:`~flexdigit.params.twin_cells`: its ``[twin]`` table, else
    :func:`~flexdigit.twin.digit.default_cells`; a batch stacks chains of one size; a rig of the batch is
    then cut at least as finely as its own default, e.g. the design study's scaled digits). Rigs of different
    section counts keep their own defaults (and the stacking refuses them, naming both sizes)."""
    params = list(params)
    if cells_per_section is not None:
        if np.ndim(cells_per_section) == 0:  # one count for every section of every rig
            return check_int(cells_per_section, "cells_per_section", owner, low=1, high=1000)
        return section_cells(params[0].geometry, cells_per_section, owner) if params else cells_per_section
    counts = {twin_cells(p) for p in params}
    if len(counts) <= 1 or len({len(c) for c in counts}) > 1:
        return None
    return tuple(int(n) for n in np.max(np.array(sorted(counts)), axis=0))


def _stacked_chain_matrices(rows: list[dict], first: Chain):
    """Stiffness, damping, inertia, gravity, gauge-curvature, link-length and base-joint arrays of every rig,
    stacked (rig first), assembled once per shared layout with ``first`` (rig 0's chain) as the size reference."""
    size, n = len(rows), first.n
    k, c, a = (np.empty((size, n, n)) for _ in range(3))
    g_grav = np.empty((size, n, 2))
    to_curvature = np.empty((size,) + first._psi_to_gauge_curvature.shape)
    link, s0 = np.empty((size, n)), np.empty(size)
    for members in _shared_layouts(rows):
        template = first if members[0] == 0 else Chain(**rows[members[0]])
        if template.n != n or template.gauge_s_m.size != first.gauge_s_m.size:
            raise ParameterError(
                f"BatchedChains: rig {members[0]} has {template.n} springs and {template.gauge_s_m.size} gauges; "
                f"rig 0 has {n} and {first.gauge_s_m.size} (same section count, cells per section and gauge "
                "count across the batch)"
            )
        stack = {
            name: check_array([rows[i][name] for i in members], name, "Chain", shape=(len(members), size_of), low=0)
            for name, size_of in (
                ("joint_stiffness_nm_rad", n),
                ("joint_damping_nms_rad", n),
                ("mass_kg", template.mass_s_m.size),
                ("mass_inertia_kg_m2", template.mass_s_m.size),
            )
        }
        k[members], c[members], a[members], g_grav[members] = chain_matrices(
            template._d,
            template._mass_lever,
            template._mass_link,
            stack["joint_stiffness_nm_rad"],
            stack["joint_damping_nms_rad"],
            stack["mass_kg"],
            stack["mass_inertia_kg_m2"],
            template.gravity,
        )
        to_curvature[members] = template._psi_to_gauge_curvature
        link[members] = template.link_length_m
        s0[members] = template.joint_s_m[0]
    return k, c, a, g_grav, to_curvature, link, s0
