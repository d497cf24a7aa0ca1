"""The calibrated twin against thesis chapter 3, one call: what the twin chapter of the report shows, as numbers.

:func:`chapter3_twin_study` simulates the release tests (tables 3.1, 3.2) and the actuation sweep (E 3.20-3.22) as
experiments and analyses them like measurements (:func:`flexdigit.calibrate.targets.release_figures`, as
``flexdigit calibrate`` does a rig's records), reads table 3.6's deflections off the twin's static shape, lists the
calibration in use (fit residuals and parameters), and repeats the closed-form checks the twin was not written
from, with their convergence as the cells are refined. It lives in the calibration layer because it judges the
twin's calibration (and uses its release fit).

Examples
--------
>>> checks = physics_checks()
>>> all(abs(v) < 0.01 for v in checks.values())      # closed forms within 1 % at the default 12 cells
True
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flexdigit._repr import fields_summary
from flexdigit._result_table import ResultTable
from flexdigit.calibrate.targets import CalibrationTargets, release_figures
from flexdigit.errors import DataFileError
from flexdigit.identify.fit import second_order_response
from flexdigit.identify.timeseries import series_from_table
from flexdigit.models.beam import elastica_tip_deflection
from flexdigit.params import RigParams
from flexdigit.reference import thesis_value
from flexdigit.twin import records
from flexdigit.twin.calibration import default_calibration, default_calibration_source, default_fit_record
from flexdigit.twin.digit import Chain
from flexdigit.twin.twin import Twin

__all__ = [
    "CONVERGENCE_CELLS",
    "ReleaseFit",
    "release_fit",
    "Table36",
    "table_3_6",
    "physics_checks",
    "convergence_table",
    "calibration_tables",
    "Chapter3TwinStudy",
    "chapter3_twin_study",
]

#: Cells of the convergence study (the twin's default is 12 over the strip).
CONVERGENCE_CELLS = (3, 6, 12, 24, 48)


@dataclass(frozen=True)
class ReleaseFit:
    """A simulated release test fitted like a measurement: ``figures`` is
    :func:`~flexdigit.calibrate.targets.release_figures` of its three gauges (``wn_rad_s`` and ``zeta``, the medians
    over the gauges identified; ``fits``; ``skipped``), and ``corr2_vs_thesis_model`` the corr2 of gauge 2 with the
    thesis's second-order model (its wn and zeta) on gauge 2's fitted offset, amplitude and release instant.
    ``refused``: where no gauge's record can be identified (a 10-bit ADC's release spanning a few of its steps), the
    reason, and wn, zeta and corr2 NaN; else None."""

    record: object
    figures: dict
    corr2_vs_thesis_model: float
    refused: str | None = None

    @property
    def wn_rad_s(self) -> float:
        return float(self.figures["wn_rad_s"])

    @property
    def zeta(self) -> float:
        return float(self.figures["zeta"])

    def gauge_fit(self, channel: str = "gauge2"):
        """The identification of ``channel``, or the first gauge identified (None where none is)."""
        fits = self.figures["fits"]
        return next((f for f in fits if f.channel == channel), fits[0] if fits else None)

    __repr__ = fields_summary


def release_fit(
    housing: bool, *, duration_s: float, seed: int, params: RigParams | None = None, orientation: str = "vertical"
) -> ReleaseFit:
    """Simulate a release test (20 mm tip deflection, 500 Hz, the digit mounted ``orientation``) and fit it (see
    :class:`ReleaseFit`)."""
    key = "with_housing" if housing else "without_housing"
    res = records.release_test(
        housing=housing, duration_s=duration_s, sample_rate_hz=500, seed=seed, params=params, orientation=orientation
    )
    t = res.column("time_s")
    gauges = [name.removesuffix("_v") for name in res.table.column_names if name.startswith("gauge")]  # G of them
    try:
        figures = release_figures([series_from_table(res, gauge) for gauge in gauges])
    except DataFileError as exc:  # no gauge identifiable: the reason, never a figure fitted to the ADC's steps
        return ReleaseFit(res, {"wn_rad_s": math.nan, "zeta": math.nan, "fits": [], "skipped": []}, math.nan, str(exc))
    wn_t = thesis_value(f"digit.release_tests_{key}.wn_avg_rad_s")
    z_t = thesis_value(f"digit.release_tests_{key}.zeta_avg")
    gauge2 = next((f for f in figures["fits"] if f.channel == "gauge2"), figures["fits"][0])
    model = second_order_response(t, "release", wn_t, z_t, gauge2.offset, gauge2.amplitude, gauge2.t0_s)
    corr = float(np.corrcoef(model, res.column(f"{gauge2.channel}_v"))[0, 1])
    return ReleaseFit(res, figures, corr)


@dataclass(frozen=True)
class Table36:
    """Table 3.6 beside table 3.4 (the thesis's model) and the twin's static deflections at the gauges (mm).

    ``worst_trusted_mm``: the twin's largest error over the readings where table 3.4 agrees within 0.5 mm (the
    readings the calibration weights); ``worst_all_mm`` over every reading. ``twin_mm`` is (3, commands)."""

    commands: tuple[int, ...]
    measured_mm: np.ndarray
    thesis_model_mm: np.ndarray
    twin_mm: np.ndarray
    trusted: np.ndarray
    worst_trusted_mm: float
    worst_all_mm: float
    table: ResultTable

    __repr__ = fields_summary


def table_3_6(params: RigParams | None = None, calibration=None) -> Table36:
    """The twin's deflections at the gauges for table 3.6's commands (see :class:`Table36`)."""
    p = params or RigParams()
    cal = calibration or default_calibration()
    targets = CalibrationTargets.from_thesis()
    commands = tuple(int(c) for c in targets.deflection_commands)
    measured = np.array(targets.deflection_mm)
    trusted = np.array(targets.deflection_weight) > 0
    theory = np.array([thesis_value(f"conversion.table_3_4_y_sg{k}_mm") for k in (1, 2, 3)])
    twin = np.column_stack([Twin(p, cal, command=c).deflection_m(p.geometry.gauge_positions_m) * 1e3 for c in commands])
    rows = tuple(
        (c, *(v for g in range(3) for v in (measured[g, j], theory[g, j], float(twin[g, j]))))
        for j, c in enumerate(commands)
    )
    err = np.abs(twin - measured)
    table = ResultTable(
        "twin.table_3_6",
        "Table 3.6 beside table 3.4 (thesis model, E 3.15) and the twin: deflection at the gauges (mm)",
        ("command",) + tuple(f"sg{g}_{k}_mm" for g in (1, 2, 3) for k in ("measured", "thesis_model", "twin")),
        rows,
    )
    worst_trusted = float(err[trusted].max()) if trusted.any() else float("nan")
    return Table36(commands, measured, theory, twin, trusted, worst_trusted, float(err.max()), table)


def physics_checks(cells: int = 12) -> dict[str, float]:
    """Relative errors of the twin's chain against closed forms it was not written from, at ``cells`` cells.

    ``tip_load``: small-deflection tip load vs P L^3/3EI; ``arc_90deg``: a tip moment bending the strip 90 deg vs
    the circular arc; ``elastica_pl2_ei_10``: a large tip load vs the elastica; ``first_frequency``: the first
    bending frequency vs Euler-Bernoulli.
    """
    ei, length = 0.012, 0.24
    chain = Chain.uniform(length, ei, cells, mass_per_length_kg_m=0.038)
    tip = chain.solve_static(tip_force_n=[[0, 1e-6]]).tip_m[0, 1]
    theta = math.pi / 2
    sol = chain.solve_static(tip_moment_nm=theta * ei / length)
    r = length / theta
    exact = np.array([r * math.sin(theta), r * (1 - math.cos(theta))])
    y = -Chain.uniform(1.0, 1.0, cells).solve_static(tip_force_n=[[0, -10.0]]).tip_m[0, 1]
    wn = chain.linear_modes()[0][0]
    return {
        "tip_load": tip / (1e-6 * length**3 / (3 * ei)) - 1,
        "arc_90deg": float(np.linalg.norm(sol.tip_m[0] - exact) / r),
        "elastica_pl2_ei_10": y / elastica_tip_deflection(10.0) - 1,
        "first_frequency": wn / (1.8751040687**2 * math.sqrt(ei / (0.038 * length**4))) - 1,
    }


def convergence_table(cells=CONVERGENCE_CELLS) -> ResultTable:
    """Relative errors against the closed forms as the cells are refined: second order (x 1/4 per halving)."""
    ei, length, mu = 0.012, 0.24, 0.038
    exact_f = 1.8751040687**2 * math.sqrt(ei / (mu * length**4))
    rows = []
    for n in cells:
        chain = Chain.uniform(length, ei, n, mass_per_length_kg_m=mu)
        tip = chain.solve_static(tip_force_n=[[0, 1e-6]]).tip_m[0, 1] / (1e-6 * length**3 / (3 * ei)) - 1
        y = (
            -Chain.uniform(1.0, 1.0, n).solve_static(tip_force_n=[[0, -10.0]]).tip_m[0, 1]
            / elastica_tip_deflection(10.0)
            - 1
        )
        wn = chain.linear_modes()[0][0] / exact_f - 1
        rows.append((n, tip, y, wn))
    return ResultTable(
        "twin.convergence",
        "Convergence with discretisation (relative errors against closed forms: tip load vs P L^3/3EI, the "
        "elastica at P L^2/EI = 10, the first frequency vs Euler-Bernoulli; the twin's default is 12 cells over "
        "the strip)",
        ("cells", "tip_load_rel_error", "elastica_rel_error", "first_frequency_rel_error"),
        tuple(rows),
    )


def calibration_tables(calibration=None) -> tuple[ResultTable, ResultTable]:
    """The calibration in use: its fit residuals and its parameters (one row per element of a list parameter)."""
    cal = calibration or default_calibration()
    residuals = default_fit_record().get("residuals", [])
    source = default_calibration_source()
    source = "packaged, fitted to the thesis by flexdigit calibrate --thesis" if source == "packaged" else source
    rows = []
    for k, v in cal.to_dict().items():
        rows += [(f"{k}[{i}]", x) for i, x in enumerate(v)] if isinstance(v, list | tuple) else [(k, v)]
    return (
        ResultTable(
            "twin.calibration_residuals",
            f"Calibration ({source}): fit residuals (flexdigit calibrate)",
            ("target", "measured", "twin", "residual", "unit"),
            tuple((r["target"], r["measured"], r["twin"], r["twin"] - r["measured"], r["unit"]) for r in residuals),
        ),
        ResultTable(
            "twin.calibration_parameters",
            f"Calibration ({source}): fitted parameters (one row per element of a per-section or per-gauge parameter)",
            ("parameter", "value"),
            tuple(rows),
        ),
    )


@dataclass(frozen=True)
class Chapter3TwinStudy:
    """Everything the twin chapter shows; tables in :attr:`tables`.

    ``releases``: housing (bool) -> :class:`ReleaseFit`; ``sweep``: the simulated actuation sweep and
    ``sweep_fits`` (slope V/command, offset V per gauge); ``table_3_6``: None on a digit other than the thesis rig
    (its readings are the thesis rig's); ``tip_angle_43_rad``: the twin's tip rotation at command
    43; ``checks``: :func:`physics_checks`; ``orientation``: the mount of every simulated record
    (:func:`flexdigit.twin.records.release_orientation`: tip up, or hanging for a digit that buckles tip up).
    """

    calibration: object
    releases: dict
    sweep: object
    sweep_fits: tuple[tuple[float, float], ...]
    table_3_6: Table36 | None
    tip_angle_43_rad: float
    checks: dict
    calibration_residuals: ResultTable
    calibration_parameters: ResultTable
    convergence: ResultTable
    orientation: str = "vertical"

    @property
    def tables(self) -> tuple[ResultTable, ...]:
        thesis = () if self.table_3_6 is None else (self.table_3_6.table,)
        return (*thesis, self.calibration_residuals, self.calibration_parameters, self.convergence)

    __repr__ = fields_summary


def chapter3_twin_study(params: RigParams | None = None, *, seed: int = 0, fast: bool = False) -> Chapter3TwinStudy:
    """The calibrated twin against chapter 3 (see the module docstring).

    ``seed`` seeds the simulated experiments; ``fast`` (tests) shortens the release tests and the sweep's settling.
    """
    p = params or RigParams()
    cal = default_calibration()
    mount = records.release_orientation(p, cal)  # tip up as the thesis, unless the digit buckles so: then hung
    # the bare digit's time constant is 1/(zeta wn) = 39 s: a zeta from fewer seconds is at the noise's mercy
    duration = {False: 15.0 if fast else 30.0, True: 5.0 if fast else 8.0}
    releases = {
        h: release_fit(h, duration_s=duration[h], seed=seed, params=p, orientation=mount) for h in (False, True)
    }
    # 20 readings a command even in fast mode: the taut cable's guide friction scatters single readings by
    # 10-40 mV (twin calibration, chapter 7), which 5 readings leave in the small E 3.22 intercept
    sweep = records.actuation_sweep(settle_s=2.0 if fast else 3.0, samples=20, seed=seed, params=p, orientation=mount)
    cmds = sweep.column("command")
    gauges = [name for name in sweep.table.column_names if name.startswith("gauge")]  # one per gauge of the digit
    fits = tuple(tuple(float(v) for v in np.polyfit(cmds, sweep.column(name), 1)) for name in gauges)
    residuals, parameters = calibration_tables(cal)
    return Chapter3TwinStudy(
        calibration=cal,
        releases=releases,
        sweep=sweep,
        sweep_fits=fits,
        table_3_6=table_3_6(p, cal) if p.is_thesis_rig() else None,  # the thesis rig's measured deflections
        tip_angle_43_rad=float(Twin(p, cal, command=43, orientation=mount).state()[0][-1]),
        checks=physics_checks(),
        calibration_residuals=residuals,
        calibration_parameters=parameters,
        convergence=convergence_table(),
        orientation=mount,
    )
