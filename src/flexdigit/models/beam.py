"""Small-deflection cantilever closed forms: the digit's strip clamped at the base (3.1, 3.3, E 3.1, E 3.12-3.13).

Euler-Bernoulli beam of bending stiffness EI, clamped at x = 0 and free at x = L; loads and deflection share a
sign (a positive load or moment gives a positive deflection). These are the oracles for the twin at small
deflections and the basis of E 3.13-3.15:

=====================  ====================================================  ==========================
load                   deflection y(x)                                       moment M(x)
=====================  ====================================================  ==========================
tip moment M0          M0 x^2 / (2 EI)                         (E 3.1/3.13)  M0
tip force P            P x^2 (3L - x) / (6 EI)                               P (L - x)
force P at a           P x^2 (3a - x) / (6 EI), x <= a;                      P (a - x), x <= a; 0 after
                       P a^2 (3x - a) / (6 EI), x > a
uniform w (N/m)        w x^2 (x^2 - 4 L x + 6 L^2) / (24 EI)     (E 3.12)    w (L - x)^2 / 2
=====================  ====================================================  ==========================

curvature = M/EI (E 3.12), surface strain = curvature x t/2, first bending frequency of a uniform cantilever
``1.8751^2 sqrt(EI / (m L^4))`` (m in kg per metre).

Examples
--------
>>> beam = Cantilever.from_params()
>>> round(beam.ei_n_m2, 6)                           # E I of the strip, table 3.7
0.011999
>>> round(float(beam.deflection(beam.length_m, tip_moment_nm=1e-3)) * 1e3, 3)   # mm
2.4
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Real

import numpy as np

from flexdigit._constants import G_STANDARD_M_S2
from flexdigit._validation import (
    Interval,
    Options,
    check_array,
    check_param,
    check_real,
    declare,
    validate_fields,
    validate_params,
)
from flexdigit.errors import ParameterError
from flexdigit.params import RigParams

__all__ = ["BETA1_L", "Cantilever", "elastica_tip_deflection"]

#: First root of ``1 + cos(b) cosh(b) = 0``, the clamped-free beam's first mode.
BETA1_L = 1.8751040687119611


def _as_x(x, length_m: float) -> np.ndarray:
    return check_array(x, "x_m", "Cantilever", low=0.0, high=length_m * (1 + 1e-12))


def _out(a: np.ndarray):
    return a if a.ndim else float(a)


@declare
@dataclass(frozen=True)
class Cantilever:
    """A uniform cantilever, clamped at x = 0.

    Attributes
    ----------
    length_m : float
        Free length L (m).
    ei_n_m2 : float
        Bending stiffness E I (N m^2).
    thickness_m : float
        Section depth t (m), for surface strain ``kappa t / 2``.
    mass_per_length_kg_m : float
        Mass per unit length (kg/m), for the natural frequency and self-weight.
    """

    length_m: float
    ei_n_m2: float
    thickness_m: float
    mass_per_length_kg_m: float = 0.0

    _parameter_constraints = {
        "length_m": [Interval(Real, 0, None, closed="neither")],
        "ei_n_m2": [Interval(Real, 0, None, closed="neither")],
        "thickness_m": [Interval(Real, 0, None, closed="neither")],
        "mass_per_length_kg_m": [Interval(Real, 0, None)],
    }

    def __post_init__(self) -> None:
        validate_fields(self)

    @classmethod
    def from_params(cls, params: RigParams | None = None, *, length: str = "strip") -> Cantilever:
        """The digit's spring-steel strip from ``params``.

        Parameters
        ----------
        length : {"strip", "digit"}
            ``"strip"``: the 3 x 80 mm = 240 mm of steel; ``"digit"``: ``l`` = 270 mm of table 3.7 (E 3.14).
        """
        p = params or RigParams()
        check_param(length, Options(("strip", "digit")), "length", "Cantilever.from_params")
        g = p.geometry
        return cls(
            length_m=g.strip_length_m if length == "strip" else g.digit_length_m,
            ei_n_m2=p.bending_stiffness_n_m2,
            thickness_m=g.strip_thickness_m,
            mass_per_length_kg_m=p.material.strip_density_kg_m3 * g.cross_section_m2,
        )

    # --- deflections -------------------------------------------------------------------------------------
    def deflection_tip_moment(self, x_m, moment_nm: float):
        """``y = M x^2 / (2 EI)`` (E 3.1, E 3.13), m."""
        x = _as_x(x_m, self.length_m)
        return _out(moment_nm * x**2 / (2.0 * self.ei_n_m2))

    def deflection_tip_load(self, x_m, force_n: float):
        """``y = P x^2 (3L - x) / (6 EI)``, m; tip value ``P L^3 / (3 EI)``."""
        return self.deflection_point_load(x_m, force_n, self.length_m)

    def deflection_point_load(self, x_m, force_n: float, position_m: float):
        """Force ``P`` at ``a = position_m``: ``P x^2 (3a - x)/(6 EI)`` for x <= a, ``P a^2 (3x - a)/(6 EI)`` after."""
        x = _as_x(x_m, self.length_m)
        a = check_real(position_m, "position_m", "Cantilever", low=0.0, high=self.length_m)
        y = np.where(x <= a, x**2 * (3.0 * a - x), a**2 * (3.0 * x - a)) * force_n / (6.0 * self.ei_n_m2)
        return _out(y)

    def deflection_uniform_load(self, x_m, load_n_per_m: float):
        """``y = w x^2 (x^2 - 4 L x + 6 L^2) / (24 EI)`` (the w term of E 3.12), m; tip ``w L^4 / (8 EI)``."""
        x = _as_x(x_m, self.length_m)
        L = self.length_m
        return _out(load_n_per_m * x**2 * (x**2 - 4.0 * L * x + 6.0 * L**2) / (24.0 * self.ei_n_m2))

    def self_weight_load_n_per_m(self, gravity_m_s2: float = G_STANDARD_M_S2) -> float:
        """Self-weight per unit length, ``m g`` (N/m): the ``w`` of E 3.12 for a horizontal digit."""
        return self.mass_per_length_kg_m * gravity_m_s2

    def deflection(
        self,
        x_m,
        *,
        tip_moment_nm: float = 0.0,
        tip_load_n: float = 0.0,
        point_loads: tuple[tuple[float, float], ...] = (),
        uniform_load_n_per_m: float = 0.0,
    ):
        """Superposition of the loads above; ``point_loads`` is a sequence of ``(force_n, position_m)``."""
        y = np.asarray(self.deflection_tip_moment(x_m, tip_moment_nm), dtype=float)
        y = y + np.asarray(self.deflection_tip_load(x_m, tip_load_n))
        for force, position in point_loads:
            y = y + np.asarray(self.deflection_point_load(x_m, force, position))
        y = y + np.asarray(self.deflection_uniform_load(x_m, uniform_load_n_per_m))
        return _out(y)

    # --- internal moment, curvature, strain -----------------------------------------------------------
    def moment(
        self,
        x_m,
        *,
        tip_moment_nm: float = 0.0,
        tip_load_n: float = 0.0,
        point_loads: tuple[tuple[float, float], ...] = (),
        uniform_load_n_per_m: float = 0.0,
    ):
        """Bending moment M(x) (N m), same loads and sign as :meth:`deflection`."""
        x = _as_x(x_m, self.length_m)
        L = self.length_m
        m = tip_moment_nm + tip_load_n * (L - x) + uniform_load_n_per_m * (L - x) ** 2 / 2.0
        for force, position in point_loads:
            a = check_real(position, "position_m", "Cantilever", low=0.0, high=L)
            m = m + np.where(x <= a, force * (a - x), 0.0)
        return _out(np.asarray(m, dtype=float))

    def curvature(self, x_m, **loads):
        """Curvature ``M(x) / EI`` (1/m), E 3.12."""
        return _out(np.asarray(self.moment(x_m, **loads)) / self.ei_n_m2)

    def surface_strain(self, x_m, **loads):
        """Surface strain ``kappa t / 2`` (dimensionless) at the gauge face."""
        return _out(np.asarray(self.curvature(x_m, **loads)) * self.thickness_m / 2.0)

    def slope(self, x_m, *, tip_moment_nm: float = 0.0, tip_load_n: float = 0.0):
        """Slope dy/dx (rad) for a tip moment and a tip force: ``M x / EI + P x (2L - x) / (2 EI)``."""
        x = _as_x(x_m, self.length_m)
        L = self.length_m
        return _out((tip_moment_nm * x + tip_load_n * x * (2.0 * L - x) / 2.0) / self.ei_n_m2)

    # --- dynamics -------------------------------------------------------------------------------------
    def first_natural_frequency_rad_s(self) -> float:
        """``1.8751^2 sqrt(EI / (m L^4))`` (rad/s), the first bending mode of a uniform clamped-free beam.

        For the bare strip (7850 kg/m^3 assumed, 240 mm) this is 34.3 rad/s; table 3.1 measures 10.16 rad/s with the
        nylon supports on the strip, which add mass the formula leaves out.
        """
        if self.mass_per_length_kg_m <= 0:
            raise ParameterError(
                "The 'mass_per_length_kg_m' parameter of Cantilever must be > 0 for a natural frequency. Got 0."
            )
        return BETA1_L**2 * math.sqrt(self.ei_n_m2 / (self.mass_per_length_kg_m * self.length_m**4))

    def tip_stiffness_n_per_m(self) -> float:
        """Tip force per tip deflection, ``3 EI / L^3`` (N/m)."""
        return 3.0 * self.ei_n_m2 / self.length_m**3

    def tip_moment_for_deflection_nm(self, tip_deflection_m: float) -> float:
        """``M = 2 EI y_max / L^2`` (E 3.13 inverted, as in 3.4.1), N m."""
        return 2.0 * self.ei_n_m2 * check_real(tip_deflection_m, "tip_deflection_m", "Cantilever") / self.length_m**2


@validate_params({"alpha2": [Interval(Real, 0, None, closed="neither")]})
def elastica_tip_deflection(alpha2: float) -> float:
    """Tip deflection / L of a cantilever under a dead tip load perpendicular to it, ``P L^2 / EI = alpha2``: the
    large-deflection elastica (Bisshopp & Drucker 1945, elliptic integrals), the closed form the twin's chain and
    PyElastica are checked against.

    Examples
    --------
    >>> round(float(elastica_tip_deflection(0.01) / (0.01 / 3)), 3)    # small loads: P L^3 / 3EI
    1.0
    >>> round(float(elastica_tip_deflection(10.0)), 4)
    0.8106
    """
    from scipy.optimize import brentq
    from scipy.special import ellipe, ellipeinc, ellipk, ellipkinc

    a = math.sqrt(alpha2)
    k = brentq(
        lambda k: ellipk(k * k) - ellipkinc(math.asin(1 / (math.sqrt(2) * k)), k * k) - a,
        1 / math.sqrt(2) + 1e-12,
        1 - 1e-12,
        xtol=1e-15,
    )
    phi1 = math.asin(1 / (math.sqrt(2) * k))
    return 1 - 2 / a * (ellipe(k * k) - ellipeinc(phi1, k * k))
