"""Generalized plants for H-infinity synthesis (thesis 4.3-4.4).

The thesis weights the tracking error with a low-pass filter ``F(s) = 1/(s + wc)`` and builds the generalized
plant ``P`` of section 4.4 with inputs ``[w; u]`` and outputs ``[z_bar; y]``::

    z_bar = F (w - G u)        (weighted tracking error)
    y     = w - G u            (tracking error, the controller's input; u = K y)

so that closing ``u = K y`` gives the unity negative-feedback loop with ``T_zw = F S``. That problem has
``D12 = 0`` (nothing weights ``u``): it is singular, and :func:`regularise` adds ``eps * u`` to ``z`` (and
``eps * v`` measurement noise when ``D21`` is rank deficient). :func:`mixed_sensitivity_plant` is the general
``W1 S / W2 KS / W3 T`` stack (python-control ``augw``).

Units: ``u`` is the servo command (0..254, about the equilibrium), ``w``, ``y`` are in the plant's output unit
(m of deflection for the thesis plant, rad of beam rotation for the consistent plant).
"""

from __future__ import annotations

import math
from numbers import Integral, Real

import control as ct
import numpy as np

from flexdigit._validation import Interval, NoValidation, check_positive, check_real, validate_params
from flexdigit.errors import DesignError

__all__ = [
    "as_statespace",
    "filter_weight",
    "thesis_generalized_plant",
    "regularise",
    "regularise_matrices",
    "mixed_sensitivity_plant",
]


def as_statespace(sys, name: str, *, weight: bool = False, siso: bool = True) -> ct.StateSpace:
    """Return ``sys`` as a continuous ``StateSpace``, or raise :class:`DesignError` naming it.

    Parameters
    ----------
    sys : LTI system or scalar
        A python-control ``TransferFunction``/``StateSpace`` or a number (a static gain).
    name : str
        The argument's name, used in the message.
    weight : bool
        A weight must also be stable (its poles strictly in the left half plane).
    siso : bool
        Require one input and one output.
    """
    if isinstance(sys, (int, float, np.floating, np.integer)) and not isinstance(sys, bool):
        value = check_real(sys, name, error=DesignError)
        return ct.ss([], [], [], [[value]])
    if isinstance(sys, ct.TransferFunction):
        for i in range(sys.noutputs):
            for j in range(sys.ninputs):
                num = np.trim_zeros(np.atleast_1d(sys.num[i][j]), "f")
                den = np.trim_zeros(np.atleast_1d(sys.den[i][j]), "f")
                if len(num) > len(den):
                    raise DesignError(
                        f"The '{name}' parameter must be a proper transfer function (numerator degree <= "
                        f"denominator degree). Got numerator degree {len(num) - 1} over {len(den) - 1} instead."
                    )
        sys = ct.ss(sys)
    elif not isinstance(sys, ct.StateSpace):
        raise DesignError(f"The '{name}' parameter must be a python-control LTI system or a number. Got {sys!r}.")
    if not sys.isctime():
        raise DesignError(f"The '{name}' parameter must be a continuous-time system. Got dt={sys.dt!r} instead.")
    if siso and (sys.ninputs, sys.noutputs) != (1, 1):
        raise DesignError(
            f"The '{name}' parameter must be single-input single-output. "
            f"Got {sys.noutputs} outputs x {sys.ninputs} inputs instead."
        )
    if not np.all(np.isfinite(sys.A)) or not np.all(np.isfinite(sys.D)):
        raise DesignError(f"The '{name}' parameter must have finite matrices.")
    if weight and sys.nstates and np.max(np.linalg.eigvals(sys.A).real) >= 0:
        raise DesignError(
            f"The '{name}' parameter must be a stable weight (poles in the open left half plane). "
            f"Got poles {np.round(np.linalg.eigvals(sys.A), 6).tolist()} instead."
        )
    return sys


def filter_weight(cutoff_hz: float) -> ct.TransferFunction:
    """The thesis's tracking-error weight ``F(s) = 1/(s + 2 pi f_c)`` (section 4.3).

    Parameters
    ----------
    cutoff_hz : float
        Cut-off frequency in Hz (5 Hz gives ``1/(s + 31.4159)``).

    Examples
    --------
    >>> F = filter_weight(5.0)
    >>> round(float(F.den[0][0][1]), 4)
    31.4159
    """
    fc = check_positive(cutoff_hz, "cutoff_hz", "filter_weight", error=DesignError)
    return ct.tf([1.0], [1.0, 2 * math.pi * fc])


def thesis_generalized_plant(plant, weight) -> ct.StateSpace:
    """The nominal generalized plant ``P`` of thesis section 4.4, built from its state-space formula.

    Parameters
    ----------
    plant : LTI system
        ``G(s)`` from command to output (m per command for the thesis plant); SISO, proper.
    weight : LTI system
        The error weight ``F(s)``; SISO, proper, stable.

    Returns
    -------
    StateSpace
        Inputs ``['w', 'u']``, outputs ``['z', 'y']``, states ``[x (plant), x_f (filter)]``::

            A_P = [[A, 0], [-B_f C, A_f]]        B_P = [[0, B], [B_f, -B_f D]]
            C_P = [[-D_f C, C_f], [-C, 0]]       D_P = [[D_f, -D_f D], [I, -D]]

    Examples
    --------
    >>> import control as ct
    >>> P = thesis_generalized_plant(ct.tf([2.0], [1.0, 1.0]), filter_weight(5.0))
    >>> P.input_labels, P.output_labels
    (['w', 'u'], ['z', 'y'])
    """
    G = as_statespace(plant, "plant")
    F = as_statespace(weight, "weight", weight=True)
    A, B, C, D = G.A, G.B, G.C, G.D
    Af, Bf, Cf, Df = F.A, F.B, F.C, F.D
    n, nf = A.shape[0], Af.shape[0]
    AP = np.block([[A, np.zeros((n, nf))], [-Bf @ C, Af]])  # 4.4
    BP = np.block([[np.zeros((n, 1)), B], [Bf, -Bf @ D]])
    CP = np.block([[-Df @ C, Cf], [-C, np.zeros((1, nf))]])
    DP = np.block([[Df, -Df @ D], [np.eye(1), -D]])
    return ct.ss(AP, BP, CP, DP, inputs=["w", "u"], outputs=["z", "y"], name="P")


@validate_params(
    {
        "P": [NoValidation()],
        "eps_u": [Interval(Real, 0, None)],
        "eps_noise": [Interval(Real, 0, None)],
        "nmeas": [Interval(Integral, 1, None)],
        "ncon": [Interval(Integral, 1, None)],
    },
    error=DesignError,
)
def regularise(P, eps_u: float, eps_noise: float = 0.0, *, nmeas: int = 1, ncon: int = 1) -> ct.StateSpace:
    """Make a singular generalized plant regular: append ``eps_u * u`` to ``z`` and ``eps_noise * v`` to ``y``.

    Parameters
    ----------
    P : StateSpace
        Generalized plant with inputs ``[w; u]`` and outputs ``[z; y]`` (last ``ncon`` inputs, last ``nmeas``
        outputs).
    eps_u : float
        Weight of the extra performance output ``eps_u * u`` (fixes ``D12 = 0``); >= 0.
    eps_noise : float
        Weight of an extra disturbance input ``eps_noise * v`` on the measurement (fixes ``D21`` rank); >= 0.

    Returns
    -------
    StateSpace
        Inputs ``[w; v; u]`` (``v`` only if ``eps_noise > 0``), outputs ``[z; z_u; y]`` (``z_u`` only if
        ``eps_u > 0``).
    """
    P = as_statespace(P, "P", siso=False)
    _check_partition(P, nmeas, ncon)
    nw, nz = P.ninputs - ncon, P.noutputs - nmeas
    return ct.ss(*regularise_matrices(P.A, P.B, P.C, P.D, nw, nz, eps_u, eps_noise))


def regularise_matrices(A, B, C, D, nw: int, nz: int, eps_u: float, eps_noise: float = 0.0):
    """:func:`regularise` on bare matrices (``nw`` exogenous inputs, ``nz`` performance outputs; unchecked):
    ``(A, B, C, D)`` of the regular plant."""
    nmeas, ncon = C.shape[0] - nz, B.shape[1] - nw
    B1, B2 = B[:, :nw], B[:, nw:]
    C1, C2 = C[:nz], C[nz:]
    D11, D12, D21, D22 = D[:nz, :nw], D[:nz, nw:], D[nz:, :nw], D[nz:, nw:]
    if eps_noise > 0:
        B1 = np.hstack([B1, np.zeros((A.shape[0], nmeas))])
        D11 = np.hstack([D11, np.zeros((nz, nmeas))])
        D21 = np.hstack([D21, eps_noise * np.eye(nmeas)])
    if eps_u > 0:
        C1 = np.vstack([C1, np.zeros((ncon, A.shape[0]))])
        D11 = np.vstack([D11, np.zeros((ncon, D11.shape[1]))])
        D12 = np.vstack([D12, eps_u * np.eye(ncon)])
    Bn = np.hstack([B1, B2])
    Cn = np.vstack([C1, C2])
    Dn = np.block([[D11, D12], [D21, D22]])
    return A, Bn, Cn, Dn


def mixed_sensitivity_plant(plant, w1=None, w2=None, w3=None) -> ct.StateSpace:
    """Generalized plant for ``|| [W1 S; W2 K S; W3 T] ||_inf`` (python-control ``augw``), validated.

    Parameters
    ----------
    plant : LTI system
        ``G(s)``, SISO, proper.
    w1, w2, w3 : LTI system or float, optional
        Weights on the sensitivity ``S``, on ``K S`` (control effort) and on ``T``; each SISO, proper,
        stable. ``W3`` must make ``W3 G`` proper.

    Returns
    -------
    StateSpace
        Inputs ``[w; u]``, outputs ``[z1; z2; z3; y]`` with ``y = w - G u``.
    """
    G = as_statespace(plant, "plant")
    weights = {}
    for name, w in (("w1", w1), ("w2", w2), ("w3", w3)):
        if w is not None:
            weights[name] = as_statespace(w, name, weight=True)
    if not weights:
        raise DesignError("mixed_sensitivity_plant needs at least one of the weights 'w1', 'w2', 'w3'.")
    return ct.augw(G, weights.get("w1"), weights.get("w2"), weights.get("w3"))


def _check_partition(P, nmeas: int, ncon: int) -> None:
    """``nmeas`` and ``ncon`` (declared positive integers) leave at least one w and one z."""
    if P.ninputs <= ncon or P.noutputs <= nmeas:
        raise DesignError(
            f"The generalized plant has {P.ninputs} inputs and {P.noutputs} outputs, too few for "
            f"ncon={ncon} control inputs and nmeas={nmeas} measurements plus at least one w and one z."
        )
