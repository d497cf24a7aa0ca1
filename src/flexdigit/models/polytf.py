"""A small frozen SISO transfer function, ``num(s)/den(s)`` as numpy polynomial coefficients (highest power first).

The models build their transfer functions with it and convert to python-control only where a caller needs a
``control.TransferFunction`` (:meth:`PolyTF.to_control`): ``import control`` costs 2 s here (it pulls in
scipy.signal, scipy.stats and matplotlib), so ``flexdigit model`` and the twin would otherwise pay it at start-up
for a few polynomial products. Products, gains, unity feedback, poles, zeros and DC gain are the same polynomial
arithmetic python-control does for a SISO ``TransferFunction`` (``np.polymul``, ``np.roots``).

Examples
--------
>>> g = PolyTF([2.0], [1.0, 3.0, 2.0])          # 2 / ((s + 1)(s + 2))
>>> g.dcgain()
1.0
>>> sorted(g.poles().real.round(6).tolist())
[-2.0, -1.0]
>>> t = (5.0 * g).feedback()                    # 10 / (s^2 + 3 s + 12)
>>> t.den.tolist()
[1.0, 3.0, 12.0]
"""

from __future__ import annotations

from dataclasses import dataclass
from numbers import Real
from typing import TYPE_CHECKING

import numpy as np

from flexdigit.errors import ParameterError

__all__ = ["PolyTF", "ctrb", "obsv"]

if TYPE_CHECKING:
    import control


@dataclass(frozen=True, eq=False)
class PolyTF:
    """``num(s) / den(s)``, coefficients highest power first; leading zeros of ``num`` are dropped.

    Attributes
    ----------
    num, den : ndarray
        Real coefficients (read-only copies). ``den`` must not be all zeros.
    """

    num: np.ndarray
    den: np.ndarray

    __array_ufunc__ = None  # numpy scalars and arrays defer to PolyTF's own * (np.float64(2) * g is a PolyTF)

    def __post_init__(self) -> None:
        num = np.trim_zeros(np.atleast_1d(np.array(self.num, dtype=float)), "f")
        den = np.trim_zeros(np.atleast_1d(np.array(self.den, dtype=float)), "f")
        if num.ndim != 1 or den.ndim != 1 or not np.all(np.isfinite(num)) or not np.all(np.isfinite(den)):
            raise ParameterError(f"PolyTF needs finite 1-D coefficients. Got num={self.num!r}, den={self.den!r}.")
        if den.size == 0:
            raise ParameterError(f"The 'den' parameter of PolyTF must not be all zeros. Got {self.den!r} instead.")
        num = num if num.size else np.zeros(1)
        num.flags.writeable = den.flags.writeable = False
        object.__setattr__(self, "num", num)
        object.__setattr__(self, "den", den)

    @classmethod
    def from_control(cls, tf: control.TransferFunction) -> PolyTF:
        """The SISO ``tf``'s numerator and denominator."""
        return cls(tf.num[0][0], tf.den[0][0])

    def __mul__(self, other: PolyTF | float) -> PolyTF:
        """Series connection with another PolyTF, or a scalar gain."""
        if isinstance(other, PolyTF):
            return PolyTF(np.polymul(self.num, other.num), np.polymul(self.den, other.den))
        if isinstance(other, Real):
            return PolyTF(self.num * float(other), self.den)
        return NotImplemented

    __rmul__ = __mul__

    def feedback(self, gain: float = 1.0) -> PolyTF:
        """Negative feedback through a constant ``gain``: ``G / (1 + gain G)`` (python-control's ``feedback``)."""
        return PolyTF(self.num, np.polyadd(self.den, float(gain) * self.num))

    def normalised(self) -> PolyTF:
        """The same transfer function with a monic denominator."""
        return PolyTF(self.num / self.den[0], self.den / self.den[0])

    def poles(self) -> np.ndarray:
        """Roots of the denominator (rad/s), complex."""
        return np.roots(self.den).astype(complex)

    def zeros(self) -> np.ndarray:
        """Roots of the numerator (rad/s), complex; empty for a constant numerator."""
        return np.roots(self.num).astype(complex)

    def dcgain(self) -> float:
        """``G(0)``: ``inf`` (or ``nan`` for 0/0) with a pole at the origin."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return float(np.float64(self.num[-1]) / np.float64(self.den[-1]))

    def __call__(self, s):
        """``G(s)`` at complex frequencies ``s``."""
        s = np.asarray(s, dtype=complex)
        out = np.polyval(self.num, s) / np.polyval(self.den, s)
        return out if out.ndim else complex(out)

    def to_control(self) -> control.TransferFunction:
        """This transfer function as a ``control.TransferFunction`` (imports python-control)."""
        import control

        return control.tf(self.num, self.den)

    def __repr__(self) -> str:
        return f"PolyTF(num={self.num.tolist()!r}, den={self.den.tolist()!r})"


def ctrb(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Controllability matrix ``[B, AB, ..., A^(n-1) B]`` (as ``control.ctrb``)."""
    cols = [np.asarray(b, dtype=float)]
    for _ in range(np.shape(a)[0] - 1):
        cols.append(a @ cols[-1])
    return np.hstack(cols)


def obsv(a: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Observability matrix ``[C; CA; ...; C A^(n-1)]`` (as ``control.obsv``)."""
    return ctrb(np.asarray(a, dtype=float).T, np.asarray(c, dtype=float).T).T
