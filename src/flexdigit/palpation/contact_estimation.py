"""Contact from the three gauges and the command: yes / no, where, how hard, point or distributed.

Beyond the thesis (chapter 8 names it: palpation and "discriminate against distributed loads"). A body touching
the digit (the tissue the cable presses it into, a finger, a retractor) shows in the gauges as a change of the
bending moment along the strip. Statics says how much the three gauges can tell: the moment at a section is
``T e - sum_{loads beyond} F (s - x)`` plus the cable's answer, and with the cable taut its stiffness pins the tip
angle, so the tension adjusts to keep ``integral kappa ds`` fixed. Hence
(:func:`flexdigit.tactile.bounds.contact_bounds` draws the map):

- a contact between the clamp and gauge 2 is seen only through ``F (s - x_1)`` (gauge 1) and a tension change
  proportional to the same product: force and position are confounded (as a hanging weight is, chapter 6);
- beyond gauge 2 force and position are both identifiable;
- on the rigid tip support (past 265 mm) the position drops out: a load there is a force plus a moment at the
  section's start, and the pinned tip angle absorbs the moment. Only the force is seen;
- a line load and a point force with the same total and centroid give the same moment at every section outside the
  loaded stretch; they differ (by up to ``F w / 8`` at its centre) at a gauge inside it, and, faintly, through the
  taut cable's tension (the pinned tip angle integrates the moment along the strip: ``F w^2 / 24`` apart). Point
  versus distributed is told mostly where a gauge lies inside the stretch.

:class:`ContactGaugeModel` is the twin's static model of the gauges under a point force, a line load or a body
(:mod:`flexdigit.twin.contact`); :class:`ContactEstimator` is the maximum-likelihood estimate under three
hypotheses (none, a point force, an even line load), each with its standard deviation from the Fisher
information at the estimate; the bounds that go beside them are in :mod:`flexdigit.tactile.bounds`.

Forces are sideways, positive towards the cable side (+b, as :meth:`flexdigit.twin.Twin.deflect`); the estimator
looks for contacts on one side (``side``: the cable side by default, where the cable presses the digit, so forces
``<= 0``).

Examples
--------
>>> import numpy as np
>>> model = ContactGaugeModel()
>>> v = model.point_v([0.2], [-0.2], 20)
>>> est = ContactEstimator(model, commands=[20]).fit()
>>> e = est.predict(v, 20)
>>> bool(e.contact[0]), round(float(e.position_m[0]), 3), round(float(e.force_n[0]), 3)
(True, 0.2, -0.2)
"""

from __future__ import annotations

from dataclasses import dataclass
from numbers import Integral, Real

import numpy as np

from flexdigit._estimator import Estimator, check_is_fitted
from flexdigit._repr import fields_summary
from flexdigit._validation import (
    Array,
    Bool,
    HasMethods,
    Interval,
    Options,
    check_array,
    check_choice,
    check_int,
    check_positive,
    check_real,
    check_values,
)
from flexdigit.errors import ParameterError
from flexdigit.params import RigParams
from flexdigit.tactile.bounds import line_steps
from flexdigit.twin.contact import Pressure, quadrature, solve_contact
from flexdigit.twin.digit_calibration import twin_calibration
from flexdigit.twin.sensors import SensorChain
from flexdigit.twin.twin import cable_shortening_m, cached_digit

__all__ = [
    "DETECT_CHI2",
    "DISTRIBUTED_LOG_ODDS",
    "POLY_DEGREE",
    "FORCE_POINTS",
    "LINE_CENTRE_STEP_M",
    "KINDS",
    "ContactGaugeModel",
    "ContactEstimate",
    "ContactEstimator",
]

#: chi-square(2 dof) 99.9 % quantile: a contact is declared when it explains the reading this much better than none.
DETECT_CHI2 = 13.8155
#: A line load is declared when the gauges make it more probable than a point (equal priors: the Bayes decision).
DISTRIBUTED_LOG_ODDS = 0.0
POLY_DEGREE = 5
#: Forces each table is fitted on (a degree-5 polynomial on 9 forces matches the twin within 6 uV up to 1 N).
FORCE_POINTS = 9
#: Grid step of the line loads' centres (m): their gauges change slowly with the centre.
LINE_CENTRE_STEP_M = 0.002
KINDS = ("none", "point", "distributed")


def _kernel():
    """The compiled kernels (:mod:`flexdigit.palpation._contact_kernel`), imported here once for every caller on
    first use: numba's import and compilation are paid when a contact is estimated, not when this module loads."""
    from flexdigit.palpation import _contact_kernel

    return _contact_kernel


class ContactGaugeModel:
    """The twin's static gauge voltages (noise-free, V) under contact, for any batch of cases.

    Parameters
    ----------
    params : RigParams, optional
    calibration : Calibration, optional
        The twin's calibration (default: the digit's own, :func:`~flexdigit.twin.digit_calibration.twin_calibration`);
        a real rig's is fitted by :func:`flexdigit.twin.calibration.calibrate`.
    orientation : str
        How the digit is mounted ("vertical", tip up: the designed mounting and the palpation set-up).
    housing : bool
    cells_per_section : int, sequence of int or None
        Springs per section (None: the description's, :func:`flexdigit.params.twin_cells`).

    Attributes
    ----------
    noise_v : ndarray, shape (3,)
        White noise of one reading (V): the calibration's ``noise_white_v`` (the thesis's non-actuated level; the
        cable-guide friction is absent until a weight is hung, :mod:`flexdigit.twin.sensors`).
    """

    def __init__(self, params=None, calibration=None, *, orientation="vertical", housing=True, cells_per_section=None):
        self.params = params or RigParams()
        self.calibration = calibration or twin_calibration(self.params)
        self.orientation = orientation
        self.housing = housing
        self.chain = cached_digit(self.params, self.calibration, bool(housing), orientation, cells_per_section)
        self.sensors = SensorChain(self.params, self.calibration, np.random.default_rng(0))
        self.noise_v = np.asarray(self.calibration.noise_white_v, dtype=float)
        self.length_m = float(self.params.geometry.digit_length_m)

    def __repr__(self) -> str:
        return f"ContactGaugeModel(orientation={self.orientation!r}, housing={self.housing}, noise_v={self.noise_v})"

    def _commands(self, command, n: int) -> np.ndarray:
        a = self.params.actuator
        c = check_values(command, "command", "ContactGaugeModel", low=a.command_min, high=a.command_max, integer=True)
        return np.broadcast_to(c.reshape(-1) if c.ndim else c, (n,)).astype(int)

    def _volts(self, load_s, load_f, command):
        b = load_s.shape[0]
        cmd = self._commands(command, b)
        sol = self.chain.solve_static(
            load_s,
            np.stack([np.zeros_like(load_f), load_f], axis=-1),
            cable_shortening_m=cable_shortening_m(cmd, self.params),
        )
        return self.sensors.clean_v(sol.curvature_1_m, sol.axial_force_n)

    def free_v(self, command) -> np.ndarray:
        """Gauges with nothing touching the digit, per command (n, 3)."""
        cmd = np.atleast_1d(np.asarray(command))
        return self._volts(np.zeros((cmd.size, 1)), np.zeros((cmd.size, 1)), cmd)

    def point_v(self, position_m, force_n, command) -> np.ndarray:
        """Gauges under one point force per case: ``position_m`` (n,) m from the base, ``force_n`` (n,) N."""
        s = check_values(position_m, "position_m", "ContactGaugeModel.point_v", low=0, high=self.length_m, unit="m")
        s = np.atleast_1d(s)
        f = np.broadcast_to(check_values(force_n, "force_n", "ContactGaugeModel.point_v", unit="N"), s.shape)
        return self._volts(s[:, None], f[:, None].astype(float), command)

    def line_v(self, centre_m, extent_m, total_n, command) -> np.ndarray:
        """Gauges under one even line load per case: ``total_n`` (N) over ``centre_m +- extent_m / 2`` (m)."""
        s, unit = self.line_points(centre_m, extent_m)
        t = np.broadcast_to(np.asarray(total_n, dtype=float), (s.shape[0],))
        if not np.all(np.isfinite(t)):
            raise ParameterError("The 'total_n' parameter of ContactGaugeModel.line_v must be finite.")
        return self._volts(s, unit * t[:, None], command)

    def line_points(self, centre_m, extent_m) -> tuple[np.ndarray, np.ndarray]:
        """Point loads equivalent to even line loads of 1 N (:func:`flexdigit.twin.contact.quadrature`): arc
        positions and forces, (n, K), padded with zero forces."""
        c = np.atleast_1d(np.asarray(centre_m, dtype=float))
        w = np.broadcast_to(np.asarray(extent_m, dtype=float), c.shape)
        lo, hi = c - w / 2, c + w / 2
        bad = (lo < -1e-5) | (hi > self.length_m + 1e-5) | ~(w > 0) | ~np.isfinite(c)  # (steps of the bounds)
        if np.any(bad):
            raise ParameterError(
                "The line loads of ContactGaugeModel must lie on the digit (0 <= centre - extent/2, centre + "
                f"extent/2 <= {self.length_m:g} m, extent > 0). Got centre {c[bad][0]!r}, extent {w[bad][0]!r}."
            )
        lo, hi = np.maximum(lo, 0.0), np.minimum(hi, self.length_m)
        pieces = [quadrature(self.chain, [Pressure(a, b, 1.0)]) for a, b in zip(lo, hi, strict=True)]
        k = max(p[0].size for p in pieces)
        s = np.zeros((c.size, k))
        f = np.zeros((c.size, k))
        for i, (ps, pf) in enumerate(pieces):
            s[i, : ps.size], f[i, : ps.size] = ps, pf[:, 1]
        return s, f

    def tissue_solution(self, tissue, command, psi0=None):
        """The body's static contact at each command: :class:`flexdigit.twin.contact.ContactSolution` and the
        gauges (n, 3). ``psi0`` (n, links): a starting shape (a neighbouring tissue's solution)."""
        cmd = np.atleast_1d(np.asarray(command)).astype(int)
        sol = solve_contact(
            self.chain, tissue=tissue, cable_shortening_m=cable_shortening_m(cmd, self.params), psi0=psi0
        )
        return sol, self.sensors.clean_v(sol.static.curvature_1_m, sol.static.axial_force_n)


@dataclass
class ContactEstimate:
    """Contact estimates of a batch of readings (arrays of length n; NaN where a quantity does not apply).

    Attributes
    ----------
    contact : ndarray of bool
        Something touches the digit (likelihood ratio against nothing over :data:`DETECT_CHI2`).
    kind : ndarray of str
        "none", "point" or "distributed".
    position_m, position_sd_m : ndarray
        Where the force acts (m from the base): the point, or the line load's centre; its standard deviation from
        the Fisher information at the estimate (inf where the gauges cannot locate it).
    force_n, force_sd_n : ndarray
        The total force (N, + towards the cable side) and its standard deviation.
    extent_m, extent_sd_m : ndarray
        The line load's length (m; 0 for a point) and its standard deviation.
    point_position_m, point_force_n : ndarray
        The point-force estimate whatever the decision (what a caller that knows it is a point uses).
    line_centre_m, line_extent_m, line_total_n : ndarray
        The line-load estimate whatever the decision.
    chi2_contact : ndarray
        ``cost(none) - cost(best)``: the likelihood-ratio statistic of the contact decision.
    log_odds_distributed : ndarray
        ``log p(reading | line load) - log p(reading | point force)``, each marginalised over its grid (uniform
        priors over positions, or centres and extents, and forces): the Bayes factor behind the point / distributed
        decision.
    """

    contact: np.ndarray
    kind: np.ndarray
    position_m: np.ndarray
    position_sd_m: np.ndarray
    force_n: np.ndarray
    force_sd_n: np.ndarray
    extent_m: np.ndarray
    extent_sd_m: np.ndarray
    point_position_m: np.ndarray
    point_force_n: np.ndarray
    line_centre_m: np.ndarray
    line_extent_m: np.ndarray
    line_total_n: np.ndarray
    chi2_contact: np.ndarray
    log_odds_distributed: np.ndarray

    def as_dict(self) -> dict:
        return {k: v.tolist() for k, v in self.__dict__.items()}

    __repr__ = fields_summary


class ContactEstimator(Estimator):
    """Maximum-likelihood contact from the three gauges and the command (see the module docstring).

    The point-force hypothesis is tabulated per command on a grid of positions (``position_step_m``), each gauge a
    degree-5 polynomial in the force (fitted on :data:`FORCE_POINTS` forces in ``[-max_force_n, 0]``: within 6 uV
    of the twin's statics); the line-load hypothesis on a grid of centres and extents. A reading's estimate
    profiles the force out at every grid point (Newton on the polynomial), takes the best point and refines it by a
    parabola; the standard deviations come from the Fisher information of the refined estimate.

    Parameters
    ----------
    model : ContactGaugeModel
    commands : sequence of int, optional
        Commands to tabulate up front (others are tabulated on first use, ~20 ms each).
    side : {"cable", "opposite"}
        Where contacts come from: the cable side (forces <= 0) or the other.
    max_force_n : float
        Largest force considered (N).
    position_step_m : float
        Grid step of point positions and line centres (m).
    extents_m : sequence of float
        Line-load lengths tabulated (m); the shortest is the least a line load can be told by.
    n_readings : int
        Readings averaged into each input row (the noise of a row is ``noise_v / sqrt(n_readings)``).
    offset_v : array_like, shape (3,), optional
        Subtracted from every reading: the rig's gauge offsets against the model (see :meth:`fit`).
    detect_chi2 : float
        Threshold of the contact's likelihood-ratio test (:data:`DETECT_CHI2`).
    classify_log_odds : float
        A line load is declared when its log Bayes factor over a point force exceeds this (:data:`DISTRIBUTED_LOG_ODDS`,
        the Bayes decision for equal priors). A short line load away from the gauges reads exactly as a point does,
        and the line hypothesis has more ways (centre, extent, force) to explain such a reading, so where the gauges
        cannot tell the two the decision is a coin the priors toss: ``point_*`` and ``line_*`` hold both estimates.
    classify : bool
        Also weigh the line-load hypothesis (point versus distributed); False keeps to point forces (faster to
        tabulate: what force control and palpation need).
    region_m : (float, float), optional
        Look for the contact only between these arc positions (m from the base), e.g. where the tissue is known to
        lie: a reading of nothing then gives a force near 0 instead of a large force where the gauges are blind.
    """

    _parameter_constraints = {
        "model": [HasMethods(("point_v", "line_v", "free_v"))],
        "commands": [Array(ndim=1, low=0, high=254)],
        "side": [Options(("cable", "opposite"))],
        "max_force_n": [Interval(Real, 0, None, closed="neither")],
        "position_step_m": [Interval(Real, 1e-4, 0.05)],
        "extents_m": [Array(ndim=1, min_length=1, low=0, low_open=True)],
        "n_readings": [Interval(Integral, 1, None)],
        "offset_v": [Array(shape=(3,)), None],
        "detect_chi2": [Interval(Real, 0, None)],
        "classify_log_odds": [Interval(Real, None, None)],
        "classify": [Bool()],
        "region_m": [Array(shape=(2,), increasing=True), None],
    }

    def __init__(
        self,
        model,
        *,
        commands=(),
        side: str = "cable",
        max_force_n: float = 1.0,
        position_step_m: float = 1e-3,
        extents_m=(0.02, 0.03, 0.04, 0.06, 0.08, 0.1, 0.12, 0.15),
        n_readings: int = 1,
        offset_v=None,
        detect_chi2: float = DETECT_CHI2,
        classify_log_odds: float = DISTRIBUTED_LOG_ODDS,
        classify: bool = True,
        region_m=None,
    ) -> None:
        self.model = model
        self.commands = commands
        self.side = side
        self.max_force_n = max_force_n
        self.position_step_m = position_step_m
        self.extents_m = extents_m
        self.n_readings = n_readings
        self.offset_v = offset_v
        self.detect_chi2 = detect_chi2
        self.classify_log_odds = classify_log_odds
        self.classify = classify
        self.region_m = region_m

    def __repr__(self) -> str:
        return (
            f"ContactEstimator(side={self.side!r}, max_force_n={self.max_force_n}, "
            f"position_step_m={self.position_step_m}, extents_m={tuple(self.extents_m)}, n_readings={self.n_readings})"
        )

    # -------------------------------------------------------------------------------------------- fitting
    def fit(self, X=None, y=None) -> ContactEstimator:
        """Validate the settings and tabulate ``commands``. With ``X`` (n, 4: gauges and command) of readings with
        nothing touching, also learn the gauges' offsets against the model (a tare), unless ``offset_v`` is given."""
        self._validate_params()
        owner = "ContactEstimator"
        check_choice(self.side, "side", ("cable", "opposite"), owner)
        self.sign_ = -1.0 if self.side == "cable" else 1.0
        check_positive(self.max_force_n, "max_force_n", owner)
        check_real(self.position_step_m, "position_step_m", owner, low=1e-4, high=0.05)
        self.extents_ = check_array(self.extents_m, "extents_m", owner, ndim=1, min_length=1, low=0, low_open=True)
        self.n_readings_ = check_int(self.n_readings, "n_readings", owner, low=1)
        self.sigma_ = np.asarray(self.model.noise_v, dtype=float) / np.sqrt(self.n_readings_)
        self.weight_ = 1.0 / self.sigma_**2
        length = self.model.length_m
        lo, hi = (0.0, length) if self.region_m is None else (float(self.region_m[0]), float(self.region_m[1]))
        lo, hi = max(lo, 0.0), min(hi, length)
        if not hi - lo >= 2 * self.position_step_m:
            raise ParameterError(
                f"The 'region_m' parameter of {owner} must span at least two grid steps on the digit (0..{length:g} m)."
                f" Got {self.region_m!r} instead."
            )
        self.s_grid_ = np.arange(lo, hi + self.position_step_m / 2, self.position_step_m)
        self.s_grid_ = np.minimum(self.s_grid_[self.s_grid_ <= hi + 1e-9], hi)
        self.f_grid_ = self.sign_ * self.max_force_n * np.linspace(0.0, 1.0, FORCE_POINTS)
        self.tables_: dict[int, dict] = {}
        n = len(self.model.params.geometry.gauge_positions_m)  # the digit's gauges
        self.offset_ = (
            np.zeros(n) if self.offset_v is None else check_array(self.offset_v, "offset_v", owner, shape=(n,))
        )
        if X is not None and self.offset_v is None:
            v, cmd = _split(X, len(self.model.params.geometry.gauge_positions_m))
            self.offset_ = np.mean(v - self.model.free_v(cmd), axis=0)
        for c in self.commands:
            self._line_table(int(c)) if self.classify else self._table(int(c))
        return self

    def _table(self, command: int) -> dict:
        if command in self.tables_:
            return self.tables_[command]
        m = self.model
        s, f = self.s_grid_, self.f_grid_
        ss, ff = np.meshgrid(s, f[1:], indexing="ij")
        g0 = m.free_v([command])[0]
        n = len(m.params.geometry.gauge_positions_m)  # the digit's gauges
        v = m.point_v(ss.ravel(), ff.ravel(), command).reshape(s.size, f.size - 1, n) - g0
        design = np.stack([f[1:] ** k for k in range(1, POLY_DEGREE + 1)], axis=1)  # (nf, K)
        coef = np.linalg.lstsq(design, v.transpose(1, 0, 2).reshape(f.size - 1, -1), rcond=None)[0]
        point = np.ascontiguousarray(coef.reshape(POLY_DEGREE, s.size, n))  # (K, ns, gauges)
        table = {"g0": g0, "point": point}
        self.tables_[command] = table
        return table

    def _line_table(self, command: int) -> dict:
        table = self._table(command)
        if "line" in table:
            return table
        # line loads: centres on a grid, each extent that fits on the digit
        rows = []
        step = max(LINE_CENTRE_STEP_M, self.position_step_m)
        lo, hi = self.s_grid_[0], self.s_grid_[-1]
        for w in self.extents_:
            centres = np.arange(max(w / 2, lo), min(self.model.length_m - w / 2, hi) + 1e-12, step)
            rows += [(c, w) for c in centres]
        cw = np.array(rows)
        table.update(line=self._line_coefficients(cw[:, 0], cw[:, 1], command, table["g0"]), line_cw=cw)
        return table

    def _line_coefficients(self, centre, extent, command: int, g0) -> np.ndarray:
        """Each gauge's polynomial in the total force (K, n, 3) of even line loads, fitted on the force grid."""
        m, f = self.model, self.f_grid_
        ls, lu = m.line_points(centre, extent)
        nf = f.size - 1
        lv = m._volts(np.tile(ls, (nf, 1)), np.repeat(f[1:], centre.size)[:, None] * np.tile(lu, (nf, 1)), command)
        design = np.stack([f[1:] ** k for k in range(1, POLY_DEGREE + 1)], axis=1)
        n = len(m.params.geometry.gauge_positions_m)
        coef = np.linalg.lstsq(design, (lv.reshape(nf, centre.size, n) - g0).reshape(nf, -1), rcond=None)[0]
        return np.ascontiguousarray(coef.reshape(POLY_DEGREE, centre.size, n))

    def _line_derivatives(self, command: int, index) -> dict:
        """The line table with its derivatives in centre and extent (``line_dc``, ``line_dw``: K, G, 3, polynomials
        in the total) filled in at entries ``index``: the central differences of
        :func:`flexdigit.tactile.bounds.line_jacobian` (same steps), fitted as the table is. Each entry's are
        computed the first time a reading is declared a line load there (32 static solves, a few ms) and kept:
        a line load's Fisher standard deviations are then a look-up instead of six static solves per reading."""
        table = self._line_table(command)
        cw, g0 = table["line_cw"], table["g0"]
        if "line_dc" not in table:
            n = table["line"].shape[2]
            table.update(
                line_dc=np.zeros((POLY_DEGREE, len(cw), n)),
                line_dw=np.zeros((POLY_DEGREE, len(cw), n)),
                line_derived=np.zeros(len(cw), dtype=bool),
            )
        need = np.unique(index[~table["line_derived"][index]])
        if need.size:
            c, w = cw[need, 0], cw[need, 1]
            hc, hw = line_steps(self.model.length_m, c, w)
            up = self._line_coefficients(np.concatenate([c + hc, c]), np.concatenate([w, w + hw]), command, g0)
            down = self._line_coefficients(np.concatenate([c - hc, c]), np.concatenate([w, w - hw]), command, g0)
            slope = (up - down) / np.concatenate([2 * hc, 2 * hw])[None, :, None]
            table["line_dc"][:, need], table["line_dw"][:, need] = slope[:, : need.size], slope[:, need.size :]
            table["line_derived"][need] = True
        return table

    # ----------------------------------------------------------------------------------------- estimating
    def _profile(self, r, coef, half: int = -1):
        """Best force and cost for every grid entry: ``r`` (B, 3) residual readings, ``coef`` (K, G, 3).

        Returns force (B, G), cost (B, G) (the weighted squared residual) and the cost's half curvature in the force
        (B, G), for the evidence's Laplace approximation: two Newton steps on the polynomial model from the linear
        model's force, the force clipped to the side's range (compiled: :mod:`flexdigit.palpation._contact_kernel`).
        With ``half >= 0`` only the ``2 half + 1`` entries around the best at the linear model's force get the
        Newton steps (all a point estimate needs; the others keep the linear model's force and cost)."""
        kernel = _kernel()

        out = kernel.empty_profile(r.shape[0], coef.shape[1])
        r = np.ascontiguousarray(r, dtype=float)
        kernel.profile(r, coef, self.weight_, self.sign_, float(self.max_force_n), int(half), *out)
        return out

    def predict(self, X, command=None) -> ContactEstimate:
        """Estimate contact from readings: ``X`` (n, 4) gauges and command, or (n, 3) gauges with ``command``."""
        if command is not None:
            v = check_array(X, "X", "ContactEstimator.predict")
            v = v.reshape(-1, len(self.model.params.geometry.gauge_positions_m))
            cmd = np.broadcast_to(np.asarray(command), (v.shape[0],)).astype(int)
        else:
            v, cmd = _split(X, len(self.model.params.geometry.gauge_positions_m))
        if not hasattr(self, "tables_"):
            check_is_fitted(self, "tables_")
        n = v.shape[0]
        out = {name: np.full(n, np.nan) for name in _FIELDS}
        kind = np.full(n, "none", dtype=object)
        contact = np.zeros(n, dtype=bool)
        for c in np.unique(cmd):
            rows = np.flatnonzero(cmd == c)
            self._predict_command(v[rows] - self.offset_, int(c), rows, out, kind, contact)
        return ContactEstimate(contact=contact, kind=kind, **out)

    def _predict_command(self, v, command, rows, out, kind, contact) -> None:
        t = self._line_table(command) if self.classify else self._table(command)
        r = v - t["g0"]
        none_cost = np.sum(self.weight_ * r * r, axis=1)
        n = r.shape[0]
        ps, pforce, pcost = np.empty(n), np.empty(n), np.empty(n)
        lcentre, lextent, ltotal, lcost, log_odds = (np.full(n, np.nan) for _ in range(5))
        lindex = np.zeros(n, dtype=int)
        for start in range(0, n, 256):  # chunks bound the (chunk, grid) temporaries
            part = slice(start, start + 256)
            pf, pc, ph = self._profile(r[part], t["point"], half=-1 if self.classify else 3)
            ps[part], pforce[part], pcost[part] = self._refine(pf, pc, self.s_grid_)
            if self.classify:
                cw = t["line_cw"]
                lf, lc, lh = self._profile(r[part], t["line"])
                li = lindex[part] = np.argmin(lc, axis=1)
                b = np.arange(li.size)
                lcost[part], lcentre[part], lextent[part], ltotal[part] = lc[b, li], cw[li, 0], cw[li, 1], lf[b, li]
                log_odds[part] = _log_evidence(lc, lh) - _log_evidence(pc, ph)
        best = np.fmin(pcost, lcost)
        chi_contact = none_cost - best
        is_contact = chi_contact > self.detect_chi2
        is_line = is_contact & (log_odds > self.classify_log_odds)  # False where not classified (NaN)
        point_sd = self._point_sd(ps, pforce, t)
        line_sd = np.full((n, 3), np.nan)
        if np.any(is_line):
            line_sd[is_line] = self._line_sd(lindex[is_line], ltotal[is_line], command)
        out["point_position_m"][rows], out["point_force_n"][rows] = ps, pforce
        out["line_centre_m"][rows], out["line_extent_m"][rows], out["line_total_n"][rows] = lcentre, lextent, ltotal
        out["chi2_contact"][rows], out["log_odds_distributed"][rows] = chi_contact, log_odds
        contact[rows] = is_contact
        kind[rows] = np.where(is_line, "distributed", np.where(is_contact, "point", "none"))
        out["position_m"][rows] = np.where(is_line, lcentre, np.where(is_contact, ps, np.nan))
        out["force_n"][rows] = np.where(is_line, ltotal, np.where(is_contact, pforce, 0.0))
        out["extent_m"][rows] = np.where(is_line, lextent, np.where(is_contact, 0.0, np.nan))
        out["position_sd_m"][rows] = np.where(is_line, line_sd[:, 0], np.where(is_contact, point_sd[:, 0], np.nan))
        out["force_sd_n"][rows] = np.where(is_line, line_sd[:, 2], point_sd[:, 1])
        out["extent_sd_m"][rows] = np.where(is_line, line_sd[:, 1], np.nan)

    def force_profile(self, gauges_v, command: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The point-force hypothesis along the grid for each reading: ``(positions_m (P,), force_n (n, P),
        chi2 (n, P))``, the force that best explains the reading with the contact at each grid position and the
        cost there above the best position's (0 at the estimate). Where the chi^2 stays within a reading's noise
        (a few units) the gauges cannot tell the place; how far the force moves there says whether they tell the
        force all the same (:func:`flexdigit.palpation.palpation.force_region`)."""
        t = self._table(int(command))
        r = np.atleast_2d(np.asarray(gauges_v, dtype=float)) - self.offset_ - t["g0"]
        force, cost, _ = self._profile(r, t["point"])
        return self.s_grid_.copy(), force, cost - cost.min(axis=1, keepdims=True)

    def rival_chi2(self, gauges_v, command: int) -> np.ndarray:
        """How much worse the best *other* local minimum of the point-contact cost explains each reading (chi^2, n),
        inf when the cost along the digit has one minimum. For noise-free readings: a small value means a distant
        contact is almost as likely, so the contact is locally locatable (a finite Cramer-Rao bound) but globally
        ambiguous (noise now and then makes the estimate jump to the rival)."""
        t = self._table(int(command))
        r = np.atleast_2d(gauges_v) - self.offset_ - t["g0"]
        _, cost, _ = self._profile(r, t["point"])
        padded = np.pad(cost, ((0, 0), (1, 1)), constant_values=np.inf)
        minimum = (cost <= padded[:, :-2]) & (cost <= padded[:, 2:])
        best = np.argmin(cost, axis=1)
        out = np.full(cost.shape[0], np.inf)
        for i in range(cost.shape[0]):
            # the global minimum's own basin ends where the cost stops falling towards it
            others = np.flatnonzero(minimum[i])
            others = others[np.abs(others - best[i]) > 1]
            if others.size:
                out[i] = float(np.min(cost[i, others]) - cost[i, best[i]])
        return out

    def _refine(self, force, cost, grid):
        """Best grid point, refined by a parabola through it and its neighbours (position and force; the force by the
        same parabola's weights, linear interpolation between the neighbours) and the cost there."""
        kernel = _kernel()

        out = np.empty((3, cost.shape[0]))
        kernel.refine(force, cost, grid, *out)
        return out[0], out[1], out[2]

    def _point_sd(self, position, force, table):
        """(n, 2) standard deviations of position and force, from the table's own derivatives."""
        kernel = _kernel()

        out = np.empty((position.size, 2))
        kernel.point_sd(position, force, self.s_grid_, table["point"], self.weight_, out)
        return out

    def _line_sd(self, index, total, command):
        """(n, 3) standard deviations of centre, extent and total of the line table's entries ``index`` at forces
        ``total``, from the derivative tables (within 1 % of :func:`flexdigit.tactile.bounds.line_bounds`)."""
        kernel = _kernel()

        t = self._line_derivatives(command, index)
        jac = np.empty((index.size, t["line"].shape[2], 3))
        kernel.line_jacobian(index, np.asarray(total, dtype=float), t["line"], t["line_dc"], t["line_dw"], jac)
        out = np.empty((index.size, 3))
        kernel.fisher_sd(jac, self.weight_, out)
        return out


_FIELDS = (
    "position_m",
    "position_sd_m",
    "force_n",
    "force_sd_n",
    "extent_m",
    "extent_sd_m",
    "point_position_m",
    "point_force_n",
    "line_centre_m",
    "line_extent_m",
    "line_total_n",
    "chi2_contact",
    "log_odds_distributed",
)


def _log_evidence(cost, curvature) -> np.ndarray:
    """``log sum_g exp(-cost_g / 2) sqrt(2 pi / curvature_g)`` over a grid (B, G), less ``log G``: the marginal
    likelihood under a uniform prior over the grid's entries, the force integrated out by Laplace's approximation
    about its best value (the common force prior's width cancels between hypotheses)."""
    kernel = _kernel()

    out = np.empty(cost.shape[0])
    kernel.log_evidence(cost, curvature, out)
    return out


def _split(X, gauges: int = 3) -> tuple[np.ndarray, np.ndarray]:
    x = check_array(X, "X", "ContactEstimator", ndim=2)
    if x.shape[1] != gauges + 1:
        raise ParameterError(f"X must have {gauges} gauge columns and the command. Got {x.shape[1]} columns.")
    return x[:, :gauges], x[:, gauges].astype(int)
