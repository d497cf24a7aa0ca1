"""Thesis chapter 3's printed tables recomputed from the component models, one call: what the models chapter of the
report compares with the thesis, as numbers.

:func:`chapter3_study` rebuilds tables 3.1 and 3.2 (zeta from the printed %OS, wn from the printed wd), table 3.4
(E 3.15, and at the tip position the printed y_max column fits), the K1/K3 fits of 3.4.1 and 3.4.3, E(s), MT(s)
and the plant G(s) of 3.5, printed and unit-consistent.

Examples
--------
>>> study = chapter3_study()
>>> round(float(study.plant_printed.tf.num[0][0][-1]), 1)     # 3.5: G(s) = 48.7 / (s^4 + ...)
48.7
>>> study.table_3_4.table.column("command")[:3]
[8, 9, 10]
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flexdigit._repr import fields_summary
from flexdigit._result_table import ResultTable
from flexdigit.models import cable, conversion, second_order, servo
from flexdigit.models.plant import Plant, build_plant
from flexdigit.params import RigParams
from flexdigit.reference import thesis_value

__all__ = [
    "CONSISTENT_OUTPUTS",
    "ReleaseTable",
    "release_table",
    "Table34",
    "table_3_4",
    "ConversionStudy",
    "conversion_study",
    "PlantStudy",
    "plant_study",
    "Chapter3Study",
    "chapter3_study",
]

#: Outputs of the consistent plant tabulated (3.5).
CONSISTENT_OUTPUTS = ("deflection_sg1_m", "tip_rotation_rad", "gauge_v_sg1", "curvature_1_per_m")


@dataclass(frozen=True)
class ReleaseTable:
    """Table 3.1 or 3.2 recomputed: zeta from each printed %OS (NaN where it is unreadable) and wn from each
    printed wd and zeta, in :attr:`table` (``models.table_3_1`` / ``models.table_3_2``)."""

    name: str
    percent_overshoot: np.ndarray
    zeta: np.ndarray
    wn_from_wd_rad_s: np.ndarray
    table: ResultTable

    __repr__ = fields_summary


def release_table(which: str) -> ReleaseTable:
    """Table 3.1 (``"without_housing"``) or 3.2 (``"with_housing"``) recomputed from its printed columns."""
    number = {"without_housing": "3.1", "with_housing": "3.2"}[which]
    t = thesis_value(f"digit.release_tests_{which}")
    os_ = np.asarray(t["percent_overshoot"], dtype=float)
    zeta = np.atleast_1d(second_order.zeta_from_overshoot(os_))
    wn_from_wd = np.atleast_1d(second_order.natural_frequency_from_damped(t["wd_rad_s"], t["zeta"]))
    rows = tuple(
        (i, os_[i - 1], t["zeta"][i - 1], zeta[i - 1], t["wn_rad_s"][i - 1], wn_from_wd[i - 1])
        for i in range(1, zeta.size + 1)
    )
    table = ResultTable(
        f"models.table_{number.replace('.', '_')}",
        f"Table {number} recomputed (release tests {which.replace('_', ' ')})",
        ("test", "percent_overshoot", "zeta_printed", "zeta_ours", "wn_printed_rad_s", "wn_from_wd_rad_s"),
        rows,
    )
    return ReleaseTable(which, os_, zeta, wn_from_wd, table)


@dataclass(frozen=True)
class Table34:
    """Table 3.4 by E 3.15 at the gauges and the tip (``ours``), at the tip position the printed y_max column fits
    (``tip_x_fit_m``, least squares; ``ours_at_fit``), in :attr:`table` (``models.table_3_4``)."""

    ours: dict
    tip_x_fit_m: float
    ours_at_fit: dict
    table: ResultTable

    __repr__ = fields_summary


def table_3_4_gauge_columns(ours: dict) -> list[str]:
    """``y_sg1_mm .. y_sgG_mm``: the gauge columns of :func:`flexdigit.models.cable.table_3_4`, in gauge order."""
    return sorted((k for k in ours if k.startswith("y_sg")), key=lambda k: int(k[4:-3]))


def table_3_4_printed(column: str, params: RigParams, rows: int) -> list[float]:
    """Table 3.4's printed ``column`` on the thesis rig; NaN on another digit (its gauges and tip are elsewhere)."""
    if params.is_thesis_rig():
        return list(thesis_value(f"conversion.table_3_4_{column}"))
    return [math.nan] * rows


def table_3_4(params: RigParams | None = None) -> Table34:
    """Table 3.4 reproduced (mm; E 3.15 with 0.8622 deg per command)."""
    p = params or RigParams()
    ours = cable.table_3_4(params=p)
    x_fit = cable.fit_tip_x_m(thesis_value("conversion.table_3_4_y_max_mm"), params=p)
    ours_fit = cable.table_3_4(params=p, tip_x_m=round(x_fit, 3))
    columns = [*table_3_4_gauge_columns(ours), "y_max_mm"]
    printed = {col: table_3_4_printed(col, p, len(ours["commands"])) for col in columns}
    rows = []
    for j, c in enumerate(ours["commands"]):
        row = [int(c)]
        for col in columns:
            row += [printed[col][j], float(ours[col][j])]
        row.append(float(ours_fit["y_max_mm"][j]))
        rows.append(tuple(row))
    gauges = tuple(name for col in columns[:-1] for name in (f"sg{col[4:-3]}_printed_mm", f"sg{col[4:-3]}_ours_mm"))
    table = ResultTable(
        "models.table_3_4",
        "Table 3.4 reproduced (mm; E 3.15 with 0.8622 deg per command; the last column at the tip position "
        f"x = {round(x_fit, 3)} m the printed y_max column fits)",
        ("command", *gauges, "y_max_printed_mm", "y_max_ours_at_l_mm", "y_max_ours_at_fitted_x_mm"),
        tuple(rows),
    )
    return Table34(ours, x_fit, ours_fit, table)


@dataclass(frozen=True)
class ConversionStudy:
    """K1 and K3 of 3.4.1 and 3.4.3 from the printed fits, and the fits redone on table 3.6.

    Attributes
    ----------
    k1, k3 : ndarray
        Per gauge, from the printed fits (E 3.16-3.18, E 3.23-3.25).
    printed_fits, through_equilibrium, ols : list of LinearFit
        The printed deflection fits, ours through (8, 0) and by ordinary least squares.
    offsets_mm : ndarray
        The K3 offsets the printed deflection and voltage fits imply.
    table : ResultTable
        ``models.k1_k3``.
    """

    k1: np.ndarray
    k3: np.ndarray
    printed_fits: list
    through_equilibrium: list
    ols: list
    offsets_mm: np.ndarray
    table: ResultTable

    __repr__ = fields_summary


def conversion_study() -> ConversionStudy:
    """K1 and K3 (3.4.1, 3.4.3): see :class:`ConversionStudy`."""
    k1 = np.asarray(conversion.k1_printed_command_per_mm())
    k3 = np.asarray(conversion.k3_printed_mm_per_v())
    ours = conversion.fit_deflection(through_equilibrium=True)
    ols = conversion.fit_deflection()
    printed = conversion.printed_deflection_fits()
    offsets = np.asarray(conversion.k3_offsets_mm(printed, conversion.printed_voltage_fits()))
    rows = tuple(
        (g + 1, printed[g].slope, -printed[g].intercept, ours[g].slope, ols[g].slope, k1[g], k3[g]) for g in range(3)
    )
    table = ResultTable(
        "models.k1_k3",
        "K1 and K3 (3.4.1, 3.4.3): the printed fits y = a command - b, ours through (8, 0) and by ordinary least "
        "squares, K1 = 1/a, K3 = a/s",
        ("gauge", "a_printed_mm_per_command", "b_printed_mm", "a_ours_through_8_mm_per_command")
        + ("a_ours_ols_mm_per_command", "k1_command_per_mm", "k3_mm_per_v"),
        rows,
    )
    return ConversionStudy(k1, k3, printed, ours, ols, offsets, table)


@dataclass(frozen=True)
class PlantStudy:
    """The plant of 3.5: printed, and unit-consistent for each output (cable-model and measured gains)."""

    printed: Plant
    consistent: dict
    measured: dict
    dc_gains: ResultTable
    poles: ResultTable

    __repr__ = fields_summary


def plant_study(params: RigParams | None = None) -> PlantStudy:
    """The printed plant and the consistent ones (:data:`CONSISTENT_OUTPUTS`), their DC gains and poles."""
    p = params or RigParams()
    g = build_plant("printed", p)
    consistent = {out: build_plant("consistent", p, output=out) for out in CONSISTENT_OUTPUTS}
    measured = {
        out: build_plant("consistent", p, output=out, gains="measured") for out in ("deflection_sg1_m", "gauge_v_sg1")
    }
    rows = [(out, c.output_unit, c.dc_gain) for out, c in consistent.items()]
    rows += [(out + " (measured gains)", c.output_unit, c.dc_gain) for out, c in measured.items()]
    rows.append(("printed G (deflection_sg1_m)", "m", g.dc_gain))
    pole_rows = [(out, z.real, z.imag) for out, c in consistent.items() for z in c.poles if z.imag >= 0]
    pole_rows += [("printed G", z.real, z.imag) for z in g.poles if z.imag >= 0]
    return PlantStudy(
        g,
        consistent,
        measured,
        ResultTable(
            "models.plant_dc_gains",
            "Plant variants: DC gain per command (in the output's unit)",
            ("output", "unit", "dc_gain_per_command"),
            tuple(rows),
        ),
        ResultTable(
            "models.plant_poles",
            "Plant variants: upper-half-plane poles (rad/s)",
            ("plant", "pole_re_rad_s", "pole_im_rad_s"),
            tuple(pole_rows),
        ),
    )


@dataclass(frozen=True)
class Chapter3Study:
    """Everything the models chapter compares with the thesis; tables in :attr:`tables`.

    ``digit_tf`` is E(s) (with housing) and ``bare_digit_tf`` the bare strip's; ``servo_tf`` MT(s) in each form
    (``"unit"``, ``"printed"``, ``"consistent"``); ``k2`` E 3.19 and ``k2_rounded_i`` with I rounded to 5.85e-14.
    """

    releases: dict
    digit_tf: object
    bare_digit_tf: object
    servo_tf: dict
    k2: float
    k2_rounded_i: float
    table_3_4: Table34
    conversion: ConversionStudy
    plant: PlantStudy

    @property
    def plant_printed(self) -> Plant:
        return self.plant.printed

    @property
    def tables(self) -> tuple[ResultTable, ...]:
        return (
            self.releases["without_housing"].table,
            self.releases["with_housing"].table,
            self.table_3_4.table,
            self.conversion.table,
            self.plant.dc_gains,
            self.plant.poles,
        )

    __repr__ = fields_summary


def chapter3_study(params: RigParams | None = None) -> Chapter3Study:
    """Thesis chapter 3's components, tables and plant recomputed (see the module docstring)."""
    p = params or RigParams()
    return Chapter3Study(
        releases={name: release_table(name) for name in ("without_housing", "with_housing")},
        digit_tf=second_order.digit_tf_from_params(p, housing=True),
        bare_digit_tf=second_order.digit_tf_from_params(p, housing=False),
        servo_tf={form: servo.servo_tf(p, form=form) for form in ("unit", "printed", "consistent")},
        k2=cable.k2_nm_per_rad(p),
        k2_rounded_i=cable.k2_nm_per_rad(p, second_moment_m4=5.85e-14),
        table_3_4=table_3_4(p),
        conversion=conversion_study(),
        plant=plant_study(p),
    )
