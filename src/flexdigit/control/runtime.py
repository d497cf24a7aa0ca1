"""The runtime controller: a state-space difference equation stepped once per sample (thesis 5.1.2, 5.2).

Every sample::

    v       = C x + D w                       w = e (error input) or [r, y] (two-degree-of-freedom)
    u_raw   = u_eq + v                        u_eq = equilibrium command (8: no deflection)
    u       = round(clip(u_raw, 0, 254))      the integer the servo board accepts
    x+      = A x + B w + L (clip(u_raw) - u_raw) + Lq (u - clip(u_raw))   anti-windup (back-calculation)

``L (clip(u_raw) - u_raw)`` feeds the difference between what was applied and what was asked back into the state. For an
observer-based controller with ``L`` = the observer's input matrix, the observer sees exactly the command the
servo got (saturated *and* quantised), so nothing winds up; for a PI it is classic back-calculation. ``"clamp"``
instead freezes the state in any sample where the output saturates and the update would drive it further in.

Bumpless start: :meth:`reset` puts the state where the output equals the command already in force (the
equilibrium command 8 by default, i.e. ``x = 0``), so the first sample sends no jump.

The update is written for speed (goal <= 5 us a step; ``benchmarks/bench_rig.py``): one matrix-vector product on
the stacked matrix ``[[A, B], [C, D]]`` into preallocated buffers.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import control as ct
import numpy as np

from flexdigit._validation import check_choice, check_real
from flexdigit.errors import DesignError, ParameterError
from flexdigit.params import RigParams

__all__ = ["RuntimeController"]


class RuntimeController:
    """A discrete controller run on the rig: saturation, integer quantisation, anti-windup, bumpless start.

    Parameters
    ----------
    sys : control.StateSpace or control.TransferFunction
        Discrete-time controller (``dt`` = the sample period) from its input(s) to the command *deviation* from
        ``u_eq``. One input (the error ``e = r - y``) or two (``[r, y]``).
    params : RigParams, optional
        Command range and equilibrium command (``actuator``).
    antiwindup : {"none", "back_calculation", "clamp"}
    aw_gain : array_like, shape (n,), optional
        ``L`` for ``"back_calculation"``.
    quantise : bool
        Round the command to an integer (True on any real board).
    aw_quantisation : bool or array_like, shape (n,)
        Gain on the rounding error ``u - clip(u_raw)`` (True: the same as ``aw_gain``). Right for an observer whose
        model must see the exact integer command; wrong for a PI, whose integrator would then track the rounded
        command and stall within half a quantum of the setpoint (a dead zone), so False by default.
    deadband : (int, float), optional
        ``(state index, width)``: that state (an integrator of ``r - y``) is not updated while ``|r - y| <= width``.
        With an integer command the output can only take values a quantum apart; an integrator asked for the
        value in between limit-cycles between the two neighbours. A deadband of half a quantum (in output units)
        stops it, at the cost of a steady-state error of at most half a quantum.
    hysteresis : float
        Quantiser hysteresis, commands (0..0.5): the command in force is kept until the unrounded command is more
        than ``0.5 + hysteresis`` away from it. Stops measurement noise toggling the command between two
        neighbours at rest (each toggle moves the beam a whole quantum, 1.7 deg).
    dither : bool
        Error-feedback quantisation (first-order noise shaping, a sigma-delta modulator): the rounding error of
        each sample is added to the next sample's command before it is rounded, so the integer commands average
        the unrounded one and the servo (a 3 Hz low-pass, 3.2.4) and the digit smooth the toggling at up to 25 Hz
        into a small ripple. The loop then holds a setpoint between two quanta (a whole command turns a digit
        1.7 deg, 6 % of a 30 deg step) instead of ending up to half a quantum off. Off by default (the thesis
        rig's chapter-5 runs round); ignored with ``hysteresis``.
    measure : callable, optional
        ``measure(reading) -> y`` used by :meth:`step` (the loop protocol) to turn a rig reading into the
        controlled variable.
    name : str

    Examples
    --------
    >>> import control as ct
    >>> c = RuntimeController(ct.tf([2.0], [1.0], 0.02))     # a pure gain of 2 commands per unit error
    >>> c.reset(); [c.update(r, 0.0) for r in (0.0, 1.0, 1.3, 500.0)]
    [8, 10, 11, 254]
    """

    def __init__(
        self,
        sys,
        params: RigParams | None = None,
        *,
        antiwindup: str = "none",
        aw_gain=None,
        quantise: bool = True,
        aw_quantisation=False,
        deadband: tuple[int, float] | None = None,
        hysteresis: float = 0.0,
        measure: Callable | None = None,
        name: str = "",
        dither: bool = False,
    ) -> None:
        if not isinstance(sys, ct.InputOutputSystem) or not ct.isdtime(sys, strict=True):
            raise DesignError(f"RuntimeController needs a discrete-time LTI system. Got {sys!r}.")
        ss = ct.ss(sys)
        if ss.noutputs != 1 or ss.ninputs not in (1, 2):
            raise DesignError(
                f"RuntimeController needs 1 output and 1 (error) or 2 ([r, y]) inputs. "
                f"Got {ss.ninputs} inputs, {ss.noutputs} outputs."
            )
        self.sys = ss
        self.period_s = float(ss.dt)
        self.params = params or RigParams()
        act = self.params.actuator
        self.u_min, self.u_max = float(act.command_min), float(min(act.command_max, 254))
        self.u_eq = float(act.equilibrium_command)
        self.antiwindup = check_choice(
            antiwindup, "antiwindup", ("none", "back_calculation", "clamp"), "RuntimeController"
        )
        n = ss.nstates
        self.nstates, self.ninputs = n, ss.ninputs
        if antiwindup == "back_calculation":
            if aw_gain is None:
                raise ParameterError("The 'aw_gain' parameter of RuntimeController is required for back_calculation.")
            L = np.asarray(aw_gain, dtype=float).reshape(-1)
            if L.shape != (n,) or not np.all(np.isfinite(L)):
                raise ParameterError(
                    f"The 'aw_gain' parameter of RuntimeController must be {n} finite numbers. Got {aw_gain!r}."
                )
        else:
            L = np.zeros(n)
        self.aw_gain = L
        self.quantise = bool(quantise)
        self.hysteresis = check_real(hysteresis, "hysteresis", "RuntimeController", low=0.0, high=0.5)
        self.dither = bool(dither) and not self.hysteresis  # (the rounding error carried: reset())
        if isinstance(aw_quantisation, bool | np.bool_):
            self._q_gain = L.copy() if aw_quantisation else np.zeros(n)
        else:
            self._q_gain = np.asarray(aw_quantisation, dtype=float).reshape(-1)
            if self._q_gain.shape != (n,):
                raise ParameterError(
                    f"The 'aw_quantisation' parameter of RuntimeController must be a bool or {n} gains."
                )
        self.aw_quantisation = aw_quantisation
        self._same_gains = bool(np.array_equal(self._q_gain, L))
        self._set_deadband(deadband, ss)
        self.measure = measure
        self.name = name or "controller"
        self._M = np.ascontiguousarray(np.block([[ss.A, ss.B], [ss.C, ss.D]]), dtype=float)
        self._v = np.zeros(n + ss.ninputs)  # [x; w]
        self._z = np.zeros(n + 1)  # [x+; v]
        self._vx, self._zx = self._v[:n], self._z[:n]  # views made once: the update writes through them
        self._tmp = np.zeros(n)
        self._c_row = np.asarray(ss.C, dtype=float).reshape(-1)
        self.saturated = False
        self.reset()

    def _set_deadband(self, deadband, ss) -> None:
        """The ``deadband`` option: which state stops integrating, how wide, and its input row."""
        self._db_index = None
        if deadband is None:
            return
        n = ss.nstates
        index, width = deadband
        index = int(index)
        if not 0 <= index < n:
            raise ParameterError(f"The 'deadband' state index of RuntimeController must be in 0..{n - 1}. Got {index}.")
        self._db_index, self._db_width = index, check_real(width, "deadband width", "RuntimeController", low=0.0)
        b = ss.B[index]
        if ss.ninputs == 1:
            self._db_b_dot = lambda r, y, b0=float(b[0]): b0 * (r - y)
        else:
            self._db_b_dot = lambda r, y, b0=float(b[0]), b1=float(b[1]): b0 * r + b1 * y

    # -- state -------------------------------------------------------------------------------------------------
    @property
    def state(self) -> np.ndarray:
        return self._v[: self.nstates].copy()

    def reset(self, command: float | None = None) -> None:
        """Bumpless start: set the state so the output equals ``command`` (default the equilibrium command).

        With zero input, ``v = C x``; the minimum-norm ``x = C^+ (command - u_eq)`` gives that output (``x = 0``
        for the equilibrium command).
        """
        c = self.u_eq if command is None else check_real(command, "command", "RuntimeController.reset")
        n = self.nstates
        self._v[:] = 0.0
        if n and c != self.u_eq:
            C = self.sys.C.reshape(1, -1)
            if np.allclose(C, 0):
                raise DesignError("bumpless start impossible: the controller output does not depend on its state")
            self._v[:n] = np.linalg.pinv(C).reshape(-1) * (c - self.u_eq)
        self.last_command = int(round(c)) if self.quantise else c
        self.saturated = False
        self._carry = 0.0

    # -- the update --------------------------------------------------------------------------------------------
    def update(self, r: float, y: float, pulses: int = 1) -> int | float:
        """One sample: setpoint ``r`` and measurement ``y`` in, the command (0..254) out.

        ``pulses``: how many of the servo's pulses will carry this command (:meth:`flexdigit.rig.base.Rig
        .command_pulses`; 2 for the serial board's frame read twice). The dither then counts the rounding error
        once per pulse, so the pulses, not the frames, average the unrounded command: the command is rounded from
        ``u + carry / pulses`` and carries ``pulses x`` its rounding error on.
        """
        v, z, n = self._v, self._z, self.nstates
        if self.ninputs == 1:
            v[n] = r - y
        else:
            v[n] = r
            v[n + 1] = y
        np.dot(self._M, v, out=z)
        u_raw = self.u_eq + z.item(n)  # .item: a Python float, cheaper to compare than a numpy scalar
        if not math.isfinite(u_raw):
            raise DesignError(f"{self.name}: the controller output is not finite ({u_raw}); its state has diverged")
        hi, lo = self.u_max, self.u_min
        u_clip = hi if u_raw > hi else (lo if u_raw < lo else u_raw)
        u = u_clip
        if self.quantise:
            last = self.last_command
            # hysteresis: keep the command in force unless u moved past the half-quantum boundary by h
            if self.hysteresis and abs(u - last) < 0.5 + self.hysteresis and lo <= last <= hi:
                u = float(last)
            elif self.dither:
                wanted = u + self._carry / pulses
                u = min(max(float(round(wanted)), lo), hi)
                # a saturated command carries no more than half a command a pulse
                self._carry = pulses * min(max(wanted - u, -0.5), 0.5)
            else:
                u = float(round(u))
        self.saturated = u_clip != u_raw
        xv, xz, tmp = self._vx, self._zx, self._tmp
        if self.antiwindup == "back_calculation":
            c_sat, c_q = u_clip - u_raw, u - u_clip
            if self._same_gains:
                np.multiply(self.aw_gain, c_sat + c_q, out=tmp)
                np.add(xz, tmp, out=xv)
            else:
                np.multiply(self.aw_gain, c_sat, out=tmp)
                np.add(xz, tmp, out=xv)
                np.multiply(self._q_gain, c_q, out=tmp)
                np.add(xv, tmp, out=xv)
        elif self.antiwindup == "clamp" and self.saturated:
            # freeze the state unless the update moves the output back towards the range
            drift = float(self._c_row @ (xz - xv))
            if (u_raw > hi and drift < 0) or (u_raw < lo and drift > 0):
                np.copyto(xv, xz)
        else:
            np.copyto(xv, xz)
        if self._db_index is not None:
            e = r - y
            if -self._db_width <= e <= self._db_width:
                # inside the deadband: undo this sample's integration (no limit cycle chasing the quantum)
                v[self._db_index] -= self._db_b_dot(r, y)
        out = int(u) if self.quantise else u
        self.last_command = out
        return out

    def step(self, setpoint: float, reading) -> int | float:
        """The loop protocol (:func:`flexdigit.rig.loop.run_loop`): ``measure(reading)`` then :meth:`update`."""
        if self.measure is None:
            raise ParameterError(f"{self.name}: no 'measure' function to turn a rig reading into the measurement")
        return self.update(setpoint, self.measure(reading))

    def simulate(self, r, y) -> np.ndarray:
        """Run :meth:`update` over sequences (open loop), from a bumpless start at the equilibrium command."""
        self.reset()
        r = np.broadcast_to(np.asarray(r, dtype=float), np.shape(y))
        return np.array([self.update(a, b) for a, b in zip(r, np.asarray(y, dtype=float), strict=True)])

    def __repr__(self) -> str:
        return (
            f"RuntimeController(name={self.name!r}, states={self.nstates}, inputs={self.ninputs}, "
            f"dt={self.period_s}, antiwindup={self.antiwindup!r}, quantise={self.quantise})"
        )
