"""Conversion coefficients K1 and K3 from the linear fits of 3.4.1 and 3.4.3 (E 3.16-3.18, E 3.20-3.25).

K1 (commands per mm) is the inverse slope of deflection against command (table 3.6): the thesis writes the fits
as ``command = (y + b) / a`` and linearises to ``K1 = 1/a``. K3 (mm per gauge volt) combines the deflection fit
``y = a command - b`` with the gauge-voltage fit ``V = s command + c`` (E 3.20-3.22): ``y = (a/s) V - a c/s - b``,
so ``K3 = a / s``.

What reproduces and what does not:

- ``K1 = 1/a`` reproduces E 3.16-3.18 from the printed ``a`` (17.699, 1.1053, 0.36095).
- The printed ``a, b`` are fits *through command 8* (``b/a = 8.00`` for all three gauges) but not least-squares
  fits of table 3.6 as printed: an ordinary least-squares fit gives a = 0.0441, 0.8713, 2.6275 mm per command
  (:func:`fit_deflection`), one through (8, 0) gives 0.0602, 0.9049, 2.7316. Only gauge 2 is close. The data
  behind the printed fits are not in the thesis (figure 3.17 goes to command 43, table 3.6 to 24).
- ``K3 = a/s`` from the printed ``a`` and ``s`` gives 6.5698, 76.025, 314.83 mm/V: E 3.23-3.25 to 4-5 digits.
- The printed offsets of ``y(V)`` are ``-a c / s`` alone: they leave out ``-b``, and gauge 1's is a tenth of it
  (0.1246 for 1.2456).

Examples
--------
>>> [round(k, 4) for k in k1_printed_command_per_mm()]
[17.6991, 1.1053, 0.3609]
>>> [round(k, 2) for k in k3_printed_mm_per_v()]
[6.57, 76.03, 314.83]
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flexdigit._validation import check_array
from flexdigit.errors import ParameterError
from flexdigit.reference import thesis_value

__all__ = [
    "LinearFit",
    "linear_fit",
    "printed_deflection_fits",
    "printed_voltage_fits",
    "k1_command_per_mm",
    "k1_printed_command_per_mm",
    "k3_mm_per_v",
    "k3_printed_mm_per_v",
    "k3_offsets_mm",
    "k3_offsets_as_printed_mm",
    "table_3_6_commands",
    "table_3_6_deflections_mm",
    "fit_deflection",
    "percent_error",
]


@dataclass(frozen=True)
class LinearFit:
    """``y = slope * x + intercept`` with its residual RMS (units of ``y``)."""

    slope: float
    intercept: float
    rms: float = float("nan")

    def __call__(self, x):
        out = self.slope * np.asarray(x, dtype=float) + self.intercept
        return out if out.ndim else float(out)

    def inverse(self, y):
        """``x`` for a given ``y``."""
        out = (np.asarray(y, dtype=float) - self.intercept) / self.slope
        return out if out.ndim else float(out)


def linear_fit(x, y, *, through=None) -> LinearFit:
    """Least-squares line through the points (numpy ``lstsq``); ``through=(x0, y0)`` constrains it to pass there.

    Parameters
    ----------
    x, y : array_like
        Same length, at least 2 points, finite.
    through : tuple of float, optional
        A point the line must pass through (e.g. the equilibrium command and zero deflection).

    Examples
    --------
    >>> f = linear_fit([0, 1, 2], [1, 3, 5])
    >>> round(f.slope, 6), round(f.intercept, 6)
    (2.0, 1.0)
    """
    xa = check_array(x, "x", "linear_fit", ndim=1, min_length=2)
    ya = check_array(y, "y", "linear_fit", ndim=1, min_length=2)
    if xa.shape != ya.shape:
        raise ParameterError(f"linear_fit needs x and y of the same length: got {xa.size} and {ya.size}.")
    if through is None:
        design = np.column_stack([xa, np.ones_like(xa)])
        (slope, intercept), *_ = np.linalg.lstsq(design, ya, rcond=None)
    else:
        x0, y0 = float(through[0]), float(through[1])
        (slope,), *_ = np.linalg.lstsq((xa - x0)[:, None], ya - y0, rcond=None)
        intercept = y0 - slope * x0
    rms = float(np.sqrt(np.mean((slope * xa + intercept - ya) ** 2)))
    return LinearFit(float(slope), float(intercept), rms)


def printed_deflection_fits() -> list[LinearFit]:
    """The printed fits of 3.4.1, ``y_mm = a command - b`` for gauges 1-3 (``command = (y + b)/a``)."""
    return [LinearFit(float(f["a"]), -float(f["b"])) for f in thesis_value("conversion.k1_fit")]


def printed_voltage_fits() -> list[LinearFit]:
    """The printed fits E 3.20-3.22, ``V_SG = slope command + offset`` for gauges 1-3."""
    return [LinearFit(float(f["slope"]), float(f["offset"])) for f in thesis_value("conversion.v_sg_fit")]


def k1_command_per_mm(fits: list[LinearFit]) -> list[float]:
    """``K1 = 1/a`` (E 3.16-3.18): commands per mm of deflection, one per gauge."""
    return [1.0 / f.slope for f in fits]


def k1_printed_command_per_mm() -> list[float]:
    """K1 from the printed fits: 17.699, 1.1053, 0.36095 commands per mm (E 3.16-3.18)."""
    return k1_command_per_mm(printed_deflection_fits())


def k3_mm_per_v(deflection_fits: list[LinearFit], voltage_fits: list[LinearFit]) -> list[float]:
    """``K3 = a / s`` (E 3.23-3.25): mm of deflection per gauge volt, one per gauge."""
    if len(deflection_fits) != len(voltage_fits):
        raise ParameterError(
            f"k3_mm_per_v needs one voltage fit per deflection fit: got {len(voltage_fits)} and {len(deflection_fits)}."
        )
    return [d.slope / v.slope for d, v in zip(deflection_fits, voltage_fits, strict=True)]


def k3_printed_mm_per_v() -> list[float]:
    """K3 from the printed fits: 6.5698, 76.025, 314.83 mm/V (printed 6.5696, 76.0252, 314.8295)."""
    return k3_mm_per_v(printed_deflection_fits(), printed_voltage_fits())


def k3_offsets_mm(deflection_fits: list[LinearFit], voltage_fits: list[LinearFit]) -> list[float]:
    """The offsets of ``y(V) = K3 V + offset``, ``-a c / s - b`` (mm), one per gauge (3.4.3, corrected)."""
    return [d.intercept - d.slope * v.intercept / v.slope for d, v in zip(deflection_fits, voltage_fits, strict=True)]


def k3_offsets_as_printed_mm(deflection_fits: list[LinearFit], voltage_fits: list[LinearFit]) -> list[float]:
    """The offsets as the thesis computed them, ``-a c / s`` without ``-b`` (mm)."""
    return [-d.slope * v.intercept / v.slope for d, v in zip(deflection_fits, voltage_fits, strict=True)]


def table_3_6_commands() -> np.ndarray:
    """The serial commands of tables 3.4 and 3.6 (8..24)."""
    return np.asarray(thesis_value("conversion.table_3_4_commands"), dtype=float)


def table_3_6_deflections_mm() -> list[np.ndarray]:
    """Table 3.6's measured deflections (mm) at gauges 1-3."""
    return [np.asarray(thesis_value(f"conversion.table_3_6_y_sg{k}_mm"), dtype=float) for k in (1, 2, 3)]


def fit_deflection(*, through_equilibrium: bool = False, equilibrium_command: float = 8.0) -> list[LinearFit]:
    """Our least-squares fits of table 3.6 (deflection mm vs command), one per gauge.

    ``through_equilibrium=True`` forces zero deflection at ``equilibrium_command``, as the printed fits do.
    """
    cmds = table_3_6_commands()
    through = (equilibrium_command, 0.0) if through_equilibrium else None
    return [linear_fit(cmds, y, through=through) for y in table_3_6_deflections_mm()]


def percent_error(theory_mm, measured_mm):
    """Table 3.6's "% error": ``|theory - measured| / measured x 100``; NaN where the measurement is 0.

    The thesis's percentages are relative to the *measured* value, within rounding of the printed deflections.
    """
    t = np.asarray(theory_mm, dtype=float)
    m = np.asarray(measured_mm, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where(m != 0, np.abs(t - m) / np.abs(m) * 100.0, np.nan)
    return out
