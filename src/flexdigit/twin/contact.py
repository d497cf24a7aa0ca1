"""Contact in the twin: a compliant body beside the digit, distributed pressure, several point forces at once.

Beyond the thesis (chapter 8: "detect low frequency palpations, identify variability in tissue stiffness,
discriminate against distributed loads"). Three kinds of load act on the chain of :mod:`flexdigit.twin.digit`:

- :class:`Tissue`: a compliant body fixed in the world beside the digit, on the cable side by default (the cable
  bends the digit into it). Its surface is the line ``b = gap`` (``b = -gap`` on the other side) over
  ``start_m <= a <= end_m`` along the undeformed digit; it is a unilateral elastic (Winkler) foundation: every
  length ``ds`` of the digit inside it and past its surface by ``delta`` is pushed back, normal to the surface, by

      ``q ds = k(a) delta^n (1 + 3/2 alpha d(delta)/dt) ds``   (Hunt & Crossley 1975; ``n = 1``, ``alpha = 0``:
      linear),

  never pulled (``q >= 0``). ``k(a)`` (the foundation modulus, N/m per m of contact for ``n = 1``) is
  ``modulus_n_m2`` with stiff (or soft) :class:`Inclusion` stretches where it is ``ratio`` times that. A layer of
  Young's modulus ``E`` and thickness ``h`` under the 12.7 mm strip is ``k ~ E w / h``; a stretch of width ``w``
  pressed uniformly is a spring of ``k w`` N/m (:attr:`Tissue.stiffness_n_m`).
- :class:`Pressure`: a world-fixed line load over a stretch of the digit (N in all, spread evenly over
  ``start_m..end_m`` of arc length), e.g. a finger or a retractor resting on it.
- :class:`PointForce`: a world-fixed force at one arc position; any number at once.

Forces are sideways, positive towards the cable side (``+b``, as :meth:`flexdigit.twin.Twin.deflect`); a body on
the cable side pushes with a negative force.

How the foundation is integrated
--------------------------------
Each rigid link of the chain is a straight segment; on it the penetration is linear in arc length, so the part of
the link inside the body and past its surface is one interval, found exactly (clipped at the body's ends, at each
inclusion's edges and where the penetration changes sign), and the load on it is integrated by Gauss-Legendre
(:data:`GAUSS_POINTS` points: exact for the linear foundation, whose integrands are quadratic). The generalised
force is then exact for the chain's shape, and continuous in the angles (no quadrature point jumps in or out of
the body). The tangent stiffness omits the motion of the interval's ends: at the surface the integrand vanishes
there, so the omission is exact, and at the body's ends it only slows Newton a little.

Examples
--------
>>> from flexdigit.twin.digit import Chain
>>> chain = Chain.uniform(length_m=0.2, ei_n_m2=0.01, n_cells=20)
>>> body = Tissue(start_m=0.19, end_m=0.2, gap_m=0.0, modulus_n_m2=1e5)
>>> sol = solve_contact(chain, tissue=body, tip_moment_nm=0.01)
>>> bool(sol.contact_force_n[0] < 0), bool(0.19 < sol.contact_centroid_m[0] < 0.2)
(True, True)
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from flexdigit._repr import fields_summary
from flexdigit._validation import check_real
from flexdigit.errors import ConvergenceWarning, ParameterError

__all__ = [
    "GAUSS_POINTS",
    "SIDES",
    "CONTINUATION",
    "Inclusion",
    "Tissue",
    "PointForce",
    "Pressure",
    "check_point_force",
    "check_pressure",
    "quadrature",
    "TissueContact",
    "ContactSolution",
    "solve_contact",
]

#: Gauss-Legendre points per clipped interval of a link.
GAUSS_POINTS = 4
_GAUSS_T, _GAUSS_W = np.polynomial.legendre.leggauss(GAUSS_POINTS)
_GAUSS_T = 0.5 * (_GAUSS_T + 1.0)  # on [0, 1]
_GAUSS_W = 0.5 * _GAUSS_W

SIDES = {"cable": 1.0, "opposite": -1.0}
#: Stiffening stages of :func:`solve_contact` when Newton does not converge at once (factors on the modulus).
CONTINUATION = (1e-3, 1e-2, 0.1, 0.3, 1.0)


@dataclass(frozen=True)
class Inclusion:
    """A stretch of the body ``ratio`` times as stiff as the rest (a nodule: ``ratio > 1``).

    Attributes
    ----------
    centre_m : float
        Centre along the undeformed digit, m from the clamp.
    width_m : float
        Length along the digit (m).
    ratio : float
        Its modulus over the body's.
    """

    centre_m: float
    width_m: float
    ratio: float

    def __post_init__(self) -> None:
        owner = "Inclusion"
        object.__setattr__(self, "centre_m", check_real(self.centre_m, "centre_m", owner))
        object.__setattr__(self, "width_m", check_real(self.width_m, "width_m", owner, low=0, low_open=True))
        object.__setattr__(self, "ratio", check_real(self.ratio, "ratio", owner, low=0, low_open=True))


@dataclass(frozen=True)
class Tissue:
    """A compliant body beside the digit: a unilateral (Hunt-Crossley) elastic foundation (module docstring).

    Attributes
    ----------
    start_m, end_m : float
        Where it lies along the undeformed digit (m from the clamp, world-fixed); it may extend past the tip.
    gap_m : float
        Distance of its surface from the straight digit's axis (m); 0 touches it, negative starts pressed in.
    modulus_n_m2 : float
        Foundation modulus ``k`` (N per m of digit per m^n of penetration; N/m^2 when ``exponent`` is 1).
    inclusions : tuple of Inclusion
        Stretches of other stiffness; they must not overlap.
    exponent : float
        Hunt-Crossley exponent ``n`` (1: linear, 1.5: Hertzian).
    damping_s_m : float
        Hunt-Crossley ``alpha`` (s/m): the load grows by ``1 + 1.5 alpha v`` while pressed in at ``v`` m/s.
    side : {"cable", "opposite"}
        Which side of the digit it lies on: the cable side (the cable bends the digit into it) or the other.
    """

    start_m: float
    end_m: float
    gap_m: float
    modulus_n_m2: float
    inclusions: tuple[Inclusion, ...] = ()
    exponent: float = 1.0
    damping_s_m: float = 0.0
    side: str = "cable"

    def __post_init__(self) -> None:
        owner = "Tissue"
        start = check_real(self.start_m, "start_m", owner)
        end = check_real(self.end_m, "end_m", owner, low=start, low_open=True)
        object.__setattr__(self, "start_m", start)
        object.__setattr__(self, "end_m", end)
        object.__setattr__(self, "gap_m", check_real(self.gap_m, "gap_m", owner))
        object.__setattr__(self, "modulus_n_m2", check_real(self.modulus_n_m2, "modulus_n_m2", owner, low=0))
        object.__setattr__(self, "exponent", check_real(self.exponent, "exponent", owner, low=1.0, high=3.0))
        object.__setattr__(self, "damping_s_m", check_real(self.damping_s_m, "damping_s_m", owner, low=0))
        if self.side not in SIDES:
            raise ParameterError(
                f"The 'side' parameter of {owner} must be one of {', '.join(map(repr, SIDES))}. "
                f"Got {self.side!r} instead."
            )
        inclusions = tuple(self.inclusions)
        for inc in inclusions:
            if not isinstance(inc, Inclusion):
                raise ParameterError(f"The 'inclusions' parameter of {owner} must hold Inclusion objects. Got {inc!r}.")
        edges = sorted((inc.centre_m - inc.width_m / 2, inc.centre_m + inc.width_m / 2) for inc in inclusions)
        for (_, hi), (lo, _) in zip(edges[:-1], edges[1:], strict=True):
            if lo < hi:
                raise ParameterError(
                    f"The 'inclusions' parameter of {owner} must not overlap. Got stretches {edges!r} instead."
                )
        object.__setattr__(self, "inclusions", inclusions)

    @property
    def sign(self) -> float:
        """+1 on the cable side, -1 on the other."""
        return SIDES[self.side]

    @property
    def stiffness_n_m(self) -> float:
        """The whole body as a spring (N/m): ``k`` times its length (uniform penetration, linear foundation)."""
        return self.modulus_n_m2 * (self.end_m - self.start_m)

    def pieces(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Stretches of constant modulus: ``(lo_m, hi_m, modulus)`` arrays, in order along the digit."""
        cuts = {self.start_m, self.end_m}
        for inc in self.inclusions:
            for edge in (inc.centre_m - inc.width_m / 2, inc.centre_m + inc.width_m / 2):
                if self.start_m < edge < self.end_m:
                    cuts.add(edge)
        x = np.array(sorted(cuts))
        lo, hi = x[:-1], x[1:]
        return lo, hi, self.modulus_at(0.5 * (lo + hi))

    def modulus_at(self, a_m) -> np.ndarray:
        """Foundation modulus at positions along the digit (0 outside the body)."""
        a = np.asarray(a_m, dtype=float)
        k = np.where((a >= self.start_m) & (a <= self.end_m), self.modulus_n_m2, 0.0)
        for inc in self.inclusions:
            k = np.where(np.abs(a - inc.centre_m) <= inc.width_m / 2, k * inc.ratio, k)
        return k

    def moved(self, offset_m: float) -> Tissue:
        """The same body shifted ``offset_m`` along the digit (towards the tip when positive): a scan step."""
        d = check_real(offset_m, "offset_m", "Tissue.moved")
        inclusions = tuple(Inclusion(i.centre_m + d, i.width_m, i.ratio) for i in self.inclusions)
        return _replace(self, start_m=self.start_m + d, end_m=self.end_m + d, inclusions=inclusions)

    def replace(self, **changes) -> Tissue:
        """A copy with some fields changed."""
        return _replace(self, **changes)


def _replace(tissue: Tissue, **changes) -> Tissue:
    import dataclasses

    return dataclasses.replace(tissue, **changes)


@dataclass(frozen=True)
class PointForce:
    """A world-fixed sideways force (N, + towards the cable side) at an arc position (m from the clamp)."""

    position_m: float
    force_n: float


@dataclass(frozen=True)
class Pressure:
    """A world-fixed sideways line load: ``total_n`` (N, + towards the cable side) spread evenly over the arc
    stretch ``start_m..end_m`` (m from the clamp)."""

    start_m: float
    end_m: float
    total_n: float

    @property
    def centre_m(self) -> float:
        return 0.5 * (self.start_m + self.end_m)

    @property
    def extent_m(self) -> float:
        return self.end_m - self.start_m


def check_point_force(position_m, force_n, length_m: float, owner: str = "PointForce") -> PointForce:
    """A point force on the digit: position in [0, length] (m from the clamp), finite force (N)."""
    s = check_real(position_m, "position_m", owner, low=0, high=length_m)
    f = check_real(force_n, "force_n", owner)
    return PointForce(s, f)


def check_pressure(start_m, end_m, total_n, length_m: float, owner: str = "Pressure") -> Pressure:
    """A line load on the digit: ``0 <= start < end <= length`` (m from the clamp), finite total (N)."""
    lo = check_real(start_m, "start_m", owner, low=0, high=length_m)
    hi = check_real(end_m, "end_m", owner, low=lo, high=length_m, low_open=True)
    return Pressure(lo, hi, check_real(total_n, "total_n", owner))


def quadrature(chain, loads) -> tuple[np.ndarray, np.ndarray]:
    """World-fixed point forces and pressures as point loads ``(s_m (K,), force_ab_n (K, 2))`` for the chain.

    A pressure is split at the springs, the links' ends and the gauges, and each piece gets the 2-point
    Gauss-Legendre rule: the levers are linear on a piece, so the generalised forces and the force carried past
    every gauge are exact.
    """
    s_out, f_out = [], []
    cuts = np.concatenate([chain.joint_s_m, chain.gauge_s_m])
    nodes = np.array([0.5 - 0.5 / np.sqrt(3.0), 0.5 + 0.5 / np.sqrt(3.0)])
    for load in loads:
        if isinstance(load, PointForce):
            s_out.append([load.position_m])
            f_out.append([load.force_n])
        elif isinstance(load, Pressure):
            inner = cuts[(cuts > load.start_m) & (cuts < load.end_m)]
            edges = np.unique(np.concatenate([[load.start_m], inner, [load.end_m]]))
            lo, width = edges[:-1], np.diff(edges)
            s_out.append((lo[:, None] + width[:, None] * nodes).ravel())
            f_out.append(np.repeat(0.5 * width * load.total_n / load.extent_m, 2))
        else:
            raise ParameterError(f"A load on the digit must be a PointForce or a Pressure. Got {load!r} instead.")
    if not s_out:
        return np.zeros(0), np.zeros((0, 2))
    s = np.concatenate(s_out)
    fb = np.concatenate(f_out)
    return s, np.column_stack([np.zeros_like(fb), fb])


class TissueContact:
    """The foundation of a :class:`Tissue` on a :class:`~flexdigit.twin.digit.Chain`: its generalised forces and
    their derivatives for any batch of shapes (the statics' and the dynamics' contact term).

    Parameters
    ----------
    chain : Chain
    tissue : Tissue
    """

    def __init__(self, chain, tissue: Tissue) -> None:
        self.chain = chain
        self.tissue = tissue
        self.sign = tissue.sign
        lo, hi, k = tissue.pieces()
        self._lo, self._hi, self._k = lo, hi, k
        # links: the clamped stretch [0, s_0] (angle 0, no degree of freedom) then one per spring
        self._link_start = np.concatenate([[0.0], chain.joint_s_m])
        self._link_len = np.concatenate([[chain.joint_s_m[0]], chain.link_length_m])
        self._chain_link_len = np.ascontiguousarray(chain.link_length_m, dtype=float)
        from flexdigit.twin._contact_points import contact_generalized, contact_points, contact_resultant

        self._contact_points = contact_points
        self._contact_generalized, self._contact_resultant = contact_generalized, contact_resultant
        self._joint_s = np.ascontiguousarray(chain.joint_s_m, dtype=float)
        self._gauge_s = np.ascontiguousarray(chain.gauge_s_m, dtype=float)

    def __repr__(self) -> str:
        return f"TissueContact(tissue={self.tissue!r})"

    def points(self, psi, omega=None):
        """Quadrature of the load on the digit for angles ``psi`` (B, n) (rates ``omega`` for the damping).

        Returns ``(s, w, delta, k, rate)``, each (B, P): arc positions (m), weights (m), penetration (m), modulus,
        penetration rate (m/s; zeros without ``omega``). Points outside the contact have weight 0.

        Compiled (:mod:`flexdigit.twin._contact_points`): the same numbers as :meth:`_points_numpy`, bit for bit,
        for ~1/20 of the CPU at a Newton solve's batch sizes.
        """
        psi = np.ascontiguousarray(np.atleast_2d(np.asarray(psi, dtype=float)))
        s, w, delta, k = self._contact_points(
            psi,
            self._link_start,
            self._link_len,
            self._chain_link_len,
            float(self.sign),
            float(self.tissue.gap_m),
            self._lo,
            self._hi,
            self._k,
            _GAUSS_T,
            _GAUSS_W,
        )
        rate = np.zeros_like(s)
        if omega is not None and self.tissue.damping_s_m > 0 and s.shape[1]:
            c = self._levers(s) * np.cos(psi)[:, None, :]  # (B, P, n): d b_p / d psi
            rate = self.sign * np.einsum("bpn,bn->bp", c, np.atleast_2d(omega))
        return s, w, delta, k, rate

    def _points_numpy(self, psi, omega=None):
        """:meth:`points` in numpy: the reference the compiled quadrature is tested against."""
        ch = self.chain
        psi = np.atleast_2d(np.asarray(psi, dtype=float))
        b = psi.shape[0]
        # link end points (B, n + 2): the clamp, the first spring (the clamped stretch is straight), then each link
        cos, sin = np.cos(psi), np.sin(psi)
        x = np.empty((b, ch.n + 2))
        y = np.zeros((b, ch.n + 2))
        x[:, 0] = 0.0
        x[:, 1:] = self._link_len[0] + np.concatenate([np.zeros((b, 1)), np.cumsum(ch.link_length_m * cos, 1)], 1)
        y[:, 2:] = np.cumsum(ch.link_length_m * sin, axis=1)
        depth = self.sign * y - self.tissue.gap_m
        # only links that reach past the surface somewhere in the batch, inside the body's extent
        reach = np.maximum(depth[:, :-1], depth[:, 1:]) > 0
        overlap = (np.maximum(x[:, :-1], x[:, 1:]) >= self._lo[0]) & (np.minimum(x[:, :-1], x[:, 1:]) <= self._hi[-1])
        links = np.flatnonzero(np.any(reach & overlap, axis=0))
        if links.size == 0:
            empty = np.zeros((b, 0))
            return empty, empty, empty, empty, empty
        x0, x1 = x[:, links, None], x[:, links + 1, None]  # (B, L, 1) against pieces (M,)
        d0, d1 = depth[:, links, None], depth[:, links + 1, None]
        dx = x1 - x0
        with np.errstate(divide="ignore", invalid="ignore"):
            ta = np.where(dx > 0, (self._lo - x0) / dx, np.where(x0 >= self._lo, 0.0, 1.0))
            tb = np.where(dx > 0, (self._hi - x0) / dx, np.where(x0 <= self._hi, 1.0, 0.0))
            # penetration > 0 between t = 0..root (d0 > 0 > d1) or root..1 (d0 < 0 < d1)
            root = np.where(d0 != d1, d0 / (d0 - d1), 0.0)
        ta, tb = np.minimum(np.maximum(ta, 0.0), 1.0), np.minimum(np.maximum(tb, 0.0), 1.0)
        ta = np.where((d0 <= 0) & (d1 > 0), np.maximum(ta, root), ta)
        tb = np.where((d0 > 0) & (d1 <= 0), np.minimum(tb, root), tb)
        empty = (tb <= ta) | ((d0 <= 0) & (d1 <= 0))
        span = np.where(empty, 0.0, tb - ta)  # (B, L, M)
        t = ta[..., None] + span[..., None] * _GAUSS_T  # (B, L, M, G)
        length = self._link_len[links][None, :, None, None]
        s = self._link_start[links][None, :, None, None] + t * length
        w = span[..., None] * _GAUSS_W * length
        delta = np.maximum(d0[..., None] + t * (d1 - d0)[..., None], 0.0)
        k = np.broadcast_to(self._k[None, None, :, None], s.shape)
        shape = (b, -1)
        s, w, delta, k = s.reshape(shape), w.reshape(shape), delta.reshape(shape), k.reshape(shape)
        rate = np.zeros_like(s)
        if omega is not None and self.tissue.damping_s_m > 0:
            c = self._levers(s) * cos[:, None, :]  # (B, P, n): d b_p / d psi
            rate = self.sign * np.einsum("bpn,bn->bp", c, np.atleast_2d(omega))
        return s, w, delta, k, rate

    def _levers(self, s):
        """:meth:`Chain.levers` without ``np.clip``'s overhead (it dominates at a few points)."""
        ch = self.chain
        return np.minimum(np.maximum(s[..., None] - ch.joint_s_m, 0.0), ch.link_length_m)

    def load(self, delta, k, rate):
        """Load per length ``q`` (N/m, >= 0), ``dq/d delta`` and ``dq/d rate`` at quadrature points."""
        n, alpha = self.tissue.exponent, self.tissue.damping_s_m
        elastic = k * delta**n
        slope = n * k * np.where(delta > 0, delta ** (n - 1), 0.0) if n != 1 else k * (delta > 0)
        factor = 1.0 + 1.5 * alpha * rate
        q = elastic * factor
        pushing = q > 0
        return (
            np.where(pushing, q, 0.0),
            np.where(pushing, slope * factor, 0.0),
            np.where(pushing, 1.5 * alpha * elastic, 0.0),
        )

    def _kernel_args(self, psi, omega):
        """``psi`` and ``omega`` (B, n; (0, n) for none) as the compiled kernels take them."""
        psi = np.ascontiguousarray(np.atleast_2d(np.asarray(psi, dtype=float)))
        if omega is None:
            omega = np.zeros((0, psi.shape[1]))
        return psi, np.ascontiguousarray(np.atleast_2d(np.asarray(omega, dtype=float)))

    def generalized(self, psi, omega=None):
        """Generalised forces ``Q`` (B, n) of the body on the chain, ``dQ/dpsi`` and ``dQ/domega`` (B, n, n; None
        without damping).

        ``Q_j = -sign sum_p w_p q_p lever_pj cos psi_j`` (the load is normal to the surface, world-fixed).
        Compiled (:func:`flexdigit.twin._contact_points.contact_generalized`): the dynamics call it twice a step,
        where numpy spent ~0.2 ms a call on a few dozen points; :meth:`_generalized_numpy` is its reference.
        """
        psi, omega = self._kernel_args(psi, omega)
        t = self.tissue
        gen, d_psi, d_omega = self._contact_generalized(
            psi, omega, self._link_start, self._link_len, self._chain_link_len, self._joint_s, float(self.sign),
            float(t.gap_m), self._lo, self._hi, self._k, _GAUSS_T, _GAUSS_W, float(t.exponent), float(t.damping_s_m),
        )  # fmt: skip
        return gen, d_psi, (d_omega if t.damping_s_m > 0 else None)

    def _generalized_numpy(self, psi, omega=None):
        """:meth:`generalized` in numpy: the reference the compiled one is tested against."""
        ch = self.chain
        psi = np.atleast_2d(np.asarray(psi, dtype=float))
        s, w, delta, k, rate = self.points(psi, omega)
        q, dq_dd, dq_dv = self.load(delta, k, rate)
        if s.shape[1] == 0:
            zeros = np.zeros((psi.shape[0], ch.n, ch.n))
            return np.zeros(psi.shape), zeros, (zeros if self.tissue.damping_s_m > 0 else None)
        lever = self._levers(s)  # (B, P, n)
        cos, sin = np.cos(psi), np.sin(psi)
        c = lever * cos[:, None, :]  # d b_p / d psi_j
        wq = w * q
        gen = -self.sign * np.einsum("bp,bpn->bn", wq, c)
        # dQ_i/dpsi_k = -sum_p w q' C_pi C_pk + delta_ik sign sum_p w q lever_pi sin psi_i
        d_psi = -np.einsum("bp,bpi,bpk->bik", w * dq_dd, c, c)
        idx = np.arange(ch.n)
        d_psi[:, idx, idx] += self.sign * np.einsum("bp,bpi->bi", wq, lever) * sin
        d_omega = -np.einsum("bp,bpi,bpk->bik", w * dq_dv, c, c) if self.tissue.damping_s_m > 0 else None
        return gen, d_psi, d_omega

    def resultant(self, psi, omega=None):
        """Total force (N, + towards the cable side; the body pushes with ``-sign``), its centroid along the arc
        (m from the clamp, NaN without contact), the contact's arc extent ``(first, last)`` (m) and the force
        carried past each gauge in the (a, b) axes (B, G, 2).

        Compiled (:func:`flexdigit.twin._contact_points.contact_resultant`): every reading of a twin beside a body
        asks it; :meth:`_resultant_numpy` is its reference."""
        psi, omega = self._kernel_args(psi, omega)
        t = self.tissue
        total, centroid, first, last, beyond = self._contact_resultant(
            psi, omega, self._link_start, self._link_len, self._chain_link_len, self._joint_s, self._gauge_s,
            float(self.sign), float(t.gap_m), self._lo, self._hi, self._k, _GAUSS_T, _GAUSS_W, float(t.exponent),
            float(t.damping_s_m),
        )  # fmt: skip
        return total, centroid, (first, last), beyond

    def _resultant_numpy(self, psi, omega=None):
        """:meth:`resultant` in numpy: the reference the compiled one is tested against."""
        psi = np.atleast_2d(np.asarray(psi, dtype=float))
        s, w, delta, k, rate = self.points(psi, omega)
        q = self.load(delta, k, rate)[0]
        wq = w * q
        total = wq.sum(axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            centroid = np.where(total > 0, (wq * s).sum(axis=1) / total, np.nan)
        touching = wq > 0
        some = touching.any(axis=1)
        first = np.where(some, np.where(touching, s, np.inf).min(axis=1, initial=np.inf), np.nan)
        last = np.where(some, np.where(touching, s, -np.inf).max(axis=1, initial=-np.inf), np.nan)
        past = s[:, None, :] > self.chain.gauge_s_m[None, :, None]  # (B, G, P)
        beyond = np.zeros((psi.shape[0], self.chain.gauge_s_m.size, 2))
        beyond[..., 1] = -self.sign * np.einsum("bgp,bp->bg", past, wq)
        return -self.sign * total, centroid, (first, last), beyond


@dataclass(frozen=True)
class ContactSolution:
    """Equilibria with contact (:func:`solve_contact`), batch of ``B`` cases.

    Attributes
    ----------
    static : StaticSolution
        The chain's solution (angles, gauge curvature, axial force with the contact included, tension, tip).
    contact_force_n : ndarray, shape (B,)
        The body's total force on the digit (N, + towards the cable side; a body on the cable side gives < 0).
    contact_centroid_m : ndarray, shape (B,)
        Where that force acts on average, m of arc from the clamp (NaN without contact).
    contact_first_m, contact_last_m : ndarray, shape (B,)
        The ends of the stretch in contact (m of arc from the clamp; NaN without contact).
    converged : bool
        Newton met its tolerance in every case.
    """

    static: object
    contact_force_n: np.ndarray
    contact_centroid_m: np.ndarray
    contact_first_m: np.ndarray
    contact_last_m: np.ndarray
    converged: bool

    @property
    def tip_m(self) -> np.ndarray:
        return self.static.tip_m

    __repr__ = fields_summary


def _merged_loads(chain, loads, load_s_m, load_force_ab_n, cable_shortening_m):
    """The per-case point loads with the world-fixed ``loads`` (as quadrature points) appended to each case."""
    s_fixed, f_fixed = quadrature(chain, loads)
    if load_s_m is None and not s_fixed.size:
        return load_s_m, load_force_ab_n
    b = 1 if cable_shortening_m is None else np.size(cable_shortening_m)
    extra_s = np.zeros((b, 0)) if load_s_m is None else np.atleast_2d(np.asarray(load_s_m, dtype=float))
    extra_f = np.zeros((b, 0, 2)) if load_force_ab_n is None else np.asarray(load_force_ab_n, dtype=float)
    extra_f = extra_f.reshape(extra_s.shape[0], -1, 2)
    rows = max(extra_s.shape[0], b)
    load_s_m = np.concatenate(
        [np.broadcast_to(extra_s, (rows, extra_s.shape[1])), np.broadcast_to(s_fixed, (rows, s_fixed.size))], axis=1
    )
    load_force_ab_n = np.concatenate(
        [np.broadcast_to(extra_f, (rows, extra_f.shape[1], 2)), np.broadcast_to(f_fixed, (rows, s_fixed.size, 2))],
        axis=1,
    )
    return load_s_m, load_force_ab_n


def _stiffen_gradually(chain, tissue, solve, psi0):
    """The last stage's solution of a stiffness continuation over ``CONTINUATION``.

    A very stiff body makes semi-smooth Newton chatter between contact sets: stiffen it gradually instead, each
    stage starting from the last stage's shape.
    """
    start = psi0
    for factor in CONTINUATION:
        stage = TissueContact(chain, tissue.replace(modulus_n_m2=factor * tissue.modulus_n_m2))
        sol = solve(stage, start)
        start = sol.psi_rad
    return sol


def solve_contact(
    chain,
    *,
    tissue: Tissue | None = None,
    loads=(),
    load_s_m=None,
    load_force_ab_n=None,
    tip_moment_nm=0.0,
    cable_shortening_m=None,
    psi0=None,
    max_iter: int = 200,
) -> ContactSolution:
    """Static equilibria of the chain pressed into ``tissue`` and under world-fixed ``loads``, batched.

    Parameters
    ----------
    chain : Chain
    tissue : Tissue, optional
        The body beside the digit (its modulus may be 0: no contact).
    loads : sequence of PointForce / Pressure
        World-fixed sideways loads, the same for every case.
    load_s_m, load_force_ab_n : optional
        Further point loads per case, as :meth:`~flexdigit.twin.digit.Chain.solve_static` takes them (hung weights).
    tip_moment_nm, cable_shortening_m, psi0
        As :meth:`~flexdigit.twin.digit.Chain.solve_static`; ``cable_shortening_m`` (B,) sets the batch.
    max_iter : int
        Newton iterations at most.

    Warns
    -----
    ConvergenceWarning
        If Newton stops before its tolerance (``converged`` is False); never silently.
    """
    load_s_m, load_force_ab_n = _merged_loads(chain, loads, load_s_m, load_force_ab_n, cable_shortening_m)
    contact = TissueContact(chain, tissue) if tissue is not None and tissue.modulus_n_m2 > 0 else None

    def solve(body, start):
        with warnings.catch_warnings():  # this function says itself when the last attempt did not converge
            warnings.simplefilter("ignore", ConvergenceWarning)
            return chain.solve_static(
                load_s_m,
                load_force_ab_n,
                tip_moment_nm=tip_moment_nm,
                cable_shortening_m=cable_shortening_m,
                psi0=start,
                contact=body,
                max_iter=max_iter,
            )

    sol = solve(contact, psi0)
    if not sol.converged and contact is not None:
        sol = _stiffen_gradually(chain, tissue, solve, psi0)
    b = sol.psi_rad.shape[0]
    converged = bool(sol.converged)
    if not converged:
        warnings.warn(
            f"contact statics did not converge in {max_iter} Newton iterations; the solution may be wrong",
            ConvergenceWarning,
            stacklevel=2,
        )
    if contact is None:
        nan = np.full(b, np.nan)
        return ContactSolution(sol, np.zeros(b), nan, nan, nan.copy(), converged)
    force, centroid, (first, last), _ = contact.resultant(sol.psi_rad)
    return ContactSolution(sol, force, centroid, first, last, converged)
