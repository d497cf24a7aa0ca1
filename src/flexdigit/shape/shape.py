"""The digit's centre line from the three gauges and the servo command, with its uncertainty (thesis 1.1, 3.3-3.4).

The thesis's digit gives "a sense of feeling and shape" (1.1); this module gives the shape. It is a beam inversion
of its own, written from the thesis's beam relations rather than from the twin's chain solver:

1. **Gauges to curvature.** Each half bridge reads ``V = V0 + S kappa`` (E 2.2-2.4: ``Vm/Vs = GF/4 * 2 eps``,
   ``eps = kappa t / 2``, times the amplifier gain): ``S`` and ``V0`` per channel from the calibration.
2. **A moment field with few unknowns.** Along the digit, curvature is ``kappa(s) = M(s) / EI(s)`` (E 3.12) on the
   three 80 mm strips (strip plus housing stiffness per section) and zero on the rigid nylon supports. The moment
   is the sum of

   - the cable's, ``T e``, the same all along (3.3: the cable runs at constant eccentricity ``e``),
   - the digit's own weight and its supports' (known masses, world-fixed gravity of the mounting),
   - one load: a weight (force ``P`` along gravity, chapters 6-7) or a press normal to the digit (force ``f``)
     at an unknown arc position ``s_L``: ``M(s) = (r_L - r(s)) x F`` for ``s < s_L``, zero beyond.

   With the cable taut the command fixes the tip angle: the cable is shortened by ``r_M (theta_M - theta_M(8))``
   (E 3.11) and takes it up as ``e psi_tip + T / k_c`` (E 3.14 with the cable's stretch), one more equation.
3. **Fit.** For every candidate ``s_L`` (1 mm grid, then a parabola through the best three) the model is linear in
   ``(T, P)`` given the shape; a weighted least-squares fit with ``T >= 0`` (a cable only pulls) and ``P >= 0``
   (a weight only hangs) over the three gauges (and the tip-angle equation) picks the best. The no-load model
   (``T`` alone) is fitted too: contact is declared when the load model lowers chi-square by more than
   ``contact_chi2`` (a likelihood-ratio test) and the load's moment is above the noise.
4. **Integrate.** ``psi(s) = int kappa``, ``r(s) = int (cos psi, sin psi)`` on a 1 mm grid (large rotations kept);
   the lever arms of the world-fixed forces depend on the shape, so steps 2-4 repeat from the straight digit
   until the shape settles (``tol_rad``). Each round ranks the load's positions on the last shape's lever arms,
   a linearisation that holds while the shape changes little with the load; where a digit sags far under its own
   weight it does not (a 0.40 m strip of 0.25 mm turns 73-84 deg lying horizontal), so wherever a load is found
   or the readings do not fit, a global search settles every candidate position of a coarse grid on its own
   shape and restarts the fit from the best one if it fits better (:meth:`ShapeEstimator._global_search`).
5. **Uncertainty.** The noise model is the calibration's: white noise per reading (``/sqrt(n_average)`` when
   readings are averaged), and, while the cable is taut, the cable-guide friction, a moment ``ratio e T`` per
   section that averaging does not remove (:mod:`flexdigit.twin.sensors`). The parameters' covariance is the
   inverse Fisher information ``(J' W J)^-1`` at the estimate; the shape's, ``J_r Cov J_r'``, is reported as a
   standard deviation normal to the centre line. Where the load's position has no information (a load between
   the clamp and gauge 1 bends no gauge on a free digit) its standard deviation is infinite and the estimate
   says the load is not locatable there (:meth:`ShapeEstimator.locatability`).

It is quasi-static (no inertia): a swinging digit is estimated as if it were at rest in its present shape.

Examples
--------
>>> from flexdigit.twin import static_gauges_v
>>> est = ShapeEstimator(orientation="horizontal")
>>> v = static_gauges_v([0.025], [0.20], [20])          # 25 g at 200 mm on the horizontal digit, command 20
>>> e = est.estimate(v, command=20)
>>> bool(e.contact[0]), round(float(e.load_position_from_base_m[0]), 2), round(float(e.load_mass_kg[0]), 3)
(True, 0.2, 0.025)
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np

from flexdigit._constants import G_STANDARD_M_S2
from flexdigit._repr import fields_summary
from flexdigit._validation import check_array, check_choice, check_int, check_real
from flexdigit.control.design20ms import digit_mount
from flexdigit.errors import ConvergenceWarning, ParameterError
from flexdigit.models.servo import command_to_angle_rad
from flexdigit.params import RigParams
from flexdigit.twin.digit import ORIENTATIONS
from flexdigit.twin.digit_calibration import twin_calibration
from flexdigit.twin.sensors import SensorChain
from flexdigit.twin.twin import DEFAULT_CELLS_PER_SECTION, cached_digit, static_gauges_v

__all__ = [
    "DigitBeam",
    "ShapeEstimate",
    "ShapeEstimator",
    "ShapeAccuracy",
    "shape_accuracy",
    "accuracy_commands",
    "accuracy_positions_m",
    "LOAD_KINDS",
    "true_centre_line_m",
]

#: What the load is: a weight (force along gravity), a press normal to the digit, or no load at all.
LOAD_KINDS = ("weight", "press", "none")


def _cross(a, b):
    """z-component of the 2-D cross product ``a x b`` over the last axis."""
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


@dataclass(frozen=True)
class DigitBeam:
    """The static beam the estimator inverts: a 1 mm grid along the digit with its stiffness and masses.

    Attributes
    ----------
    s_m : ndarray, shape (P,)
        Cell mid-points along the digit from the clamp (m).
    ds_m : float
        Cell length (m).
    inv_ei : ndarray, shape (P,)
        ``1 / EI`` per cell (1/(N m^2)), 0 on the rigid supports and the clamped stretch.
    gauge_s_m, gauge_inv_ei : ndarray, shape (3,)
        Gauge positions (m) and ``1 / EI`` there.
    mass_s_m, mass_kg : ndarray
        Point masses (strip per cell, supports) along the digit.
    gravity : ndarray, shape (2,)
        Gravity in the digit's (along, towards-cable) axes (m/s^2) for the mounting.
    eccentricity_m, cable_stiffness_n_m, pulley_radius_m, taut_angle_rad : float
        Cable geometry (table 3.7), its stiffness and the servo angle at which it is just taut (command 8).
    """

    length_m: float
    s_m: np.ndarray
    ds_m: float
    inv_ei: np.ndarray
    gauge_s_m: np.ndarray
    gauge_inv_ei: np.ndarray
    mass_s_m: np.ndarray
    mass_kg: np.ndarray
    gravity: np.ndarray
    eccentricity_m: float
    cable_stiffness_n_m: float
    pulley_radius_m: float
    taut_angle_rad: float
    params: RigParams = field(repr=False)

    @classmethod
    def from_params(
        cls,
        params: RigParams | None = None,
        calibration=None,
        *,
        orientation: str = "vertical",
        housing: bool = True,
        ds_m: float = 1e-3,
    ) -> DigitBeam:
        """The thesis digit (2.2, tables 3.5, 3.7) with the calibration's housing stiffness and support masses."""
        params = params or RigParams()
        calibration = calibration or twin_calibration(params)
        check_choice(orientation, "orientation", tuple(ORIENTATIONS), "DigitBeam")
        geo, mat = params.geometry, params.material
        length = geo.digit_length_m
        n = max(int(round(length / check_real(ds_m, "ds_m", "DigitBeam", low=1e-5, high=0.01))), 10)
        ds = length / n
        s = (np.arange(n) + 0.5) * ds
        bounds = np.asarray(geo.section_bounds_m)  # (section_count, 2): each section's free strip
        ei_strip = mat.youngs_modulus_pa * geo.second_moment_m4
        housing_ei = np.asarray(calibration.housing_ei_n_m2, dtype=float)
        if housing_ei.size != geo.section_count:
            raise ParameterError(
                f"The 'housing_ei_n_m2' parameter of Calibration must have {geo.section_count} values. "
                f"Got {housing_ei.tolist()!r} instead."
            )

        def inv_ei_at(x):
            x = np.asarray(x, dtype=float)
            k = np.clip(np.searchsorted(bounds[:, 0], x, side="right") - 1, 0, geo.section_count - 1)
            flexible = (x > bounds[k, 0]) & (x < bounds[k, 1])
            ei = ei_strip + (housing_ei[k] if housing else 0.0)
            return np.where(flexible, 1.0 / ei, 0.0)

        mu = mat.strip_density_kg_m3 * geo.cross_section_m2
        supports = np.asarray(calibration.support_mass_kg, dtype=float)
        support_s = np.asarray(geo.support_centres_m)
        housing_mass = calibration.housing_mass_kg if housing else 0.0
        flexible_cells = inv_ei_at(s) > 0
        cell_mass = mu * ds + (housing_mass / max(int(flexible_cells.sum()), 1)) * flexible_cells
        gauges = np.asarray(geo.gauge_positions_m, dtype=float)
        mass_s = np.concatenate([s, support_s])
        order = np.argsort(mass_s, kind="stable")
        a = params.actuator
        return cls(
            length_m=length,
            s_m=s,
            ds_m=ds,
            inv_ei=inv_ei_at(s),
            gauge_s_m=gauges,
            gauge_inv_ei=inv_ei_at(gauges),
            mass_s_m=mass_s[order],
            mass_kg=np.concatenate([cell_mass, supports])[order],
            gravity=np.asarray(ORIENTATIONS[orientation], dtype=float) * G_STANDARD_M_S2,
            eccentricity_m=geo.cable_eccentricity_m,
            cable_stiffness_n_m=calibration.cable_stiffness_n_m,
            pulley_radius_m=a.cable_m_per_servo_rad,  # the gearing folded in (E 3.11)
            taut_angle_rad=float(command_to_angle_rad(a.equilibrium_command, params)),
            params=params,
        )

    # --------------------------------------------------------------------------------------------- geometry
    def integrate(self, curvature_1_m: np.ndarray):
        """Angles and positions from a curvature field (..., P): ``(psi_nodes, r_nodes, r_mid)``.

        ``psi_nodes`` (..., P+1) at the cell edges (0 at the clamp), ``r_nodes`` (..., P+1, 2) and ``r_mid``
        (..., P, 2) in the (along, towards-cable) axes; each cell is a circular arc's chord (second order in ds).
        """
        k = np.asarray(curvature_1_m, dtype=float)
        dpsi = k * self.ds_m
        psi = np.concatenate([np.zeros(k.shape[:-1] + (1,)), np.cumsum(dpsi, axis=-1)], axis=-1)
        mid_angle = psi[..., :-1] + 0.5 * dpsi
        step = self.ds_m * np.stack([np.cos(mid_angle), np.sin(mid_angle)], axis=-1)
        r = np.concatenate([np.zeros(k.shape[:-1] + (1, 2)), np.cumsum(step, axis=-2)], axis=-2)
        quarter = psi[..., :-1] + 0.25 * dpsi
        r_mid = r[..., :-1, :] + 0.5 * self.ds_m * np.stack([np.cos(quarter), np.sin(quarter)], axis=-1)
        return psi, r, r_mid

    def locate(self, x_m):
        """Cell index and fraction of arc positions ``x_m`` (any shape) for interpolating node values."""
        # np.minimum(np.maximum()) rather than np.clip: the same numbers at a fifth of the cost on small arrays
        # (np.clip's dispatch is ~25 us; the live page's estimate locates nine times a frame)
        x = np.minimum(np.maximum(np.asarray(x_m, dtype=float), 0.0), self.length_m)
        i = np.minimum(np.maximum(np.floor(x / self.ds_m).astype(int), 0), self.s_m.size - 1)
        return i, x / self.ds_m - i

    def at(self, nodes: np.ndarray, x_m, *, vector: bool | None = None) -> np.ndarray:
        """Node values (B, P+1) or (B, P+1, 2) interpolated at arc positions ``x_m``, (Q,) or (B, Q)."""
        vector = nodes.ndim == 3 if vector is None else vector
        i, w = self.locate(x_m)
        rows = np.arange(nodes.shape[0])[:, None] if i.ndim == 2 else slice(None)
        if i.ndim == 2:
            lo, hi = nodes[rows, i], nodes[rows, i + 1]
        else:
            lo, hi = nodes[:, i], nodes[:, i + 1]
        return lo + (w[..., None] if vector else w) * (hi - lo)

    def interpolation(self, x_m) -> np.ndarray:
        """Matrix (Q, P+1) taking node values to their linear interpolation at arc positions ``x_m`` (Q,)."""
        i, w = self.locate(np.atleast_1d(x_m))
        out = np.zeros((i.size, self.s_m.size + 1))
        rows = np.arange(i.size)
        out[rows, i] = 1.0 - w
        out[rows, i + 1] += w
        return out

    def weight_operator(self, x_m) -> np.ndarray:
        """Matrix (Q, P+1) ``W`` with ``(W r) x g`` the moment (N m) of the digit's own masses at ``x_m``.

        ``M(x) = sum_{s_k > x} m_k (r_k - r(x)) x g``: linear in the node positions ``r``, so one product per
        shape (the world-fixed weight's lever arms follow the shape).
        """
        x = np.atleast_1d(np.asarray(x_m, dtype=float))
        moment = self.mass_kg[:, None] * self.interpolation(self.mass_s_m)  # (K, P+1): m_k r_k
        suffix = np.concatenate([np.cumsum(moment[::-1], axis=0)[::-1], np.zeros((1, moment.shape[1]))])
        suffix_m = np.r_[np.cumsum(self.mass_kg[::-1])[::-1], 0.0]
        j = np.searchsorted(self.mass_s_m, x, side="right")  # first mass beyond x
        return suffix[j] - suffix_m[j][:, None] * self.interpolation(x)

    def weight_moment(self, r_nodes: np.ndarray, operator: np.ndarray) -> np.ndarray:
        """Moment (B, Q) of the digit's own weight for shapes (B, P+1, 2) through a :meth:`weight_operator`."""
        return _cross(np.matmul(operator, r_nodes), self.gravity)

    def weight_moment_at(self, r_nodes: np.ndarray, x_m) -> np.ndarray:
        """:meth:`weight_moment` at arc positions ``x_m`` (Q,) without the (Q, P+1) operator: suffix sums of the
        masses' ``m_k r_k``, O(P + K) a shape instead of O(Q P) (the cells' moment of thousands of shapes at once
        in the estimator's global search)."""
        x = np.atleast_1d(np.asarray(x_m, dtype=float))
        r_k = self.at(r_nodes, self.mass_s_m)  # (B, K, 2)
        suffix = np.cumsum((self.mass_kg[:, None] * r_k)[:, ::-1], axis=1)[:, ::-1]
        suffix = np.concatenate([suffix, np.zeros(r_k.shape[:1] + (1, 2))], axis=1)
        suffix_m = np.r_[np.cumsum(self.mass_kg[::-1])[::-1], 0.0]
        j = np.searchsorted(self.mass_s_m, x, side="right")  # first mass beyond x
        return _cross(suffix[:, j] - suffix_m[j][:, None] * self.at(r_nodes, x), self.gravity)

    __repr__ = fields_summary


@dataclass
class ShapeEstimate:
    """What :meth:`ShapeEstimator.estimate` returns for B readings (SI units; positions from the clamp).

    Attributes
    ----------
    s_m : ndarray, shape (P+1,)
        Arc positions of the centre-line nodes (m).
    centre_line_m : ndarray, shape (B, P+1, 2)
        Node positions in the (along, towards-cable) axes (m).
    angle_rad : ndarray, shape (B, P+1)
        Tangent angle of the centre line at the nodes (rad; the tip's is the beam rotation).
    sd_normal_m : ndarray, shape (B, P+1)
        Standard deviation of each node normal to the centre line (m).
    tip_sd_m : ndarray, shape (B, 2)
        Standard deviation of the tip position along each axis (m).
    curvature_1_m : ndarray, shape (B, P)
        The fitted curvature field on the cells (1/m).
    tension_n : ndarray, shape (B,)
        Estimated cable tension (N; 0 slack or no cable).
    contact : ndarray of bool, shape (B,)
        A load was found (likelihood-ratio test against "no load").
    load_position_from_base_m, load_position_sd_m : ndarray, shape (B,)
        Where the load is (NaN without contact) and its standard deviation (inf where it cannot be located): the
        larger of the local (Fisher) one and half the profile-likelihood interval at one standard deviation.
    load_position_interval_m : ndarray, shape (B, 2)
        Every position consistent with the readings at two standard deviations (profile likelihood, chi-square
        within 4 of the best), from the lowest to the highest: wide where two branches fit (between gauges 1
        and 2 position and mass trade off).
    load_force_n, load_force_sd_n : ndarray, shape (B,)
        The load's force (N; a weight's ``m g``; a press's normal force, positive towards the cable side).
    chi2_no_load, chi2_load : ndarray, shape (B,)
        The two fits' chi-square.
    consistent : ndarray of bool, shape (B,)
        The chosen fit's chi-square is below ``misfit_chi2``: False means the readings are not what this rig and
        calibration can produce (wrong calibration, orientation or command, a second load, a fault) and the
        estimate should not be trusted.
    load_kind : str
        "weight", "press" or "none" (:data:`LOAD_KINDS`).
    """

    s_m: np.ndarray
    centre_line_m: np.ndarray
    angle_rad: np.ndarray
    sd_normal_m: np.ndarray
    tip_sd_m: np.ndarray
    curvature_1_m: np.ndarray
    tension_n: np.ndarray
    contact: np.ndarray
    load_position_from_base_m: np.ndarray
    load_position_sd_m: np.ndarray
    load_position_interval_m: np.ndarray
    load_force_n: np.ndarray
    load_force_sd_n: np.ndarray
    chi2_no_load: np.ndarray
    chi2_load: np.ndarray
    consistent: np.ndarray
    load_kind: str = "weight"

    @property
    def tip_m(self) -> np.ndarray:
        """Tip positions (B, 2), m."""
        return self.centre_line_m[:, -1, :]

    @property
    def load_mass_kg(self) -> np.ndarray:
        """A weight's mass, ``force / g`` (kg; NaN for a press or without contact)."""
        if self.load_kind != "weight":
            return np.full(self.contact.shape, np.nan)
        return self.load_force_n / G_STANDARD_M_S2

    def row(self, i: int = 0, every: int = 1) -> dict:
        """Reading ``i`` as plain numbers (JSON, the live page), every ``every``-th centre-line node and the tip."""
        idx = np.unique(np.r_[np.arange(0, self.s_m.size, max(int(every), 1)), self.s_m.size - 1])
        contact = bool(self.contact[i])

        def num(x):
            x = float(x)
            return x if math.isfinite(x) else None

        def load(x):
            return num(x) if contact else None

        return {
            "s_m": np.round(self.s_m[idx], 5).tolist(),
            "centre_line_m": np.round(self.centre_line_m[i, idx], 6).tolist(),
            "sd_normal_m": [num(x) for x in np.round(self.sd_normal_m[i, idx], 6)],
            "tip_m": [num(x) for x in self.tip_m[i]],
            "tip_sd_m": [num(x) for x in self.tip_sd_m[i]],
            "tip_angle_deg": num(math.degrees(self.angle_rad[i, -1])),
            "tension_n": num(self.tension_n[i]),
            "consistent": bool(self.consistent[i]),
            "contact": contact,
            "load_kind": self.load_kind,
            "load_position_from_base_m": load(self.load_position_from_base_m[i]),
            "load_position_sd_m": load(self.load_position_sd_m[i]),
            "load_position_interval_m": [load(x) for x in self.load_position_interval_m[i]],
            "load_force_n": load(self.load_force_n[i]),
            "load_force_sd_n": load(self.load_force_sd_n[i]),
            "load_mass_kg": load(self.load_mass_kg[i]),
        }

    __repr__ = fields_summary


class ShapeEstimator:
    """Centre line, cable tension and one load from the three gauge voltages (module docstring).

    Parameters
    ----------
    params : RigParams, optional
        The rig (thesis rig by default).
    calibration : Calibration, optional
        Channel gains and offsets, housing stiffness, support masses, cable stiffness and the noise model
        (the twin's default calibration by default; a real rig's from its calibration).
    orientation : {"vertical", "hanging", "horizontal"}
        Mounting: where gravity points (horizontal: cable side up, chapters 6-7).
    housing : bool
        With the elastomer housing.
    cable : bool
        Cable attached. False: the non-actuated digit of chapter 6 (no tension, no tip-angle equation).
    load : {"weight", "press", "none"}
        What a load is: a weight along gravity, a press normal to the digit, or never any load.
    n_average : int
        Readings averaged into each one passed (divides the white noise's variance, not the friction's).
    tip_angle_sd_rad : float
        Standard deviation of the tip angle the command implies (servo deadband, cable stretch), rad.
    contact_chi2 : float
        Chi-square drop that declares contact (likelihood ratio; 2 extra parameters: 13.8 is p = 0.001).
    max_force_n : float
        The largest load force considered (N; 5 N is about half a kilogram hung).
    misfit_chi2 : float
        Chi-square of the chosen fit above which the readings are declared inconsistent with the model.
    max_iterations : int
        Most updates of the world-fixed forces' lever arms from the shape (large rotations); a
        :class:`~flexdigit.errors.ConvergenceWarning` says when they had not settled.
    tol_rad : float
        The lever arms have settled when no tangent angle moved by more than this in an update (rad).
    ds_m : float
        Grid step along the digit (m): the centre line's nodes and the load's candidate positions.

    Examples
    --------
    >>> from flexdigit.twin import static_gauges_v
    >>> v, twin = static_gauges_v([0.0], [0.0], [30], orientation="vertical", return_solution=True)
    >>> e = ShapeEstimator().estimate(v, command=30)
    >>> bool(e.contact[0]), round(float(np.degrees(e.angle_rad[0, -1])), 1)   # no load; beam rotation, deg
    (False, 37.0)
    >>> round(float(np.degrees(twin.psi_rad[0, -1])), 1)                      # the twin's own
    37.0
    """

    def __init__(
        self,
        params: RigParams | None = None,
        calibration=None,
        *,
        orientation: str = "vertical",
        housing: bool = True,
        cable: bool = True,
        load: str = "weight",
        n_average: int = 1,
        tip_angle_sd_rad: float = 0.01,
        contact_chi2: float = 25.0,
        max_force_n: float = 5.0,
        misfit_chi2: float = 30.0,
        max_iterations: int = 100,
        tol_rad: float = 1e-7,
        ds_m: float = 1e-3,
    ) -> None:
        self.params = params
        self.calibration = calibration
        self.orientation = orientation
        self.housing = housing
        self.cable = cable
        self.load = load
        self.n_average = n_average
        self.tip_angle_sd_rad = tip_angle_sd_rad
        self.contact_chi2 = contact_chi2
        self.max_force_n = max_force_n
        self.misfit_chi2 = misfit_chi2
        self.max_iterations = max_iterations
        self.tol_rad = tol_rad
        self.ds_m = ds_m

    def __repr__(self) -> str:
        return (
            f"ShapeEstimator(orientation={self.orientation!r}, housing={self.housing}, cable={self.cable}, "
            f"load={self.load!r}, n_average={self.n_average}, tip_angle_sd_rad={self.tip_angle_sd_rad}, "
            f"contact_chi2={self.contact_chi2}, max_force_n={self.max_force_n}, "
            f"misfit_chi2={self.misfit_chi2}, max_iterations={self.max_iterations}, "
            f"tol_rad={self.tol_rad}, ds_m={self.ds_m})"
        )

    # ------------------------------------------------------------------------------------------------ set-up
    def _key(self) -> tuple:
        return tuple(
            id(v) if k in ("params", "calibration") else v for k, v in sorted(vars(self).items()) if not k[-1] == "_"
        )

    def _setup(self) -> None:
        """Validate the settings and build the beam (once per settings, as scikit-learn validates in fit)."""
        if getattr(self, "ready_", None) == self._key():
            return
        owner = "ShapeEstimator"
        self.params_ = self.params or RigParams()
        self.calibration_ = self.calibration or twin_calibration(self.params_)
        check_choice(self.load, "load", LOAD_KINDS, owner)
        check_int(self.n_average, "n_average", owner, low=1)
        check_real(self.tip_angle_sd_rad, "tip_angle_sd_rad", owner, low=0, low_open=True)
        check_real(self.contact_chi2, "contact_chi2", owner, low=0)
        check_real(self.max_force_n, "max_force_n", owner, low=0, low_open=True)
        check_real(self.misfit_chi2, "misfit_chi2", owner, low=0, low_open=True)
        check_int(self.max_iterations, "max_iterations", owner, low=1, high=1000)
        check_real(self.tol_rad, "tol_rad", owner, low=0, low_open=True)
        self.beam_ = DigitBeam.from_params(
            self.params_, self.calibration_, orientation=self.orientation, housing=bool(self.housing), ds_m=self.ds_m
        )
        sensors = SensorChain(self.params_, self.calibration_, np.random.default_rng(0))
        g = self.gauges_ = len(self.params_.geometry.gauge_positions_m)  # G gauge rows, then the tip equation's
        self.volts_per_curvature_ = sensors.volts_per_curvature(np.zeros(g), np.zeros(g))
        self.offset_v_ = sensors.clean_v(np.zeros(g), np.zeros(g))
        self.white_v_ = np.asarray(self.calibration_.noise_white_v, dtype=float)
        self.friction_ratio_ = float(self.calibration_.cable_friction_ratio) if self.cable else 0.0
        beam = self.beam_
        self.nodes_m_ = np.arange(beam.s_m.size + 1) * beam.ds_m  # also the load's candidates
        # linear maps of the node positions, fixed for the beam: the gauges' positions and the own weight's moment
        # at the gauges, on the cells and integrated along the digit (the tip equation)
        self.gauge_interp_ = beam.interpolation(beam.gauge_s_m)
        self.weight_gauges_ = beam.weight_operator(beam.gauge_s_m)
        self.weight_cells_ = beam.weight_operator(beam.s_m)
        self.weight_tip_ = (beam.inv_ei * beam.ds_m) @ self.weight_cells_
        # the measurement model's constant parts (:meth:`_rows`), once rather than per row set: the cable's row
        # per unit tension, the cumulative compliance along the cells and a weight's direction
        e, w_cells = beam.eccentricity_m, beam.inv_ei * beam.ds_m
        self.cable_row_ = np.r_[e * beam.gauge_inv_ei, e * np.sum(w_cells) + 1.0 / (beam.cable_stiffness_n_m * e)]
        # an antagonistic pair ([cables] count = 2): the tension fitted is the net one, T1 - T2 (either sign; the
        # moment e (T1 - T2)), and the tip equation's stretch term follows the twin's cable law (:meth:`_cable_model`)
        cables = self.params_.cables
        self.pair_ = bool(self.cable) and cables.count == 2
        self.pretension_n_ = float(cables.pretension_n) if self.pair_ else 0.0
        self.cum_compliance_ = np.r_[0.0, np.cumsum(w_cells)]
        self.down_ = beam.gravity / np.linalg.norm(beam.gravity)
        self.ready_ = self._key()

    def curvature_from_volts(self, gauges_v) -> np.ndarray:
        """Curvature (1/m) at the gauges from their voltages (n, 3), E 2.2-2.4 through the calibration."""
        self._setup()
        return (np.asarray(gauges_v, dtype=float) - self.offset_v_) / self.volts_per_curvature_

    def volts_from_curvature(self, curvature_1_m) -> np.ndarray:
        """The inverse of :meth:`curvature_from_volts`: gauge voltages (n, 3) for curvatures at the gauges."""
        self._setup()
        return np.asarray(curvature_1_m, dtype=float) * self.volts_per_curvature_ + self.offset_v_

    def _tip_equation(self, command, b: int) -> np.ndarray:
        """Per reading, the cable shortening the command asks for over e (rad), or NaN where there is none."""
        if command is None or not self.cable:
            return np.full(b, np.nan)
        a = self.params_.actuator
        c = check_array(command, "command", "ShapeEstimator", low=a.command_min, high=a.command_max)
        c = np.broadcast_to(c.reshape(-1) if c.ndim else c, (b,))
        shortening = self.beam_.pulley_radius_m * (command_to_angle_rad(c, self.params_) - self.beam_.taut_angle_rad)
        return shortening / self.beam_.eccentricity_m

    def _straight(self, b: int):
        psi = np.zeros((b, self.nodes_m_.size))
        r = np.zeros((b, self.nodes_m_.size, 2))
        r[..., 0] = self.nodes_m_
        return psi, r

    # ------------------------------------------------------------------------------------------------ the fit
    def estimate(self, gauges_v, command=None, *, start: ShapeEstimate | None = None) -> ShapeEstimate:
        """Estimate the shape (and the load) for readings ``gauges_v`` (3,) or (B, 3), V.

        Parameters
        ----------
        gauges_v : array_like, shape (G,) or (B, G)
            Gauge voltages (V), gauges 1..G from the base (the thesis rig's 3); averages of ``n_average`` readings
            each.
        command : int or array_like, shape (B,), optional
            The servo command in force (0..254). None: unknown or actuation disabled (no tip-angle equation).
        start : ShapeEstimate, optional
            A previous estimate of the same B readings to take the lever arms from: one fit instead of
            iterating to convergence (a live stream, where the last frame's shape is close to this one's).

        Returns
        -------
        ShapeEstimate
        """
        estimate, unsettled, change, rounds = self._estimate(gauges_v, command, start)
        if unsettled:
            warnings.warn(
                f"ShapeEstimator: the lever arms had not settled after {rounds} iterations on "
                f"{unsettled} of {change.size} readings (last change {np.max(change):.2g} rad); raise max_iterations",
                ConvergenceWarning,
                stacklevel=2,
            )
        return estimate

    def _estimate(self, gauges_v, command, start):
        """:meth:`estimate` without its warning: ``(estimate, readings unsettled, last change (B,), rounds)``.

        For callers in threads of their own (the live page's locatability map), where ``warnings.catch_warnings``
        would change the warning filters of every thread while it ran.
        """
        self._setup()
        owner = "ShapeEstimator.estimate"
        # the ADC cannot read beyond its range: 30, 40, 50 V was 'fitted' by a digit curled through 6900 deg
        low, high = self.params_.sensors.adc_range_v
        v = check_array(gauges_v, "gauges_v", f"{owner} (ADC readings: sensors.adc_range_v)", low=low, high=high)
        v = v.reshape(1, -1) if v.ndim == 1 else v
        if v.ndim != 2 or v.shape[1] != self.gauges_:
            raise ParameterError(
                f"The 'gauges_v' parameter of {owner} must have {self.gauges_} gauge columns (the digit's gauges). "
                f"Got shape {np.shape(gauges_v)} instead."
            )
        beam = self.beam_
        b = v.shape[0]
        kappa_g = self.curvature_from_volts(v)
        tip_eq = self._tip_equation(command, b)
        sd_white = (self.white_v_ / math.sqrt(self.n_average)) / np.abs(self.volts_per_curvature_)
        warm = start is not None and start.centre_line_m.shape[:2] == (b, self.nodes_m_.size)
        if warm:
            psi, r, tension, rounds = start.angle_rad, start.centre_line_m, start.tension_n, 0
        else:
            (psi, r), tension, rounds = self._straight(b), np.zeros(b), int(self.max_iterations)
        fit, psi, r, tension, change = self._settle(kappa_g, tip_eq, sd_white, psi, r, tension, rounds)
        if not warm and self.load != "none":
            fit, psi, r, tension, change = self._global_search(
                kappa_g, tip_eq, sd_white, (fit, psi, r, tension, change)
            )
        unsettled = int(np.sum(change >= self.tol_rad)) if rounds else 0
        sd_k = self._sd_curvature(sd_white, tension)
        fit = self._fit(kappa_g, tip_eq, sd_k, r, psi, fit if rounds > self.HOLD_AFTER else None, tension)
        curvature = self._curvature_field(fit, r, psi)
        psi, r, _ = beam.integrate(curvature)
        unc = self._uncertainty(fit, tip_eq, sd_k, r, psi)
        contact = fit["contact"]
        # the position's standard deviation: the local (Fisher) one, or half the one-sigma profile interval when
        # that is wider (a second branch of solutions, a flat chi-square)
        half_width = 0.5 * np.diff(fit["interval_1sd"], axis=1)[:, 0]
        position_sd = np.fmax(unc["position_sd_m"], half_width)
        estimate = ShapeEstimate(
            s_m=self.nodes_m_,
            centre_line_m=r,
            angle_rad=psi,
            sd_normal_m=unc["sd_normal_m"],
            tip_sd_m=unc["tip_sd_m"],
            curvature_1_m=curvature,
            tension_n=fit["T"],
            contact=contact,
            load_position_from_base_m=np.where(contact, fit["sL"], np.nan),
            load_position_sd_m=np.where(contact, position_sd, np.nan),
            load_position_interval_m=np.where(contact[:, None], fit["interval_2sd"], np.nan),
            load_force_n=np.where(contact, fit["P"], np.nan),
            load_force_sd_n=np.where(contact, unc["force_sd_n"], np.nan),
            chi2_no_load=fit["chi2_0"],
            chi2_load=fit["chi2_1"],
            consistent=np.where(fit["loaded"], fit["chi2_1"], fit["chi2_0"]) <= self.misfit_chi2,
            load_kind=self.load,
        )
        return estimate, unsettled, change, rounds

    def _settle(self, kappa_g, tip_eq, sd_white, psi, r, tension, rounds: int, hold: dict | None = None):
        """Fit and shape in turn from the lever arms ``(psi, r)`` until the shape settles (at most ``rounds``
        updates): ``(fit, psi, r, tension, last change (B,))``. The model choice and the load's branch are held
        after :attr:`HOLD_AFTER` updates, or from the start near ``hold``'s load (a start from the global search).
        """
        settle, fit = _Settle(self.beam_, psi, self.tol_rad), None
        for k in range(rounds):
            held = (fit or hold) if hold is not None else (fit if k >= self.HOLD_AFTER else None)
            fit = self._fit(kappa_g, tip_eq, self._sd_curvature(sd_white, tension), r, psi, held, tension)
            psi, r = settle.step(self._curvature_field(fit, r, psi))
            tension = fit["T"]
            if settle.done:
                break
        return fit, psi, r, tension, settle.gap

    #: The global search's candidate load positions: this many equally spaced along the digit (the tip included),
    #: and the middle of every stretch between neighbouring gauges.
    SEARCH_POSITIONS = 24
    #: The global search's lever arms have settled when no tangent angle moves by more than this (rad): enough to
    #: rank the candidates; the chosen one is then settled to ``tol_rad``.
    SEARCH_TOL_RAD = 1e-4
    #: The global search's answer replaces the local one where it lowers chi-square by more than this: the local
    #: answer is otherwise inside the one-standard-deviation profile interval of the better one (chi-square
    #: within 1), as good an estimate, and the thesis rig's estimates stay what they were.
    SEARCH_GAIN_CHI2 = 1.0

    def _global_search(self, kappa_g, tip_eq, sd_white, local):
        """The load's position over the whole digit, each candidate on its own settled shape (profile likelihood).

        The local fit ranks load positions on one shape's lever arms, the shape of its last guess. Where a digit
        sags far under its own weight (a long, thin strip lying horizontal: 70-85 deg at the tip) the shape depends
        on where the load hangs as much as the readings do, so that ranking is a linearisation about a wrong shape:
        started from the straight digit it walks to the nearest local minimum (a load at the tip of a 0.40 m strip
        found at 0.30 m, chi-square 37). Here every candidate of a coarse grid (:attr:`SEARCH_POSITIONS`) gets its
        own fixed point, force and tension fitted on the shape that force bends; the best one seeds the local fit
        again, held to its branch from the start, and that replaces the first answer wherever it fits better (by
        more than :attr:`SEARCH_GAIN_CHI2`). Readings the local fit left without a load and consistent with the
        model keep it.
        """
        fit, psi, r, tension, change = local
        chosen = np.where(fit["loaded"], fit["chi2_1"], fit["chi2_0"])
        todo = np.flatnonzero(fit["loaded"] | (chosen > self.misfit_chi2))
        if todo.size == 0:
            return local
        grid = self._search_positions()
        best_s, best_chi, start_psi, start_r, start_t = self._profile(kappa_g[todo], tip_eq[todo], sd_white, grid)
        again = np.isfinite(best_chi) & (best_chi < chosen[todo] - self.SEARCH_GAIN_CHI2)
        todo, best_s = todo[again], best_s[again]
        if todo.size == 0:
            return local
        hold = {"sL": best_s, "loaded": np.ones(todo.size, dtype=bool)}
        redo = self._settle(
            kappa_g[todo], tip_eq[todo], sd_white, start_psi[again], start_r[again], start_t[again],
            int(self.max_iterations), hold,
        )  # fmt: skip
        redo_chi = np.where(redo[0]["loaded"], redo[0]["chi2_1"], redo[0]["chi2_0"])
        better = redo_chi < chosen[todo] - self.SEARCH_GAIN_CHI2
        todo = todo[better]
        fit = {k: v.copy() for k, v in fit.items()}
        for key, value in redo[0].items():
            fit[key][todo] = value[better]
        out = [fit]
        for whole, part in zip((psi, r, tension, change), redo[1:], strict=True):
            whole = whole.copy()
            whole[todo] = part[better]
            out.append(whole)
        return tuple(out)

    def _search_positions(self) -> np.ndarray:
        """The global search's candidates (m): an even grid to the tip and the middle of each stretch between
        neighbouring gauges (and between the last gauge and the tip), on the grid's nodes."""
        length = self.beam_.length_m
        ends = np.r_[self.beam_.gauge_s_m, length]
        middles = 0.5 * (ends[:-1] + ends[1:])
        even = length * np.arange(1, self.SEARCH_POSITIONS + 1) / self.SEARCH_POSITIONS
        nodes = np.round(np.r_[even, middles] / self.beam_.ds_m) * self.beam_.ds_m
        return np.unique(np.clip(nodes, self.beam_.ds_m, length))

    def _profile(self, kappa_g, tip_eq, sd_white, grid):
        """Every reading (B) at every candidate position (C) settled with the load held there: the best candidate
        per reading ``(position (B,), chi-square (B,), psi (B, P+1), r (B, P+1, 2), tension (B,))``."""
        b, c = kappa_g.shape[0], grid.size
        kappa = np.repeat(kappa_g, c, axis=0)
        tip = np.repeat(tip_eq, c)
        s_l = np.tile(grid, b)
        psi, r = self._straight(b * c)
        tension = np.zeros(b * c)
        settle = _Settle(self.beam_, psi.copy(), self.SEARCH_TOL_RAD)
        rows = np.arange(b * c)  # the shapes still moving: settled ones drop out (the slowest set the count)
        for _ in range(int(self.max_iterations)):
            fit = self._fit_at(kappa[rows], tip[rows], self._sd_curvature(sd_white, tension[rows]), r[rows],
                               psi[rows], s_l[rows], tension[rows])  # fmt: skip
            psi[rows], r[rows] = settle.step_rows(self._curvature_field(fit, r[rows], psi[rows]), rows)
            tension[rows] = fit["T"]
            rows = rows[~settle.settled[rows]]
            if rows.size == 0:
                break
        fit = self._fit_at(kappa, tip, self._sd_curvature(sd_white, tension), r, psi, s_l, tension)
        chi = np.where(fit["loaded"], fit["chi2_1"], np.inf).reshape(b, c)
        best = np.argmin(chi, axis=1)
        pick = np.arange(b) * c + best
        return grid[best], chi[np.arange(b), best], psi[pick], r[pick], fit["T"][pick]

    def _fit_at(self, kappa_g, tip_eq, sd_k, r, psi, s_load, tension) -> dict:
        """Weighted least squares for (T, P) with the load held at ``s_load`` (B,): what :meth:`_fit` does at one
        candidate (the force's prior row included)."""
        b, g = kappa_g.shape[0], self.gauges_
        has_tip = np.isfinite(tip_eq)
        sd = np.concatenate([sd_k, np.full((b, 1), self.tip_angle_sd_rad)], axis=1)
        y = np.concatenate([kappa_g, np.where(has_tip, tip_eq, 0.0)[:, None]], axis=1)
        w = 1.0 / sd**2
        w[:, g] = np.where(has_tip, w[:, g], 0.0)
        _, b_w, a_p = self._rows(r, psi, s_load[:, None])
        a_t, offset = self._cable_model(tension)
        res = np.concatenate([y - b_w - offset, np.zeros((b, 1))], axis=1)
        w = np.concatenate([w, np.full((b, 1), self.PRIOR_FORCE_N**-2.0)], axis=1)
        a_p = np.concatenate([a_p, np.ones(a_p.shape[:2] + (1,))], axis=-1)
        t, p, chi = _fit_load(
            res[:, None, :], np.concatenate([a_t, np.zeros((b, 1))], axis=1)[:, None, :], a_p, w[:, None, :],
            bool(self.cable), self.load == "weight", self.max_force_n, g, self.pair_,
        )  # fmt: skip
        loaded = p[:, 0] != 0
        s_l = np.where(loaded, s_load, np.nan)
        return {"T": t[:, 0], "P": p[:, 0], "sL": s_l, "loaded": loaded, "chi2_1": chi[:, 0]}

    def _sd_curvature(self, sd_white: np.ndarray, tension: np.ndarray) -> np.ndarray:
        """Per reading and gauge, the curvature noise (1/m): white (averaged) and the cable-guide friction (of the
        tension the guides hold: a pair's ``T1 + T2``, :meth:`_cable_model`)."""
        pull = np.maximum(np.abs(tension), 2.0 * self.pretension_n_) if self.pair_ else tension
        friction = self.friction_ratio_ * self.beam_.eccentricity_m * pull[:, None] * self.beam_.gauge_inv_ei
        return np.sqrt(sd_white[None, :] ** 2 + friction**2)

    def _cable_model(self, tension: np.ndarray):
        """The cable's rows per reading: ``(a_T (B, G + 1), offset (B, G + 1))``, the model being
        ``a_T T + offset + ...`` (the offset only on the tip row).

        One cable: :attr:`cable_row_` (``T = k_c (s - e psi_tip)``, E 3.11 with the stretch), no offset. An
        antagonistic pair (:mod:`flexdigit.twin.digit`'s law, ``T1 = k_c max(0, p + s - e psi)``, ``T2 = k_c
        max(0, p - s + e psi)``, ``p`` the pretension's stretch): the net tension ``T = T1 - T2`` gives
        ``psi + T / (2 k_c e) = s / e`` while both are taut (``|T| < 2 k_c p``) and ``psi + T / (k_c e) -+ p / e
        = s / e`` once one goes slack; the branch is the one of ``tension`` (the last iteration's net tension),
        the law being continuous where they meet.
        """
        b = tension.shape[0]
        a_t = np.broadcast_to(self.cable_row_, (b, self.cable_row_.size))
        offset = np.zeros((b, self.cable_row_.size))
        if not self.pair_:
            return a_t, offset
        beam, g = self.beam_, self.gauges_
        kc, e = beam.cable_stiffness_n_m, beam.eccentricity_m
        both = np.abs(tension) < 2.0 * self.pretension_n_
        a_t = a_t.copy()
        a_t[:, g] += np.where(both, -0.5, 0.0) / (kc * e)  # the stretch term is 1 / (k_c e) in cable_row_
        offset[:, g] = np.where(both, 0.0, -np.sign(tension) * self.pretension_n_ / (kc * e))
        return a_t, offset

    def _rows(self, r, psi, s_load=None):
        """The measurement model: curvature at the G gauges and the tip-angle equation (G + 1 rows; 4 on the thesis
        rig).

        Returns ``a_T`` (G + 1,) per unit tension, ``b_w`` (B, G + 1) from the digit's own weight and, for loads at
        ``s_load`` (B, C) (``"nodes"``: every node of the grid), ``a_P`` (B, C, G + 1) per unit load force.
        """
        beam = self.beam_
        inv_g = beam.gauge_inv_ei
        w_cells = beam.inv_ei * beam.ds_m
        # cable: T e everywhere; the tip equation is psi_tip + T / (k_c e) (E 3.11 with the cable's stretch)
        a_t = self.cable_row_
        m_g = beam.weight_moment(r, self.weight_gauges_)  # (B, 3)
        b_w = np.concatenate([m_g * inv_g, beam.weight_moment(r, self.weight_tip_[None, :])], axis=1)
        if s_load is None:
            return a_t, b_w, None
        r_mid = 0.5 * (r[:, :-1, :] + r[:, 1:, :])
        cum_r = np.concatenate([np.zeros((r.shape[0], 1, 2)), np.cumsum(r_mid * w_cells[None, :, None], axis=1)], 1)
        cum_w = self.cum_compliance_
        if isinstance(s_load, str):  # every node: no interpolation
            s_load = np.broadcast_to(self.nodes_m_, r.shape[:2])
            r_l, r_before, w_before = r, cum_r, np.broadcast_to(cum_w, r.shape[:2])
            angle = psi
        else:
            r_l = beam.at(r, s_load)  # (B, C, 2)
            r_before = beam.at(cum_r, s_load)
            w_before = beam.at(np.broadcast_to(cum_w, r.shape[:2]), s_load, vector=False)
            angle = beam.at(psi, s_load, vector=False) if self.load == "press" else None
        if self.load == "press":
            d = np.stack([-np.sin(angle), np.cos(angle)], axis=-1)  # normal towards the cable side
        else:
            d = np.broadcast_to(self.down_, r_l.shape)
        # moment per unit force at x < s_L: (r_L - r(x)) x d = r_L x d - r(x) x d
        rl_x_d = _cross(r_l, d)  # (B, C)
        r_g = np.matmul(self.gauge_interp_, r)  # (B, 3, 2)
        rg_x_d = _cross(r_g[:, None, :, :], d[:, :, None, :])  # (B, C, 3)
        before = beam.gauge_s_m[None, None, :] < s_load[:, :, None]
        gauge_rows = np.where(before, rl_x_d[:, :, None] - rg_x_d, 0.0) * inv_g
        # tip row: int_0^{s_L} (r_L x d - r(x) x d) / EI dx, from cumulative sums over the cells
        tip_row = rl_x_d * w_before - _cross(r_before, d)
        return a_t, b_w, np.concatenate([gauge_rows, tip_row[..., None]], axis=-1)

    #: After this many updates of the lever arms the model (load or not) and the load's branch are held, and the
    #: position is sought within :attr:`HOLD_WINDOW_M` of the last one: a discrete choice that flips with the
    #: shape would otherwise make the fixed point cycle.
    HOLD_AFTER = 4
    HOLD_WINDOW_M = 0.005
    #: Prior standard deviations of the tension (N) and the load's force (N) (the position's is the digit's
    #: length over sqrt(12), uniform): weak, so they matter only where the readings say nothing.
    PRIOR_TENSION_N = 50.0
    PRIOR_FORCE_N = 1.0
    #: A load counts as located when its position's standard deviation is below this share of the prior's.
    LOCATED_FRACTION = 0.5

    def _fit(self, kappa_g, tip_eq, sd_k, r, psi, hold: dict | None = None, tension=None) -> dict:
        """Weighted least squares for (T, P) at every candidate position; contact by likelihood ratio.

        ``hold``: a previous fit whose model choice is kept and near whose load position the position is sought.
        ``tension`` (B,): the last net tension, the branch of a pair's cable law (:meth:`_cable_model`).
        """
        b, g = kappa_g.shape[0], self.gauges_
        cable = bool(self.cable)
        has_tip = np.isfinite(tip_eq)
        sd = np.concatenate([sd_k, np.full((b, 1), self.tip_angle_sd_rad)], axis=1)
        y = np.concatenate([kappa_g, np.where(has_tip, tip_eq, 0.0)[:, None]], axis=1)
        w = 1.0 / sd**2
        w[:, g] = np.where(has_tip, w[:, g], 0.0)
        _, b_w, _ = self._rows(r, psi)
        a_t, offset = self._cable_model(np.zeros(b) if tension is None else tension)
        res = y - b_w - offset  # what the tension (and the load) must explain
        # the cable's state (taut or slack) is held with the model: at the command where the cable just comes
        # taut (the straight one) the better of the two flips with the shape, and the lever arms cycled between
        # them for ever (a 0.44 m geared digit tip up: T 0 <-> 0.005 N, 7e-4 rad, chi-square within 0.2)
        taut_held = None if hold is None or "T" not in hold else hold["T"] > 0
        t0, chi0 = _fit_tension(res, a_t, w, cable, g, self.pair_, taut_held)
        out = {"T": t0, "P": np.zeros(b), "sL": np.full(b, np.nan), "chi2_0": chi0, "chi2_1": chi0.copy()}
        out["contact"] = out["loaded"] = np.zeros(b, dtype=bool)
        out["interval_1sd"] = out["interval_2sd"] = np.full((b, 2), np.nan)
        if self.load == "none":
            return out
        positive = self.load == "weight"
        cand = np.broadcast_to(self.nodes_m_, (b, self.nodes_m_.size))
        _, _, a_p = self._rows(r, psi, "nodes")
        # the force's weak prior as a fifth row (P = 0 +- PRIOR_FORCE_N): a ridge that keeps a huge force just past
        # a gauge from explaining the friction's scatter better than a modest one where the load really is
        a_t = np.concatenate([a_t, np.zeros((b, 1))], axis=1)[:, None, :]
        res = np.concatenate([res, np.zeros((b, 1))], axis=1)
        w = np.concatenate([w, np.full((b, 1), self.PRIOR_FORCE_N**-2.0)], axis=1)
        a_p = np.concatenate([a_p, np.ones(a_p.shape[:2] + (1,))], axis=-1)
        t1, p1, chi1 = _fit_load(
            res[:, None, :], a_t, a_p, w[:, None, :], cable, positive, self.max_force_n, g, self.pair_
        )
        rows = np.arange(b)
        if hold is not None:
            near = np.abs(self.nodes_m_[None, :] - np.nan_to_num(hold["sL"])[:, None]) <= self.HOLD_WINDOW_M
            best = np.argmin(np.where(near | ~hold["loaded"][:, None], chi1, np.inf), axis=1)
        else:
            best = np.argmin(chi1, axis=1)
        refined = _parabola(self.nodes_m_, chi1, best)[:, None]
        _, _, a_ref = self._rows(r, psi, refined)
        a_ref = np.concatenate([a_ref, np.ones(a_ref.shape[:2] + (1,))], axis=-1)
        t_r, p_r, chi_r = _fit_load(
            res[:, None, :], a_t, a_ref, w[:, None, :], cable, positive, self.max_force_n, g, self.pair_
        )
        better = chi_r[:, 0] <= chi1[rows, best]
        s_hat = np.where(better, refined[:, 0], cand[rows, best])
        t_hat = np.where(better, t_r[:, 0], t1[rows, best])
        p_hat = np.where(better, p_r[:, 0], p1[rows, best])
        chi_hat = np.where(better, chi_r[:, 0], chi1[rows, best])
        # profile likelihood of the position: every candidate within 1 (4) of the best chi-square is consistent
        # with the readings at one (two) standard deviations; a disjoint second branch widens the interval
        out["interval_1sd"] = _span(self.nodes_m_, chi1 <= chi_hat[:, None] + 1.0, s_hat)
        out["interval_2sd"] = _span(self.nodes_m_, chi1 <= chi_hat[:, None] + 4.0, s_hat)
        # the shape takes the load model whenever it is the better model (Akaike: two more parameters must lower
        # chi-square by more than 4); a contact is declared only on the stricter likelihood-ratio test
        loaded = (chi0 - chi_hat > min(4.0, self.contact_chi2)) & (p_hat != 0)
        if hold is not None:
            loaded = hold["loaded"] & (p_hat != 0)
        out.update(
            T=np.where(loaded, t_hat, t0),
            P=np.where(loaded, p_hat, 0.0),
            sL=np.where(loaded, s_hat, np.nan),
            chi2_1=chi_hat,
            loaded=loaded,
            contact=loaded & (chi0 - chi_hat > self.contact_chi2),
        )
        return out

    def _curvature_field(self, fit, r, psi) -> np.ndarray:
        """kappa(s) on the cells (B, P) for the fitted (T, P, s_L) on the shape ``r``."""
        beam = self.beam_
        m = fit["T"][:, None] * beam.eccentricity_m + beam.weight_moment_at(r, beam.s_m)
        if np.any(fit["loaded"]):
            s_l = np.where(fit["loaded"], fit["sL"], 0.0)
            m = m + np.where(fit["loaded"], fit["P"], 0.0)[:, None] * self._load_moment(r, psi, s_l)
        return m * beam.inv_ei

    def _load_moment(self, r, psi, s_load) -> np.ndarray:
        """Moment per unit force (m) on the cells of a load at ``s_load``: (B,) -> (B, P); (B, C) -> (B, C, P)."""
        beam = self.beam_
        s_l = np.asarray(s_load, dtype=float)
        single = s_l.ndim == 1
        s_l = s_l[:, None] if single else s_l
        r_l = beam.at(r, s_l)  # (B, C, 2)
        if self.load == "press":
            angle = beam.at(psi, s_l, vector=False)
            d = np.stack([-np.sin(angle), np.cos(angle)], axis=-1)
        else:
            d = np.broadcast_to(self.down_, r_l.shape)
        r_mid = 0.5 * (r[:, :-1, :] + r[:, 1:, :])  # (B, P, 2)
        lever = _cross(r_l[:, :, None, :] - r_mid[:, None, :, :], d[:, :, None, :])  # (B, C, P)
        out = np.where(beam.s_m[None, None, :] < s_l[:, :, None], lever, 0.0)
        return out[:, 0] if single else out

    # ------------------------------------------------------------------------------------------- uncertainty
    def _uncertainty(self, fit, tip_eq, sd_k, r, psi) -> dict:
        """Parameter covariance (inverse Fisher information) and its image on the centre line."""
        beam = self.beam_
        b, g = sd_k.shape[0], self.gauges_
        taut = (fit["T"] > 0) | self.pair_  # a pair's net tension has either sign, and a pair is never slack
        contact = fit["loaded"]
        w = np.concatenate([1.0 / sd_k**2, np.full((b, 1), self.tip_angle_sd_rad**-2.0)], axis=1)
        w[:, g] = np.where(np.isfinite(tip_eq) & taut, w[:, g], 0.0)
        step = 1e-3
        s_l = np.where(contact, fit["sL"], 0.0)
        s_lo, s_hi = np.clip(s_l - step, 0, beam.length_m), np.clip(s_l + step, 0, beam.length_m)
        _, _, a_p = self._rows(r, psi, np.stack([s_l, s_lo, s_hi], axis=1))
        a_t, _ = self._cable_model(fit["T"])
        d_sl = np.where(s_hi > s_lo, s_hi - s_lo, 1.0)
        p = np.where(contact, fit["P"], 0.0)
        a_s = p[:, None] * (a_p[:, 2] - a_p[:, 1]) / d_sl[:, None]
        # Jacobian columns: T (while the cable is taut), P and s_L (with contact); inactive ones held exactly
        cols = np.stack([a_t, a_p[:, 0], a_s], axis=2)  # (B, G + 1, 3)
        active = np.stack([taut, contact, contact], axis=1)
        fisher = np.einsum("bmi,bm,bmj->bij", cols, w, cols)
        both = active[:, :, None] & active[:, None, :]
        # a weak prior keeps the inverse finite where the readings leave a direction free (position and mass
        # trading off between gauges 1 and 2, no gauge bending before gauge 1): the shape's band then stays finite
        # (that direction barely moves the shape) while the position's standard deviation comes out at the prior's
        prior_sd = np.array([self.PRIOR_TENSION_N, self.PRIOR_FORCE_N, beam.length_m / math.sqrt(12.0)])
        fisher = np.where(both, fisher, 0.0) + np.diag(1.0 / prior_sd**2)[None]
        cov = np.where(both, np.linalg.inv(fisher), 0.0)
        # located: the readings, not the prior, set the position (its variance well under the prior's)
        locatable = cov[:, 2, 2] < (self.LOCATED_FRACTION * prior_sd[2]) ** 2
        # the centre line's sensitivity to each parameter (lever arms held), by differences of the integral
        base = self._curvature_field(fit, r, psi)
        _, r0, _ = beam.integrate(base)
        moments = self._load_moment(r, psi, np.stack([s_l, s_lo, s_hi], axis=1)) * beam.inv_ei  # (B, 3, P)
        unit = np.stack(
            [
                np.broadcast_to(beam.eccentricity_m * beam.inv_ei, base.shape),
                moments[:, 0],
                p[:, None] * (moments[:, 2] - moments[:, 1]) / d_sl[:, None],
            ],
            axis=1,
        )  # (B, 3, P): curvature per unit T, P and s_L
        eps = np.array([1e-3, 1e-3, 1e-4])
        _, r1, _ = beam.integrate(base[:, None, :] + eps[None, :, None] * unit)  # all three at once
        jac_r = np.moveaxis((r1 - r0[:, None]) / eps[None, :, None, None], 1, -1)  # (B, P+1, 2, 3)
        # variances J Cov J' of the normal offset at each node and of the tip's two coordinates (matrix products:
        # a three-operand einsum here was a third of a live estimate's time)
        normal = np.stack([-np.sin(psi), np.cos(psi)], axis=-1)
        jac_n = np.matmul(normal[:, :, None, :], jac_r)[:, :, 0, :]  # (B, P+1, 3): the normal offset's gradient
        var_n = np.sum(np.matmul(jac_n, cov) * jac_n, axis=-1)
        jac_tip = jac_r[:, -1]  # (B, 2, 3)
        var_tip = np.sum(np.matmul(jac_tip, cov) * jac_tip, axis=-1)
        if self.load != "none" and not np.all(contact):  # a load the readings cannot tell from the noise
            free = ~contact
            unseen_n, unseen_tip = self._unseen_load(w[free], a_t[free], taut[free], r[free], psi[free], base[free])
            var_n[free] = np.maximum(var_n[free], unseen_n)
            var_tip[free] = np.where(
                np.sum(unseen_tip, axis=1, keepdims=True) > np.sum(var_tip[free], axis=1, keepdims=True),
                unseen_tip,
                var_tip[free],
            )
        sd_normal = np.sqrt(np.maximum(var_n, 0.0))
        tip_sd = np.sqrt(np.maximum(var_tip, 0.0))
        bad = contact & ~locatable
        return {
            "cov": cov,
            "sd_normal_m": sd_normal,
            "tip_sd_m": tip_sd,
            "position_sd_m": np.where(bad, np.inf, np.sqrt(np.maximum(cov[:, 2, 2], 0.0))),
            "force_sd_n": np.where(bad, np.inf, np.sqrt(np.maximum(cov[:, 1, 1], 0.0))),
        }

    def _unseen_load(self, w, a_t, taut, r, psi, base) -> tuple[np.ndarray, np.ndarray]:
        """The shape's variance where no load was found, counting the load the readings cannot exclude: at each
        candidate position (:meth:`_search_positions`) the tension and a load of unknown force (its weak prior
        ``PRIOR_FORCE_N``) from the readings' Fisher information, the worst position's variance kept
        (``(normal (B, P+1), tip (B, 2))``). Without it the band held the tension's alone, and a 25 g weight that
        the cable-guide friction hides (ratio 0.3: chi-square lowered by ~4) bent the tip 21 mm past a 1.3 mm band.
        """
        beam = self.beam_
        b = r.shape[0]
        grid = np.broadcast_to(self._search_positions(), (b, self._search_positions().size))
        _, _, a_p = self._rows(r, psi, grid)  # (B, K, G + 1)
        cols = np.stack([np.broadcast_to(a_t[:, None, :], a_p.shape), a_p], axis=-1)  # (B, K, G + 1, 2)
        fisher = np.einsum("bkmi,bm,bkmj->bkij", cols, w, cols)
        active = np.stack([taut, np.ones(b, dtype=bool)], axis=1)
        both = (active[:, :, None] & active[:, None, :])[:, None]
        prior = np.diag([self.PRIOR_TENSION_N**-2.0, self.PRIOR_FORCE_N**-2.0])
        cov = np.where(both, np.linalg.inv(np.where(both, fisher, 0.0) + prior), 0.0)  # (B, K, 2, 2)
        _, r0, _ = beam.integrate(base)
        eps = 1e-3
        _, r_t, _ = beam.integrate(base + eps * beam.eccentricity_m * beam.inv_ei)
        unit_p = self._load_moment(r, psi, grid) * beam.inv_ei  # (B, K, P)
        _, r_p, _ = beam.integrate(base[:, None, :] + eps * unit_p)
        jac_t = np.broadcast_to(((r_t - r0) / eps)[:, None], r_p.shape)
        jac = np.stack([jac_t, (r_p - r0[:, None]) / eps], axis=-1)  # (B, K, P+1, 2, 2)
        normal = np.stack([-np.sin(psi), np.cos(psi)], axis=-1)
        jac_n = np.einsum("bnc,bkncp->bknp", normal, jac)
        var_n = np.einsum("bknp,bkpq,bknq->bkn", jac_n, cov, jac_n).max(axis=1)
        var_tip = np.einsum("bkcp,bkpq,bkcq->bkc", jac[:, :, -1], cov, jac[:, :, -1])
        worst = np.argmax(var_tip.sum(axis=-1), axis=1)
        return var_n, var_tip[np.arange(b), worst]

    # ------------------------------------------------------------------------------------------ forward model
    def predict(self, positions_from_base_m, force_n, command=None):
        """The model's own noise-free state for one load per case: ``(curvature at the gauges (B, 3), fit,
        centre line (B, P+1, 2), angles (B, P+1))``; force 0 means no load.

        The forward problem: tension from the command while the cable is taut (or 0), the shape iterated.
        """
        self._setup()
        beam = self.beam_
        s_l = np.atleast_1d(check_array(positions_from_base_m, "positions_from_base_m", "ShapeEstimator.predict"))
        p = np.broadcast_to(check_array(force_n, "force_n", "ShapeEstimator.predict"), s_l.shape).astype(float)
        b, g = s_l.size, self.gauges_
        tip_eq = self._tip_equation(command, b)
        psi, r = self._straight(b)
        fit = {"T": np.zeros(b), "P": p, "sL": s_l, "contact": p != 0, "loaded": p != 0}
        settle = _Settle(beam, psi, 1e-3 * self.tol_rad)
        for _ in range(10 * int(self.max_iterations)):
            if np.all(np.isfinite(tip_eq)):
                _, b_w, a_p = self._rows(r, psi, s_l[:, None])
                psi_free = b_w[:, g] + p * a_p[:, 0, g]  # tip equation without the cable
                fit["T"] = self._tension_from_tip(tip_eq - psi_free)
            psi, r = settle.step(self._curvature_field(fit, r, psi))
            if settle.done:
                break
        a_t, b_w, a_p = self._rows(r, psi, s_l[:, None])
        kappa = fit["T"][:, None] * a_t[:g] + b_w[:, :g] + p[:, None] * a_p[:, 0, :g]
        return kappa, fit, r, psi

    def _tension_from_tip(self, lead_rad: np.ndarray) -> np.ndarray:
        """The (net) tension the tip equation asks for, ``lead_rad`` being its right side less the loads' share:
        a single cable's ``max(0, lead / a)``; a pair's on the branch of its law that holds (:meth:`_cable_model`)."""
        g = self.gauges_
        if not self.pair_:
            return np.maximum(lead_rad / self.cable_row_[g], 0.0)
        both_a, _ = self._cable_model(np.zeros(lead_rad.shape))
        t_both = lead_rad / both_a[:, g]
        one_a, offset = self._cable_model(np.where(lead_rad >= 0, np.inf, -np.inf))
        t_one = (lead_rad - offset[:, g]) / one_a[:, g]
        return np.where(np.abs(t_both) < 2.0 * self.pretension_n_, t_both, t_one)

    def locatability(self, positions_from_base_m, force_n: float = 0.25, command=None) -> np.ndarray:
        """Standard deviation (m) of the estimated position of a load at each position (inf: not found or not
        locatable), as :meth:`estimate` reports it on the model's own noise-free readings.

        ``force_n`` (N; 0.25 N is about a 25 g weight) on the digit at ``command``, readings averaged
        ``n_average`` at a time. The live page shades the stretches of the digit where it exceeds a threshold ("the
        gauges cannot place a load here"): before gauge 1 no gauge bends on a free digit; between gauges 1 and 2
        position and mass trade off. It does not warn when a heavily sagging digit's lever arms settle slowly (the
        standard deviations hold): it runs in a thread of its own on the live page.
        """
        self._setup()
        force = check_real(force_n, "force_n", "ShapeEstimator.locatability", low=0, low_open=True)
        pos = np.atleast_1d(check_array(positions_from_base_m, "positions_from_base_m", "ShapeEstimator"))
        kappa, fit, r, psi = self.predict(pos, np.full(pos.size, force), command)
        # the lever arms start where the model put them (its own noise-free readings' fixed point): one fit instead
        # of iterating from the straight digit, the same answer (the true position fits with chi-square 0)
        start = _Start(centre_line_m=r, angle_rad=psi, tension_n=fit["T"])
        est = self._estimate(self.volts_from_curvature(kappa), command, start)[0]
        return np.where(est.contact, est.load_position_sd_m, np.inf)


@dataclass(frozen=True)
class _Start:
    """The lever arms an estimate starts from (what :meth:`ShapeEstimator.estimate` reads of its ``start``)."""

    centre_line_m: np.ndarray
    angle_rad: np.ndarray
    tension_n: np.ndarray


class _Settle:
    """The fixed point of the lever arms: curvature from the shape, shape from the curvature, repeated.

    The plain iteration takes each new curvature field whole while its update shrinks to :attr:`CONTRACTION` of
    the last one or less. A heavily loaded free digit (a large sag) makes it overshoot: a 0.47 m digit of eight
    sections lying horizontal swung between 18 and 99 deg at the tip for ever (its equilibrium: 63 deg), each
    update 0.1 % smaller than the last; halving the step whenever an update grew never caught that, and where it
    did halve, the steps shrank to nothing with the update still large (a shape "settled" 0.01 rad from its
    fixed point). From the first update that does not contract, a reading's step is Aitken's dynamic relaxation
    (Irons and Tuck 1969; Kuttler and Wall 2008, fluid-structure coupling): ``w_k = -w_(k-1) r_(k-1).(r_k -
    r_(k-1)) / |r_k - r_(k-1)|^2`` over the curvature updates ``r``, the secant estimate of the step that lands
    on the fixed point, at most 1 (halved instead where it is below :attr:`MIN_RELAX` or not positive: the
    updates jump where the fit switches, a bound or a slack cable). The shape has settled when the whole update moves no
    tangent angle by ``tol_rad`` or more, or, where the updates jump, when the halved steps do.
    """

    #: An update at least this share of the last one (in tangent angle) is not converging: relax from then on.
    CONTRACTION = 0.9
    #: The smallest Aitken factor taken as one: below it the updates jump rather than overshoot.
    MIN_RELAX = 0.02

    def __init__(self, beam: DigitBeam, psi: np.ndarray, tol_rad: float) -> None:
        self.beam, self.psi, self.tol_rad = beam, psi, tol_rad
        self.curvature = None
        b = psi.shape[0]
        self.relax = np.ones(b)
        self.aitken = np.zeros(b, dtype=bool)  # rows that left the plain iteration
        self.update = None  # the last whole update of the curvature (B, P)
        self.change = np.full(b, np.inf)  # the tangent angle the last step moved (rad)
        self.residual = np.full(b, np.inf)  # the tangent angle the whole last update would have moved (rad)

    def step(self, target: np.ndarray):
        """Move towards the curvature field ``target`` (B, P); return the new ``(psi, r)``."""
        return self.step_rows(target, slice(None))

    def step_rows(self, target: np.ndarray, rows):
        """:meth:`step` for the shapes ``rows`` only (``target`` (R, P)), the others left where they are (the first
        call takes every row)."""
        if self.curvature is None:
            psi, r, _ = self.beam.integrate(target)
            self.change = np.max(np.abs(psi - self.psi), axis=1)
            self.residual = self.change.copy()
            self.psi, self.curvature = psi, target
            self.update = np.zeros_like(target)
            return psi, r
        current, last = self.curvature[rows], self.update[rows]
        update = target - current
        whole = np.max(np.abs(np.cumsum(update, axis=1) * self.beam.ds_m), axis=1)
        aitken = self.aitken[rows] | (whole > self.CONTRACTION * self.residual[rows])
        diff = update - last
        denom = np.sum(diff * diff, axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            secant = -self.relax[rows] * np.sum(last * diff, axis=1) / denom
        # a secant step below MIN_RELAX (or none): the updates jump (a bound of the fit, the cable going slack),
        # so there is no smooth fixed point to aim at; halve the step instead, as the plain rule did
        aim = np.isfinite(secant) & (denom > 0) & (secant >= self.MIN_RELAX)
        relax = np.where(aim, np.minimum(secant, 1.0), 0.5 * self.relax[rows])
        relax = np.where(aitken, relax, 1.0)
        new = current + relax[:, None] * update
        psi, r, _ = self.beam.integrate(new)
        self.change[rows] = np.max(np.abs(psi - self.psi[rows]), axis=1)
        self.residual[rows], self.relax[rows], self.aitken[rows] = whole, relax, aitken
        self.psi[rows], self.curvature[rows], self.update[rows] = psi, new, update
        return psi, r

    @property
    def settled(self) -> np.ndarray:
        """Per reading: the whole update is below ``tol_rad``, or its steps, halved below :attr:`MIN_RELAX` where
        the updates jump, move less than that (the shape sits where the fit switches)."""
        return (self.residual < self.tol_rad) | ((self.relax < self.MIN_RELAX) & (self.change < self.tol_rad))

    @property
    def gap(self) -> np.ndarray:
        """Per reading, how far from settled (rad): 0 where :attr:`settled`, else the whole last update."""
        return np.where(self.settled, 0.0, self.residual)

    @property
    def done(self) -> bool:
        return bool(np.all(self.settled))


def _fit_tension(res, a_t, w, cable: bool, gauges: int = 3, signed: bool = False, taut_held=None):
    """T >= 0 alone: ``(T (B,), chi2 (B,))``. With T = 0 the tip row (row ``gauges``, after the gauges') drops
    out (a slack cable fixes nothing). ``signed``: an antagonistic pair's net tension, of either sign and never
    slack. ``taut_held`` (B,) bool: the cable's state kept from an earlier fit (taut while its tension stays
    positive) instead of the better chi-square's."""
    chi_slack = np.sum(w[:, :gauges] * res[:, :gauges] ** 2, axis=1)
    if not cable:
        return np.zeros(res.shape[0]), chi_slack
    t = np.sum(w * a_t * res, axis=1) / np.sum(w * a_t * a_t, axis=1)
    chi_taut = np.sum(w * (res - t[:, None] * a_t) ** 2, axis=1)
    if signed:
        return t, chi_taut
    taut = (t > 0) & ((chi_taut < chi_slack) if taut_held is None else taut_held)
    return np.where(taut, t, 0.0), np.where(taut, chi_taut, chi_slack)


def _fit_load(
    res, a_t, a_p, w, cable: bool, positive: bool, max_force_n: float = np.inf, gauges: int = 3, signed: bool = False
):
    """(T, P) per candidate with T >= 0 (a cable only pulls), |P| <= ``max_force_n`` and, for weights, P >= 0: the
    active sets are enumerated (both free; P alone with the cable slack). Shapes (B, C); chi-square is infinite
    where no feasible load explains the readings. ``signed``: an antagonistic pair's net tension, either sign,
    never slack (no "P alone")."""
    slack_w = w.copy()
    slack_w[..., gauges] = 0.0  # the tip row
    sp = np.sum(slack_w * a_p * a_p, axis=-1)
    p_only = np.sum(slack_w * a_p * res, axis=-1) / np.where(sp > 0, sp, 1.0)
    p_only = np.maximum(p_only, 0.0) if positive else p_only
    chi = np.sum(slack_w * (res - p_only[..., None] * a_p) ** 2, axis=-1)
    chi = np.where((np.abs(p_only) <= max_force_n) & (not (cable and signed)), chi, np.inf)
    t_best, p_best = np.zeros(chi.shape), p_only
    if not cable:
        return t_best, p_best, chi
    a_tb = np.broadcast_to(a_t, a_p.shape)
    h11 = np.sum(w * a_tb * a_tb, axis=-1)
    h22 = np.sum(w * a_p * a_p, axis=-1)
    h12 = np.sum(w * a_tb * a_p, axis=-1)
    g1 = np.sum(w * a_tb * res, axis=-1)
    g2 = np.sum(w * a_p * res, axis=-1)
    det = h11 * h22 - h12**2
    ok = det > 1e-12 * h11 * np.maximum(h22, 1e-300)
    safe = np.where(ok, det, 1.0)
    t = np.where(ok, (h22 * g1 - h12 * g2) / safe, 0.0)
    p = np.where(ok, (h11 * g2 - h12 * g1) / safe, 0.0)
    chi_tp = np.sum(w * (res - t[..., None] * a_tb - p[..., None] * a_p) ** 2, axis=-1)
    take = ok & ((t > 0) | signed) & ((p >= 0) if positive else True) & (np.abs(p) <= max_force_n) & (chi_tp < chi)
    return np.where(take, t, t_best), np.where(take, p, p_best), np.where(take, chi_tp, chi)


def _span(grid: np.ndarray, inside: np.ndarray, best: np.ndarray) -> np.ndarray:
    """(B, 2): the lowest and highest grid point marked ``inside`` each row, widened to include ``best``."""
    lo = np.where(inside.any(axis=1), grid[np.argmax(inside, axis=1)], best)
    hi = np.where(inside.any(axis=1), grid[grid.size - 1 - np.argmax(inside[:, ::-1], axis=1)], best)
    return np.stack([np.minimum(lo, best), np.maximum(hi, best)], axis=1)


def _parabola(grid: np.ndarray, chi: np.ndarray, best: np.ndarray) -> np.ndarray:
    """The minimum of the parabola through the best grid point and its neighbours (m); the point itself at an end."""
    i = np.clip(best, 1, grid.size - 2)
    rows = np.arange(chi.shape[0])
    y0, y1, y2 = chi[rows, i - 1], chi[rows, i], chi[rows, i + 1]
    with np.errstate(invalid="ignore"):  # an infeasible neighbour (infinite chi-square): no refinement
        denom = y0 - 2 * y1 + y2
        usable = np.isfinite(denom) & (denom > 0)
        shift = np.clip(np.where(usable, 0.5 * (y0 - y2) / np.where(usable, denom, 1.0), 0.0), -1.0, 1.0)
    at_end = (best == 0) | (best == grid.size - 1)
    return np.where(at_end, grid[best], grid[i] + shift * (grid[1] - grid[0]))


def true_centre_line_m(psi_rad, chain, s_m) -> np.ndarray:
    """The twin's centre line (B, Q, 2) at arc positions ``s_m`` from its link angles (B, n): the reference the
    estimator is scored against (:meth:`flexdigit.twin.digit.Chain.positions`)."""
    return chain.positions(np.atleast_2d(psi_rad), np.asarray(s_m, dtype=float))


@dataclass
class ShapeAccuracy:
    """The estimator against the twin's true centre line over a set of static cases (:func:`shape_accuracy`).

    Attributes
    ----------
    case : ndarray of str, shape (B,)
        The case group of each row ("bare, upright", "bare, horizontal", "weight, horizontal").
    command, mass_kg, position_from_base_m : ndarray, shape (B,)
        The case: servo command, hung weight (0: none) and where (m from the clamp).
    tip_error_m, rms_error_m : ndarray, shape (B,)
        Distance between estimated and true tip (m), RMS distance along the digit (m).
    tip_sd_m : ndarray, shape (B,)
        The estimate's own standard deviation of the tip position (m, both axes combined).
    contact : ndarray of bool, shape (B,)
        Whether the estimator declared a load.
    load_position_error_m, load_position_sd_m : ndarray, shape (B,)
        Its load position's error and standard deviation (m; NaN without contact).
    settled : ndarray of bool, shape (B,)
        Whether the estimate's lever arms settled (``tol_rad``): where not, the row is an estimate it cannot
        stand behind (flagged here and by ``shape --accuracy``, rather than warned about).
    """

    case: np.ndarray
    command: np.ndarray
    mass_kg: np.ndarray
    position_from_base_m: np.ndarray
    tip_error_m: np.ndarray
    rms_error_m: np.ndarray
    tip_sd_m: np.ndarray
    contact: np.ndarray
    load_position_error_m: np.ndarray
    load_position_sd_m: np.ndarray
    settled: np.ndarray
    seed: int = 0
    #: The bare group's mount: "vertical" (tip up), or "hanging" for a digit that buckles tip up.
    mount: str = "vertical"

    def summary(self) -> list[dict]:
        """Per case group: cases, tip error median / 95th percentile / max (mm), mean RMS along the digit (mm),
        share of tips within two of their standard deviations, contact rate, estimates unsettled."""
        out = []
        for group in dict.fromkeys(self.case.tolist()):
            rows = self.case == group
            tip = self.tip_error_m[rows] * 1e3
            out.append(
                {
                    "case": group,
                    "cases": int(rows.sum()),
                    "tip_error_median_mm": float(np.median(tip)),
                    "tip_error_p95_mm": float(np.percentile(tip, 95)),
                    "tip_error_max_mm": float(np.max(tip)),
                    "rms_error_mean_mm": float(np.mean(self.rms_error_m[rows]) * 1e3),
                    "tip_within_2sd": float(np.mean(self.tip_error_m[rows] <= 2 * self.tip_sd_m[rows])),
                    "contact_rate": float(np.mean(self.contact[rows])),
                    "unsettled": int(np.sum(~self.settled[rows])),
                }
            )
        return out

    __repr__ = fields_summary


#: Where :func:`shape_accuracy` hangs its weight on the thesis rig: every centimetre from the clamp to the tip (m).
ACCURACY_POSITIONS_M = tuple(round(0.01 * k, 2) for k in range(1, 28))
#: Commands :func:`accuracy_commands` takes from the straight command to each end of the operating range (the
#: thesis rig's 8, 13, ..., 43).
ACCURACY_STEPS = 7


def accuracy_commands(params: RigParams | None = None) -> tuple[int, ...]:
    """The commands :func:`shape_accuracy` (and ``flexdigit shape --accuracy``) scores a digit at: from its
    straight command (``equilibrium_command``) to each end of its ``operating_commands`` in
    :data:`ACCURACY_STEPS` equal steps, rounded; one side for the single cable (8, 13, ..., 43 on the thesis
    rig), both for an antagonistic pair (127 -+ 35 on a pair described without a range).

    >>> accuracy_commands()
    (8, 13, 18, 23, 28, 33, 38, 43)
    """
    a = (params or RigParams()).actuator
    ends = [c for c in a.operating_commands if c != a.equilibrium_command]
    sweeps = [np.linspace(a.equilibrium_command, end, ACCURACY_STEPS + 1) for end in ends]
    commands = np.unique(np.round(np.concatenate([[a.equilibrium_command], *sweeps])).astype(int))
    return tuple(int(c) for c in commands)


def accuracy_positions_m(params: RigParams | None = None) -> tuple[float, ...]:
    """Where :func:`shape_accuracy` hangs its weight: the thesis rig's :data:`ACCURACY_POSITIONS_M` as fractions
    of its 0.27 m digit, on this digit (27 places, the tip included), rounded to 0.1 mm."""
    length = (params or RigParams()).geometry.digit_length_m
    return tuple(round(length * k / len(ACCURACY_POSITIONS_M), 4) for k in range(1, len(ACCURACY_POSITIONS_M) + 1))


def shape_accuracy(
    commands=None,
    positions_from_base_m=None,
    mass_kg: float = 0.025,
    *,
    seed: int = 0,
    params: RigParams | None = None,
    calibration=None,
) -> ShapeAccuracy:
    """Score :class:`ShapeEstimator` against the twin's true centre line over the actuation range.

    Three groups of static cases, one noisy reading each (the twin's white noise and, with the cable taut, one
    draw of its cable-guide friction per case, seeded): the bare digit upright (the designed mounting) and
    horizontal at every command of ``commands``, and the horizontal digit with ``mass_kg`` hung at every position
    of ``positions_from_base_m`` at every command. A digit that buckles tip up
    (:func:`flexdigit.control.design20ms.digit_mount`, the mount ``run`` takes) has no upright case: its bare group
    hangs tip down ("bare, hanging"; :attr:`ShapeAccuracy.mount` says which). ``commands`` default to the
    digit's :func:`accuracy_commands`, ``positions_from_base_m`` to its :func:`accuracy_positions_m`. The twin
    (:func:`flexdigit.twin.static_gauges_v`, a discrete elastica solved by Newton) gives the readings and the true
    shape; the estimator sees only the readings and the command.

    Examples
    --------
    >>> acc = shape_accuracy(commands=(8, 30), positions_from_base_m=(0.2,), seed=1)
    >>> [(g["case"], g["cases"]) for g in acc.summary()]
    [('bare, upright', 2), ('bare, horizontal', 2), ('weight, horizontal', 2)]
    >>> bool(np.all(acc.tip_error_m < 0.01))
    True
    """
    params = params or RigParams()
    calibration = calibration or twin_calibration(params)
    a = params.actuator
    commands = accuracy_commands(params) if commands is None else commands
    positions_from_base_m = accuracy_positions_m(params) if positions_from_base_m is None else positions_from_base_m
    cmds = check_array(commands, "commands", "shape_accuracy", ndim=1, min_length=1, low=a.command_min)
    cmds = cmds.astype(int)
    pos = check_array(positions_from_base_m, "positions_from_base_m", "shape_accuracy", ndim=1, low=0)
    mass = check_real(mass_kg, "mass_kg", "shape_accuracy", low=0, low_open=True)
    mount = digit_mount(params, calibration)  # tip up, or hanging where the digit buckles tip up
    bare = "bare, upright" if mount == "vertical" else f"bare, {mount}"
    groups = [
        (bare, mount, cmds, np.zeros(cmds.size), np.zeros(cmds.size)),
        ("bare, horizontal", "horizontal", cmds, np.zeros(cmds.size), np.zeros(cmds.size)),
    ]
    cc, pp = np.meshgrid(cmds, pos, indexing="ij")
    groups.append(("weight, horizontal", "horizontal", cc.ravel(), np.full(cc.size, mass), pp.ravel()))
    columns: dict[str, list] = {k: [] for k in ShapeAccuracy.__dataclass_fields__ if k not in ("seed", "mount")}
    for k, (name, orientation, c, m, s) in enumerate(groups):
        volts, sol = static_gauges_v(
            m, s, c, params=params, calibration=calibration, orientation=orientation, seed=seed + k,
            return_solution=True,
        )  # fmt: skip
        estimator = ShapeEstimator(params, calibration, orientation=orientation)
        est, _, change, rounds = estimator._estimate(volts, c, None)  # unsettled rows: a column, not a warning
        chain = cached_digit(params, calibration, True, orientation, DEFAULT_CELLS_PER_SECTION)
        truth = true_centre_line_m(sol.psi_rad, chain, est.s_m)
        dist = np.linalg.norm(est.centre_line_m - truth, axis=-1)
        columns["case"].append(np.full(c.size, name))
        columns["command"].append(c)
        columns["mass_kg"].append(m)
        columns["position_from_base_m"].append(s)
        columns["tip_error_m"].append(dist[:, -1])
        columns["rms_error_m"].append(np.sqrt(np.mean(dist**2, axis=1)))
        columns["tip_sd_m"].append(np.hypot(est.tip_sd_m[:, 0], est.tip_sd_m[:, 1]))
        columns["contact"].append(est.contact)
        columns["load_position_error_m"].append(np.where(m > 0, est.load_position_from_base_m - s, np.nan))
        columns["load_position_sd_m"].append(est.load_position_sd_m)
        columns["settled"].append(change < estimator.tol_rad if rounds else np.ones(c.size, dtype=bool))
    return ShapeAccuracy(**{k: np.concatenate(v) for k, v in columns.items()}, seed=seed, mount=mount)
