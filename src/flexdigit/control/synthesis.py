"""H-infinity synthesis by two independent routes (thesis 4.4).

* :func:`hinf_riccati`: the Glover-Doyle Riccati solution (SLICOT ``SB10AD`` through slycot): bisection for the
  optimal ``gamma`` from a known feasible upper bound, then the central controller at
  ``gamma = (1 + margin) gamma_opt``. It needs a regular problem (``D12`` full column rank, ``D21`` full row rank):
  regularise the thesis's singular problem first (:func:`flexdigit.control.generalized.regularise`).
* :func:`hinf_lmi`: the Gahinet-Apkarian bounded-real-lemma LMIs (cvxpy), which need no rank conditions and
  give the optimal ``gamma`` of the same (or the singular) problem.

Both routes scale the problem first (state balancing, and the control and measurement channels normalised)
because the thesis plant gives ~1e-3 m per command and its controllers ~1e5 commands per m.

Convention: python-control/SLICOT ``u = K y`` on the generalized plant (for the thesis ``P``, ``y = w - G u``
so ``K`` sits in an ordinary negative-feedback loop).
"""

from __future__ import annotations

import math
import threading
import warnings
from dataclasses import dataclass
from numbers import Integral, Real

import control as ct
import numpy as np
import scipy.linalg

from flexdigit._repr import summary
from flexdigit._validation import Array, Interval, NoValidation, Options, validate_params
from flexdigit.control._threads import single_blas_thread
from flexdigit.control.generalized import as_statespace, regularise, regularise_matrices
from flexdigit.errors import DesignError

__all__ = [
    "HinfDesign",
    "LmiResult",
    "hinf_riccati",
    "hinf_lmi",
    "regularisation_path",
    "reduce_controller",
    "hinfsyn_plain",
]


@dataclass(frozen=True)
class HinfDesign:
    """The result of an H-infinity synthesis.

    Attributes
    ----------
    controller : StateSpace
        ``K(s)`` from the measurement ``y`` to the control ``u`` (commands per output unit), ``u = K y``.
    gamma : float
        The level the central controller was built for, ``(1 + margin) * gamma_opt``.
    gamma_opt : float
        The optimal (infimal) ``gamma`` found by bisection, to ``gtol``.
    margin : float
        Relative sub-optimality of ``gamma``.
    achieved : float
        ``||T_zw||_inf`` of the closed loop with ``controller`` (<= ``gamma``).
    closed_loop : StateSpace
        ``T_zw`` (all performance outputs from all exogenous inputs).
    method : str
        ``"riccati"``.
    """

    controller: ct.StateSpace
    gamma: float
    gamma_opt: float
    margin: float
    achieved: float
    closed_loop: ct.StateSpace
    method: str = "riccati"

    def __repr__(self) -> str:
        return summary(
            self,
            method=self.method,
            gamma=self.gamma,
            gamma_opt=self.gamma_opt,
            achieved=self.achieved,
            controller_order=self.controller.nstates,
            closed_loop_order=self.closed_loop.nstates,
        )


@dataclass(frozen=True)
class LmiResult:
    """Optimal ``gamma`` from the Gahinet-Apkarian LMIs, with the solver's matrices (scaled coordinates)."""

    gamma: float
    R: np.ndarray
    S: np.ndarray
    status: str
    solver: str

    def __repr__(self) -> str:
        return summary(self, gamma=self.gamma, status=self.status, solver=self.solver, order=self.R.shape[0])


@dataclass(frozen=True)
class _Scaling:
    """Similarity ``x = T x_s`` and channel scalings ``u = su u_s``, ``y_s = sy y``."""

    T: np.ndarray
    su: np.ndarray
    sy: np.ndarray


def _partition(P, nmeas, ncon):
    nw, nz = P.ninputs - ncon, P.noutputs - nmeas
    if nw < 1 or nz < 1 or nmeas < 1 or ncon < 1:
        raise DesignError(
            f"The generalized plant has {P.ninputs} inputs and {P.noutputs} outputs: too few for "
            f"ncon={ncon} and nmeas={nmeas} plus at least one exogenous input and one performance output."
        )
    return nw, nz


def _scale(P, nmeas: int, ncon: int):
    """Balance the states and normalise the u and y channels; ``gamma`` is unchanged (w and z untouched)."""
    nw, nz = _partition(P, nmeas, ncon)
    A, B, C, D, scaling = _scale_matrices(P.A, P.B, P.C, P.D, nw, nz)
    return ct.ss(A, B, C, D), scaling


def _scale_matrices(A, B, C, D, nw: int, nz: int):
    """:func:`_scale` on bare matrices: ``(A, B, C, D, scaling)``."""
    A, B, C, D = (np.asarray(M, float) for M in (A, B, C, D))
    n = A.shape[0]
    # scipy's balancing (LAPACK gebal) on the whole system matrix equalises row and column norms; keep its
    # state part only, a similarity that leaves every transfer function as it was.
    M = np.block([[A, B], [C, D]]) if B.shape[1] == C.shape[0] else None
    if M is not None:
        _, (d, _) = scipy.linalg.matrix_balance(M, permute=False, separate=True)
        t = d[:n]
    else:
        _, (t, _) = scipy.linalg.matrix_balance(A, permute=False, separate=True)
    T = np.diag(t)
    Ti = np.diag(1 / t)
    A, B, C = Ti @ A @ T, Ti @ B, C @ T
    B2 = np.vstack([B[:, nw:], D[:nz, nw:]])
    C2 = np.hstack([C[nz:], D[nz:, :nw]])
    su = 1 / np.maximum(np.linalg.norm(B2, axis=0), 1e-300)
    sy = 1 / np.maximum(np.linalg.norm(C2, axis=1), 1e-300)
    B = B.copy()
    C = C.copy()
    D = D.copy()
    B[:, nw:] *= su
    D[:, nw:] *= su
    C[nz:] *= sy[:, None]
    D[nz:] *= sy[:, None]
    return A, B, C, D, _Scaling(T, su, sy)


def _unscale_controller(Ks: ct.StateSpace, sc: _Scaling) -> ct.StateSpace:
    # u = su u_s, y_s = sy y:  K = diag(su) K_s diag(sy)
    return ct.ss(Ks.A, Ks.B * sc.sy[None, :], sc.su[:, None] * Ks.C, sc.su[:, None] * Ks.D * sc.sy[None, :])


def _sb10ad(P, nmeas, ncon, gamma, job, gtol=0.0):
    from slycot import sb10ad

    n, m, p = P.nstates, P.ninputs, P.noutputs
    try:
        return sb10ad(n, m, p, ncon, nmeas, gamma, P.A, P.B, P.C, P.D, job=job, gtol=gtol)
    except Exception as exc:  # slycot raises SlycotArithmeticError/ValueError with SLICOT's info code
        text = str(exc).strip().splitlines()
        raise DesignError(
            f"H-infinity Riccati synthesis failed at gamma={gamma:.6g}: {text[-1] if text else exc!r}. "
            "Is the problem regular (D12 full column rank, D21 full row rank; see regularise()) and gamma feasible?"
        ) from exc


def _check_regular(P, nmeas, ncon):
    nw, nz = _partition(P, nmeas, ncon)
    D12 = np.asarray(P.D)[:nz, nw:]
    D21 = np.asarray(P.D)[nz:, :nw]
    if np.linalg.matrix_rank(D12) < ncon:
        raise DesignError(
            "The Riccati route needs D12 of full column rank; got D12 = "
            f"{np.round(D12, 12).tolist()} (nothing weights the control signal: the singular problem of thesis "
            "4.4). Regularise it with regularise(P, eps_u) or use hinf_lmi()."
        )
    if np.linalg.matrix_rank(D21) < nmeas:
        raise DesignError(
            f"The Riccati route needs D21 of full row rank; got D21 = {np.round(D21, 12).tolist()}. "
            "Regularise it with regularise(P, eps_u, eps_noise) or use hinf_lmi()."
        )


def _upper_gamma(Ps, nmeas, ncon):
    """A feasible starting level: ||P11|| (K = 0 achieves it) when P is stable, else a large number."""
    nw, nz = _partition(Ps, nmeas, ncon)
    if Ps.nstates and np.max(np.linalg.eigvals(Ps.A).real) < 0:
        P11 = ct.ss(Ps.A, Ps.B[:, :nw], Ps.C[:nz], Ps.D[:nz, :nw])
        return 1.05 * float(ct.linfnorm(P11)[0]) + 1e-12
    return 1e12


#: The partition of a generalized plant: measurements and control inputs (declared once, for every route).
_PARTITION = {"P": [NoValidation()], "nmeas": [Interval(Integral, 1, None)], "ncon": [Interval(Integral, 1, None)]}
_POSITIVE = Interval(Real, 0, None, closed="neither")


@validate_params(
    _PARTITION
    | {
        "gamma": [_POSITIVE, None],
        "margin": [Interval(Real, 0, None)],
        "gtol": [Interval(Real, 0, 0.5, closed="right")],
        "gamma_opt": [_POSITIVE, None],
    },
    error=DesignError,
)
def hinf_riccati(
    P,
    nmeas: int = 1,
    ncon: int = 1,
    *,
    gamma: float | None = None,
    margin: float = 0.0,
    gtol: float = 1e-4,
    gamma_opt: float | None = None,
) -> HinfDesign:
    """Riccati-based H-infinity synthesis with ``gamma`` iteration (thesis 4.4; MATLAB ``hinfric``).

    Parameters
    ----------
    P : StateSpace
        Regular generalized plant, inputs ``[w; u]``, outputs ``[z; y]`` (last ``ncon`` / ``nmeas``).
    nmeas, ncon : int
        Number of measurements and control inputs.
    gamma : float, optional
        Build the central controller at this level instead of ``(1 + margin) gamma_opt``; raises
        :class:`DesignError` if it is below the optimum (infeasible).
    margin : float
        Relative sub-optimality of the central controller, ``>= 0``. At ``margin = 0`` the controller is the
        one of the last feasible bisection step, typically with one very fast pole (the optimum is singular).
    gtol : float
        Relative accuracy of the ``gamma`` bisection.
    gamma_opt : float, optional
        A known optimum of this very problem (from an earlier call): skips the bisection, for sweeps over
        ``margin``.

    Returns
    -------
    HinfDesign

    Examples
    --------
    >>> import control as ct
    >>> from flexdigit.control.generalized import filter_weight, regularise, thesis_generalized_plant
    >>> P = regularise(thesis_generalized_plant(ct.tf([1.0], [1.0, 1.0]), filter_weight(1.0)), 0.1)
    >>> d = hinf_riccati(P, margin=0.05)
    >>> d.achieved <= d.gamma
    True
    """
    with single_blas_thread():
        return _riccati_design(P, nmeas, ncon, gamma, margin, gtol, gamma_opt)


def _riccati_design(P, nmeas, ncon, gamma, margin, gtol, gamma_opt) -> HinfDesign:
    P = as_statespace(P, "P", siso=False)
    _check_regular(P, nmeas, ncon)
    Ps, sc = _scale(P, nmeas, ncon)
    out, gamma_opt, level = _central_solution(Ps, nmeas, ncon, gamma, margin, gtol, gamma_opt)
    Ks = ct.ss(out[1], out[2], out[3], out[4])
    K = _unscale_controller(Ks, sc)
    CL = ct.ss(out[5], out[6], out[7], out[8])
    achieved = float(ct.linfnorm(CL)[0])
    return HinfDesign(K, float(level), gamma_opt, float(level / gamma_opt - 1), achieved, CL)


def _central_solution(Ps, nmeas, ncon, gamma, margin, gtol, gamma_opt):
    """SLICOT's central controller for the scaled plant ``Ps``: ``(sb10ad's output, gamma_opt, level)``;
    :class:`DesignError` if the level is infeasible or the controller does not stabilise the plant."""
    if gamma_opt is None:
        g_up = _upper_gamma(Ps, nmeas, ncon)
        out = _sb10ad(Ps, nmeas, ncon, g_up, job=1, gtol=gtol)
        gamma_opt = float(out[0])
    else:
        out = None
    if gamma is not None:
        level = gamma
        if level < gamma_opt * (1 - 2 * gtol):
            raise DesignError(
                f"The 'gamma' parameter of hinf_riccati must be feasible: >= the optimum {gamma_opt:.6g} "
                f"(to {gtol:g}). Got {level!r} instead."
            )
        level = max(level, gamma_opt)
    else:
        level = gamma_opt * (1 + margin)
    if out is None or level != gamma_opt:
        out = _sb10ad(Ps, nmeas, ncon, level, job=4)
    A_cl = np.asarray(out[5])
    if A_cl.size and np.max(np.linalg.eigvals(A_cl).real) >= 0:
        raise DesignError(f"The central controller at gamma={level:.6g} does not stabilise the plant.")
    return out, gamma_opt, level


def central_controller_poles(P_singular, eps_u: float, margin: float, gamma_opts: dict | None = None) -> np.ndarray:
    """The poles of ``hinf_riccati(regularise(P_singular, eps_u), margin=margin).controller`` (rad/s), unsorted.

    The same SLICOT calls on the same matrices, without the python-control systems, the achieved norm and the
    argument checks around them (a fourth of the time): for searches that try hundreds of ``(eps_u, margin)``
    (:func:`~flexdigit.control.thesis_designs.fit_thesis_regularisation`). SISO partition; ``margin >= 0``.
    ``gamma_opts`` (``{eps_u: gamma_opt}``, filled as it goes) skips the bisection for an ``eps_u`` seen before,
    as ``hinf_riccati(..., gamma_opt=...)`` does.
    """
    P = as_statespace(P_singular, "P_singular", siso=False)
    abcd = regularise_matrices(P.A, P.B, P.C, P.D, P.ninputs - 1, P.noutputs - 1, eps_u)
    Pr = _Matrices(*abcd)
    _check_regular(Pr, 1, 1)
    A, B, C, D, _ = _scale_matrices(*abcd, Pr.ninputs - 1, Pr.noutputs - 1)
    # at margin 0 the design is the bisection's own last controller, so only a margin > 0 may skip it
    known = None if gamma_opts is None or margin == 0 else gamma_opts.get(eps_u)
    with single_blas_thread():
        out, gamma_opt, _ = _central_solution(_Matrices(A, B, C, D), 1, 1, None, margin, 1e-4, known)
    if gamma_opts is not None:
        gamma_opts[eps_u] = gamma_opt
    return np.linalg.eigvals(out[1]) if np.size(out[1]) else np.array([])


@dataclass(frozen=True)
class _Matrices:
    """A state-space plant as bare matrices: what SLICOT's wrappers read (``ct.ss`` costs ~0.2 ms to build)."""

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray

    @property
    def nstates(self) -> int:
        return self.A.shape[0]

    @property
    def ninputs(self) -> int:
        return self.B.shape[1]

    @property
    def noutputs(self) -> int:
        return self.C.shape[0]


def hinfsyn_plain(P, nmeas: int = 1, ncon: int = 1):
    """``control.hinfsyn`` as it is (no scaling, SLICOT's own gamma search from 1e100): the benchmark's peer."""
    return ct.hinfsyn(P, nmeas, ncon)


def _lmi_coordinates(P, nmeas, ncon, nz):
    """``(Ps, zscale)``: ``P`` scaled, ``z`` divided by ``zscale`` (optimum ``gamma`` O(1)), balanced if stable."""
    Ps, _ = _scale(P, nmeas, ncon)
    # gamma scale: normalise z so that the optimum is O(1) (the thesis problem has gamma ~ 0.02)
    zscale = _upper_gamma(Ps, nmeas, ncon) / 1.05 if Ps.nstates else 1.0
    if not (math.isfinite(zscale) and 0 < zscale < 1e11):
        zscale = 1.0
    C, D = np.array(Ps.C), np.array(Ps.D)
    C[:nz] /= zscale
    D[:nz] /= zscale
    Ps = ct.ss(Ps.A, Ps.B, C, D)
    if Ps.nstates and np.max(np.linalg.eigvals(Ps.A).real) < 0:
        Ps = _balanced(Ps)
    return Ps, zscale


def _lmi_rounds(Ps, nw, nz, solver, strict, iterations, centre_margin):
    """The best ``LmiResult`` of at most ``iterations`` (minimise, centre, re-coordinate) rounds (:func:`hinf_lmi`)."""
    best, stalled = None, 0
    for _ in range(iterations):
        try:
            res, viol = _lmi_once(Ps, nw, nz, solver, strict)
        except DesignError:
            if best is None:
                raise
            break
        if best is None:
            best = res
        elif viol < 1e-8 and res.gamma < best.gamma:
            stalled = stalled + 1 if res.gamma > best.gamma * (1 - 1e-4) else 0
            best = res
        else:
            stalled += 1
        if stalled >= 2 or not Ps.nstates:
            break
        try:
            R, S = _lmi_centre(Ps, nw, nz, solver, strict, res.gamma * (1 + centre_margin))
            T = _contragredient(R, S)
        except (DesignError, np.linalg.LinAlgError):
            break  # no better coordinates from here: keep the best level so far
        Ti = np.linalg.inv(T)
        Ps = ct.ss(Ti @ Ps.A @ T, Ti @ Ps.B, Ps.C @ T, Ps.D)
    return best


@validate_params(
    _PARTITION
    | {
        "solver": [Options(("CLARABEL", "SCS"))],
        "strict": [_POSITIVE],
        "iterations": [Interval(Integral, 1, None)],
        "centre_margin": [Interval(Real, 0, 0.5, closed="right")],
    },
    error=DesignError,
)
def hinf_lmi(
    P,
    nmeas: int = 1,
    ncon: int = 1,
    *,
    solver: str = "CLARABEL",
    strict: float = 1e-9,
    iterations: int = 10,
    centre_margin: float = 1e-3,
) -> LmiResult:
    """Optimal ``gamma`` from the H-infinity synthesis LMIs of Gahinet & Apkarian (1994), no rank conditions.

    Minimise ``gamma`` over symmetric ``R, S`` such that (``N_R``, ``N_S`` bases of the null spaces of
    ``[B2' D12']`` and ``[C2 D21]``)::

        [N_R 0; 0 I]' [[A R + R A', R C1', B1], [C1 R, -g I, D11], [B1', D11', -g I]] [N_R 0; 0 I] < 0
        [N_S 0; 0 I]' [[A' S + S A, S B1, C1'], [B1' S, -g I, D11'], [C1, D11, -g I]] [N_S 0; 0 I] < 0
        [[R, I], [I, S]] >= 0

    Near-singular problems (the thesis's at small ``eps_u``) need ``R`` with eigenvalues over ten decades in
    the plant's own coordinates, and the interior-point solver then stops up to 10 % above the optimum. So the
    LMIs are solved again in better coordinates, found from the route's own iterates (never from the Riccati
    route): after each ``gamma`` minimisation, the "centre" ``R, S`` at ``(1 + centre_margin) gamma`` that
    minimises ``trace R + trace S`` gives the contragredient similarity ``x = T x_new`` making both equal and
    diagonal (``T^-1 R T^-T = T' S T = Sigma``, the balanced-realization construction), and ``gamma`` is
    minimised again there. ``gamma`` is invariant under the similarity; the smallest level whose LMIs hold at the
    returned point (relative violation < 1e-8) is kept. On the thesis's 5 Hz problem at ``eps_u = 1.05e-7``
    this takes the LMI optimum from 10 % to < 0.1 % above the Riccati route's.

    Parameters
    ----------
    P : StateSpace
        Generalized plant (singular or not), inputs ``[w; u]``, outputs ``[z; y]``.
    nmeas, ncon : int
        Number of measurements and control inputs.
    solver : str
        A cvxpy conic solver that handles semidefinite cones: "CLARABEL" (interior point, the default) or "SCS"
        (first order: 2 % high on the thesis's 5 Hz problem at ``eps_u = 1e-6``).
    strict : float
        Margin used for the strict inequalities, relative to the scaled problem.
    iterations : int
        Largest number of (minimise, centre, re-coordinate) rounds; stops earlier once two rounds in a row
        improve ``gamma`` by less than 1e-4 (relative).
    centre_margin : float
        Relative distance above the last ``gamma`` at which the centring solve is done, in (0, 0.5].

    Returns
    -------
    LmiResult
        ``R`` and ``S`` are in the scaled coordinates of the round that gave the returned ``gamma``.

    Examples
    --------
    >>> import control as ct
    >>> from flexdigit.control.generalized import filter_weight, regularise, thesis_generalized_plant
    >>> P = regularise(thesis_generalized_plant(ct.tf([1.0], [1.0, 1.0]), filter_weight(1.0)), 0.1)
    >>> lmi, ric = hinf_lmi(P).gamma, hinf_riccati(P, gtol=1e-6).gamma_opt
    >>> abs(lmi / ric - 1) < 1e-3
    True
    """
    P = as_statespace(P, "P", siso=False)
    nw, nz = _partition(P, nmeas, ncon)
    Ps, zscale = _lmi_coordinates(P, nmeas, ncon, nz)
    with single_blas_thread():
        best = _lmi_rounds(Ps, nw, nz, solver, strict, iterations, centre_margin)
    return LmiResult(best.gamma * zscale, best.R, best.S, best.status, solver)


def _contragredient(R, S) -> np.ndarray:
    """``T`` with ``T^-1 R T^-T = T' S T = Sigma`` diagonal (``Sigma^2`` the eigenvalues of ``R S``)."""
    L = scipy.linalg.cholesky((R + R.T) / 2, lower=True)  # LinAlgError if R is not positive definite
    U, s2, _ = np.linalg.svd(L.T @ ((S + S.T) / 2) @ L)
    if not np.all(np.isfinite(s2)) or s2.min() <= 0:
        raise np.linalg.LinAlgError("R S is not positive definite")
    return L @ U @ np.diag(s2**-0.25)


def _balanced(P):
    """Balanced realization of a stable system from its Gramians (better conditioned LMIs)."""
    Wc = ct.gram(P, "c")
    Wo = ct.gram(P, "o")
    try:
        Lc = scipy.linalg.cholesky((Wc + Wc.T) / 2, lower=True)
    except np.linalg.LinAlgError:
        return P
    U, s, _ = np.linalg.svd(Lc.T @ Wo @ Lc)
    T = Lc @ U @ np.diag(s**-0.25)
    Ti = np.linalg.inv(T)
    return ct.ss(Ti @ P.A @ T, Ti @ P.B, P.C @ T, P.D)


def _lmi_data(Ps, nw, nz):
    """``A, B1, C1, D11`` and the null-space bases ``N_R`` of ``[B2' D12']`` and ``N_S`` of ``[C2 D21]``."""
    A, B, C, D = (np.asarray(M, float) for M in (Ps.A, Ps.B, Ps.C, Ps.D))
    B1, B2, C1, C2 = B[:, :nw], B[:, nw:], C[:nz], C[nz:]
    D11, D12, D21 = D[:nz, :nw], D[:nz, nw:], D[nz:, :nw]
    NR = scipy.linalg.null_space(np.hstack([B2.T, D12.T]))
    NS = scipy.linalg.null_space(np.hstack([C2, D21]))
    return A, B1, C1, D11, NR, NS


def _lmi_constraints(Ps, nw, nz, R, S, g, strict):
    """The LMIs of :func:`hinf_lmi` written out as cvxpy expressions: the reference :func:`_lmi_maps` is tested
    against (the route itself solves the compiled problems of :func:`_lmi_problem`)."""
    import cvxpy as cp

    A, B1, C1, D11, NR, NS = _lmi_data(Ps, nw, nz)
    n = A.shape[0]
    cons = [cp.bmat([[R, np.eye(n)], [np.eye(n), S]]) >> 0]
    if NR.size:
        WR = scipy.linalg.block_diag(NR, np.eye(nw))
        MR = cp.bmat(
            [
                [A @ R + R @ A.T, R @ C1.T, B1],
                [C1 @ R, -g * np.eye(nz), D11],
                [B1.T, D11.T, -g * np.eye(nw)],
            ]
        )
        LR = WR.T @ MR @ WR
        cons.append((LR + LR.T) / 2 << -strict * np.eye(WR.shape[1]))
    if NS.size:
        WS = scipy.linalg.block_diag(NS, np.eye(nz))
        MS = cp.bmat(
            [
                [A.T @ S + S @ A, S @ B1, C1.T],
                [B1.T @ S, -g * np.eye(nw), D11.T],
                [C1, D11, -g * np.eye(nz)],
            ]
        )
        LS = WS.T @ MS @ WS
        cons.append((LS + LS.T) / 2 << -strict * np.eye(WS.shape[1]))
    return cons


def _lmi_maps(Ps, nw, nz):
    """Each LMI of :func:`_lmi_constraints` as the affine map ``L(X, g) = Q X P' + P X Q' + g G + C0`` of its
    variable ``X`` (``R``, then ``S``) and ``g``: ``(P, Q, G, C0)``, or None where the null space is empty.

    With ``W = blockdiag(N, I)`` and its rows split like the middle matrix (``P`` the state rows, ``F_m``, ``F_l``
    the other two blocks): ``Q = P A + F_m C1``, ``G = -(F_m F_m' + F_l F_l')``, ``C0 = H + H'`` with
    ``H = (P B1 + F_m D11) F_l'`` for the ``R`` LMI; the ``S`` LMI is the same with ``A', C1', B1', D11'``.
    """
    A, B1, C1, D11, NR, NS = _lmi_data(Ps, nw, nz)
    n = A.shape[0]
    maps = []
    for N, a, c1, b1, d11, m_mid, m_last in ((NR, A, C1, B1, D11, nz, nw), (NS, A.T, B1.T, C1.T, D11.T, nw, nz)):
        if not N.size:
            maps.append(None)
            continue
        W = scipy.linalg.block_diag(N, np.eye(m_last))
        P, Fm, Fl = W[:n].T, W[n : n + m_mid].T, W[n + m_mid :].T
        H = (P @ b1 + Fm @ d11) @ Fl.T
        maps.append((P, P @ a + Fm @ c1, -(Fm @ Fm.T + Fl @ Fl.T), H + H.T))
    return maps


#: The LMI problems compiled so far, by (kind, states, LMI sizes, strict): cvxpy compiles a problem once (DPP) and
#: re-solves it for new data by matrix products; compiling was ~75 % of the route's time (issue 15).
_LMI_PROBLEMS: dict = {}
_LMI_LOCK = threading.Lock()


def _lmi_problem(kind: str, n: int, sizes: tuple[int, int], strict: float):
    """The cvxpy problem ``"gamma"`` (minimise ``g``) or ``"centre"`` (least ``trace R + trace S`` at a level in
    the data) for ``n`` states, with its LMIs as parameters: ``vec(L) = M vec(X) + vec(C0) (+ g vec(G))``, ``M =
    P (x) Q + Q (x) P`` (Kronecker products, column-major vec), which cvxpy compiles once (DPP)."""
    import cvxpy as cp

    key = (kind, n, sizes, strict)
    if key not in _LMI_PROBLEMS:
        R = cp.Variable((n, n), symmetric=True)
        S = cp.Variable((n, n), symmetric=True)
        g = cp.Variable() if kind == "gamma" else None
        cons, params = [cp.bmat([[R, np.eye(n)], [np.eye(n), S]]) >> 0], []
        for X, k in zip((R, S), sizes, strict=True):
            if not k:
                params.append(None)
                continue
            M, C0 = cp.Parameter((k * k, n * n)), cp.Parameter((k, k))
            L = cp.reshape(M @ cp.vec(X, order="F"), (k, k), order="F") + C0
            G = cp.Parameter((k, k)) if g is not None else None
            if G is not None:
                L = L + g * G
            cons.append((L + L.T) / 2 << -strict * np.eye(k))
            params.append((M, C0, G))
        objective = cp.Minimize(g) if g is not None else cp.Minimize(cp.trace(R) + cp.trace(S))
        problem = cp.Problem(objective, cons)
        _LMI_PROBLEMS[key] = (problem, R, S, g, cons, params)
    return _LMI_PROBLEMS[key]


def _solve_lmis(Ps, nw, nz, solver, strict, gamma=None):
    """Solve :func:`_lmi_problem` for ``Ps``: minimise ``g`` (``gamma`` None) or centre at ``gamma``."""
    maps = _lmi_maps(Ps, nw, nz)
    sizes = tuple(0 if m is None else m[0].shape[0] for m in maps)
    with _LMI_LOCK:
        problem, R, S, g, cons, params = _lmi_problem("gamma" if gamma is None else "centre", Ps.nstates, sizes, strict)
        for m, p in zip(maps, params, strict=True):
            if m is None:
                continue
            P, Q, G, C0 = m
            p[0].value = np.kron(P, Q) + np.kron(Q, P)
            p[1].value = C0 if gamma is None else C0 + gamma * G
            if p[2] is not None:
                p[2].value = G
        _solve(problem, solver)
        values = (None if g is None else g.value, R.value, S.value)
        viol = 0.0
        if gamma is None and g.value is not None:
            # relative violation of the LMIs at the returned point (the solver's own tolerances are absolute)
            for con in cons:
                expr = np.asarray(con.expr.value)  # cvxpy keeps every LMI as "expr is PSD"
                lam = np.linalg.eigvalsh((expr + expr.T) / 2)
                viol = max(viol, float(-lam.min() / max(np.abs(lam).max(), 1e-300)))
        return values, problem.status, viol


def _solve(prob, solver):
    import cvxpy as cp

    try:
        with warnings.catch_warnings():
            # "may be inaccurate": the status says so, and the LMIs are re-checked by the caller
            warnings.simplefilter("ignore", UserWarning)
            prob.solve(solver=solver)
    except cp.error.SolverError as exc:
        raise DesignError(f"The LMI solver {solver} failed: {exc}") from exc
    if prob.status not in ("optimal", "optimal_inaccurate"):
        raise DesignError(f"The H-infinity LMIs are infeasible or the solver failed (status {prob.status!r}).")


def _lmi_once(Ps, nw, nz, solver, strict) -> tuple[LmiResult, float]:
    """Minimise ``gamma``; return the result and the LMIs' relative violation at the returned point."""
    (g, R, S), status, viol = _solve_lmis(Ps, nw, nz, solver, strict)
    if g is None:
        raise DesignError(f"The H-infinity LMIs are infeasible or the solver failed (status {status!r}).")
    return LmiResult(float(g), np.asarray(R), np.asarray(S), status, solver), viol


def _lmi_centre(Ps, nw, nz, solver, strict, gamma) -> tuple[np.ndarray, np.ndarray]:
    """The feasible ``R, S`` of least ``trace R + trace S`` at a fixed ``gamma``: tight in every direction.

    Minimising ``gamma`` alone leaves ``R`` and ``S`` as large as the solver likes where their LMIs are slack
    (``R S`` up to 1e11 on the thesis problem), which says nothing about the coordinates the optimum needs.
    """
    (_, R, S), status, _ = _solve_lmis(Ps, nw, nz, solver, strict, gamma)
    if R is None or S is None:
        raise DesignError(f"The H-infinity LMIs at gamma={gamma:.6g} returned no point (status {status!r}).")
    return np.asarray(R), np.asarray(S)


@validate_params(
    {
        "P_singular": [NoValidation()],
        "eps_values": [Array(ndim=1, min_length=1, low=0, low_open=True)],
        "margin": [Interval(Real, 0, None)],
        "nmeas": [Interval(Integral, 1, None)],
        "ncon": [Interval(Integral, 1, None)],
    },
    error=DesignError,
)
def regularisation_path(P_singular, eps_values, *, margin: float = 0.0, nmeas: int = 1, ncon: int = 1):
    """Design for a decreasing sequence of ``eps_u`` and return one row per level.

    Returns
    -------
    list of dict
        ``eps``, ``gamma_opt``, ``design`` (:class:`HinfDesign`), ``dc_gain`` (controller, commands per unit) and
        ``fastest_pole`` (rad/s, the magnitude of the fastest controller pole).
    """
    rows = []
    for eps in eps_values:
        d = hinf_riccati(regularise(P_singular, eps, nmeas=nmeas, ncon=ncon), nmeas, ncon, margin=margin)
        poles = np.linalg.eigvals(d.controller.A)
        rows.append(
            {
                "eps": float(eps),
                "gamma_opt": d.gamma_opt,
                "design": d,
                "dc_gain": float(np.real(ct.dcgain(d.controller))),
                "fastest_pole": float(np.max(np.abs(poles))) if poles.size else math.nan,
            }
        )
    return rows


@validate_params({"K": [NoValidation()], "order": [Interval(Integral, 1, None)]}, error=DesignError)
def reduce_controller(K, order: int) -> ct.StateSpace:
    """Balanced truncation of a stable controller to ``order`` states (``control.balred``)."""
    K = as_statespace(K, "K", siso=False)
    if order > K.nstates:
        raise DesignError(f"The 'order' parameter must be an integer in [1, {K.nstates}]. Got {order!r} instead.")
    if K.nstates and np.max(np.linalg.eigvals(K.A).real) >= 0:
        raise DesignError("Balanced truncation needs a stable controller; this one has unstable poles.")
    if order == K.nstates:
        return K
    return ct.balred(K, order, method="truncate")
