"""The digit as a planar large-deflection chain: rigid links joined by rotational springs (a discrete elastica).

Why this model
--------------
The digit is an inextensible spring-steel strip (axial stiffness ~10^6 N against loads < 1 N) carrying rigid nylon
supports, bent by a cable and by hanging weights, up to ~60 degrees at the tip. An inextensible planar elastica is
the right continuum, and its standard discretisation is the Hencky chain: the strip is cut into cells, each
cell's bending is lumped into a rotational spring ``k = EI / h`` at the cell's mid-point (the mid-point rule for
``theta' = M / EI``, second order in ``h``), and the links between springs are rigid. This choice, rather than a
Cosserat rod (PyElastica) or beam finite elements, gives:

- exact large rotations with one coordinate per cell (absolute link angles ``psi``), no shear or axial stiffness
  to resolve (a Cosserat rod's axial and shear waves force microsecond explicit steps), so an L-stable implicit
  step of 20 ms follows the digit's 10-25 rad/s modes and quenches the fast cell modes (:class:`DynamicState`);
- rigid supports for free: a support is simply a stretch of link with no spring in it;
- a spring moment equal to the bending moment at the joint in equilibrium, so gauge strains are exact on the
  discrete configuration;
- a closed-form mass matrix ``M_jk = A_jk cos(psi_j - psi_k)`` with a constant ``A`` (the N-link pendulum), and
  generalised forces of world-fixed loads that are ``-sin(psi) G_a + cos(psi) G_b`` with constant ``G``. Statics
  vectorise over thousands of load cases (one batched Newton solve); dynamics are a few small dense products per
  step.

The cable (3.3) runs at constant eccentricity ``e`` (the thesis's assumption): its path is ``e * psi_tip`` shorter
than the strip, so its only generalised force is the moment ``T e`` on the tip angle. The compression ``T`` it puts
on the strip is self-equilibrated (a tendon in a duct does not buckle its duct) and appears only as axial strain
at the gauges, which the half bridge cancels and a quarter bridge sees. The cable is a stiff, tension-only spring
(``T = k_c max(0, r_M dtheta_M - e psi_tip)``, E 3.11), so a slack cable and a taut one are both handled.

With an antagonistic pair (``[cables] count = 2``, 2.1's "two cable system") a second cable runs on the far side
(eccentricity ``-e``), wound the other way on the same pulley, both pretensioned: ``T1 = k_c max(0, p + s - e
psi_tip)``, ``T2 = k_c max(0, p - s + e psi_tip)`` with ``p = pretension / k_c`` (the batched twin's law,
:mod:`flexdigit.twin.batched`): the tip carries ``e (T1 - T2)``, the strip ``T1 + T2`` of compression, and a
command below the straight one bends the digit the other way.

Axes: ``a`` along the undeformed digit (base to tip), ``b`` towards the cable side (positive bending). Angles in
rad, lengths in m, forces in N, moments in N m.

Examples
--------
>>> chain = Chain.uniform(length_m=0.2, ei_n_m2=0.01, n_cells=40)
>>> sol = chain.solve_static(tip_force_n=[[0.0, 1e-4]])
>>> round(float(sol.tip_m[0, 1] / (1e-4 * 0.2**3 / (3 * 0.01))), 3)     # P L^3 / 3 EI
1.0
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
from scipy.linalg.lapack import dgesv as _gesv
from scipy.linalg.lapack import dgetrf as _getrf
from scipy.linalg.lapack import dgetrs as _getrs

from flexdigit._constants import G_STANDARD_M_S2
from flexdigit._repr import fields_summary, summary
from flexdigit._validation import check_array, check_choice, check_int, check_positive, check_real, check_values
from flexdigit.errors import ConvergenceWarning, ParameterError
from flexdigit.params import MAX_CELL_LENGTH_M, MIN_CELLS_PER_SECTION, cells_no_longer_than, twin_cells

__all__ = [
    "G_STANDARD_M_S2",
    "ORIENTATIONS",
    "StaticSolution",
    "chain_matrices",
    "Chain",
    "DynamicState",
    "uniform_cells",
    "build_digit",
    "digit_arrays",
    "default_cells",
    "MAX_CELL_LENGTH_M",
    "MIN_CELLS_PER_SECTION",
]


def _solve(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a x = b`` through LAPACK gesv directly: ``np.linalg.solve`` costs ~20 us of Python overhead per call,
    more than the 9 x 9 solve itself, and the dynamics call it twice per step."""
    _, _, x, info = _gesv(a, b)
    if info != 0:
        raise ArithmeticError("singular mass or iteration matrix in the digit dynamics")
    return x


def _factor(a: np.ndarray):
    """LU factors of ``a`` (LAPACK getrf) for :func:`_solve_factored`: the ROS2 step solves its iteration matrix
    twice, and gesv is getrf then getrs, so factoring once gives the same bits for one factorisation less (n^3/3
    flops: a third of a step's solves at 35 springs)."""
    lu, piv, info = _getrf(a)
    if info != 0:
        raise ArithmeticError("singular mass or iteration matrix in the digit dynamics")
    return lu, piv


def _solve_factored(factors, b: np.ndarray) -> np.ndarray:
    """``a x = b`` from :func:`_factor`'s ``a`` (LAPACK getrs)."""
    x, info = _getrs(*factors, b)
    if info != 0:
        raise ArithmeticError("singular mass or iteration matrix in the digit dynamics")
    return x


#: Gravity direction in the digit's (a, b) axes for each mounting: "vertical" tip up (the designed mounting, 2.2.4),
#: "hanging" tip down, "horizontal" with the cable side up (chapters 6-7: weights hang off the digit).
ORIENTATIONS = {"vertical": (-1.0, 0.0), "hanging": (1.0, 0.0), "horizontal": (0.0, -1.0)}


@dataclass(frozen=True)
class StaticSolution:
    """Equilibria of a batch of load cases.

    Attributes
    ----------
    psi_rad : ndarray, shape (B, n)
        Absolute link angles.
    curvature_1_m : ndarray, shape (B, n_gauges)
        Strip curvature at the gauge positions (1/m, positive towards the cable side).
    axial_force_n : ndarray, shape (B, n_gauges)
        Axial force in the strip at the gauges (N, tension positive).
    tension_n : ndarray, shape (B,)
        Cable tension (N).
    tip_m : ndarray, shape (B, 2)
        Tip position in the (a, b) axes (m).
    iterations : int
        Newton iterations used.
    converged : bool
        Whether the Newton iteration met its tolerance within ``max_iter`` (else a
        :class:`~flexdigit.errors.ConvergenceWarning` was issued).
    """

    psi_rad: np.ndarray
    curvature_1_m: np.ndarray
    axial_force_n: np.ndarray
    tension_n: np.ndarray
    tip_m: np.ndarray
    iterations: int
    converged: bool = True

    __repr__ = fields_summary


def chain_matrices(d, mass_lever, mass_link, stiffness, damping, mass_kg, inertia, gravity):
    """A chain's constant matrices ``(K, C, A, G)``: ``K = D^T diag(k) D``, ``C`` alike, the mass matrix's
    ``A = L^T diag(m) L + diag(J)`` and the gravity forces ``G = L^T (m g)`` (n, 2), from the point masses' levers
    ``L`` (P, n) and links. ``stiffness`` ... ``gravity`` may carry a leading axis: chains of one layout stacked
    (:meth:`flexdigit.twin.batched.BatchedChains.from_rigs`), each the same numbers as its own :class:`Chain`."""
    k = d.T @ (stiffness[..., :, None] * d)
    c = d.T @ (damping[..., :, None] * d)
    on = mass_link >= 0
    j_diag = np.zeros(stiffness.shape)
    np.add.at(j_diag.T, mass_link[on], inertia[..., on].T)  # the masses in order, as one chain adds them
    a = mass_lever.T @ (mass_kg[..., :, None] * mass_lever) + j_diag[..., :, None] * np.eye(d.shape[0])
    g = mass_lever.T @ (mass_kg[..., :, None] * gravity[..., None, :])
    return k, c, a, g


class Chain:
    """A clamped planar chain of rigid links and rotational springs (see the module docstring).

    Parameters
    ----------
    length_m : float
        Clamp-to-tip length.
    joint_s_m : array_like, shape (n,)
        Arc positions of the springs, increasing, inside (0, length_m).
    joint_stiffness_nm_rad : array_like, shape (n,)
        Spring stiffness ``EI / h`` of each cell (N m / rad).
    joint_damping_nms_rad : array_like, shape (n,)
        Viscous damping of each spring (N m s / rad): structural damping, stiffness-proportional by default.
    cell_length_m : array_like, shape (n,)
        Length ``h`` of the cell each spring lumps (curvature = joint angle / h).
    mass_s_m, mass_kg, mass_inertia_kg_m2 : array_like, shape (P,)
        Point masses on the chain: arc position, mass, rotary inertia about their own centre.
    gauge_s_m : array_like, shape (G,)
        Arc positions where curvature and axial force are reported (the strain gauges).
    gravity_ab_m_s2 : (float, float)
        Gravity in the (a, b) axes (m/s^2).
    cable_eccentricity_m, cable_stiffness_n_m : float
        Cable offset ``e`` from the neutral axis, and its tension-only stiffness (N/m).
    cable_pretension_n : float
        With ``antagonist``: the pretension both cables keep with the digit straight (N).
    antagonist : bool
        A second, antagonistic cable at ``-e`` (module docstring).
    """

    def __init__(
        self,
        length_m,
        joint_s_m,
        joint_stiffness_nm_rad,
        joint_damping_nms_rad,
        cell_length_m,
        mass_s_m,
        mass_kg,
        mass_inertia_kg_m2,
        gauge_s_m=(),
        gravity_ab_m_s2=(0.0, 0.0),
        cable_eccentricity_m=0.0,
        cable_stiffness_n_m=0.0,
        strip_axial_stiffness_n=np.inf,
        cable_pretension_n=0.0,
        antagonist=False,
    ):
        owner = "Chain"
        self.length_m = check_positive(length_m, "length_m", owner)
        s = check_array(joint_s_m, "joint_s_m", owner, ndim=1, min_length=1, increasing=True, low=0, high=length_m)
        n = s.size
        self.joint_s_m = s
        self.stiffness = check_array(joint_stiffness_nm_rad, "joint_stiffness_nm_rad", owner, shape=(n,), low=0)
        self.damping = check_array(joint_damping_nms_rad, "joint_damping_nms_rad", owner, shape=(n,), low=0)
        self.cell_length_m = check_array(cell_length_m, "cell_length_m", owner, shape=(n,), low=0, low_open=True)
        self.link_length_m = np.diff(np.append(s, self.length_m))
        ms = check_array(mass_s_m, "mass_s_m", owner, ndim=1, low=0, high=length_m)
        self.mass_s_m = ms
        self.mass_kg = check_array(mass_kg, "mass_kg", owner, shape=(ms.size,), low=0)
        self.mass_inertia = check_array(mass_inertia_kg_m2, "mass_inertia_kg_m2", owner, shape=(ms.size,), low=0)
        self.gauge_s_m = check_array(gauge_s_m, "gauge_s_m", owner, ndim=1, low=0, high=length_m)
        self.gravity = check_array(gravity_ab_m_s2, "gravity_ab_m_s2", owner, shape=(2,))
        self.eccentricity = check_real(cable_eccentricity_m, "cable_eccentricity_m", owner, low=0)
        self.cable_stiffness = check_real(cable_stiffness_n_m, "cable_stiffness_n_m", owner, low=0)
        self.strip_axial_stiffness = float(strip_axial_stiffness_n)
        self.antagonist = bool(antagonist)
        pretension = check_real(cable_pretension_n, "cable_pretension_n", owner, low=0) if antagonist else 0.0
        #: The pretension as a stretch of each cable (m), ``p = pretension / k_c`` (0 without the antagonist).
        self.cable_pretension_m = pretension / self.cable_stiffness if self.cable_stiffness > 0 else 0.0
        # phi = D psi: relative joint angles from absolute link angles (the clamp link has angle 0)
        d = np.eye(n) - np.eye(n, k=-1)
        self._d = d
        self._mass_lever = self.levers(ms)  # (P, n)
        self._mass_link = np.clip(np.searchsorted(s, ms, side="right") - 1, -1, n - 1)
        self.k_psi, self.c_psi, self.a_mass, self.g_gravity = chain_matrices(
            d,
            self._mass_lever,
            self._mass_link,
            self.stiffness,
            self.damping,
            self.mass_kg,
            self.mass_inertia,
            self.gravity,
        )
        # weight beyond each gauge (for the axial force)
        self._mass_beyond_gauge = (ms[None, :] > self.gauge_s_m[:, None]) @ self.mass_kg
        self._gauge_interp = self._interpolation(self.gauge_s_m)
        self._gauge_link = np.clip(np.searchsorted(s, self.gauge_s_m, side="right") - 1, -1, n - 1)
        self._gauge_take = np.maximum(self._gauge_link, 0)
        self._gauge_on_chain = (self._gauge_link >= 0).astype(float)
        # curvature at the gauges = W (phi / h) = W diag(1/h) D psi: one product per read
        self._psi_to_gauge_curvature = self._gauge_interp @ (d / self.cell_length_m[:, None])

    def __repr__(self) -> str:
        # what the chain is, not its matrices (issue 23: a model prints a summary)
        return summary(
            self,
            links=self.n,
            length_m=self.length_m,
            masses=self.mass_kg.size,
            gauges=self.gauge_s_m.size,
            total_mass_kg=float(self.mass_kg.sum()),
            cable_stiffness_n_m=self.cable_stiffness,
            antagonist=self.antagonist,
        )

    # ----------------------------------------------------------------------------------------------- geometry
    @property
    def n(self) -> int:
        """Number of springs (= degrees of freedom)."""
        return self.joint_s_m.size

    def levers(self, s_m) -> np.ndarray:
        """Lever of each link for points at arc positions ``s_m``: ``clip(s - s_j, 0, l_j)``, shape (P, n).

        A point's position is ``s_0 a + sum_j lever_j u(psi_j)`` (or ``s a`` on the clamped first stretch).
        """
        s_m = np.asarray(s_m, dtype=float)
        return np.clip(s_m[..., None] - self.joint_s_m, 0.0, self.link_length_m)

    def _interpolation(self, s_query: np.ndarray) -> np.ndarray:
        """Matrix W (Q, n): curvature at ``s_query`` = W @ (phi / h), linear between springs of the same span and
        linearly extrapolated from its two end springs beyond them (the half cell between a span's end spring and
        its support).

        A spring's ``phi / h`` is its cell's mean curvature, the curvature at the cell's centre to O(h^2); along a
        strip of one stiffness the moment of point loads and the cable is linear, so the line through the end
        springs reads a gauge near a support as the continuum does, where holding the end spring's value was off
        by the moment's slope times up to half a cell (2.8 % at 1.7 mm from a support on a 23 mm section with 3
        cells; a gauge on a spring, as the thesis's midway gauges are, reads its spring either way)."""
        s = self.joint_s_m
        w = np.zeros((s_query.size, self.n))
        # a "span" is a run of springs whose cells touch (no rigid stretch between them)
        gaps = s[1:] - s[:-1] > 0.5 * (self.cell_length_m[1:] + self.cell_length_m[:-1]) + 1e-12
        span = np.concatenate([[0], np.cumsum(gaps)])
        for q, sq in enumerate(s_query):
            j = int(np.argmin(np.abs(s - sq)))
            idx = np.flatnonzero(span == span[j])
            if idx.size >= 2 and (sq < s[idx[0]] or sq > s[idx[-1]]):
                a, b = (idx[0], idx[1]) if sq < s[idx[0]] else (idx[-2], idx[-1])
                t = (sq - s[a]) / (s[b] - s[a])
                w[q, a], w[q, b] = 1.0 - t, t
                continue
            eye = np.eye(idx.size)
            for c in range(idx.size):
                w[q, idx[c]] = np.interp(sq, s[idx], eye[c])
        return w

    def positions(self, psi: np.ndarray, s_m) -> np.ndarray:
        """Positions (.., P, 2) in the (a, b) axes of points at arc positions ``s_m`` for angles ``psi`` (.., n)."""
        psi = np.asarray(psi, dtype=float)
        s_m = np.asarray(s_m, dtype=float)
        lever = self.levers(s_m)  # (P, n)
        u = np.stack([np.cos(psi), np.sin(psi)], axis=-1)  # (.., n, 2)
        pos = np.einsum("pn,...nk->...pk", lever, u)
        base = np.minimum(s_m, self.joint_s_m[0])
        pos[..., 0] += base
        return pos

    def tip(self, psi: np.ndarray) -> np.ndarray:
        """Tip position (.., 2)."""
        return self.positions(psi, [self.length_m])[..., 0, :]

    @property
    def gauge_curvature_per_moment(self) -> np.ndarray:
        """Curvature (1/m) at each gauge per N m of extra bending moment carried by its section, ``W (1 / (k h))``.

        The local compliance: what a moment confined to the gauge's section (e.g. a cable-guide friction moment,
        :mod:`flexdigit.twin.sensors`) does to the gauge's curvature, the rest of the chain held.
        """
        with np.errstate(divide="ignore"):
            flex = np.where(self.stiffness > 0, 1.0 / (self.stiffness * self.cell_length_m), 0.0)
        return self._gauge_interp @ flex

    def curvature_at_gauges(self, psi: np.ndarray) -> np.ndarray:
        """Strip curvature (1/m) at the gauges for angles ``psi`` (.., n)."""
        return np.asarray(psi, dtype=float) @ self._psi_to_gauge_curvature.T

    # ------------------------------------------------------------------------------------------------ loads
    def load_forces(self, s_m, force_ab_n) -> np.ndarray:
        """Constant force vector ``G`` (.., n, 2) of world-fixed point forces: Q_j = -sin psi_j G_a + cos psi_j G_b.

        ``s_m`` (.., K) arc positions and ``force_ab_n`` (.., K, 2) forces in the (a, b) axes.
        """
        lever = self.levers(s_m)  # (.., K, n)
        return np.einsum("...kn,...kc->...nc", lever, np.asarray(force_ab_n, dtype=float))

    def cable_tensions(self, psi_tip, cable_shortening_m):
        """``(T1, T2, taut1, taut2)``: the main cable's tension ``k_c max(0, p + s - e psi_tip)`` (E 3.11; ``p`` = 0
        with one cable) and the antagonist's ``k_c max(0, p - s + e psi_tip)`` (0 and False without one), N."""
        lead = np.asarray(cable_shortening_m) - self.eccentricity * np.asarray(psi_tip)
        stretch1 = self.cable_pretension_m + lead
        stretch2 = self.cable_pretension_m - lead if self.antagonist else np.full_like(stretch1, -np.inf, dtype=float)
        stretch2 = np.where(np.isneginf(cable_shortening_m), -np.inf, stretch2)  # detached: neither cable pulls
        kc = self.cable_stiffness
        return kc * np.maximum(stretch1, 0.0), kc * np.maximum(stretch2, 0.0), stretch1 > 0, stretch2 > 0

    def cable_tension(self, psi_tip, cable_shortening_m):
        """Compression the cable(s) put on the strip (N), ``T1 + T2``, and whether any cable is taut."""
        t1, t2, taut1, taut2 = self.cable_tensions(psi_tip, cable_shortening_m)
        return t1 + t2, taut1 | taut2

    def _cable_stretches(self, psi_tip: float, shortening: float) -> tuple[float, float]:
        """The two cables' stretch (m) for the dynamics, as floats: ``p + s - e psi_tip`` and ``p - s + e psi_tip``
        (-inf without the antagonist); the single cable's ``s - e psi_tip`` to the bit."""
        lead = shortening - self.eccentricity * psi_tip
        if not self.antagonist:
            return lead, -math.inf
        if shortening == -math.inf:  # detached (the twin's cable=False): neither cable pulls, not the second at +inf
            return -math.inf, -math.inf
        return self.cable_pretension_m + lead, self.cable_pretension_m - lead

    def axial_force(self, psi, g_forces_beyond_ab, tension):
        """Axial force (N, tension +) in the strip at the gauges: ``F_beyond . u - T`` (quasi-static)."""
        psi_g = np.take(psi, self._gauge_take, axis=-1) * self._gauge_on_chain  # 0 on the clamped stretch
        fa, fb = g_forces_beyond_ab[..., 0], g_forces_beyond_ab[..., 1]
        return fa * np.cos(psi_g) + fb * np.sin(psi_g) - np.asarray(tension)[..., None]

    # ------------------------------------------------------------------------------------------------ statics
    def solve_static(
        self,
        load_s_m=None,
        load_force_ab_n=None,
        *,
        tip_force_n=None,
        tip_moment_nm=0.0,
        cable_shortening_m=None,
        psi0=None,
        tol=1e-11,
        max_iter=80,
        max_step_rad=0.35,
        contact=None,
    ) -> StaticSolution:
        """Equilibria of a batch of load cases (batched Newton on the total potential energy's gradient).

        Parameters
        ----------
        load_s_m : array_like, shape (B, K) or (B,), optional
            Arc positions (m from the clamp, in ``[0, length_m]``) of world-fixed point forces (hanging weights),
            ``K`` per case (one when 1-D).
        load_force_ab_n : array_like, shape (B, K, 2), optional
            Those forces in the (a, b) axes (N), finite. Self-weight is always included.
        tip_force_n : array_like, shape (B, 2), optional
            An extra world-fixed force at the tip (N).
        tip_moment_nm : float or array_like, shape (B,)
            A pure moment at the tip (N m), positive towards ``b``.
        cable_shortening_m : array_like, shape (B,), optional
            Motor-side cable shortening ``r_M (theta_M - theta_M0)`` (E 3.11); None: no cable.
        psi0 : array_like, shape (B, n), optional
            Starting angles.
        contact : optional
            A shape-dependent load (:class:`flexdigit.twin.contact.TissueContact`): ``generalized(psi)`` gives its
            generalised forces and their derivatives, ``resultant(psi)`` the force it carries past the gauges.

        Returns
        -------
        StaticSolution

        Raises
        ------
        ParameterError
            A load position outside ``[0, length_m]`` (beyond the tip), a load position without its force (or the
            other way round), a non-finite force, moment, cable shortening or starting angle, or batch sizes that
            disagree.
        ArithmeticError
            If the Newton iteration diverges on valid inputs.

        Warns
        -----
        ConvergenceWarning
            If it has not met ``tol`` after ``max_iter`` iterations: the result says so (``converged=False``).
        """
        owner = "Chain.solve_static"
        load_s_m, load_force_ab_n = self._checked_point_loads(load_s_m, load_force_ab_n, owner)
        tip_force_n, tip_moment_nm, cable_shortening_m, psi0, b = self._checked_static_inputs(
            load_s_m, tip_force_n, tip_moment_nm, cable_shortening_m, psi0, owner
        )
        g, beyond = self._static_loads(b, load_s_m, load_force_ab_n, tip_force_n)
        moment = np.broadcast_to(tip_moment_nm, (b,))
        has_cable = cable_shortening_m is not None and self.cable_stiffness > 0
        short = np.broadcast_to(cable_shortening_m, (b,)) if has_cable else None  # None: no cable
        psi = np.zeros((b, self.n)) if psi0 is None else np.broadcast_to(psi0.reshape(-1, self.n), (b, self.n)).copy()
        scale = max(float(np.max(self.stiffness)), 1e-300)
        psi, iterations, converged, res, biggest = self._static_newton(
            psi, g, moment, short, contact, tol * scale, max_iter, max_step_rad
        )
        if not np.all(np.isfinite(psi)):
            bad = int(np.sum(~np.all(np.isfinite(psi), axis=1)))
            raise ArithmeticError(f"static solve diverged (non-finite angles) in {bad} of {b} load cases")
        if not converged:
            warnings.warn(
                f"{owner}: the Newton iteration did not meet its tolerance in {max_iter} iterations (largest "
                f"residual {np.max(np.abs(res)) / scale:.3g} of the stiffness, last step {np.max(biggest):.3g} rad); "
                "the solution has converged=False",
                ConvergenceWarning,
                stacklevel=2,
            )
        return self._static_solution(psi, beyond, short, contact, iterations, converged)

    def _checked_point_loads(self, load_s_m, load_force_ab_n, owner):
        """``(load_s_m (B, K), load_force_ab_n (B, K, 2))`` checked and shaped, or ``(None, None)``."""
        if (load_s_m is None) != (load_force_ab_n is None):
            given = "load_s_m" if load_force_ab_n is None else "load_force_ab_n"
            raise ParameterError(
                f"The 'load_s_m' and 'load_force_ab_n' parameters of {owner} go together (a position and a force "
                f"per load). Got only '{given}'."
            )
        if load_s_m is None:
            return None, None
        load_s_m = check_values(
            load_s_m,
            "load_s_m",
            owner,
            low=0,
            high=self.length_m,
            unit="m",
            note=f"{self.length_m:g} is the tip: a load beyond the tip is off the chain",
        )
        load_force_ab_n = check_values(load_force_ab_n, "load_force_ab_n", owner, unit="N")
        # (B,) is one load per case, (B, K) K loads per case
        load_s_m = load_s_m.reshape(load_s_m.shape[0], -1) if load_s_m.ndim else load_s_m.reshape(1, 1)
        if load_force_ab_n.size != 2 * load_s_m.size or load_force_ab_n.shape[-1:] != (2,):
            raise ParameterError(
                f"The 'load_force_ab_n' parameter of {owner} must hold an (a, b) force per entry of 'load_s_m' "
                f"(shape {(*load_s_m.shape, 2)}). Got shape {load_force_ab_n.shape} instead."
            )
        return load_s_m, load_force_ab_n.reshape(*load_s_m.shape, 2)

    def _checked_static_inputs(self, load_s_m, tip_force_n, tip_moment_nm, cable_shortening_m, psi0, owner):
        """The other inputs of :meth:`solve_static` checked and shaped, and the batch size ``B`` they agree on."""
        if tip_force_n is not None:
            tip_force_n = check_values(tip_force_n, "tip_force_n", owner, unit="N")
            if tip_force_n.shape[-1:] != (2,) or tip_force_n.ndim > 2:
                raise ParameterError(
                    f"The 'tip_force_n' parameter of {owner} must have shape (B, 2) (an (a, b) force per load case). "
                    f"Got shape {tip_force_n.shape} instead."
                )
            tip_force_n = tip_force_n.reshape(-1, 2)
        tip_moment_nm = check_values(tip_moment_nm, "tip_moment_nm", owner, unit="N m").reshape(-1)
        if cable_shortening_m is not None:
            cable_shortening_m = check_values(cable_shortening_m, "cable_shortening_m", owner, unit="m").reshape(-1)
        sizes = {}
        for name, arr in (
            ("load_s_m", load_s_m),
            ("tip_force_n", tip_force_n),
            ("cable_shortening_m", cable_shortening_m),
            ("tip_moment_nm", tip_moment_nm),
        ):
            if arr is not None and arr.shape[0] != 1:
                sizes[name] = arr.shape[0]
        b = max(sizes.values(), default=1)
        if any(size != b for size in sizes.values()):
            raise ParameterError(
                f"The load cases given to {owner} must agree in number (or be one). Got "
                + ", ".join(f"{size} in '{name}'" for name, size in sizes.items())
                + " instead."
            )
        if psi0 is not None:
            psi0 = check_values(psi0, "psi0", owner, unit="rad")
            if psi0.size not in (self.n, b * self.n):
                raise ParameterError(
                    f"The 'psi0' parameter of {owner} must have shape ({b}, {self.n}) (or ({self.n},) for all "
                    f"cases). Got shape {psi0.shape} instead."
                )
        return tip_force_n, tip_moment_nm, cable_shortening_m, psi0, b

    def _static_loads(self, b, load_s_m, load_force_ab_n, tip_force_n):
        """``(G (B, n, 2), forces beyond each gauge (B, gauges, 2))``: gravity plus the world-fixed point loads."""
        g = np.broadcast_to(self.g_gravity, (b, self.n, 2)).copy()
        beyond = np.broadcast_to(self._mass_beyond_gauge[:, None] * self.gravity, (b, self.gauge_s_m.size, 2)).copy()
        if load_s_m is not None:
            ls = np.broadcast_to(load_s_m, (b, load_s_m.shape[1]))
            lf = np.broadcast_to(load_force_ab_n, (b, load_s_m.shape[1], 2))
            g += self.load_forces(ls, lf)
            beyond += np.einsum("bgk,bkc->bgc", (ls[:, None, :] > self.gauge_s_m[None, :, None]).astype(float), lf)
        if tip_force_n is not None:
            tf = np.broadcast_to(tip_force_n, (b, 2))
            g += self.link_length_m[None, :, None] * tf[:, None, :]
            beyond += tf[:, None, :]
        return g, beyond

    def _static_solution(self, psi, beyond, short, contact, iterations, converged) -> StaticSolution:
        """The :class:`StaticSolution` at the (finite) angles ``psi``: cable tension, gauge curvatures, axial forces."""
        tension = self.cable_tension(psi[:, -1], short)[0] if short is not None else np.zeros(psi.shape[0])
        if contact is not None:
            beyond = beyond + contact.resultant(psi)[3]
        return StaticSolution(
            psi_rad=psi,
            curvature_1_m=self.curvature_at_gauges(psi),
            axial_force_n=self.axial_force(psi, beyond, tension),
            tension_n=tension,
            tip_m=self.tip(psi),
            iterations=iterations,
            converged=converged,
        )

    def _static_newton(self, psi, g, moment, short, contact, res_tol, max_iter, max_step_rad):
        """The batched, step-limited Newton iteration of :meth:`solve_static` from ``psi`` (changed in place).

        ``short`` is the cable shortening (None: no cable); ``res_tol`` the residual tolerance in N m. Returns
        ``(psi, iterations, converged, last residual, last largest step per case)``.
        """
        ga, gb = g[..., 0], g[..., 1]
        e = self.eccentricity
        kc = self.cable_stiffness
        # without a contact the Jacobian is K_psi (tridiagonal: D^T diag(k) D) plus a diagonal: over a batch, a
        # tridiagonal elimination costs ~40 x less than LAPACK's dense solve per case (a tactile grid of 10^4 cases)
        banded = contact is None and psi.shape[0] >= _BANDED_MIN_BATCH and self.n >= _BANDED_MIN_LINKS
        iterations, converged = 0, False
        for iterations in range(1, max_iter + 1):  # noqa: B007 (returned)
            s, c = np.sin(psi), np.cos(psi)
            res = psi @ self.k_psi + s * ga - c * gb
            res[:, -1] -= moment
            diag = np.diagonal(self.k_psi) + (c * ga + s * gb)  # as the dense Jacobian summed it
            if short is not None:
                t1, t2, taut1, taut2 = self.cable_tensions(psi[:, -1], short)
                res[:, -1] -= e * (t1 - t2) if self.antagonist else e * t1
                diag[:, -1] += kc * e * e * (taut1 + taut2.astype(float) if self.antagonist else taut1)
            if banded:
                step = _tridiagonal_solve(self.k_psi, diag, res)
            else:
                jac = _dense_jacobian(self.k_psi, diag)
                if contact is not None:
                    q_contact, dq_contact, _ = contact.generalized(psi)
                    res -= q_contact
                    jac -= dq_contact
                step = np.linalg.solve(jac, res[..., None])[..., 0]
            biggest = np.max(np.abs(step), axis=1, keepdims=True)
            step *= np.minimum(1.0, max_step_rad / np.maximum(biggest, 1e-300))
            psi -= step
            if np.max(np.abs(res)) < res_tol and np.max(biggest) < 1e-9:
                converged = True
                break
        return psi, iterations, converged, res, biggest

    # ----------------------------------------------------------------------------------------------- dynamics
    def linear_modes(self, psi_eq=None, g_extra=None, cable_taut=False):
        """Natural frequencies (rad/s) and damping ratios of the chain linearised about ``psi_eq`` (sorted).

        Uses the tangent stiffness (springs, gravity, taut cable) and the spring dampers.
        """
        import scipy.linalg

        psi = np.zeros(self.n) if psi_eq is None else np.asarray(psi_eq, dtype=float)
        g = self.g_gravity + (0 if g_extra is None else g_extra)
        m = self.a_mass * np.cos(psi[:, None] - psi[None, :])
        k = self.tangent_stiffness(psi, g, cable_taut)
        n = self.n
        a = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(m, k), -np.linalg.solve(m, self.c_psi)]])
        lam = scipy.linalg.eigvals(a)
        lam = lam[lam.imag > 0] if np.any(lam.imag > 0) else lam
        wn = np.abs(lam)
        zeta = -lam.real / wn
        order = np.argsort(wn)
        return wn[order], zeta[order]

    def tangent_stiffness(self, psi, g, cable_taut):
        """``K_psi + diag(cos psi G_a + sin psi G_b) + k_c e^2 [taut]`` (n, n); ``cable_taut`` True or the number
        of taut cables (2 for a pretensioned pair about the straight digit)."""
        k = self.k_psi + np.diag(np.cos(psi) * g[:, 0] + np.sin(psi) * g[:, 1])
        if cable_taut:
            k[-1, -1] += self.cable_stiffness * self.eccentricity**2 * float(cable_taut)
        return k


#: From this many load cases on, the static Newton solves its tridiagonal Jacobians by elimination over the batch
#: (:func:`_tridiagonal_solve`); below it LAPACK's dense solve per case is cheaper than the elimination's n steps.
_BANDED_MIN_BATCH = 16
#: ... and on chains of this many links or more. A shorter chain's dense solves cost little (the thesis rig's 9
#: links: ~0.2 s of its report's tactile chapters), and keep their bits: the elimination rounds differently, and
#: 1-ulp changes in the thesis rig's static volts moved its report's per-position estimator tables by up to 5e-8
#: relative (the inversion's finite differences amplify them; compare.py holds a report to 1e-9).
_BANDED_MIN_LINKS = 12
#: A pivot of the tridiagonal elimination below this fraction of its row's largest diagonal entry: that case is
#: solved again densely (LAPACK, partial pivoting), as an indefinite Jacobian near a fold may need.
_SMALL_PIVOT = 1e-10


def _dense_jacobian(k_psi, diag):
    """The static Newton's Jacobian (B, n, n): ``K_psi`` off the diagonal, ``diag`` (B, n) on it."""
    jac = np.broadcast_to(k_psi, (diag.shape[0], *k_psi.shape)).copy()
    idx = np.arange(k_psi.shape[0])
    jac[:, idx, idx] = diag
    return jac


def _tridiagonal_solve(k_psi, diag, rhs):
    """Solve ``J x = rhs`` for a batch of symmetric tridiagonal ``J``: ``diag`` (B, n) on the diagonal and
    ``K_psi``'s off the diagonal (the same for every case). Elimination without pivoting, vectorised over the
    batch (Thomas' algorithm); a case with a small or non-finite pivot is solved densely instead."""
    off = np.diagonal(k_psi, 1)
    d, r = diag.T.copy(), rhs.T.copy()  # (n, B): each step of the elimination is one contiguous row
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for i in range(1, d.shape[0]):
            f = off[i - 1] / d[i - 1]
            d[i] -= f * off[i - 1]
            r[i] -= f * r[i - 1]
        r[-1] /= d[-1]
        for i in range(d.shape[0] - 2, -1, -1):
            r[i] -= off[i] * r[i + 1]
            r[i] /= d[i]
    x = r.T
    bad = ~(np.min(np.abs(d), axis=0) > _SMALL_PIVOT * np.max(np.abs(diag), axis=1)) | ~np.all(np.isfinite(x), axis=1)
    if np.any(bad):
        x[bad] = np.linalg.solve(_dense_jacobian(k_psi, diag[bad]), rhs[bad][..., None])[..., 0]
    return x


class DynamicState:
    """Integrates the chain's equations of motion with a two-stage L-stable Rosenbrock method (ROS2).

    ``sum_k A_jk [cos(psi_j - psi_k) psi''_k + sin(psi_j - psi_k) psi'_k^2] = Q_j`` (springs, stiffness-
    proportional dampers, world-fixed loads, self-weight, cable). Verwer et al.'s ROS2 (1999),
    ``y+ = y + h (3/2 k1 + 1/2 k2)``, ``W k1 = f(y)``, ``W k2 = f(y + h k1) - 2 k1``, ``W = I - gamma h J``, with
    the exact Jacobian (mass-matrix and Coriolis derivatives included) and ``gamma = 1 - 1/sqrt(2)``: second order
    and L-stable, so the chain's fast cell modes and the stiff cable are quenched rather than left ringing, while
    the slow modes keep their damping: its numerical damping ratio grows like (w h)^3 with a small constant,
    4e-5 for an 11 rad/s mode at the twin's default 20 ms step (1.5 % of the bare digit's 0.0025, 0.06 % of the
    housed 0.068), where the usual ``gamma = 1 + 1/sqrt(2)`` adds ~4 (w h)^3 = 4e-2, far more than the digit's
    own damping (both measured in the tests' set-up). A step costs two
    force evaluations and three LU factorisations (the iteration matrix's solved twice from one).

    Parameters
    ----------
    chain : Chain
    psi, omega : array_like, shape (n,)
        Initial angles (rad) and angular rates (rad/s).
    """

    GAMMA = 1.0 - 1.0 / np.sqrt(2.0)

    def __init__(self, chain: Chain, psi=None, omega=None):
        self.chain = chain
        n = chain.n
        self.psi = np.zeros(n) if psi is None else np.array(psi, dtype=float)
        self.omega = np.zeros(n) if omega is None else np.array(omega, dtype=float)
        self._idx = np.arange(n)
        #: A shape-dependent load (:class:`flexdigit.twin.contact.TissueContact`) or None.
        self.contact = None
        self._kernel = None  # the compiled step, once :meth:`use_compiled` has loaded it
        self.set_loads(None, None)

    @property
    def compiled(self) -> bool:
        """Whether steps go through the compiled kernel (:meth:`use_compiled`; a body beside the digit aside)."""
        return self._kernel is not None

    def use_compiled(self, *, background: bool = False):
        """Step from now on with the batched twin's compiled kernel (:mod:`flexdigit.twin._batched_kernel`), for
        one rig: the same ROS2 step and step halving in machine code, ~20 x less CPU than numpy's small-array
        dispatch (what the live page's twin spends its time on).

        It rounds differently (unpivoted LU, ``cos(psi_j - psi_k)`` from products): within 1e-9 rad of the numpy
        path (``tests/twin/test_compiled_dynamics.py``), so it is opt-in: the wall-clock ``sim+paced`` backend,
        and the report's tactile collections (``tactile.thesis_experiments.twin_rig``), whose readings the ADC's
        quantum leaves bit for bit the numpy twin's (``tests/tactile/test_thesis_experiments.py``). A body beside
        the digit (:attr:`contact`) is stepped in numpy. The kernel is compiled on its first use on a machine (~10 s),
        loaded from numba's cache after that (~1 s, numba's import included).

        Parameters
        ----------
        background : bool
            Load the kernel in a thread of its own and keep stepping in numpy until it is ready (returns the
            thread); else load it now.
        """
        if not background:
            self._load_kernel()
            return None
        import threading

        thread = threading.Thread(target=self._load_kernel, name="flexdigit-twin-compile", daemon=True)
        thread.start()
        return thread

    def _load_kernel(self) -> None:
        from flexdigit.twin._batched_kernel import advance_rigs

        args = self._kernel_args()
        # no steps: compiles (or loads from the cache) for these argument types without touching the state
        advance_rigs(np.zeros((1, self.chain.n)), np.zeros((1, self.chain.n)), np.zeros((1, 1)), 0.0, *args)
        self._kernel = advance_rigs

    def _kernel_args(self) -> tuple:
        """The chain and its loads as :func:`~flexdigit.twin._batched_kernel.advance_rigs` takes them (one rig)."""
        ch = self.chain
        coupled = (ch.k_psi != 0) | (ch.c_psi != 0)
        rows, cols = np.nonzero(coupled)
        bandwidth = int(np.max(np.abs(rows - cols))) if rows.size else 0
        one = np.ones(1)
        return (
            self._a[None].copy(), ch.k_psi[None].copy(), ch.c_psi[None].copy(), bandwidth,
            self._ga[None].copy(), self._gb[None].copy(), ch.eccentricity * one, ch.cable_stiffness * one,
            ch.cable_pretension_m * one, np.full(1, ch.antagonist), self.MAX_ROTATION_PER_STEP_RAD, 0, 1,
            np.zeros(1, dtype=np.int64),
        )  # fmt: skip

    def set_loads(self, load_s_m, load_mass_kg, force_s_m=None, force_ab_n=None):
        """Hang weights (kg) at arc positions (m): they add mass and weight; None clears them. World-fixed forces
        ``force_ab_n`` (K, 2) at arc positions ``force_s_m`` (K,) (presses, :mod:`flexdigit.twin.contact`) add
        their load only."""
        ch = self.chain
        a = ch.a_mass.copy()
        g = ch.g_gravity.copy()
        beyond = ch._mass_beyond_gauge[:, None] * ch.gravity
        if load_s_m is not None and np.size(load_s_m):
            s = np.asarray(load_s_m, dtype=float).reshape(-1)
            m = np.asarray(load_mass_kg, dtype=float).reshape(-1)
            lever = ch.levers(s)
            a += lever.T @ (m[:, None] * lever)
            g += lever.T @ (m[:, None] * ch.gravity[None, :])
            beyond = beyond + ((s[None, :] > ch.gauge_s_m[:, None]) @ m)[:, None] * ch.gravity
        if force_s_m is not None and np.size(force_s_m):
            fs = np.asarray(force_s_m, dtype=float).reshape(-1)
            fab = np.asarray(force_ab_n, dtype=float).reshape(-1, 2)
            g = g + ch.load_forces(fs, fab)
            beyond = beyond + (fs[None, :] > ch.gauge_s_m[:, None]).astype(float) @ fab
        self._a = a
        self._g = g
        self._ga, self._gb = g[:, 0].copy(), g[:, 1].copy()
        self._beyond = beyond
        self._compiled_args = None  # rebuilt for the new loads at the next compiled step

    def _rhs(self, psi, omega, shortening):
        """Mass matrix, ``sin``-weighted A, ``M alpha = Q - N`` and the cable's state at a point."""
        ch = self.chain
        s, c = np.sin(psi), np.cos(psi)
        delta = psi[:, None] - psi[None, :]
        m = self._a * np.cos(delta)
        sm = self._a * np.sin(delta)
        rhs = c * self._gb - s * self._ga - ch.k_psi @ psi - ch.c_psi @ omega - sm @ (omega * omega)
        stretch1, stretch2 = ch._cable_stretches(psi[-1], shortening)
        taut = int(stretch1 > 0) + int(stretch2 > 0)  # taut cables: each pulls the tip with k_c e^2 of stiffness
        if taut:
            rhs[-1] += ch.eccentricity * ch.cable_stiffness * (max(stretch1, 0.0) - max(stretch2, 0.0))
        if self.contact is not None:
            q_contact, self._dq_psi, self._dq_omega = self.contact.generalized(psi[None], omega[None])
            rhs = rhs + q_contact[0]
        return m, sm, rhs, s, c, taut

    #: A step is halved (recursively) when it would turn any link faster than this many radians per step: the
    #: linearisation behind a Rosenbrock step holds for small rotations per step, and a sudden cable pull sets the
    #: fast cell modes moving that the default step does not resolve. Quiet motion never trips it.
    MAX_ROTATION_PER_STEP_RAD = 0.1

    def step(self, h: float, shortening0: float, shortening1: float, _depth: int = 0) -> None:
        """Advance by ``h`` seconds; the cable shortening goes linearly from ``shortening0`` to ``shortening1`` (m).

        Halves the step while a step would rotate a link by more than :attr:`MAX_ROTATION_PER_STEP_RAD`.
        """
        if self._kernel is not None and self.contact is None:
            self.step_run(h, (shortening0, shortening1))
            return
        psi0, omega0 = self.psi, self.omega
        self._ros2(h, shortening0, shortening1)
        # ndarray methods, not np.max/np.all: their dispatch was a tenth of a 35-spring step
        fast = h * max(np.abs(omega0).max(), np.abs(self.omega).max()) > self.MAX_ROTATION_PER_STEP_RAD
        if (fast or not np.isfinite(self.omega).all()) and _depth < 12:
            self.psi, self.omega = psi0, omega0
            mid = 0.5 * (shortening0 + shortening1)
            self.step(0.5 * h, shortening0, mid, _depth + 1)
            self.step(0.5 * h, mid, shortening1, _depth + 1)
        elif not np.isfinite(self.psi).all():
            raise ArithmeticError("the digit dynamics diverged (non-finite angles)")

    def step_run(self, h: float, shortenings) -> None:
        """:meth:`step` ``len(shortenings) - 1`` times, the cable shortening (m) going linearly between successive
        ``shortenings``: in one call of the compiled kernel when it is in use."""
        if self._kernel is None or self.contact is not None:
            for s0, s1 in zip(shortenings[:-1], shortenings[1:], strict=True):
                self.step(h, s0, s1)
            return
        if self._compiled_args is None:
            self._compiled_args = self._kernel_args()
        psi, omega = self.psi[None].copy(), self.omega[None].copy()
        short = np.array(shortenings, dtype=float).reshape(-1, 1)
        if self._kernel(psi, omega, short, h, *self._compiled_args) >= 0:
            raise ArithmeticError("the digit dynamics diverged (a singular matrix, or non-finite angles)")
        self.psi, self.omega = psi[0], omega[0]

    def _ros2(self, h: float, shortening0: float, shortening1: float) -> None:
        ch = self.chain
        idx = self._idx
        psi, omega = self.psi, self.omega
        gam = self.GAMMA
        gh = gam * h
        m, sm, rhs, s, c, taut = self._rhs(psi, omega, shortening0)
        alpha = _solve(m, rhs)
        w2 = omega * omega
        # Jacobians of F = M alpha + N(psi, omega) - Q(psi, omega)
        f_psi = sm * alpha - m * w2 + ch.k_psi
        f_psi[idx, idx] += -(sm @ alpha) + (m @ w2) + c * self._ga + s * self._gb
        # dQ/dt of the cable (its shortening is linear in t over the step): the non-autonomous ROS2 terms
        q_t = np.zeros(ch.n)
        if taut:  # per taut cable: -d(e (T1 - T2))/dpsi_tip = k_c e^2 and d/ds = k_c e (both cables' signs agree)
            f_psi[-1, -1] += ch.cable_stiffness * ch.eccentricity**2 * taut
            q_t[-1] = ch.eccentricity * ch.cable_stiffness * taut * (shortening1 - shortening0) / h
        f_omega = (2.0 * sm) * omega + ch.c_psi
        if self.contact is not None:  # F = M alpha + N - Q: the contact's Q enters with a minus
            f_psi = f_psi - self._dq_psi[0]
            if self._dq_omega is not None:
                f_omega = f_omega - self._dq_omega[0]
        iteration = m + gh * f_omega + (gh * gh) * f_psi
        # stage 1: W k1 = f(y) + gamma h f_t, in the M-scaled block form (see the module docstring)
        factors = _factor(iteration)  # solved twice: factored once
        b1 = _solve_factored(factors, rhs + gh * q_t - gh * (f_psi @ omega))
        a1 = omega + gh * b1
        # stage 2: W k2 = f(y + h k1) - 2 k1 - gamma h f_t
        psi2, omega2 = psi + h * a1, omega + h * b1
        m2, _, rhs2, _, _, _ = self._rhs(psi2, omega2, shortening1)
        alpha2 = _solve(m2, rhs2)
        r1 = omega2 - 2.0 * a1
        b2 = _solve_factored(factors, m @ (alpha2 - 2.0 * b1) - gh * q_t - gh * (f_psi @ r1))
        a2 = r1 + gh * b2
        self.psi = psi + h * (1.5 * a1 + 0.5 * a2)
        self.omega = omega + h * (1.5 * b1 + 0.5 * b2)
        self.alpha = alpha

    def tension(self, shortening: float) -> float:
        """Cable tension (N) at the current angles."""
        return float(self.chain.cable_tension(self.psi[-1], shortening)[0])

    def axial_force(self, shortening: float) -> np.ndarray:
        """Quasi-static axial force at the gauges (N, tension +)."""
        return self.chain.axial_force(self.psi, self.beyond(), self.tension(shortening))

    def beyond(self, psi=None) -> np.ndarray:
        """Force carried past each gauge (G, 2): weights, presses and, at angles ``psi`` (default now), contact."""
        if self.contact is None:
            return self._beyond
        return self._beyond + self.contact.resultant((self.psi if psi is None else psi)[None])[3][0]


def uniform_cells(start_m: float, end_m: float, n_cells: int):
    """Mid-points and length of ``n_cells`` equal cells on [start, end]."""
    n_cells = check_int(n_cells, "n_cells", "uniform_cells", low=1, high=10_000)
    h = (end_m - start_m) / n_cells
    return start_m + h * (np.arange(n_cells) + 0.5), np.full(n_cells, h)


def _uniform(length_m, ei_n_m2, n_cells, mass_per_length_kg_m=0.0, damping_ratio_beta_s=0.0, gravity=(0.0, 0.0)):
    s, h = uniform_cells(0.0, length_m, n_cells)
    k = ei_n_m2 / h
    link_edges = np.append(s, length_m)
    link_len = np.diff(link_edges)
    centres = s + 0.5 * link_len
    mass = mass_per_length_kg_m * link_len
    inertia = mass * link_len**2 / 12.0
    # the first half cell is clamped: its mass never moves
    return Chain(
        length_m,
        s,
        k,
        damping_ratio_beta_s * k,
        h,
        centres,
        mass,
        inertia,
        gauge_s_m=(),
        gravity_ab_m_s2=gravity,
    )


def _chain_uniform(
    length_m: float,
    ei_n_m2: float,
    n_cells: int,
    mass_per_length_kg_m: float = 0.0,
    beta_s: float = 0.0,
    gravity_ab_m_s2=(0.0, 0.0),
) -> Chain:
    """A uniform clamped strip: ``n_cells`` cells, distributed mass as rigid-bar links (for validation)."""
    check_positive(length_m, "length_m", "Chain.uniform")
    check_positive(ei_n_m2, "ei_n_m2", "Chain.uniform")
    check_real(mass_per_length_kg_m, "mass_per_length_kg_m", "Chain.uniform", low=0)
    if not np.isfinite(beta_s) or beta_s < 0:
        raise ParameterError(f"The 'beta_s' parameter of Chain.uniform must be >= 0. Got {beta_s!r} instead.")
    return _uniform(length_m, ei_n_m2, n_cells, mass_per_length_kg_m, beta_s, gravity_ab_m_s2)


Chain.uniform = staticmethod(_chain_uniform)


def default_cells(geometry) -> tuple[int, ...]:
    """Cells per section of the default resolution: ``ceil(l_k / MAX_CELL_LENGTH_M)``, at least
    ``MIN_CELLS_PER_SECTION`` and odd, for each section's free strip ``l_k`` (``Geometry.section_bounds_m``,
    unequal sections too). The thesis rig's 80 mm sections: ``(3, 3, 3)``. A description's ``[twin]`` table
    may ask for another (:func:`flexdigit.params.twin_cells`, what the builders take).

    >>> from flexdigit.params import RigParams
    >>> default_cells(RigParams().geometry)
    (3, 3, 3)
    """
    return cells_no_longer_than(geometry, MAX_CELL_LENGTH_M)


def section_cells(geometry, cells_per_section=None, owner: str = "build_digit") -> tuple[int, ...]:
    """Cells of each section: :func:`default_cells` for None, one int for every section, or one per section
    (:func:`digit_arrays` passes a description's own, :func:`flexdigit.params.twin_cells`, for None)."""
    nsec = geometry.section_count
    if cells_per_section is None:
        return default_cells(geometry)
    if np.ndim(cells_per_section) == 0:
        return (check_int(cells_per_section, "cells_per_section", owner, low=1, high=1000),) * nsec
    cells = tuple(cells_per_section)
    if len(cells) != nsec:
        raise ParameterError(
            f"The 'cells_per_section' parameter of {owner} must be one count or {nsec} (one per section). "
            f"Got {list(cells)!r} instead."
        )
    return tuple(check_int(c, "cells_per_section", owner, low=1, high=1000) for c in cells)


def build_digit(
    params,
    calibration,
    *,
    housing: bool = True,
    orientation: str = "vertical",
    cells_per_section=None,
) -> Chain:
    """The thesis digit as a :class:`Chain` (2.2, table 3.5, table 3.7).

    Each of the ``section_count`` sections is ``section_pitch_m`` long (90 mm): a flexible strip of
    ``strip_length_m / section_count`` (80 mm) between rigid nylon supports, half a support (5 mm) at each end, so
    the supports sit at 0, 90, 180, 270 mm and the gauges (45, 135, 225 mm) midway on the strip. Sections of
    unequal lengths are laid out by ``Geometry.section_bounds_m`` and ``support_centres_m``. The flexible part
    of section ``k`` has ``EI = E I_strip + housing_ei_n_m2[k]`` (with ``housing``), cut into ``cells_per_section``
    cells (:func:`default_cells`: no longer than ``MAX_CELL_LENGTH_M``, odd, so a mid-section gauge falls on a
    spring). Masses: the strip (rigid-bar links, density from params), the support masses at 90, 180, 270 mm and
    the housing mass spread on the sections. Damping is stiffness-proportional:
    ``c = beta_strip k_strip + beta_housing k_housing``.

    Parameters
    ----------
    params : RigParams
    calibration : Calibration
        Support masses, housing stiffness/mass, damping, cable stiffness (see :mod:`flexdigit.twin.calibration`).
    housing : bool
        With the elastomer housing (table 3.2) or the bare strip (table 3.1).
    orientation : {"vertical", "hanging", "horizontal"}
    cells_per_section : int, sequence of int or None
        Springs per section (one count for all, or one per section); None: the description's own
        (:func:`flexdigit.params.twin_cells`: its ``[twin]`` table, else :func:`default_cells`, cells no longer
        than ``MAX_CELL_LENGTH_M``).
    """
    return Chain(
        **digit_arrays(
            params, calibration, housing=housing, orientation=orientation, cells_per_section=cells_per_section
        )
    )


def digit_arrays(
    params, calibration, *, housing: bool = True, orientation: str = "vertical", cells_per_section=None
) -> dict:
    """The keyword arguments of :func:`build_digit`'s :class:`Chain`: springs, cells, masses, gauges, gravity, cable
    (for chains stacked without building each one, :meth:`flexdigit.twin.batched.BatchedChains.from_rigs`)."""
    check_choice(orientation, "orientation", tuple(ORIENTATIONS), "build_digit")
    geo, mat = params.geometry, params.material
    # None: the description's own resolution ([twin], else the default), so every builder honours a user's setting
    cells = twin_cells(params) if cells_per_section is None else section_cells(geo, cells_per_section)
    nsec = geo.section_count
    bounds = geo.section_bounds_m  # each section's free strip (unequal sections too)
    ei_strip = mat.youngs_modulus_pa * geo.second_moment_m4
    housing_ei = np.asarray(calibration.housing_ei_n_m2, dtype=float)
    if housing_ei.size != nsec:
        raise ParameterError(
            f"The 'housing_ei_n_m2' parameter of Calibration must have {nsec} values (one per section). "
            f"Got {housing_ei.tolist()!r} instead."
        )
    s_list, h_list, k_strip, k_house = [], [], [], []
    for k in range(nsec):
        s, h = uniform_cells(*bounds[k], cells[k])
        s_list.append(s)
        h_list.append(h)
        k_strip.append(ei_strip / h)
        k_house.append((housing_ei[k] if housing else 0.0) / h)
    s = np.concatenate(s_list)
    h = np.concatenate(h_list)
    ks, kh = np.concatenate(k_strip), np.concatenate(k_house)
    stiffness = ks + kh
    damping = calibration.strip_beta_s * ks + (calibration.housing_beta_s * kh if housing else 0.0)
    length = geo.digit_length_m
    link_len = np.diff(np.append(s, length))
    mu = mat.strip_density_kg_m3 * geo.cross_section_m2
    mass_s = [s + 0.5 * link_len]
    mass_kg = [mu * link_len]
    inertia = [mu * link_len**3 / 12.0]
    supports = np.asarray(calibration.support_mass_kg, dtype=float)
    if supports.size != nsec:
        raise ParameterError(
            f"The 'support_mass_kg' parameter of Calibration must have {nsec} values (supports at "
            f"{[round(c, 4) for c in geo.support_centres_m]} m). Got {supports.tolist()!r} instead."
        )
    mass_s.append(np.asarray(geo.support_centres_m))  # the tip support's centre never past the tip
    mass_kg.append(supports)
    inertia.append(np.zeros(nsec))
    if housing and calibration.housing_mass_kg > 0:
        mass_s.append(s)
        if geo.equal_sections:  # every cell equally long: the same share each (as ever, to the bit)
            mass_kg.append(np.full(s.size, calibration.housing_mass_kg / s.size))
        else:  # a cell's share of the housing is its share of the strip: a longer section carries more
            mass_kg.append(calibration.housing_mass_kg * h / h.sum())
        inertia.append(np.zeros(s.size))
    g = np.asarray(ORIENTATIONS[orientation]) * G_STANDARD_M_S2
    return {
        "length_m": length,
        "joint_s_m": s,
        "joint_stiffness_nm_rad": stiffness,
        "joint_damping_nms_rad": damping,
        "cell_length_m": h,
        "mass_s_m": np.concatenate(mass_s),
        "mass_kg": np.concatenate(mass_kg),
        "mass_inertia_kg_m2": np.concatenate(inertia),
        "gauge_s_m": geo.gauge_positions_m,
        "gravity_ab_m_s2": g,
        "cable_eccentricity_m": geo.cable_eccentricity_m,
        "cable_stiffness_n_m": calibration.cable_stiffness_n_m,
        "strip_axial_stiffness_n": mat.youngs_modulus_pa * geo.cross_section_m2,
        "cable_pretension_n": params.cables.pretension_n if params.cables.count == 2 else 0.0,
        "antagonist": params.cables.count == 2,
    }
