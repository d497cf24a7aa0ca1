"""A discretised controller as one self-contained C99 file and header, and what quantising it does (thesis ch. 5).

The thesis's conclusion asks for the controller to run where the gauges are read: on the microcontroller. This
module writes the :class:`~flexdigit.control.runtime.RuntimeController` (state-space difference equation,
saturation to 0..254, the integer command, anti-windup, hysteresis or dither, deadband, bumpless reset) and the
gauge -> rotation map of any digit's 1 to 8 gauges as C that needs no heap, no libm and no library, in one of two
number formats:

``float32``
    every signal and coefficient an IEEE single (the ATmega328P emulates it in software; a Cortex-M4F has it in
    hardware). Each sample does exactly the Python runtime's operations in the same order of decisions.
``fixed``
    int32 signals, each with its own binary point chosen from the bound on that signal over the command range (the
    l1 norm of the anti-windup state update's impulse response, see :func:`fixed_format`), int32 coefficients and
    one int64 accumulator per row, rounded once. The arithmetic is integer only, so
    :class:`FixedPointController` reproduces it bit for bit in Python (the analysis uses it for limit cycles).

:func:`analyse_export` says what the rounding costs: the quantised controller's poles and those of its anti-windup
state update (what keeps the state bounded), the closed loop with the quantised controller (stable, gain and phase
margins), the bound on every state and on the command over the whole command range (no overflow), the error bound
on the unrounded command against the exact (float64) controller, and limit cycles of the loop with the integer
command. The rounding bounds follow Higham, *Accuracy and Stability of Numerical Algorithms* (2002), thm 3.1:
a length-m dot product in a format of unit roundoff u errs by at most ``gamma_m |a|.|b|``, ``gamma_m = m u/(1-mu)``.

Examples
--------
>>> import control as ct
>>> from flexdigit.control.runtime import RuntimeController
>>> rc = RuntimeController(ct.ss([[0.5]], [[1.0]], [[1.0]], [[2.0]], 0.01))
>>> spec = ControllerSpec.from_runtime(rc)
>>> c_text, h_text = render_c(spec, prefix="pi")
>>> "pi_update" in h_text and "malloc" not in c_text
True
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import control as ct
import numpy as np

from flexdigit import __version__
from flexdigit._io import atomic_write, check_output
from flexdigit._repr import fields_summary
from flexdigit._validation import check_choice, check_real
from flexdigit.control.design20ms import closed_loop
from flexdigit.control.runtime import RuntimeController
from flexdigit.errors import DesignError, ParameterError

__all__ = [
    "FORMATS",
    "ControllerSpec",
    "RotationMap",
    "FixedFormat",
    "fixed_format",
    "FixedPointController",
    "Float32Controller",
    "render_c",
    "QuantisedAnalysis",
    "analyse_export",
    "ExportResult",
    "export_controller",
    "FLOAT32_EPS",
    "FAULT_CODES",
]

FORMATS = ("float", "fixed")
#: Unit roundoff of IEEE single precision (round to nearest): 2^-24.
FLOAT32_EPS = 2.0**-24
#: Return codes of the exported ``update`` (0: a command was produced).
FAULT_CODES = {1: "not finite (the controller state diverged)", 2: "input outside the analysed range"}
#: Headroom kept above every signal's bound in fixed point: values stay below 2^29 of the int32's 2^31.
FIXED_VALUE_BITS = 29
#: Largest int32 coefficient magnitude, 2^30 (so a coefficient times a signal fits an int64 with room to sum).
FIXED_COEF_BITS = 30
#: Samples of the limit-cycle simulation and the tail over which the command must be constant.
LIMIT_CYCLE_SAMPLES = 3000
LIMIT_CYCLE_TAIL = 500


#: Most gauges a rotation map weighs (a digit has 1 to 8, issue 24; the stream protocol's version 2 carries 8).
MAX_MAP_GAUGES = 8


@dataclass(frozen=True)
class RotationMap:
    """The gauge -> measurement map the loop uses: ``y = coef @ gauges_v + offset`` (offset = intercept - tare),
    one weight per gauge of the digit (1 to :data:`MAX_MAP_GAUGES`, base first)."""

    coef: tuple[float, ...]
    offset: float
    unit: str = "deg"

    def __post_init__(self) -> None:
        c = np.asarray(self.coef, dtype=float).reshape(-1)
        if not 1 <= c.size <= MAX_MAP_GAUGES or not np.all(np.isfinite(c)) or not math.isfinite(self.offset):
            raise ParameterError(
                f"a rotation map needs 1 to {MAX_MAP_GAUGES} finite gauge weights and a finite offset. "
                f"Got {c.tolist()!r}, {self.offset!r}."
            )

    @property
    def gauges(self) -> int:
        """How many gauges the map weighs."""
        return len(self.coef)

    @classmethod
    def from_estimator(cls, estimator) -> RotationMap:
        """From a fitted and tared :class:`flexdigit.rig.rotation.RotationEstimator` (duck-typed: control sits
        below rig in the chain), of any number of gauges."""
        c = np.asarray(estimator.coef_, dtype=float).reshape(-1)
        return cls(tuple(float(v) for v in c), float(estimator.intercept_) - float(estimator.tare_deg_))

    def __call__(self, gauges_v) -> float:
        # summed in order, as the C does (a dot product's order would change the last bit)
        total = 0.0
        for g, c in zip(gauges_v, self.coef, strict=True):
            total += float(g) * c
        return float(total) + self.offset


@dataclass(frozen=True)
class ControllerSpec:
    """Everything the C needs from a :class:`RuntimeController`, as plain numbers.

    Attributes
    ----------
    A, B, C, D : ndarray
        The discrete controller (inputs ``e`` or ``[r, y]``, output the command deviation from ``u_eq``).
    period_s, u_eq, u_min, u_max : float
    antiwindup : {"none", "back_calculation", "clamp"}
    aw_gain, q_gain : ndarray
        ``L`` on ``clip(u_raw) - u_raw`` and ``Lq`` on ``u - clip(u_raw)``.
    quantise : bool
    hysteresis : float
    dither : bool
        The runtime's error-feedback quantisation (the rounding error carried to the next sample).
    deadband : (int, float) or None
    rotation : RotationMap or None
    setpoint_scale : float
        The setpoint passed to ``step`` is multiplied by this (the thesis controllers take metres, the loop degrees).
    name : str
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    period_s: float
    u_eq: float
    u_min: float
    u_max: float
    antiwindup: str
    aw_gain: np.ndarray
    q_gain: np.ndarray
    quantise: bool
    hysteresis: float
    deadband: tuple[int, float] | None
    rotation: RotationMap | None = None
    setpoint_scale: float = 1.0
    name: str = "controller"
    dither: bool = False

    @classmethod
    def from_runtime(
        cls, rc: RuntimeController, rotation: RotationMap | None = None, setpoint_scale: float = 1.0
    ) -> ControllerSpec:
        if not isinstance(rc, RuntimeController):
            raise DesignError(f"ControllerSpec.from_runtime needs a RuntimeController. Got {type(rc).__name__}.")
        ss = rc.sys
        deadband = None if rc._db_index is None else (int(rc._db_index), float(rc._db_width))
        arrays = [np.array(m, dtype=float) for m in (ss.A, ss.B, ss.C, ss.D)]
        for m in arrays:
            if not np.all(np.isfinite(m)):
                raise DesignError(f"{rc.name}: the controller has non-finite coefficients")
        return cls(
            *arrays,
            period_s=float(rc.period_s),
            u_eq=float(rc.u_eq),
            u_min=float(rc.u_min),
            u_max=float(rc.u_max),
            antiwindup=rc.antiwindup,
            aw_gain=np.array(rc.aw_gain, dtype=float),
            q_gain=np.array(rc._q_gain, dtype=float),
            quantise=bool(rc.quantise),
            hysteresis=float(rc.hysteresis),
            deadband=deadband,
            rotation=rotation,
            setpoint_scale=check_real(setpoint_scale, "setpoint_scale", "ControllerSpec"),
            name=rc.name,
            dither=bool(rc.dither and rc.quantise),
        )

    @property
    def nstates(self) -> int:
        return self.A.shape[0]

    @property
    def ninputs(self) -> int:
        return self.B.shape[1]

    @property
    def aw_state_update(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(A_aw, B_aw, L)``: the state update with the applied command as an input.

        With back-calculation, ``x+ = A x + B w + L (u - u_raw)`` and ``u_raw = u_eq + C x + D w`` give
        ``x+ = (A - L C) x + (B - L D) w + L (u - u_eq)`` (same gains for saturation and rounding): what keeps the
        state bounded is ``A - L C``, not ``A``. Without anti-windup it is ``A`` itself.
        """
        L = self.aw_gain if self.antiwindup == "back_calculation" else np.zeros(self.nstates)
        L = L.reshape(-1, 1)
        return self.A - L @ self.C, self.B - L @ self.D, L

    def runtime(self) -> RuntimeController:
        """The Python runtime controller this spec describes (the reference the C is tested against)."""
        rc = RuntimeController(
            ct.ss(self.A, self.B, self.C, self.D, self.period_s),
            antiwindup=self.antiwindup,
            aw_gain=self.aw_gain if self.antiwindup == "back_calculation" else None,
            quantise=self.quantise,
            aw_quantisation=self.q_gain if self.antiwindup == "back_calculation" else False,
            deadband=self.deadband,
            hysteresis=self.hysteresis,
            name=self.name,
            dither=self.dither,
        )
        rc.u_min, rc.u_max, rc.u_eq = self.u_min, self.u_max, self.u_eq
        rc.reset()
        return rc

    def reset_state(self, command: float | None = None) -> np.ndarray:
        """The runtime's bumpless state for ``command`` (``x = C^+ (command - u_eq)``)."""
        c = self.u_eq if command is None else float(command)
        if c == self.u_eq or self.nstates == 0:
            return np.zeros(self.nstates)
        return np.linalg.pinv(self.C.reshape(1, -1)).reshape(-1) * (c - self.u_eq)

    __repr__ = fields_summary


# -- fixed point: the format and a bit-exact Python model of the C ----------------------------------------------


def _l1_gain(A: np.ndarray, B: np.ndarray, max_terms: int = 200_000) -> np.ndarray:
    """``sum_k |A^k B|`` (elementwise, (n, m)): the worst-case state per unit of each bounded input.

    Summed until the terms are below 1e-15 of the sum, with a geometric bound on the rest from the decay of the
    last terms. A state update with spectral radius >= 1 has no finite bound (DesignError).
    """
    n = A.shape[0]
    if n == 0:
        return np.zeros((0, B.shape[1]))
    rho = float(np.max(np.abs(np.linalg.eigvals(A))))
    if rho >= 1.0:
        raise DesignError(
            f"the controller's state update has spectral radius {rho:.6g} >= 1: its state is not bounded over "
            "the command range, so no fixed-point format can hold it (export it as float)"
        )
    total = np.zeros((n, B.shape[1]))
    term = B.astype(float)
    k = 0
    while k < max_terms:
        total += np.abs(term)
        term = A @ term
        k += 1
        if np.max(np.abs(term)) <= 1e-15 * max(1.0, float(np.max(total))):
            break
    # the tail: |A^k| decays at least like rho^k once transients are over; a generous geometric bound on the rest
    tail = np.abs(term) / max(1e-12, 1.0 - math.sqrt(rho))
    return total + tail


def _l1_matrix_sum(A: np.ndarray) -> np.ndarray:
    """``sum_k |A^k|`` (elementwise), for the accumulation of per-sample errors."""
    return _l1_gain(A, np.eye(A.shape[0]))


def _frac_bits(bound: float) -> int:
    """Fractional bits for a signal whose magnitude never exceeds ``bound``: ``bound * 2^f < 2^29``."""
    bound = max(float(bound), 2.0**-20)
    return int(math.floor(FIXED_VALUE_BITS - math.log2(bound))) - (1 if math.log2(bound).is_integer() else 0)


@dataclass(frozen=True)
class _Row:
    """One accumulated row: ``acc = sum coef_j * S_j (+ const)``, then ``round(acc / 2^shift)``."""

    coefs: tuple[int, ...]  # one per source, in the order of FixedFormat.sources
    const: int
    acc_bits: int  # F: fractional bits of the accumulator
    shift: int  # F - f_target (>= 0)


@dataclass(frozen=True)
class FixedFormat:
    """The fixed-point realisation: fractional bits of each signal and the integer coefficients of each row.

    Sources of every row, in order: the states ``x_0..x_{n-1}`` (``state_bits``), the inputs (``input_bits``), then
    for the state rows ``c_sat = clip(u_raw) - u_raw`` and ``c_q = u - clip(u_raw)`` (``command_bits``).

    Attributes
    ----------
    state_bits : tuple of int
    input_bits, command_bits : int
    input_max : float
        The analysed input range: ``|w| <= input_max`` for each controller input (the C refuses more).
    state_bound, command_bound : ndarray, float
        Worst-case ``|x_i|`` and ``|u_raw|`` over inputs in range and any applied command in 0..254.
    rows_state : tuple of _Row
    row_output : _Row
    """

    state_bits: tuple[int, ...]
    input_bits: int
    command_bits: int
    input_max: float
    state_bound: np.ndarray = field(repr=False)
    command_bound: float
    rows_state: tuple[_Row, ...] = field(repr=False)
    row_output: _Row = field(repr=False)

    def q_name(self, bits: int, bound: float) -> str:
        integer = max(0, 31 - bits)
        return f"Q{integer}.{bits}"

    def realised(self, spec: ControllerSpec) -> dict[str, np.ndarray]:
        """The coefficients the integers stand for (real units): A, B, C, D, L, Lq, u_eq."""
        n, m = spec.nstates, spec.ninputs
        src = list(self.state_bits) + [self.input_bits] * m + [self.command_bits] * 2

        def real(row: _Row) -> np.ndarray:
            return np.array([c * 2.0 ** (s - row.acc_bits) for c, s in zip(row.coefs, src, strict=False)])

        A = np.zeros((n, n))
        B = np.zeros((n, m))
        L = np.zeros(n)
        Lq = np.zeros(n)
        for i, row in enumerate(self.rows_state):
            r = real(row)
            A[i], B[i], L[i], Lq[i] = r[:n], r[n : n + m], r[n + m], r[n + m + 1]
        r = real(self.row_output)
        return {
            "A": A,
            "B": B,
            "C": r[:n].reshape(1, n),
            "D": r[n : n + m].reshape(1, m),
            "L": L,
            "Lq": Lq,
            "u_eq": self.row_output.const * 2.0**-self.row_output.acc_bits,
        }

    __repr__ = fields_summary


def _make_row(values, source_bits, source_bounds, target_bits: int, const: float = 0.0) -> _Row:
    """Integer coefficients for ``target = sum values_j * source_j + const`` with the widest accumulator that fits."""
    values = np.asarray(values, dtype=float)
    limits = [62 - 1 - math.ceil(math.log2(max(float(np.sum(np.abs(values) * source_bounds)) + abs(const), 1e-30)))]
    for v, s in zip(values, source_bits, strict=True):
        if v != 0.0:
            limits.append(s + FIXED_COEF_BITS - math.ceil(math.log2(abs(v))) - 1)
    F = min(min(limits), target_bits + 32)
    if F < target_bits:
        raise DesignError(
            f"fixed point: a row of the controller needs {target_bits - F} more bits than int64 allows "
            "(coefficients too large against the signal ranges); export it as float"
        )
    coefs = []
    for v, s in zip(values, source_bits, strict=True):
        if F - s < -30:
            raise DesignError("fixed point: a coefficient is too large for its source's format; export it as float")
        coefs.append(int(round(v * 2.0 ** (F - s))))
    return _Row(tuple(coefs), int(round(const * 2.0**F)), F, F - target_bits)


def fixed_format(spec: ControllerSpec, input_max: float) -> FixedFormat:
    """Choose the fixed-point format from the signal ranges.

    ``|w| <= input_max`` for each input, and the applied command anywhere in ``u_min..u_max``. Each state's bound is
    ``sum_k |A_aw^k [B_aw, L]| [w_max; u_dev_max]`` plus the largest bumpless reset state (see
    :attr:`ControllerSpec.aw_state_update`); the unrounded command's is ``u_eq + |C| x_max + |D| w_max``. Each
    signal gets the most fractional bits that keep it below 2^29 (4x headroom in the int32).

    Examples
    --------
    >>> import control as ct
    >>> from flexdigit.control.runtime import RuntimeController
    >>> spec = ControllerSpec.from_runtime(RuntimeController(ct.ss([[0.5]], [[1.0]], [[1.0]], [[0.0]], 0.01)))
    >>> fmt = fixed_format(spec, 10.0)
    >>> [round(float(b), 3) for b in fmt.state_bound], fmt.state_bits   # 10/(1 - 0.5) + a reset at 254: 246
    ([266.0], (20,))
    """
    input_max = check_real(input_max, "input_max", "fixed_format", low=0.0, low_open=True)
    if spec.antiwindup == "clamp" or spec.deadband is not None:
        raise DesignError(
            "fixed point supports antiwindup 'none' and 'back_calculation' without a deadband (their state bounds "
            "are analysed); export this controller as float"
        )
    n, m = spec.nstates, spec.ninputs
    A_aw, B_aw, L = spec.aw_state_update
    u_dev = max(spec.u_max - spec.u_eq, spec.u_eq - spec.u_min)
    if n:
        gain = _l1_gain(A_aw, np.hstack([B_aw, L]))
        x_max = gain @ np.r_[np.full(m, input_max), u_dev]
        x0 = max((np.abs(spec.reset_state(c)) for c in (spec.u_min, spec.u_max)), key=lambda v: float(np.sum(v)))
        x_max = x_max + _l1_reset_peak(A_aw, x0)
    else:
        x_max = np.zeros(0)
    u_bound = abs(spec.u_eq) + float(np.abs(spec.C).reshape(-1) @ x_max) + float(np.sum(np.abs(spec.D))) * input_max
    state_bits = tuple(_frac_bits(b) for b in x_max)
    input_bits = _frac_bits(input_max)
    command_bits = _frac_bits(max(u_bound, spec.u_max, abs(spec.u_min)))
    # c_sat = clip - raw is at most |u_raw| + max|clip|; c_q = u - clip is at most 0.5 + hysteresis + 1
    c_sat_max = u_bound + max(abs(spec.u_min), abs(spec.u_max))
    sources_bits = list(state_bits) + [input_bits] * m + [command_bits, command_bits]
    sources_bound = np.r_[x_max, np.full(m, input_max), c_sat_max, 2.0]
    Lq = spec.q_gain if spec.antiwindup == "back_calculation" else np.zeros(n)
    Lsat = spec.aw_gain if spec.antiwindup == "back_calculation" else np.zeros(n)
    rows = tuple(
        _make_row(np.r_[spec.A[i], spec.B[i], Lsat[i], Lq[i]], sources_bits, sources_bound, state_bits[i])
        for i in range(n)
    )
    out = _make_row(
        np.r_[spec.C.reshape(-1), spec.D.reshape(-1)],
        sources_bits[: n + m],
        sources_bound[: n + m],
        command_bits,
        const=spec.u_eq,
    )
    return FixedFormat(state_bits, input_bits, command_bits, float(input_max), x_max, u_bound, rows, out)


def _l1_reset_peak(A: np.ndarray, x0: np.ndarray) -> np.ndarray:
    """Peak ``|A^k x0|`` over k (elementwise): how far a bumpless reset state can carry each state."""
    peak = np.abs(x0).astype(float)
    x = x0.astype(float)
    for _ in range(10_000):
        x = A @ x
        peak = np.maximum(peak, np.abs(x))
        if np.max(np.abs(x)) < 1e-12:
            break
    return peak


def _round_shift(value: int, shift: int) -> int:
    """``round(value / 2^shift)``, half up, as the C does it: ``(v + 2^(s-1)) >> s`` (arithmetic shift)."""
    return (value + (1 << (shift - 1))) >> shift if shift > 0 else value


def _round_half_even_q(value: int, bits: int) -> int:
    """Nearest integer to ``value / 2^bits``, ties to even (Python's ``round``), in integers."""
    if bits == 0:
        return value
    floor = value >> bits
    rest = value - (floor << bits)
    half = 1 << (bits - 1)
    if rest > half or (rest == half and floor & 1):
        floor += 1
    return floor


class FixedPointController:
    """The exported fixed-point controller, bit for bit (Python integers do exactly what the C's int32/int64 do).

    ``update(r_q, y_q)`` takes inputs already in their Q format (``round(v * 2^input_bits)``); ``update_float``
    converts first, as the C's float wrapper does.
    """

    def __init__(self, spec: ControllerSpec, fmt: FixedFormat) -> None:
        self.spec, self.fmt = spec, fmt
        f = fmt.command_bits
        self.lo_q, self.hi_q = int(round(spec.u_min * 2**f)), int(round(spec.u_max * 2**f))
        self.hyst_q = int(round((0.5 + spec.hysteresis) * 2**f))
        self.w_max_q = int(math.floor(fmt.input_max * 2**fmt.input_bits))
        self.reset()

    def reset(self, command: int | None = None) -> None:
        c = self.spec.u_eq if command is None else float(command)
        spec, f32 = self.spec, np.float32
        pinv = spec.reset_state(spec.u_eq + 1.0) if spec.nstates and np.any(spec.C) else np.zeros(spec.nstates)
        dev = f32(c) - f32(spec.u_eq)
        self.x = [to_q(float(f32(p) * dev), b) for p, b in zip(pinv, self.fmt.state_bits, strict=True)]
        self.last = _round_half_even_q(to_q(c, self.fmt.command_bits), self.fmt.command_bits)
        self.saturated = False
        self.u_raw_q = 0
        self.carry_q = 0  # the dither's carried rounding error, command_bits fractional bits

    def state_real(self) -> np.ndarray:
        return np.array([x * 2.0**-b for x, b in zip(self.x, self.fmt.state_bits, strict=True)])

    def update(self, r_q: int, y_q: int) -> int:
        """One sample; returns the command, or raises :class:`OverflowError` for an input out of range."""
        spec, fmt = self.spec, self.fmt
        n = spec.nstates
        if abs(r_q) > self.w_max_q or abs(y_q) > self.w_max_q:
            raise OverflowError("input outside the analysed range")
        w = [r_q - y_q] if spec.ninputs == 1 else [r_q, y_q]
        if spec.ninputs == 1 and abs(w[0]) > self.w_max_q:
            raise OverflowError("input outside the analysed range")
        src = self.x + w
        row = fmt.row_output
        acc = row.const + sum(c * s for c, s in zip(row.coefs, src, strict=True))
        u_raw = _round_shift(acc, row.shift)
        u_clip = self.hi_q if u_raw > self.hi_q else (self.lo_q if u_raw < self.lo_q else u_raw)
        f = fmt.command_bits
        if spec.quantise:
            last_q = self.last << f
            if spec.hysteresis > 0 and abs(u_clip - last_q) < self.hyst_q and self.lo_q <= last_q <= self.hi_q:
                u = self.last
            elif spec.dither:
                wanted = u_clip + self.carry_q
                u = min(max(_round_half_even_q(wanted, f), self.lo_q >> f), self.hi_q >> f)
                half = 1 << (f - 1)
                self.carry_q = min(max(wanted - (u << f), -half), half)
            else:
                u = _round_half_even_q(u_clip, f)
            u_q = u << f
        else:  # the command stays in Q; reported rounded to an integer for the C's int16 output
            u_q = u_clip
            u = _round_half_even_q(u_clip, f)
        self.saturated = u_clip != u_raw
        c_sat, c_q = u_clip - u_raw, u_q - u_clip
        new = []
        for i in range(n):
            r = fmt.rows_state[i]
            acc = sum(c * s for c, s in zip(r.coefs, [*src, c_sat, c_q], strict=True))
            new.append(_round_shift(acc, r.shift))
        self.x = new
        self.u_raw_q = u_raw
        self.last = u
        return u

    def update_float(self, r: float, y: float) -> int:
        """As the C's float wrapper: refuse out of range (or NaN), then convert with :func:`to_q`."""
        w = self.fmt.input_max
        if not (-w <= r <= w and -w <= y <= w):
            raise OverflowError("input outside the analysed range")
        b = self.fmt.input_bits
        return self.update(to_q(r, b), to_q(y, b))


def to_q(value: float, bits: int) -> int:
    """The C's ``to_q``: scale in float32 (exact: a power of two), add +-0.5 in float32, truncate."""
    s = np.float32(value) * np.float32(2.0**bits)
    s = s - np.float32(0.5) if s < 0 else s + np.float32(0.5)
    return int(s)


class Float32Controller:
    """The float32 export's arithmetic in Python (numpy float32 scalars), for analysis only: tests compare the
    C with the float64 :class:`RuntimeController`, never with this."""

    def __init__(self, spec: ControllerSpec) -> None:
        self.spec = spec
        f = np.float32
        self.M = np.block([[spec.A, spec.B], [spec.C, spec.D]]).astype(f)
        self.rc = spec.runtime()
        self.rc._M = self.M.astype(float)  # the float32 coefficients, run in float64: the coefficient error alone
        self.reset()

    def reset(self, command=None) -> None:
        self.rc.reset(command)

    def update_float(self, r: float, y: float) -> int:
        return self.rc.update(r, y)


# -- C code ----------------------------------------------------------------------------------------------------


def _f32(v: float) -> str:
    """A C float literal that reads back as exactly the float32 nearest ``v``."""
    x = float(np.float32(v))
    if x == 0.0:
        return "0.0f"
    text = f"{x:.9g}"
    if "e" not in text and "." not in text:
        text += ".0"
    return text + "f"


def _dot_float(coefs, names) -> str:
    terms = [f"{_f32(c)} * {name}" for c, name in zip(coefs, names, strict=True) if np.float32(c) != 0]
    return " + ".join(terms) if terms else "0.0f"


def _shift_expr(prefix: str, expr: str, shift: int) -> str:
    return f"{prefix}_shift({expr}, {shift})" if shift > 0 else f"(int32_t)({expr})"


def _dot_int(coefs, names) -> str:
    terms = [f"(int64_t){c} * {name}" for c, name in zip(coefs, names, strict=True) if c != 0]
    return " + ".join(terms) if terms else "0"


#: Prefixes whose ``P_t`` is a type of <stdint.h>, which the header includes (``int16`` would redeclare int16_t).
_STDINT_TYPE = re.compile(r"u?int(_least|_fast)?(8|16|32|64)|u?int(ptr|max)")
#: C99 5.2.4.1: 31 significant initial characters in an external identifier; the longest is ``P_update_q``.
_PREFIX_MAX_CHARS = 31 - len("_update_q")


def _check_prefix(prefix: str) -> None:
    """Refuse a ``prefix`` that would make C that does not compile, or names a compiler may cut short."""
    expected = (
        f"a C identifier of 1 to {_PREFIX_MAX_CHARS} ASCII characters that names no <stdint.h> type "
        "(its P_t would redeclare that type)"
    )
    if (
        not isinstance(prefix, str)
        or not prefix.isidentifier()
        or not prefix.isascii()
        or len(prefix) > _PREFIX_MAX_CHARS
        or _STDINT_TYPE.fullmatch(prefix)
    ):
        raise ParameterError(f"The 'prefix' of render_c (--prefix) must be {expected}. Got {prefix!r}.")


_HEADER_COMMON = """\
/* {title}
 * Generated by flexdigit {version} (flexdigit export controller); do not edit, re-export.
 * Controller: {name}, {n} states, inputs {inputs}, period {period_s} s, format {fmt}.
 * Command: u_raw = {u_eq} + C x + D w, clipped to {u_min}..{u_max}{quantised}; anti-windup {aw}.
 * No heap, no libm: one {prefix}_t per controller instance, updated once per period.
 */
#ifndef {guard}
#define {guard}

#include <stdint.h>

#define {P}_NSTATES {n}
#define {P}_NINPUTS {ni}
#define {P}_PERIOD_US {period_us}UL
#define {P}_COMMAND_MIN {u_min_i}
#define {P}_COMMAND_MAX {u_max_i}
#define {P}_COMMAND_EQ {u_eq_i}
#define {P}_SETPOINT_SCALE {scale}
#define {P}_FIXED_POINT {is_fixed}
#define {P}_HAS_MEASURE {has_measure}
#define {P}_GAUGES {gauges}
#define {P}_DITHER {dither}
/* update() return codes */
#define {P}_OK 0
#define {P}_FAULT_NONFINITE 1
#define {P}_FAULT_INPUT_RANGE 2
"""


def render_c(
    spec: ControllerSpec, fmt: FixedFormat | None = None, *, prefix: str = "fd_ctrl", header_name: str | None = None
) -> tuple[str, str]:
    """The C99 source and header of ``spec``: float32 if ``fmt`` is None, else fixed point in ``fmt``.

    API (``P`` = ``prefix``)::

        void P_reset(P_t *c, float command);          bumpless start at command (the runtime's reset)
        int  P_update(P_t *c, float r, float y, int16_t *command);   one sample; 0 or a fault code
        float P_measure(const float gauges_v[P_GAUGES]);   the rotation map (when exported), G = 1..8 gauges
        int  P_step(P_t *c, float setpoint, const float gauges_v[P_GAUGES], int16_t *command);
        int  P_update_q(P_t *c, int32_t r_q, int32_t y_q, int16_t *command);   fixed point only

    ``c->u_raw`` holds the last unrounded command (float, or Q for fixed) and ``c->x`` the state.
    """
    _check_prefix(prefix)
    n, m = spec.nstates, spec.ninputs
    P = prefix.upper()
    fixed = fmt is not None
    period_us = int(round(spec.period_s * 1e6))
    quantised = ", rounded to an integer (ties to even)" if spec.quantise else ""
    head = _HEADER_COMMON.format(
        title=f"{prefix}.h: discrete controller exported from flexdigit",
        version=__version__,
        name=spec.name,
        n=n,
        inputs="e = r - y" if m == 1 else "[r, y]",
        period_s=f"{spec.period_s:g}",
        fmt=("fixed point " + _format_summary(fmt)) if fixed else "float32",
        u_eq=f"{spec.u_eq:g}",
        u_min=f"{spec.u_min:g}",
        u_max=f"{spec.u_max:g}",
        quantised=quantised,
        aw=spec.antiwindup,
        prefix=prefix,
        guard=f"{P}_H",
        P=P,
        ni=m,
        period_us=period_us,
        u_min_i=int(math.ceil(spec.u_min)),
        u_max_i=int(math.floor(spec.u_max)),
        u_eq_i=int(round(spec.u_eq)),
        scale=_f32(spec.setpoint_scale),
        is_fixed=1 if fixed else 0,
        has_measure=0 if spec.rotation is None else 1,
        gauges=0 if spec.rotation is None else spec.rotation.gauges,
        dither=1 if spec.dither and spec.quantise and spec.hysteresis <= 0 else 0,
    )
    nx = max(n, 1)  # a zero-length array is not C99
    if fixed:
        head += (
            f"#define {P}_INPUT_BITS {fmt.input_bits}\n#define {P}_COMMAND_BITS {fmt.command_bits}\n"
            f"/* inputs must satisfy |w| <= {fmt.input_max:g} (the analysed range) */\n\n"
            f"typedef struct {{\n    int32_t x[{nx}];   /* state; fractional bits {list(fmt.state_bits)} */\n"
            f"    int32_t u_raw;   /* last unrounded command, {fmt.command_bits} fractional bits */\n"
            f"    int32_t carry;   /* the dither's carried rounding error, {fmt.command_bits} fractional bits */\n"
            f"    int16_t last;    /* last command */\n    uint8_t saturated;\n}} {prefix}_t;\n\n"
            f"int {prefix}_update_q({prefix}_t *c, int32_t r_q, int32_t y_q, int16_t *command);\n"
        )
    else:
        head += (
            f"\ntypedef struct {{\n    float x[{nx}];\n    float u_raw;     /* last unrounded command */\n"
            f"    float carry;     /* the dither's carried rounding error */\n"
            f"    int16_t last;    /* last command */\n    uint8_t saturated;\n}} {prefix}_t;\n\n"
        )
    head += (
        f"void {prefix}_reset({prefix}_t *c, float command);\n"
        f"int {prefix}_update({prefix}_t *c, float r, float y, int16_t *command);\n"
    )
    if spec.rotation is not None:
        head += (
            f"/* the gauge -> measurement ({spec.rotation.unit}) map of the loop */\n"
            f"float {prefix}_measure(const float gauges_v[{P}_GAUGES]);\n"
            f"int {prefix}_step({prefix}_t *c, float setpoint, const float gauges_v[{P}_GAUGES], "
            "int16_t *command);\n"
        )
    head += f"\n#endif /* {P}_H */\n"
    body = _render_fixed(spec, fmt, prefix) if fixed else _render_float(spec, prefix)
    return body.replace(f'#include "{prefix}.h"', f'#include "{header_name or prefix + ".h"}"', 1), head


def _format_summary(fmt: FixedFormat) -> str:
    return (
        f"(int32; fractional bits: states {list(fmt.state_bits)}, inputs {fmt.input_bits}, command {fmt.command_bits})"
    )


def _reset_float_lines(spec: ControllerSpec, prefix: str) -> list[str]:
    n = spec.nstates
    lines = [f"void {prefix}_reset({prefix}_t *c, float command)", "{"]
    pinv = spec.reset_state(spec.u_eq + 1.0) if n and np.any(spec.C) else np.zeros(n)
    lines.append(f"    float dev = command - {_f32(spec.u_eq)};")
    for i in range(max(n, 1)):
        lines.append(f"    c->x[{i}] = {_f32(pinv[i]) if i < n else '0.0f'} * dev;")
    lines += [
        "    c->u_raw = command;",
        "    c->carry = 0.0f;",
        f"    c->last = {prefix}_round(command);",
        "    c->saturated = 0;",
        "}",
        "",
    ]
    return lines


def _render_float(spec: ControllerSpec, prefix: str) -> str:
    """The float32 C source: the helpers, ``reset``, ``update`` and (with a rotation map) ``measure``/``step``."""
    out = _float_helper_lines(prefix)
    out += _reset_float_lines(spec, prefix)
    out += _update_float_lines(spec, prefix)
    out += _measure_lines(spec, prefix)
    return "\n".join(out)


def _float_helper_lines(prefix: str) -> list[str]:
    """The include and the static ``round`` (ties to even) and ``finite`` helpers of the float32 source."""
    return [
        f'#include "{prefix}.h"',
        "",
        "/* round to nearest, ties to even (Python's round) for 0 <= v < 2^15; no libm */",
        f"static int16_t {prefix}_round(float v)",
        "{",
        "    float neg = v < 0.0f ? -1.0f : 1.0f;",
        "    float a = v * neg;",
        "    int16_t i = (int16_t)a;",
        "    float d = a - (float)i;",
        "    if (d > 0.5f || (d == 0.5f && (i & 1))) {",
        "        i = (int16_t)(i + 1);",
        "    }",
        "    return neg < 0.0f ? (int16_t)-i : i;",
        "}",
        "",
        f"static int {prefix}_finite(float v)",
        "{",
        "    return v - v == 0.0f;   /* false for inf and NaN */",
        "}",
        "",
    ]


def _update_float_lines(spec: ControllerSpec, prefix: str) -> list[str]:
    """``P_update`` in float32: state and command, clip, quantise, anti-windup, deadband, store."""
    n, m = spec.nstates, spec.ninputs
    xs = [f"x{j}" for j in range(n)]
    ws = ["w0"] if m == 1 else ["w0", "w1"]
    lo, hi, ueq = _f32(spec.u_min), _f32(spec.u_max), _f32(spec.u_eq)
    out = [f"int {prefix}_update({prefix}_t *c, float r, float y, int16_t *command)", "{"]
    for j in range(n):
        out.append(f"    float x{j} = c->x[{j}];")
    if m == 1:
        out.append("    float w0 = r - y;")
    else:
        out += ["    float w0 = r;", "    float w1 = y;"]
    for i in range(n):
        out.append(f"    float z{i} = {_dot_float(np.r_[spec.A[i], spec.B[i]], xs + ws)};")
    out += [
        f"    float u_raw = {ueq} + ({_dot_float(np.r_[spec.C.reshape(-1), spec.D.reshape(-1)], xs + ws)});",
        "    float u_clip, u;",
        f"    if (!{prefix}_finite(u_raw)) {{",
        "        return " + f"{prefix.upper()}_FAULT_NONFINITE;",
        "    }",
        f"    u_clip = u_raw > {hi} ? {hi} : (u_raw < {lo} ? {lo} : u_raw);",
    ]
    out += _quantise_float_lines(spec, prefix)
    out.append("    c->saturated = (uint8_t)(u_clip != u_raw);")
    out += _antiwindup_float_lines(spec)
    out += _deadband_float_lines(spec)
    out += [
        "    c->u_raw = u_raw;",
        f"    c->last = {prefix}_round(u);",
        "    *command = c->last;",
        f"    return {prefix.upper()}_OK;",
        "}",
        "",
    ]
    return out


def _quantise_float_lines(spec: ControllerSpec, prefix: str) -> list[str]:
    """``u`` from ``u_clip``: as it is, rounded, or rounded with hysteresis around the last command."""
    if not spec.quantise:
        return ["    u = u_clip;"]
    if spec.hysteresis <= 0 and spec.dither:
        # the runtime's dither: the rounding error carried to the next sample (at most half a command)
        lo, hi = _f32(spec.u_min), _f32(spec.u_max)
        return [
            "    {",
            "        float wanted = u_clip + c->carry;",
            "        float e;",
            f"        u = (float){prefix}_round(wanted);",
            f"        u = u < {lo} ? {lo} : (u > {hi} ? {hi} : u);",
            "        e = wanted - u;",
            "        c->carry = e < -0.5f ? -0.5f : (e > 0.5f ? 0.5f : e);",
            "    }",
        ]
    if spec.hysteresis <= 0:
        return [f"    u = (float){prefix}_round(u_clip);"]
    lo, hi = _f32(spec.u_min), _f32(spec.u_max)
    return [
        "    {",
        "        float last = (float)c->last;",
        "        float diff = u_clip - last;",
        "        if (diff < 0.0f) { diff = -diff; }",
        f"        if (diff < {_f32(0.5 + spec.hysteresis)} && {lo} <= last && last <= {hi}) {{",
        "            u = last;",
        "        } else {",
        f"            u = (float){prefix}_round(u_clip);",
        "        }",
        "    }",
    ]


def _antiwindup_float_lines(spec: ControllerSpec) -> list[str]:
    """The state update ``c->x = z`` under the spec's anti-windup (back-calculation, clamp or none)."""
    n = spec.nstates
    if spec.antiwindup == "back_calculation":
        L, Lq = spec.aw_gain, spec.q_gain
        out = ["    {", "        float c_sat = u_clip - u_raw, c_q = u - u_clip;"]
        if np.array_equal(L, Lq):
            out.append("        float c_all = c_sat + c_q;")
            out += [f"        c->x[{i}] = z{i} + {_f32(L[i])} * c_all;" for i in range(n)]
        else:
            out += [f"        c->x[{i}] = z{i} + {_f32(L[i])} * c_sat + {_f32(Lq[i])} * c_q;" for i in range(n)]
        return [*out, "        (void)c_sat; (void)c_q;", "    }"]
    if spec.antiwindup == "clamp":
        lo, hi = _f32(spec.u_min), _f32(spec.u_max)
        drift = _dot_float(spec.C.reshape(-1), [f"(z{j} - x{j})" for j in range(n)])
        return [
            "    {",
            "        int update = 1;",
            "        if (c->saturated) {",
            f"            float drift = {drift};",
            f"            update = (u_raw > {hi} && drift < 0.0f) || (u_raw < {lo} && drift > 0.0f);",
            "        }",
            "        if (update) {",
            *[f"            c->x[{i}] = z{i};" for i in range(n)],
            "        }",
            "    }",
        ]
    return [f"    c->x[{i}] = z{i};" for i in range(n)]


def _deadband_float_lines(spec: ControllerSpec) -> list[str]:
    """Undo the error's contribution to the deadband state while ``|r - y| <= width`` (nothing without one)."""
    if spec.deadband is None:
        return []
    idx, width = spec.deadband
    b = spec.B[idx]
    bdot = f"{_f32(b[0])} * (r - y)" if spec.ninputs == 1 else f"{_f32(b[0])} * r + {_f32(b[1])} * y"
    return [
        "    {",
        "        float e = r - y;",
        f"        if ({_f32(-width)} <= e && e <= {_f32(width)}) {{",
        f"            c->x[{idx}] = c->x[{idx}] - ({bdot});",
        "        }",
        "    }",
    ]


def _measure_lines(spec: ControllerSpec, prefix: str) -> list[str]:
    if spec.rotation is None:
        return []
    rot = spec.rotation
    P = prefix.upper()
    names = [f"gauges_v[{i}]" for i in range(rot.gauges)]
    return [
        f"float {prefix}_measure(const float gauges_v[{P}_GAUGES])",
        "{",
        f"    return {_dot_float(rot.coef, names)} + {_f32(rot.offset)};",
        "}",
        "",
        f"int {prefix}_step({prefix}_t *c, float setpoint, const float gauges_v[{P}_GAUGES], int16_t *command)",
        "{",
        f"    return {prefix}_update(c, setpoint * {_f32(spec.setpoint_scale)}, {prefix}_measure(gauges_v), command);",
        "}",
        "",
    ]


def _render_fixed(spec: ControllerSpec, fmt: FixedFormat, prefix: str) -> str:
    """The fixed-point C source: the helpers, ``reset``, ``update_q``, ``update`` and ``measure``/``step``."""
    out = _fixed_helper_lines(fmt, prefix)
    out += _reset_fixed_lines(spec, fmt, prefix)
    out += _update_q_fixed_lines(spec, fmt, prefix)
    out += _update_fixed_lines(fmt, prefix)
    out += _measure_lines(spec, prefix)
    return "\n".join(out)


def _fixed_helper_lines(fmt: FixedFormat, prefix: str) -> list[str]:
    """The include and the static ``shift`` (only when a row shifts), ``round_q`` and ``to_q`` helpers."""
    f = fmt.command_bits
    out = [f'#include "{prefix}.h"', ""]
    if any(r.shift for r in (*fmt.rows_state, fmt.row_output)):
        out += [
            "/* round(v / 2^s), half up: the arithmetic right shift of a signed int64 (gcc and avr-gcc) */",
            f"static int32_t {prefix}_shift(int64_t v, int s)",
            "{",
            "    return (int32_t)((v + ((int64_t)1 << (s - 1))) >> s);",
            "}",
            "",
        ]
    return out + [
        "/* nearest integer to v / 2^bits, ties to even (Python's round) */",
        f"static int16_t {prefix}_round_q(int32_t v)",
        "{",
        f"    int32_t fl = v >> {f};",
        f"    int32_t rest = v - (int32_t)((uint32_t)fl << {f});",
        f"    if (rest > ((int32_t)1 << {f - 1}) || (rest == ((int32_t)1 << {f - 1}) && (fl & 1))) {{",
        "        fl = fl + 1;",
        "    }",
        "    return (int16_t)fl;",
        "}",
        "",
        "/* v x 2^bits (scale is that power of two: the product is exact), rounded half away from zero */",
        f"static int32_t {prefix}_to_q(float v, float scale)",
        "{",
        "    float s = v * scale;",
        "    return (int32_t)(s < 0.0f ? s - 0.5f : s + 0.5f);",
        "}",
        "",
    ]


def _reset_fixed_lines(spec: ControllerSpec, fmt: FixedFormat, prefix: str) -> list[str]:
    """``P_reset`` in fixed point: the bumpless state for ``command``, each in its own Q format."""
    n, f = spec.nstates, fmt.command_bits
    out = [f"void {prefix}_reset({prefix}_t *c, float command)", "{", f"    float dev = command - {_f32(spec.u_eq)};"]
    pinv = spec.reset_state(spec.u_eq + 1.0) if n and np.any(spec.C) else np.zeros(n)
    for i in range(max(n, 1)):
        if i < n:
            out.append(f"    c->x[{i}] = {prefix}_to_q({_f32(pinv[i])} * dev, {_f32(2.0 ** fmt.state_bits[i])});")
        else:
            out.append(f"    c->x[{i}] = 0;")
    return out + [
        f"    c->u_raw = {prefix}_to_q(command, {_f32(2.0**f)});",
        "    c->carry = 0;",
        f"    c->last = {prefix}_round_q({prefix}_to_q(command, {_f32(2.0**f)}));",
        "    c->saturated = 0;",
        "}",
        "",
    ]


def _update_q_fixed_lines(spec: ControllerSpec, fmt: FixedFormat, prefix: str) -> list[str]:
    """``P_update_q``: range checks, the command row, clip, quantise, the state rows (anti-windup in them)."""
    n, m = spec.nstates, spec.ninputs
    P = prefix.upper()
    fpc = FixedPointController(spec, fmt)
    xs = [f"c->x[{j}]" for j in range(n)]
    ws = ["w0"] if m == 1 else ["w0", "w1"]
    out = [
        f"int {prefix}_update_q({prefix}_t *c, int32_t r_q, int32_t y_q, int16_t *command)",
        "{",
        f"    const int32_t w_max = {fpc.w_max_q}L;",
        "    int32_t w0;" if m == 1 else "    int32_t w0 = r_q, w1 = y_q;",
        "    int32_t u_raw, u_clip, u_q, c_sat, c_q;",
        "    int16_t u;",
        f"    int32_t xn[{max(n, 1)}];",
        "    if (r_q > w_max || r_q < -w_max || y_q > w_max || y_q < -w_max) {",
        f"        return {P}_FAULT_INPUT_RANGE;",
        "    }",
    ]
    if m == 1:
        out += [
            "    w0 = r_q - y_q;",
            "    if (w0 > w_max || w0 < -w_max) {",
            f"        return {P}_FAULT_INPUT_RANGE;",
            "    }",
        ]
    row = fmt.row_output
    u_expr = f"(int64_t){row.const}LL + {_dot_int(row.coefs, xs + ws)}"
    out.append(f"    u_raw = {_shift_expr(prefix, u_expr, row.shift)};")
    out.append(f"    u_clip = u_raw > {fpc.hi_q}L ? {fpc.hi_q}L : (u_raw < {fpc.lo_q}L ? {fpc.lo_q}L : u_raw);")
    out += _quantise_fixed_lines(spec, fmt, fpc, prefix)
    out += [
        "    c->saturated = (uint8_t)(u_clip != u_raw);",
        "    c_sat = u_clip - u_raw;",
        "    c_q = u_q - u_clip;",
        "    (void)c_sat; (void)c_q;",
    ]
    for i in range(n):
        r = fmt.rows_state[i]
        out.append(f"    xn[{i}] = {_shift_expr(prefix, _dot_int(r.coefs, [*xs, *ws, 'c_sat', 'c_q']), r.shift)};")
    out += [f"    c->x[{i}] = xn[{i}];" for i in range(n)]
    return out + [
        "    (void)xn;",
        "    c->u_raw = u_raw;",
        "    c->last = u;",
        "    *command = u;",
        f"    return {P}_OK;",
        "}",
        "",
    ]


def _quantise_fixed_lines(spec: ControllerSpec, fmt: FixedFormat, fpc: FixedPointController, prefix: str) -> list[str]:
    """``u`` and ``u_q`` from ``u_clip``: as it is, rounded, or rounded with hysteresis around the last command."""
    f = fmt.command_bits
    if not spec.quantise:
        return ["    u_q = u_clip;", f"    u = {prefix}_round_q(u_clip);"]
    if spec.hysteresis > 0:
        lo, hi = fpc.lo_q, fpc.hi_q
        out = [
            "    {",
            f"        int32_t last_q = (int32_t)((uint32_t)(int32_t)c->last << {f});",
            "        int32_t diff = u_clip - last_q;",
            "        if (diff < 0) { diff = -diff; }",
            f"        if (diff < {fpc.hyst_q}L && {lo}L <= last_q && last_q <= {hi}L) {{",
            "            u = c->last;",
            "        } else {",
            f"            u = {prefix}_round_q(u_clip);",
            "        }",
            "    }",
        ]
    elif spec.dither:
        lo, hi = fpc.lo_q >> f, fpc.hi_q >> f
        half = 1 << (f - 1)
        out = [
            "    {",
            "        int32_t wanted = u_clip + c->carry;",
            "        int32_t e;",
            f"        u = {prefix}_round_q(wanted);",
            f"        u = (int16_t)(u < {lo} ? {lo} : (u > {hi} ? {hi} : u));",
            f"        e = wanted - (int32_t)((uint32_t)(int32_t)u << {f});",
            f"        c->carry = e < -{half}L ? -{half}L : (e > {half}L ? {half}L : e);",
            "    }",
        ]
    else:
        out = [f"    u = {prefix}_round_q(u_clip);"]
    return [*out, f"    u_q = (int32_t)((uint32_t)(int32_t)u << {f});"]


def _update_fixed_lines(fmt: FixedFormat, prefix: str) -> list[str]:
    """``P_update`` of the fixed-point source: the float inputs range-checked, converted, passed to ``update_q``."""
    return [
        f"int {prefix}_update({prefix}_t *c, float r, float y, int16_t *command)",
        "{",
        f"    const float w_max = {_f32(fmt.input_max)};",
        "    if (!(r <= w_max && r >= -w_max && y <= w_max && y >= -w_max)) {   /* also NaN */",
        f"        return {prefix.upper()}_FAULT_INPUT_RANGE;",
        "    }",
        f"    return {prefix}_update_q(c, {prefix}_to_q(r, {_f32(2.0**fmt.input_bits)}), "
        f"{prefix}_to_q(y, {_f32(2.0**fmt.input_bits)}), command);",
        "}",
        "",
    ]


# -- analysis ----------------------------------------------------------------------------------------------------


def _gamma(k: int, u: float = FLOAT32_EPS) -> float:
    """Higham's ``gamma_k = k u / (1 - k u)``: the relative error bound of a k-term dot product."""
    return k * u / (1 - k * u)


@dataclass(frozen=True)
class _Realisation:
    """Exact and realised coefficients and the per-sample arithmetic error model of one export."""

    spec: ControllerSpec
    fmt: FixedFormat | None

    def coefficients(self) -> dict[str, np.ndarray]:
        spec = self.spec
        n = spec.nstates
        L = spec.aw_gain if spec.antiwindup == "back_calculation" else np.zeros(n)
        Lq = spec.q_gain if spec.antiwindup == "back_calculation" else np.zeros(n)
        exact = {"A": spec.A, "B": spec.B, "C": spec.C, "D": spec.D, "L": L, "Lq": Lq, "u_eq": spec.u_eq}
        if self.fmt is not None:
            return exact, self.fmt.realised(spec)
        f = np.float32
        return exact, {k: np.asarray(v, dtype=f).astype(float) for k, v in exact.items()}

    def one_step_bound(self, x, w, c_sat: float, c_q: float) -> tuple[float, np.ndarray]:
        """Largest error of the unrounded command and of each next state in one sample, from the same state and
        inputs, against exact arithmetic (the float64 runtime, whose own rounding is included at 64 eps).

        ``x``: the state; ``w``: the controller inputs; ``c_sat``, ``c_q``: the anti-windup terms of the sample.
        """
        exact, q = self.coefficients()
        n, m = self.spec.nstates, self.spec.ninputs
        ax, aw = np.abs(np.asarray(x, dtype=float)), np.abs(np.asarray(w, dtype=float))
        dC, dD = np.abs(q["C"] - exact["C"]).reshape(-1), np.abs(q["D"] - exact["D"]).reshape(-1)
        mag_u = abs(exact["u_eq"]) + np.abs(exact["C"]).reshape(-1) @ ax + np.abs(exact["D"]).reshape(-1) @ aw
        if self.fmt is None:
            arith_u = _gamma(n + m + 2) * mag_u
        else:
            arith_u = 2.0 ** -(self.fmt.command_bits + 1)
        e_u = float(dC @ ax + dD @ aw + abs(q["u_eq"] - exact["u_eq"]) + arith_u + 64 * 2.0**-53 * mag_u)
        mag_x = (
            np.abs(exact["A"]) @ ax
            + np.abs(exact["B"]) @ aw
            + np.abs(exact["L"]) * abs(c_sat)
            + np.abs(exact["Lq"]) * abs(c_q)
        )
        if self.fmt is None:
            arith_x = _gamma(n + m + 5) * (mag_x + (np.abs(exact["L"]) + np.abs(exact["Lq"])) * e_u)
        else:
            arith_x = 2.0 ** -(np.asarray(self.fmt.state_bits, dtype=float) + 1)
        e_x = (
            np.abs(q["A"] - exact["A"]) @ ax
            + np.abs(q["B"] - exact["B"]) @ aw
            + np.abs(q["L"] - exact["L"]) * (abs(c_sat) + e_u)
            + np.abs(q["Lq"] - exact["Lq"]) * (abs(c_q) + e_u)
            + (np.abs(exact["L"]) + np.abs(exact["Lq"])) * e_u
            + arith_x
            + 64 * 2.0**-53 * mag_x
        )
        return e_u, e_x


@dataclass(frozen=True)
class QuantisedAnalysis:
    """What the number format does to the controller (see :func:`analyse_export`).

    Attributes
    ----------
    format : {"float", "fixed"}
    name : str
    period_s : float
    signal_formats : dict
        ``{"all": "float32"}`` or the Q format of each state, the inputs and the command.
    poles_exact, poles_quantised : ndarray
        Eigenvalues of the controller's ``A`` and of the realised one.
    pole_shift : float
        Largest distance between a pole and its realised counterpart (z-plane).
    aw_radius_exact, aw_radius_quantised : float
        Spectral radius of the anti-windup state update ``A - L C`` (what bounds the state; < 1 required).
    closed_loop_poles : ndarray or None
        The loop with the design plant and the realised controller (None without a plant).
    closed_loop_radius, closed_loop_radius_exact : float or None
    gain_margin_db, phase_margin_deg : float or None
        Margins of the loop broken at the plant input, realised controller (inf when never crossed).
    gain_margin_db_exact, phase_margin_deg_exact : float or None
    input_max : float
        The analysed input range ``|w| <= input_max``.
    state_bound : ndarray or None
        Worst-case ``|x_i|`` over the input range and any command in range (None: unbounded).
    command_bound : float or None
        Worst-case ``|u_raw|`` (commands).
    headroom_bits : float or None
        Fixed point: the fewest bits any signal's worst case stays below the int32 limit (> 0: no overflow).
    command_error_bound : float
        Bound on the unrounded command's error against the exact controller in free run, while the applied
        integer commands agree (commands; inf when the state is unbounded).
    limit_cycles : tuple of dict
        For each setpoint: the command's peak-to-peak over the last samples of a closed-loop run with the integer
        command, and its period (0: constant, or no period: a dithered command toggles without one).
    dithered : bool
        The command is dithered (the rounding error carried): it toggles between neighbours by design, so a
        peak-to-peak of one command is its working, not a limit cycle to avoid.
    """

    format: str
    name: str
    period_s: float
    signal_formats: dict
    poles_exact: np.ndarray
    poles_quantised: np.ndarray
    pole_shift: float
    aw_radius_exact: float
    aw_radius_quantised: float
    closed_loop_poles: np.ndarray | None
    closed_loop_radius: float | None
    closed_loop_radius_exact: float | None
    gain_margin_db: float | None
    phase_margin_deg: float | None
    gain_margin_db_exact: float | None
    phase_margin_deg_exact: float | None
    input_max: float
    state_bound: np.ndarray | None
    command_bound: float | None
    headroom_bits: float | None
    command_error_bound: float
    limit_cycles: tuple
    dithered: bool = False

    @property
    def closed_loop_stable(self) -> bool | None:
        return None if self.closed_loop_radius is None else self.closed_loop_radius < 1.0

    @property
    def limit_cycle_free(self) -> bool:
        return all(lc["peak_to_peak"] == 0 for lc in self.limit_cycles)

    def to_dict(self) -> dict:
        out = {k: getattr(self, k) for k in self.__dataclass_fields__}
        out["closed_loop_stable"] = self.closed_loop_stable
        out["limit_cycle_free"] = self.limit_cycle_free
        return out

    def __repr__(self) -> str:
        def num(v, spec=".4g"):
            return "-" if v is None else format(v, spec)

        lines = [
            f"QuantisedAnalysis({self.name!r}, {self.format}, T = {self.period_s * 1000:g} ms)",
            f"  formats: {self.signal_formats}",
            f"  controller poles: max |z| {np.max(np.abs(self.poles_quantised), initial=0):.6f} "
            f"(exact {np.max(np.abs(self.poles_exact), initial=0):.6f}), largest shift {self.pole_shift:.3g}",
            f"  anti-windup state update: spectral radius {self.aw_radius_quantised:.6f} "
            f"(exact {self.aw_radius_exact:.6f})",
        ]
        if self.closed_loop_radius is not None:
            lines.append(
                f"  closed loop: {'stable' if self.closed_loop_stable else 'UNSTABLE'}, max |z| "
                f"{self.closed_loop_radius:.6f} (exact {num(self.closed_loop_radius_exact, '.6f')}); margins "
                f"{num(self.gain_margin_db, '.2f')} dB, {num(self.phase_margin_deg, '.1f')} deg (exact "
                f"{num(self.gain_margin_db_exact, '.2f')} dB, {num(self.phase_margin_deg_exact, '.1f')} deg)"
            )
        if self.state_bound is None:
            lines.append("  overflow: the state is unbounded over the command range")
        else:
            lines.append(
                f"  |inputs| <= {self.input_max:g}: |x| <= {np.array2string(self.state_bound, precision=4)}, "
                f"|u_raw| <= {self.command_bound:.4g}"
                + (f", headroom {self.headroom_bits:.2f} bits" if self.headroom_bits is not None else "")
            )
        lines.append(f"  command error vs exact (free run, same integer commands) <= {self.command_error_bound:.3g}")
        if self.limit_cycles:
            parts = [
                f"{lc['setpoint']:g}: "
                + ("none" if lc["peak_to_peak"] == 0 else f"{lc['peak_to_peak']} p-p, period {lc['period_samples']}")
                for lc in self.limit_cycles
            ]
            note = " (dithered: one command peak-to-peak is the dither's toggling)" if self.dithered else ""
            lines.append("  limit cycles (setpoint: command): " + "; ".join(parts) + note)
        return "\n".join(lines)


def _margins(Ky, P) -> tuple[float | None, float | None]:
    import warnings

    try:
        loop = ct.series(P, -Ky)  # broken at the plant input, negative feedback on y
        with warnings.catch_warnings():  # python-control's note that it falls back to the frequency grid
            warnings.simplefilter("ignore")
            gm, pm, *_ = ct.stability_margins(loop)
    except Exception:  # noqa: BLE001 - no crossing, or python-control declining: reported as unknown
        return None, None
    gm_db = float("inf") if gm is None or not np.isfinite(gm) else float(20 * np.log10(gm))
    pm = float("inf") if pm is None or not np.isfinite(pm) else float(pm)
    return gm_db, pm


def _two_input(A, B, C, D, dt) -> ct.StateSpace:
    """``u = K (r - y)`` as a two-input controller ``[r, y]``."""
    B, D = np.asarray(B), np.asarray(D)
    if B.shape[1] == 2:
        return ct.ss(A, B, C, D, dt)
    return ct.ss(A, np.hstack([B, -B]), C, np.hstack([D, -D]), dt)


def _loop_figures(A, B, C, D, plant_d, dt):
    K2 = _two_input(A, B, C, D, dt)
    loop = closed_loop(plant_d, K2)
    poles = loop.poles()
    Ky = ct.ss(K2.A, K2.B[:, 1:2], K2.C, K2.D[:, 1:2], dt)
    gm, pm = _margins(Ky, ct.ss(plant_d))
    return poles, float(np.max(np.abs(poles))), gm, pm


def _limit_cycle(controller, plant_d, setpoint: float, u_eq: float) -> dict:
    """Run the loop (linear plant, the controller with its integer command) and look at the command's tail."""
    P = ct.ss(plant_d)
    A, B, C = np.asarray(P.A), np.asarray(P.B).reshape(-1), np.asarray(P.C).reshape(-1)
    xp = np.zeros(A.shape[0])
    controller.reset()
    commands = []
    try:
        for _ in range(LIMIT_CYCLE_SAMPLES):
            y = float(C @ xp)
            u = controller.update_float(setpoint, y)
            commands.append(u)
            xp = A @ xp + B * (float(u) - u_eq)
            if not np.all(np.isfinite(xp)) or np.max(np.abs(xp)) > 1e12:
                raise OverflowError("diverged")
    except (OverflowError, ValueError):
        return {"setpoint": setpoint, "peak_to_peak": None, "period_samples": None, "diverged": True}
    tail = np.asarray(commands[-LIMIT_CYCLE_TAIL:], dtype=float)
    p2p = float(np.ptp(tail))
    period = 0
    if p2p > 0:
        for p in range(1, LIMIT_CYCLE_TAIL // 2):
            if np.array_equal(tail[p:], tail[:-p]):
                period = p
                break
    return {"setpoint": setpoint, "peak_to_peak": p2p, "period_samples": period, "diverged": False}


def analyse_export(
    spec: ControllerSpec,
    fmt: FixedFormat | None = None,
    *,
    plant_d=None,
    input_max: float = 180.0,
    setpoints=(),
) -> QuantisedAnalysis:
    """Analyse the controller as exported (float32 if ``fmt`` is None, else fixed point in ``fmt``).

    Parameters
    ----------
    spec : ControllerSpec
    fmt : FixedFormat, optional
    plant_d : control.StateSpace, optional
        The discrete design plant (command deviation -> the controller's measurement) for the closed loop,
        margins and limit cycles.
    input_max : float
        Input range for the float32 bounds (fixed point uses ``fmt.input_max``).
    setpoints : sequence of float
        Setpoints (controller units) of the limit-cycle runs (needs ``plant_d``).
    """
    real = _Realisation(spec, fmt)
    exact, q = real.coefficients()
    n = spec.nstates
    if fmt is not None:
        input_max = fmt.input_max
    poles_e = np.linalg.eigvals(exact["A"]) if n else np.zeros(0)
    poles_q = np.linalg.eigvals(q["A"]) if n else np.zeros(0)
    shift = float(np.max(np.min(np.abs(poles_e[:, None] - poles_q[None, :]), axis=1))) if n else 0.0
    Aaw_e, rho_e = _anti_windup_update(exact, n)
    _, rho_q = _anti_windup_update(q, n)
    cl_poles = cl_r = cl_r_e = gm = pm = gm_e = pm_e = None
    if plant_d is not None:
        cl_poles, cl_r, gm, pm = _loop_figures(q["A"], q["B"], q["C"], q["D"], plant_d, spec.period_s)
        _, cl_r_e, gm_e, pm_e = _loop_figures(spec.A, spec.B, spec.C, spec.D, plant_d, spec.period_s)
    formats, headroom, x_max, u_bound = _export_bounds(spec, fmt, input_max)
    if x_max is None or (n and rho_e >= 1):
        err = float("inf")
    else:
        err = _command_error_bound(real, spec, exact["C"], Aaw_e, x_max, u_bound, input_max)
    cycles = []
    if plant_d is not None and setpoints:
        ctrl = FixedPointController(spec, fmt) if fmt is not None else Float32Controller(spec)
        cycles = [_limit_cycle(ctrl, plant_d, float(s), spec.u_eq) for s in setpoints]
    return QuantisedAnalysis(
        format="fixed" if fmt is not None else "float",
        name=spec.name,
        period_s=spec.period_s,
        signal_formats=formats,
        poles_exact=poles_e,
        poles_quantised=poles_q,
        pole_shift=shift,
        aw_radius_exact=rho_e,
        aw_radius_quantised=rho_q,
        closed_loop_poles=cl_poles,
        closed_loop_radius=cl_r,
        closed_loop_radius_exact=cl_r_e,
        gain_margin_db=gm,
        phase_margin_deg=pm,
        gain_margin_db_exact=gm_e,
        phase_margin_deg_exact=pm_e,
        input_max=float(input_max),
        state_bound=None if x_max is None else np.asarray(x_max, dtype=float),
        command_bound=None if u_bound is None else float(u_bound),
        headroom_bits=headroom,
        command_error_bound=err,
        limit_cycles=tuple(cycles),
        dithered=bool(spec.dither and spec.quantise and spec.hysteresis <= 0),
    )


def _anti_windup_update(c, n: int):
    """The anti-windup state update ``A - L C`` of coefficients ``c`` and its spectral radius."""
    if not n:
        return np.zeros((0, 0)), 0.0
    Aaw = c["A"] - np.outer(c["L"], c["C"].reshape(-1))
    return Aaw, float(np.max(np.abs(np.linalg.eigvals(Aaw))))


def _export_bounds(spec: ControllerSpec, fmt: FixedFormat | None, input_max: float):
    """``(signal formats, headroom bits, state bound, command bound)`` over the command range.

    Fixed point: the format's bounds and its headroom below 31 bits. Float32: the anti-windup loop's l1 gain
    from inputs and command deviation (bounds None when the design has no such gain).
    """
    n, m = spec.nstates, spec.ninputs
    u_dev = max(spec.u_max - spec.u_eq, spec.u_eq - spec.u_min)
    headroom = None
    if fmt is not None:
        x_max, u_bound = np.asarray(fmt.state_bound), fmt.command_bound
        sig = [(b, f) for b, f in zip(x_max, fmt.state_bits, strict=True)]
        sig += [(input_max, fmt.input_bits), (u_bound, fmt.command_bits)]
        headroom = float(min(31 - math.log2(max(b, 1e-30) * 2.0**f) for b, f in sig))
        formats = {f"x{i}": fmt.q_name(b, 0) for i, b in enumerate(fmt.state_bits)}
        formats.update(inputs=fmt.q_name(fmt.input_bits, 0), command=fmt.q_name(fmt.command_bits, 0))
    else:
        formats = {"all": "float32"}
        try:
            A_aw, B_aw, L = spec.aw_state_update
            gain = _l1_gain(A_aw, np.hstack([B_aw, L])) if n else np.zeros((0, m + 1))
            x_max = gain @ np.r_[np.full(m, input_max), u_dev]
            u_bound = abs(spec.u_eq) + float(np.abs(spec.C).reshape(-1) @ x_max) + np.sum(np.abs(spec.D)) * input_max
        except DesignError:
            x_max, u_bound = None, None
    return formats, headroom, x_max, u_bound


def _command_error_bound(real, spec: ControllerSpec, c_exact, Aaw_e, x_max, u_bound, input_max: float) -> float:
    """Worst-case command error of the realisation: one step's error, accumulated through the anti-windup loop."""
    n, m = spec.nstates, spec.ninputs
    c_sat_max = (u_bound or 0.0) + max(abs(spec.u_min), abs(spec.u_max))
    e_u1, e_x1 = real.one_step_bound(x_max, np.full(m, input_max), c_sat_max, 1.0 + spec.hysteresis)
    if n:
        # the per-sample errors accumulate through the anti-windup state update: sum_k |A_aw^k| e_x1
        e_x = _l1_matrix_sum(Aaw_e) @ e_x1
        return float(np.abs(c_exact).reshape(-1) @ e_x + e_u1)
    return e_u1


# -- the export ----------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class ExportResult:
    """The written files and the analysis of what they compute."""

    source_path: Path
    header_path: Path
    format: str
    prefix: str
    analysis: QuantisedAnalysis

    def __repr__(self) -> str:
        return (
            f"ExportResult({self.source_path} + {self.header_path.name}, {self.format}, prefix {self.prefix!r})\n"
            + (repr(self.analysis))
        )


def export_controller(
    spec: ControllerSpec,
    out,
    *,
    format: str = "float",
    input_max: float = 180.0,
    plant_d=None,
    setpoints=(),
    prefix: str = "fd_ctrl",
    force: bool = False,
) -> ExportResult:
    """Write ``spec`` as ``out`` (C99 source) and ``out`` with ``.h`` (header), atomically, and analyse it.

    Both destinations are checked before anything is written; neither is replaced without ``force``.
    """
    format = check_choice(format, "format", FORMATS, "export_controller")
    out = Path(out)
    if out.suffix != ".c":
        raise ParameterError(f"The '--out' file of export_controller must end in .c. Got {str(out)!r}.")
    header = out.with_suffix(".h")
    check_output(out, force=force)
    check_output(header, force=force)
    fmt = fixed_format(spec, input_max) if format == "fixed" else None
    analysis = analyse_export(spec, fmt, plant_d=plant_d, input_max=input_max, setpoints=setpoints)
    source, head = render_c(spec, fmt, prefix=prefix, header_name=header.name)
    with atomic_write(header, "w", force=force) as fh:
        fh.write(head)
    with atomic_write(out, "w", force=force) as fh:
        fh.write(source)
    return ExportResult(out, header, format, prefix, analysis)
