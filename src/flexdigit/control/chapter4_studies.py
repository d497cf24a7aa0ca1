"""The studies of thesis chapter 4, one call each: what report chapter 4 shows, as numbers.

- :func:`k1_closed_loop_study`: the closed loop of 4.2 without a controller (gain K1), its poles beside table
  4.1's, and the K1 that table 4.1's slow pair needs (4.2, table 4.1).
- :func:`gamma_study`: the fitted regularisations that reproduce the printed controllers (tables 4.2, 4.3), the
  optimal gamma by the Riccati and LMI routes, the singular problem and the regularisation path (4.4).
- :func:`filter_sweep_study`: the additive-uncertainty tolerances of the filter sweep (4.6-4.7), in the thesis's
  arithmetic and by the small-gain theorem.
- :func:`chapter4_study`: all of them, the 5 Hz loop's norms and steps (4.4-4.5), and the servo-ready
  mixed-sensitivity design beside the printed 39 Hz controller.

Every table is a :class:`~flexdigit._result_table.ResultTable` of numbers; controllers and loops are
python-control objects.

Examples
--------
>>> k1 = k1_closed_loop_study()
>>> round(k1.k1, 4), round(k1.k1_for_table_slow_pair, 2)
(1.77, 1.05)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import control as ct
import numpy as np

from flexdigit._repr import fields_summary
from flexdigit._result_table import ResultTable
from flexdigit.control.analysis import (
    LoopMaps,
    additive_tolerance,
    hinf_norm,
    loop_maps,
    margins,
    root_locus,
    step_metrics,
)
from flexdigit.control.generalized import filter_weight, regularise, thesis_generalized_plant
from flexdigit.control.mixsyn import check_requirements, design_mixsyn
from flexdigit.control.synthesis import hinf_lmi, hinf_riccati, regularisation_path
from flexdigit.control.thesis_designs import fit_thesis_regularisation, printed_controller, sorted_poles, thesis_design
from flexdigit.models.plant import build_plant
from flexdigit.reference import thesis_complex, thesis_value

__all__ = [
    "SWEEP_FILTERS_HZ",
    "PRINTED_FILTERS_HZ",
    "PATH_EPS_U",
    "PRINTED_GAIN_FACTOR",
    "K1Study",
    "k1_closed_loop_study",
    "RegularisationFit",
    "GammaStudy",
    "fit_printed_controller",
    "gamma_study",
    "FilterSweepStudy",
    "filter_sweep_study",
    "Chapter4Study",
    "chapter4_study",
]

#: Cut-offs of the thesis's filter sweep (4.7), Hz.
SWEEP_FILTERS_HZ = (0.5, 5.0, 39.0, 50.0)
#: Cut-offs whose controllers the thesis prints (tables 4.2, 4.3), Hz.
PRINTED_FILTERS_HZ = (5.0, 39.0)
#: Regularisations of the singular 5 Hz problem on the regularisation path.
PATH_EPS_U = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8)
#: The thesis's printed controllers are 10x ours (same poles): figures that scale with the gain are shown x10.
PRINTED_GAIN_FACTOR = 10.0


def _printed_plant():
    return build_plant("printed")


# ------------------------------------------------------------------------------------ 4.2: K1, no controller
@dataclass(frozen=True)
class K1Study:
    """The closed loop of 4.2 with gain K1 and no controller (table 4.1).

    Attributes
    ----------
    k1 : float
        86.2/48.7 = 1.7699: the printed closed-loop numerator over the plant's (a tenth of E 3.16's 17.6991).
    poles, poles_printed_tf, poles_table : ndarray
        Closed-loop poles on our printed plant with ``k1``, of the printed G_cl's own polynomial, and of table 4.1
        (sorted alike).
    k1_for_table_slow_pair : float
        The K1 (grid 0.5..2, step 0.001) whose closed loop has table 4.1's slowest pole, and ``poles_at_that_k1``.
    table : ResultTable
        ``control.k1_closed_loop``: the four columns of poles, magnitudes in rad/s.
    """

    k1: float
    poles: np.ndarray
    poles_printed_tf: np.ndarray
    poles_table: np.ndarray
    k1_for_table_slow_pair: float
    poles_at_that_k1: np.ndarray
    table: ResultTable

    __repr__ = fields_summary


def k1_closed_loop_study() -> K1Study:
    """Table 4.1 rebuilt: see :class:`K1Study`."""
    G = _printed_plant()
    k1 = 86.2 / 48.7
    poles = sorted_poles(ct.poles(G.closed_loop(k1)))
    printed_tf = sorted_poles(
        ct.poles(ct.tf(thesis_value("plant.closed_loop_num"), thesis_value("plant.closed_loop_den")))
    )
    table_poles = sorted_poles(thesis_complex("plant.closed_loop_poles"))
    # closed-loop poles are the roots of den + K1 num: the K1 that puts one on table 4.1's slowest pole
    g_num, g_den = np.asarray(G.tf.num[0][0], float), np.asarray(G.tf.den[0][0], float)
    slow = table_poles[np.argmin(np.abs(table_poles))]
    grid = np.linspace(0.5, 2.0, 1501)
    miss = np.nanmin(np.abs(root_locus(G.tf, grid) - slow), axis=1)  # np.roots of each k, in one LAPACK call
    k1_slow = float(grid[int(np.argmin(miss))])
    fitted = sorted_poles(np.roots(np.polyadd(g_den, k1_slow * g_num)))
    rows = tuple(
        (i, abs(t), abs(o), abs(p), abs(f))
        for i, (t, o, p, f) in enumerate(zip(table_poles, poles, printed_tf, fitted, strict=True))
    )
    table = ResultTable(
        "control.k1_closed_loop",
        f"Closed-loop poles without controller (4.2, table 4.1): table 4.1, ours with K1 = {k1:.4f}, the printed "
        f"G_cl's own, and ours with the K1 = {k1_slow:.3f} that gives table 4.1's slow pair (magnitudes)",
        ("pole", "table_4_1_rad_s", "ours_rad_s", "printed_g_cl_rad_s", "ours_at_fitted_k1_rad_s"),
        rows,
    )
    return K1Study(k1, poles, printed_tf, table_poles, k1_slow, fitted, table)


# ------------------------------------------------------------------------------ 4.4: regularisation and gamma
@dataclass(frozen=True)
class RegularisationFit:
    """The ``(eps_u, margin)`` whose central controller has a printed controller's poles (tables 4.2, 4.3)."""

    filter_hz: float
    eps_u: float
    margin: float
    pole_error: float
    controller: ct.StateSpace
    poles: np.ndarray
    poles_printed: np.ndarray
    zeros_vs_plant_poles: float
    numerator_lead: float

    __repr__ = fields_summary


@dataclass(frozen=True)
class GammaStudy:
    """gamma of the 4.4 problem: fitted regularisations, two synthesis routes, the singular problem.

    Attributes
    ----------
    fits : dict
        Cut-off (Hz) -> :class:`RegularisationFit` for the printed 5 and 39 Hz controllers.
    gamma_riccati, gamma_lmi : float
        Optimal gamma of the 5 Hz problem at its fitted eps_u by the Riccati (SLICOT) and LMI (cvxpy) routes.
    gamma_lmi_singular : float
        The LMI route on the unregularised problem (D12 = 0): where the solver runs out of conditioning.
    routes, path, poles_5hz, poles_39hz : ResultTable
        ``control.gamma_routes`` (cut-off, eps_u, both gammas, their difference in %), ``control.regularisation
        _path`` (eps_u, gamma_opt, K(0), fastest controller pole), and the fitted controllers' poles beside the
        printed ones.
    """

    fits: dict
    gamma_riccati: float
    gamma_lmi: float
    gamma_lmi_singular: float
    routes: ResultTable
    path: ResultTable
    poles_5hz: ResultTable
    poles_39hz: ResultTable

    __repr__ = fields_summary


def fit_printed_controller(filter_hz: float, plant=None) -> RegularisationFit:
    """Fit the regularisation to the printed controller of ``filter_hz`` (5 or 39 Hz) and compare it."""
    G = plant if plant is not None else _printed_plant().tf
    f = fit_thesis_regularisation(filter_hz, plant=G)
    K = f["design"].controller
    key = f"{filter_hz:g}hz"
    zeros = sorted_poles(ct.zeros(K))
    return RegularisationFit(
        filter_hz=float(filter_hz),
        eps_u=f["eps_u"],
        margin=f["margin"],
        pole_error=f["pole_error"],
        controller=K,
        poles=sorted_poles(np.linalg.eigvals(K.A)),
        poles_printed=sorted_poles(thesis_complex(f"hinf.k_{key}_poles")),
        zeros_vs_plant_poles=float(np.max(np.abs(zeros - sorted_poles(ct.poles(G))) / np.abs(zeros))),
        numerator_lead=float(ct.tf(K).num[0][0][0]),
    )


def gamma_study(plant=None) -> GammaStudy:
    """The regularisation fits and gamma by both routes (4.4): see :class:`GammaStudy`."""
    G = plant if plant is not None else _printed_plant().tf
    fits = {hz: fit_printed_controller(hz, G) for hz in PRINTED_FILTERS_HZ}
    eps5, eps39 = fits[5.0].eps_u, fits[39.0].eps_u
    routes = []
    for hz, eps in ((5.0, 1e-5), (5.0, 1e-6), (5.0, eps5), (39.0, eps39)):
        P = regularise(thesis_generalized_plant(G, filter_weight(hz)), eps)
        g_ric, g_lmi = hinf_riccati(P, gtol=1e-6).gamma_opt, hinf_lmi(P).gamma
        routes.append((hz, eps, g_ric, g_lmi, 100 * (g_lmi / g_ric - 1)))
    P5 = thesis_generalized_plant(G, filter_weight(5.0))
    path = regularisation_path(P5, list(PATH_EPS_U))

    def pole_table(hz):
        fit = fits[hz]
        return ResultTable(
            f"control.controller_poles_{hz:g}hz",
            f"Poles of the {hz:g} Hz controller: printed (table {'4.2' if hz == 5 else '4.3'}) and ours at the "
            f"fitted eps_u = {fit.eps_u:.4g}, gamma margin {fit.margin:.3f}",
            ("printed_re", "printed_im", "ours_re", "ours_im"),
            tuple((p.real, p.imag, o.real, o.imag) for p, o in zip(fit.poles_printed, fit.poles, strict=True)),
        )

    return GammaStudy(
        fits=fits,
        gamma_riccati=routes[2][2],
        gamma_lmi=routes[2][3],
        gamma_lmi_singular=hinf_lmi(P5).gamma,
        routes=ResultTable(
            "control.gamma_routes",
            "gamma_opt by the two synthesis routes (issue: agree within 1 %); the last two rows are the levels "
            "fitted to the printed controllers",
            ("filter_hz", "eps_u", "gamma_riccati", "gamma_lmi", "lmi_minus_riccati_percent"),
            tuple(routes),
        ),
        path=ResultTable(
            "control.regularisation_path",
            "Regularisation path of the 5 Hz problem (D12 = 0 replaced by eps_u): gamma falls, gain rises",
            ("eps_u", "gamma_opt", "dc_gain_command_per_m", "fastest_pole_rad_s"),
            tuple((r["eps"], r["gamma_opt"], r["dc_gain"], r["fastest_pole"]) for r in path),
        ),
        poles_5hz=pole_table(5.0),
        poles_39hz=pole_table(39.0),
    )


# --------------------------------------------------------------------------- 4.6-4.7: the filter sweep
@dataclass(frozen=True)
class FilterSweepStudy:
    """Additive-uncertainty tolerances of the filter sweep (4.6-4.7).

    Attributes
    ----------
    designs : dict
        Cut-off (Hz) -> the thesis design (:func:`~flexdigit.control.thesis_designs.thesis_design`).
    table : ResultTable
        ``control.filter_sweep``: cut-off; the printed %; ours in the thesis's arithmetic, 100/(||T_pq|| in dB)
        with the printed 10x gain (+20 dB); ||T_pq|| in dB (ours); the small-gain tolerance 1/||T_pq|| in m per
        command and as % of |G(0)|; our controller's leading numerator coefficient.
    printed_39hz : dict
        :func:`~flexdigit.control.analysis.additive_tolerance` of the printed 39 Hz controller itself.
    """

    designs: dict
    table: ResultTable
    printed_39hz: dict

    __repr__ = fields_summary


def filter_sweep_study(plant=None) -> FilterSweepStudy:
    """The filter sweep of 4.7 on our designs: see :class:`FilterSweepStudy`."""
    G = plant if plant is not None else _printed_plant().tf
    printed_pct = thesis_value("hinf.additive_tolerance_percent")
    designs, rows = {}, []
    for hz in SWEEP_FILTERS_HZ:
        d = thesis_design(hz, G)
        designs[hz] = d
        tol = additive_tolerance(G, d.controller)
        shifted = tol["tpq_db"] + 20 * math.log10(PRINTED_GAIN_FACTOR)
        rows.append(
            (
                hz,
                printed_pct[f"{hz:g}Hz"],
                100 / shifted if shifted > 0 else math.nan,
                tol["tpq_db"],
                tol["tolerance"],
                tol["tolerance_relative_percent"],
                float(ct.tf(d.controller).num[0][0][0]),
            )
        )
    table = ResultTable(
        "control.filter_sweep",
        "Filter sweep of 4.7: the printed tolerance, ours in the thesis's arithmetic (100/||T_pq|| dB, printed 10x "
        "gain) and the small-gain tolerance",
        (
            "filter_hz",
            "thesis_percent",
            "ours_thesis_arithmetic_percent",
            "tpq_db",
            "tolerance_m_per_command",
            "tolerance_percent_of_dc_gain",
            "numerator_lead",
        ),
        tuple(rows),
    )
    return FilterSweepStudy(designs, table, additive_tolerance(G, printed_controller("39hz")))


# ------------------------------------------------------------------------------------------- the whole chapter
@dataclass(frozen=True)
class Chapter4Study:
    """Everything report chapter 4 shows (see the module docstring); tables in :attr:`tables`.

    Attributes
    ----------
    plant : TransferFunction
        The printed plant G(s) of 4.2.
    filter_peak_db : float
        ``|F(0)|`` of the 5 Hz weight in dB, and ``filter_peak_read_at_rad_s``: where ``|F(j w)|`` is the printed peak.
    printed_5hz_worst_pole : complex
        The rightmost closed-loop pole of the printed 5 Hz controller on the printed plant.
    loop_5hz : LoopMaps
        The fitted 5 Hz design's loop; ``tzw_peak`` (gain, rad/s), ``settling_s`` of T_yw, ``tuw_step_peak`` and
        ``tuw_step_peak_0p5hz`` (x10, the printed gain).
    mixsyn : object
        The mixed-sensitivity design (:func:`~flexdigit.control.mixsyn.design_mixsyn`) on the consistent plant,
        its ``mixsyn_plant`` and ``requirements`` (:func:`~flexdigit.control.mixsyn.check_requirements`).
    """

    plant: ct.TransferFunction
    filter_peak_db: float
    filter_peak_read_at_rad_s: float
    k1: K1Study
    printed_5hz_worst_pole: complex
    gamma: GammaStudy
    loop_5hz: LoopMaps
    tzw_peak: tuple[float, float]
    settling_s: float
    tuw_step_peak: float
    tuw_step_peak_0p5hz: float
    sweep: FilterSweepStudy
    mixsyn: object
    mixsyn_plant: object
    requirements: dict
    comparison: ResultTable

    @property
    def tables(self) -> tuple[ResultTable, ...]:
        """Every table of the chapter, in reading order."""
        g = self.gamma
        return (self.k1.table, g.poles_5hz, g.poles_39hz, g.routes, g.path, self.sweep.table, self.comparison)

    __repr__ = fields_summary


def chapter4_study(*, fast: bool = False, seed: int = 0) -> Chapter4Study:
    """Thesis chapter 4 rebuilt (designs, loops, sweep) and a servo-ready design beside it.

    Parameters
    ----------
    fast : bool
        100 Monte Carlo samples for the mixsyn robustness check instead of 1000 (tests).
    seed : int
        Seed of that Monte Carlo.
    """
    G = _printed_plant().tf
    F = filter_weight(5.0)
    peak_printed = thesis_value("hinf.filter_peak_db")
    wc = 2 * math.pi * 5.0
    worst = loop_maps(G, printed_controller("5hz")).poles
    maps5 = loop_maps(G, thesis_design(5.0, G).controller)
    m05 = loop_maps(G, thesis_design(0.5, G).controller)
    info = build_plant("consistent", output="tip_rotation_rad")
    md = design_mixsyn(info.tf)
    requirements = check_requirements(info, md.controller, n_monte_carlo=100 if fast else 1000, seed=seed)
    return Chapter4Study(
        plant=G,
        filter_peak_db=20 * math.log10(abs(F(0))),
        # |F(j w)| = 1/sqrt(w^2 + wc^2): the frequency at which it is the printed figure
        filter_peak_read_at_rad_s=math.sqrt(max(10 ** (-peak_printed / 10) - wc**2, 0.0)),
        k1=k1_closed_loop_study(),
        printed_5hz_worst_pole=complex(worst[np.argmax(worst.real)]),
        gamma=gamma_study(G),
        loop_5hz=maps5,
        tzw_peak=hinf_norm(maps5.T_zw, "T_zw"),
        settling_s=step_metrics(maps5.T_yw, t_final=3.0)["settling_time_s"],
        tuw_step_peak=PRINTED_GAIN_FACTOR * step_metrics(maps5.T_uw, t_final=3.0)["peak"],
        tuw_step_peak_0p5hz=PRINTED_GAIN_FACTOR * step_metrics(m05.T_uw, t_final=3.0)["peak"],
        sweep=filter_sweep_study(G),
        mixsyn=md,
        mixsyn_plant=info,
        requirements=requirements,
        comparison=_comparison(G, info.tf, md.controller),
    )


def _comparison(G, mixsyn_plant, mixsyn_controller) -> ResultTable:
    """The printed 39 Hz controller (printed plant) beside the mixsyn design (consistent plant)."""

    def row(name, plant, K):
        maps = loop_maps(plant, K)
        zeta = -maps.poles.real / np.abs(maps.poles)
        return (
            name,
            abs(complex(ct.evalfr(maps.T_zw, 1e-9))),
            float(zeta.min()),
            margins(plant, K)["disk_gain_margin"],
            step_metrics(maps.T_yw, t_final=10.0)["settling_time_s"],
            len(np.trim_zeros(ct.tf(K).den[0][0], "f")) - 1,
        )

    return ResultTable(
        "control.mixsyn_vs_thesis_39hz",
        "Thesis 39 Hz controller (as printed, printed plant) beside the mixsyn design (consistent plant)",
        (
            "controller",
            "steady_state_error_abs_s0",
            "min_closed_loop_damping",
            "disk_gain_margin",
            "settling_s",
            "order",
        ),
        (row("thesis 39 Hz", G, printed_controller("39hz")), row("mixsyn (ours)", mixsyn_plant, mixsyn_controller)),
    )
