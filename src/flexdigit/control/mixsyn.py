"""Beyond the thesis: a mixed-sensitivity controller the servo can follow (consistent plant, beam rotation).

The thesis's controllers ask for 2e5 commands from a 0..254 servo (5 Hz) or do almost nothing (39 Hz, loop gain
3e-4 at DC). This design, on ``build_plant("consistent", output="tip_rotation_rad")``, weights

* ``W1 = (s/M + wb)/(s + wb A)`` on the tracking error (near-integral action, bandwidth ``wb``),
* a constant ``W2`` on the command (keeps a 30 deg step inside 0..254),
* a constant ``Wd`` on an input disturbance (``G S`` in the cost: the H-infinity optimum would otherwise cancel
  the lightly damped beam mode with controller zeros and leave it ringing at zeta = 0.07),

solves it by :func:`flexdigit.control.synthesis.hinf_riccati`, then moves the controller's slow pole
(``~ -wb A``) to the origin for exact integral action. Requirements (i)-(iv) of issue 5 are checked by
:func:`check_requirements` on the linear plant.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Real

import control as ct
import numpy as np

from flexdigit._repr import summary
from flexdigit._validation import Interval, declare, validate_fields
from flexdigit.control._lsim import step_output
from flexdigit.control.analysis import (
    closed_loop_poles,
    closed_loop_poles_batch,
    hinf_norm,
    loop_maps,
    monte_carlo_stability,
)
from flexdigit.control.generalized import as_statespace
from flexdigit.control.synthesis import HinfDesign, hinf_riccati
from flexdigit.errors import DesignError
from flexdigit.models.plant import build_plant

__all__ = [
    "MixsynSpec",
    "MixsynDesign",
    "disturbance_plant",
    "design_mixsyn",
    "plant_family",
    "PlantFamily",
    "small_gain_certificate",
    "check_requirements",
    "mixsyn_on_the_digit",
]

#: Equilibrium servo command of the rig (thesis 3.4.1: the digit is straight at command 8) and the command range.
EQUILIBRIUM_COMMAND = 8.0
COMMAND_RANGE = (0.0, 254.0)


@declare
@dataclass(frozen=True)
class MixsynSpec:
    """Weights of the mixed-sensitivity design (units: rad of beam rotation, commands, rad/s).

    Attributes
    ----------
    bandwidth_rad_s : float
        ``wb`` of ``W1``.
    s_peak : float
        ``M``, the allowed sensitivity peak (high-frequency gain of ``1/W1``).
    integral_eps : float
        ``A``: ``W1`` has its pole at ``-wb A`` (moved to 0 afterwards).
    w_command : float
        ``W2``, per command.
    w_disturbance : float
        ``Wd``, commands of input disturbance per unit of ``d``.
    margin : float
        Relative gamma margin of the central controller.
    """

    bandwidth_rad_s: float = 1.0
    s_peak: float = 2.0
    integral_eps: float = 1e-4
    w_command: float = 0.04
    w_disturbance: float = 40.0
    margin: float = 0.05

    _parameter_constraints = {
        "bandwidth_rad_s": [Interval(Real, 0, None, closed="neither")],
        "s_peak": [Interval(Real, 1, None)],
        "integral_eps": [Interval(Real, 0, 0.1, closed="right")],
        "w_command": [Interval(Real, 0, None, closed="neither")],
        "w_disturbance": [Interval(Real, 0, None)],
        "margin": [Interval(Real, 0, None)],
    }

    def __post_init__(self):
        validate_fields(self, error=DesignError)


@dataclass(frozen=True)
class MixsynDesign:
    """A mixed-sensitivity design: the integral controller, the raw H-infinity result and the spec."""

    controller: ct.TransferFunction
    hinf: HinfDesign
    spec: MixsynSpec

    @property
    def order(self) -> int:
        return len(np.trim_zeros(self.controller.den[0][0], "f")) - 1

    def __repr__(self) -> str:
        # the controller's order and the figures, not its coefficient arrays (python-control prints them in full)
        spec = self.spec
        return summary(
            self,
            controller_order=self.order,
            gamma=self.hinf.gamma,
            bandwidth_rad_s=spec.bandwidth_rad_s,
            s_peak=spec.s_peak,
            integral_eps=spec.integral_eps,
        )


def disturbance_plant(plant, w1, w2, wd) -> ct.StateSpace:
    """Generalized plant with reference ``r`` and input disturbance ``d``: ``[W1 e; W2 u; e]`` from ``[r; d; u]``.

    ``e = r - G (u + Wd d)``; ``u = K e``.
    """
    G = as_statespace(plant, "plant")
    W1 = as_statespace(w1, "w1", weight=True)
    W2 = as_statespace(w2, "w2", weight=True)
    Wd = as_statespace(wd, "wd", weight=True)
    blocks = [
        ct.ss(G, inputs="ut", outputs="yp", name="G"),
        ct.ss(W1, inputs="e", outputs="z1", name="W1"),
        ct.ss(W2, inputs="u", outputs="z2", name="W2"),
        ct.ss(Wd, inputs="d", outputs="dd", name="Wd"),
        ct.summing_junction(["u", "dd"], "ut", name="sum_u"),
        ct.summing_junction(["r", "-yp"], "e", name="sum_e"),
    ]
    return ct.interconnect(blocks, inplist=["r", "d", "u"], outlist=["z1", "z2", "e"])


def design_mixsyn(plant, spec: MixsynSpec | None = None) -> MixsynDesign:
    """Design the integral mixed-sensitivity controller (see the module docstring).

    Examples
    --------
    >>> from flexdigit.models.plant import build_plant
    >>> d = design_mixsyn(build_plant("consistent", output="tip_rotation_rad").tf)
    >>> float(d.controller.den[0][0][-1])        # a pole at s = 0: integral action
    0.0
    """
    spec = MixsynSpec() if spec is None else spec
    wb, A = spec.bandwidth_rad_s, spec.integral_eps
    W1 = ct.tf([1 / spec.s_peak, wb], [1.0, wb * A])
    P = disturbance_plant(plant, W1, spec.w_command, spec.w_disturbance)
    hd = hinf_riccati(P, nmeas=1, ncon=1, margin=spec.margin)
    K = ct.tf(ct.minreal(hd.controller, verbose=False))
    num, den = np.asarray(K.num[0][0], float), np.asarray(K.den[0][0], float)
    roots = np.roots(den)
    i = int(np.argmin(np.abs(roots)))
    if not abs(roots[i]) < 10 * wb * A + 1e-9:
        raise DesignError(f"The design has no slow pole near -{wb * A:g} rad/s to turn into an integrator.")
    rest = np.real(np.poly(np.delete(roots, i)))
    # keep the gain at frequencies >> |slow|: K_int = num / (s * rest), den = (s - slow) * rest
    Kint = ct.tf(num / den[0], np.polymul([1.0, 0.0], rest))
    return MixsynDesign(Kint, hd, spec)


class PlantFamily:
    """``family(gain=1, wn=1) -> G``: the consistent plant with its DC gain and beam frequency scaled.

    Uses the components of :class:`flexdigit.models.plant.Plant`: ``dc_gain x MT_unit(s) x E(s)``, with the beam
    factor ``E(s) = wn^2/(s^2 + 2 zeta wn s + wn^2)`` re-built at ``wn x factor`` (same zeta). Calling it gives
    one member as a transfer function; :meth:`state_space` gives many members' matrices at once (what the
    robustness checks need: their closed-loop poles, :func:`~flexdigit.control.analysis.closed_loop_poles_batch`).
    """

    def __init__(self, plant_info):
        self.plant_info = plant_info
        self._mt = plant_info.components["MT_unit"]
        E = plant_info.components["E_digit_housing"]
        e_den = np.asarray(E.den[0][0], float)
        self._wn0 = math.sqrt(e_den[2] / e_den[0])
        self._zeta = e_den[1] / e_den[0] / (2 * self._wn0)
        self._dc = float(plant_info.dc_gain)
        mt = as_statespace(self._mt, "MT_unit")
        self._mt_abcd = tuple(np.asarray(M, dtype=float) for M in (mt.A, mt.B, mt.C, mt.D))

    def __repr__(self) -> str:
        return f"PlantFamily({self.plant_info.variant!r} plant, wn0={self._wn0:.6g} rad/s, zeta={self._zeta:.6g})"

    def __call__(self, gain: float = 1.0, wn: float = 1.0):
        w = self._wn0 * wn
        return gain * self._dc * self._mt * ct.tf([w * w], [1.0, 2 * self._zeta * w, w * w])

    def state_space(self, gain=1.0, wn=1.0) -> tuple[np.ndarray, ...]:
        """``(A, B, C, D)`` of the members at the factors ``gain`` and ``wn`` (arrays, broadcast together): shapes
        ``(N, n, n)``, ``(N, n, 1)``, ``(N, 1, n)``, ``(N, 1, 1)``.

        ``MT_unit`` (python-control's realisation) in series with ``gain x dc_gain x E`` in companion form: the
        poles of :meth:`__call__`'s transfer function, from matrices built in numpy for all members at once.
        """
        gain, wn = np.broadcast_arrays(np.atleast_1d(np.asarray(gain, float)), np.atleast_1d(np.asarray(wn, float)))
        Am, Bm, Cm, Dm = self._mt_abcd
        N, nm = gain.size, Am.shape[0]
        w = self._wn0 * wn.ravel()
        k = (gain.ravel() * self._dc)[:, None, None]
        A = np.zeros((N, nm + 2, nm + 2))
        A[:, :nm, :nm] = Am
        A[:, nm, nm + 1] = 1.0
        A[:, nm + 1, nm] = -w * w
        A[:, nm + 1, nm + 1] = -2 * self._zeta * w
        A[:, nm + 1 :, :nm] = k * Cm  # E's input is k times MT's output
        B = np.zeros((N, nm + 2, 1))
        B[:, :nm] = Bm
        B[:, nm + 1 :] = k * Dm
        C = np.zeros((N, 1, nm + 2))
        C[:, 0, nm] = w * w
        return A, B, C, np.zeros((N, 1, 1))


def plant_family(plant_info) -> PlantFamily:
    """The :class:`PlantFamily` of ``plant_info`` (the consistent plant) for the robustness checks."""
    return PlantFamily(plant_info)


def small_gain_certificate(
    plant_info,
    controller,
    *,
    gain_spread: float = 0.3,
    wn_spread: float = 0.2,
    n_gain: int = 2,
    n_wn: int = 4,
    omega=None,
) -> dict:
    """Small-gain certificate of stability over the box gain x (1 +- gain_spread), beam wn x (1 +- wn_spread).

    The closed-loop characteristic polynomial ``p = D_G D_K + N_G N_K`` of any plant in a sub-box is written
    ``p = p_c (1 + Delta)`` about the sub-box centre ``p_c`` (a stable loop). ``Delta = (p - p_c)/p_c`` is a
    stable loop gain in the sense of the small-gain theorem: if ``|Delta(jw)| < 1`` for all ``w`` and every
    plant of the sub-box, no closed-loop root can cross the imaginary axis (Rouche), so the sub-box is stable.
    The whole box (``n_gain x n_wn`` sub-boxes) is certified if every sub-box is. One box (1 x 1) is too
    conservative for a 20 % shift of a zeta = 0.07 resonance; the partition is what makes the test usable.
    ``w`` is gridded (``omega``) and so is ``wn`` inside each sub-box (11 points; ``|p - p_c|`` is affine in
    the gain, so its two end values suffice).

    Returns
    -------
    dict
        ``peak`` (largest ``|Delta|`` over sub-boxes and frequencies), ``certified`` (``peak < 1`` and every
        centre stable), ``n_boxes``.
    """
    mt = plant_info.components["MT_unit"]
    E = plant_info.components["E_digit_housing"]
    e_den = np.asarray(E.den[0][0], float) / float(E.den[0][0][0])
    wn0 = math.sqrt(e_den[2])
    zeta = e_den[1] / (2 * wn0)
    dc = float(plant_info.dc_gain)
    mn, md = np.asarray(mt.num[0][0], float), np.asarray(mt.den[0][0], float)
    K = ct.tf(controller)
    NK, DK = np.asarray(K.num[0][0], float), np.asarray(K.den[0][0], float)
    w = np.logspace(-3, 3, 4000) if omega is None else np.asarray(omega, float)
    s = 1j * w
    mds, mns, DKs, NKs = (np.polyval(c, s) for c in (md, mn, DK, NK))

    def char(g, wf):
        wn = wn0 * wf
        return mds * (s**2 + 2 * zeta * wn * s + wn**2) * DKs + g * dc * mns * wn**2 * NKs

    factory = plant_family(plant_info)
    g_edges = np.linspace(1 - gain_spread, 1 + gain_spread, n_gain + 1)
    w_edges = np.linspace(1 - wn_spread, 1 + wn_spread, n_wn + 1)
    peak, centres_stable = 0.0, True
    for g0, g1 in zip(g_edges[:-1], g_edges[1:], strict=True):
        for w0, w1 in zip(w_edges[:-1], w_edges[1:], strict=True):
            gc, wc = (g0 + g1) / 2, (w0 + w1) / 2
            centres_stable &= bool(np.max(closed_loop_poles(factory(gc, wc), controller).real) < 0)
            pc = char(gc, wc)
            for g in (g0, g1):
                for wf in np.linspace(w0, w1, 11):
                    peak = max(peak, float(np.max(np.abs(char(g, wf) - pc) / np.abs(pc))))
    return {"peak": peak, "certified": bool(centres_stable and peak < 1.0), "n_boxes": n_gain * n_wn}


def check_requirements(
    plant_info, controller, *, step_rad: float = math.radians(30.0), n_monte_carlo: int = 300, seed: int = 0
) -> dict:
    """Issue 5's requirements on the linear plant.

    (i) the command for a 0..``step_rad`` step stays in ``[0 - 8, 254 - 8]`` about the equilibrium command;
    (ii) zero steady-state error (``|S(0)|``); (iii) every closed-loop pole has damping >= 0.3;
    (iv) stable for gain x [0.7, 1.3] and beam frequency x [0.8, 1.2]: a grid of the corners and edges, Monte
    Carlo (seeded), and the small-gain certificate of :func:`small_gain_certificate` (the one-box unstructured
    test ``|T(jw)| l(w) < 1``, ``l(w) = max |G_p/G - 1|``, is reported too: it is too conservative here).
    """
    G = plant_info.tf
    maps = loop_maps(G, controller)
    if not maps.stable:
        return {"stable": False}
    t = np.linspace(0.0, 10.0, 5001)
    u = step_output(maps.T_uw, t) * step_rad
    y = step_output(maps.T_yw, t) * step_rad
    lo, hi = COMMAND_RANGE[0] - EQUILIBRIUM_COMMAND, COMMAND_RANGE[1] - EQUILIBRIUM_COMMAND
    poles = maps.poles
    zeta = -poles.real / np.abs(poles)
    s0 = abs(complex(ct.evalfr(maps.T_zw, 1e-9)))
    factory = plant_family(plant_info)
    grid = [(g, w) for g in np.linspace(0.7, 1.3, 7) for w in np.linspace(0.8, 1.2, 9)]
    poles_grid = closed_loop_poles_batch(factory.state_space(*np.array(grid).T), controller)
    grid_stable = bool(np.all(np.max(poles_grid.real, axis=1) < 0))
    mc = monte_carlo_stability(factory, controller, {"gain": 0.3, "wn": 0.2}, n=n_monte_carlo, seed=seed)
    omega = np.logspace(-2, 3, 3000)
    Gn = G(1j * omega)
    ell = np.max([np.abs(factory(g, w)(1j * omega) / Gn - 1) for g, w in grid], axis=0)
    T = np.abs(maps.T_yw(1j * omega))
    small_gain = float(np.max(T * ell))
    cert = small_gain_certificate(plant_info, controller)
    info = ct.step_info(maps.T_yw, T=t)
    return {
        "stable": True,
        "command_min": float(u.min()),
        "command_max": float(u.max()),
        "command_final": float(u[-1]),
        "command_window": (lo, hi),
        "req_i_command_ok": bool(u.min() >= lo and u.max() <= hi),
        "sensitivity_dc": s0,
        "output_final_rad": float(y[-1]),
        "req_ii_integral": bool(s0 < 1e-6),
        "min_damping": float(zeta.min()),
        "req_iii_damping": bool(zeta.min() >= 0.3),
        "grid_stable": grid_stable,
        "monte_carlo": mc,
        "small_gain_peak": small_gain,
        "req_iv_robust": bool(grid_stable and mc["stable_fraction"] == 1.0),
        "small_gain_partition_peak": cert["peak"],
        "small_gain_boxes": cert["n_boxes"],
        "req_iv_small_gain": cert["certified"],
        "settling_time_s": float(info["SettlingTime"]),
        "overshoot_percent": float(info["Overshoot"]),
        "ks_norm": hinf_norm(maps.T_uw, "T_uw")[0],
        "closed_loop_poles": poles,
    }


def mixsyn_on_the_digit(spec: MixsynSpec | None = None, *, seed: int = 0) -> tuple[MixsynDesign, dict]:
    """``flexdigit design mixsyn``: :func:`design_mixsyn` on the consistent plant (command -> tip rotation, rad) and
    its :func:`check_requirements` (Monte Carlo seeded by ``seed``), with an ``"all_met"`` entry added: every
    requirement (i)-(iv) met, the small-gain certificate included."""
    plant = build_plant("consistent", output="tip_rotation_rad")
    design = design_mixsyn(plant.tf, spec)
    req = check_requirements(plant, design.controller, seed=seed)
    if req.get("stable"):
        met = ("req_i_command_ok", "req_ii_integral", "req_iii_damping", "req_iv_robust", "req_iv_small_gain")
        req["all_met"] = all(req[k] for k in met)
    return design, req
