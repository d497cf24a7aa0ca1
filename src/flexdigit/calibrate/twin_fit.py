"""Fit the twin's free parameters to targets (``scipy.optimize.least_squares``): the calibration layer's core.

This layer sits above the twin and the tactile package (params -> models -> twin -> identify -> ... -> tactile ->
calibrate): it runs the twin's models, reduces records with ``identify``, and, for the thesis's actuated noise,
scores candidate calibrations through the tactile pipeline. The twin itself keeps only what it needs to run (the
:class:`~flexdigit.twin.calibration.Calibration`, its file and the packaged default).

What is fitted to what (see :mod:`flexdigit.twin.calibration` for the parameters): the mechanics (support mass,
housing stiffness and its base factor, strip and housing damping, cable stiffness) against the release tests' wn
and zeta and the deflections; then each channel's gain and offset against its gauge-volt line; noise levels copied
from a resting record; the cable-guide friction from the actuated repeatability or a corr2 score.

Examples
--------
>>> from flexdigit.calibrate.targets import CalibrationTargets
>>> result = calibrate(CalibrationTargets(bare_wn_rad_s=10.0, bare_zeta=0.003))
>>> round(result.calibration.support_mass_kg[0] * 1e3, 2), round(result.residuals[0]["twin"], 6)
(8.61, 10.0)
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from flexdigit._repr import summary
from flexdigit.calibrate.friction import actuated_rest_sd_v, fit_level, friction_ratio_from_repeatability
from flexdigit.calibrate.targets import CalibrationTargets
from flexdigit.errors import ParameterError
from flexdigit.palpation.palpation import command_scale
from flexdigit.params import RigParams
from flexdigit.tactile.thesis_experiments import actuated_corr2_score
from flexdigit.twin.calibration import Calibration
from flexdigit.twin.digit import build_digit
from flexdigit.twin.digit_calibration import calibration_for
from flexdigit.twin.sensors import SensorChain
from flexdigit.twin.twin import cable_shortening_m

_log = logging.getLogger(__name__)

__all__ = ["MECHANICS", "CalibrationResult", "model_response", "calibrate", "calibrate_to_thesis", "THESIS_SOURCE"]

#: Parameters the mechanical fit can move, and the targets that identify each: a parameter no given target
#: identifies is held at its initial value (a least-squares step would move it along a flat valley).
MECHANICS = {
    "support_mass_kg": ("bare_wn_rad_s", "housing_wn_rad_s"),
    # deflections alone cannot: with a stiff cable the tip turns as far as the pulley pulls whatever the housing
    "housing_ei_n_m2": ("housing_wn_rad_s",),
    "housing_base_factor": ("deflection_mm",),
    "strip_beta_s": ("bare_zeta", "housing_zeta"),
    "housing_beta_s": ("housing_zeta",),
    "cable_stiffness_n_m": ("deflection_mm",),
}


@dataclass
class CalibrationResult:
    """What :func:`calibrate` returns: the calibration, a residual table and the optimiser's report.

    Attributes
    ----------
    calibration : Calibration
    residuals : list of dict
        One row per target: ``target``, ``measured``, ``twin`` (the calibrated twin's value), ``unit``, and for the
        mechanical targets ``scale``, the miss the fit weighs as one (1 % of wn or zeta, a deflection's resolution).
    cost : float
        The mechanical fit's final cost (half the sum of squared scaled residuals).
    success : bool
        Whether the optimiser converged.
    message : str
        The optimiser's report.
    fitted : list of str
        The calibration's fields the fit set (the others kept their initial values).
    targets : CalibrationTargets or None
        What was fitted.
    notes : list of str
        What the records could not tell apart or determine, one line each (those values kept as started).
    """

    calibration: Calibration
    residuals: list[dict[str, Any]] = field(default_factory=list)
    cost: float = 0.0
    success: bool = True
    message: str = ""
    fitted: list[str] = field(default_factory=list)
    targets: CalibrationTargets | None = None
    notes: list[str] = field(default_factory=list)

    def residual_rows(self) -> list[dict[str, Any]]:
        """The residuals with ``residual`` (twin - measured) and ``relative`` (residual / abs(measured); None at 0)."""
        rows = []
        for r in self.residuals:
            residual = float(r["twin"]) - float(r["measured"])
            relative = residual / abs(float(r["measured"])) if float(r["measured"]) != 0 else None
            rows.append({**r, "residual": residual, "relative": relative})
        return rows

    def worst(self) -> tuple[dict[str, Any] | None, float]:
        """The target the twin misses most, in units of its scale (1 % of a release test's wn or zeta, the reading
        resolution of a deflection: what the mechanical fit weighs), and that multiple; ``(None, 0)`` if none."""
        scaled = [(r, abs(r["twin"] - r["measured"]) / r["scale"]) for r in self.residuals if r.get("scale")]
        return max(scaled, key=lambda item: item[1], default=(None, 0.0))

    def table(self) -> str:
        """The residuals as text, one line per target."""
        lines = [f"{'target':<44} {'measured':>12} {'twin':>12} {'residual':>12} unit"]
        for r in self.residual_rows():
            lines.append(
                f"{r['target']:<44} {r['measured']:>12.5g} {r['twin']:>12.5g} {r['residual']:>12.4g} {r['unit']}"
            )
        return "\n".join(lines)

    def fit_record(self, source: str) -> dict[str, Any]:
        """The ``[fit]`` table of a calibration file: how it was made, its targets and residuals."""
        record: dict[str, Any] = {"source": source, "cost": self.cost, "success": self.success}
        record["fitted"] = list(self.fitted)
        if self.targets is not None:
            record["targets"] = self.targets.to_dict()
        record["residuals"] = [dict(r) for r in self.residuals]
        if self.notes:
            record["notes"] = list(self.notes)
        return record

    def __repr__(self) -> str:
        return summary(
            self,
            success=self.success,
            cost=self.cost,
            fitted=self.fitted,
            targets=len(self.residuals),
            message=self.message,
        )


def model_response(
    params,
    calibration: Calibration,
    targets: CalibrationTargets,
    *,
    cells_per_section: int | None = None,
    orientation: str = "vertical",
):
    """Everything the fit compares: modal wn/zeta bare and housed, deflections and bridge ratios on the sweep, of
    the digit mounted as the records were taken (``orientation``: tip up as the thesis's; a long digit hangs)."""
    out: dict[str, Any] = {}
    bare = build_digit(params, calibration, housing=False, orientation=orientation, cells_per_section=cells_per_section)
    house = build_digit(params, calibration, housing=True, orientation=orientation, cells_per_section=cells_per_section)
    out["bare_wn"], out["bare_zeta"] = (float(v[0]) for v in bare.linear_modes())
    out["housing_wn"], out["housing_zeta"] = (float(v[0]) for v in house.linear_modes())
    if targets.deflection_commands is not None:
        cmds = np.asarray(targets.deflection_commands, dtype=float)
        sol = house.solve_static(cable_shortening_m=cable_shortening_m(cmds, params))
        out["deflection_mm"] = house.positions(sol.psi_rad, params.geometry.gauge_positions_m)[..., 1].T * 1e3
    if targets.sweep_commands is not None:
        cmds = np.asarray(targets.sweep_commands, dtype=float)
        sol = house.solve_static(cable_shortening_m=cable_shortening_m(cmds, params))
        gauges = len(params.geometry.gauge_positions_m)
        unit = calibration.replace(channel_gain=(1.0,) * gauges, channel_offset_v=(0.0,) * gauges)
        out["sweep_unit_v"] = SensorChain(params, unit, np.random.default_rng(0)).clean_v(
            sol.curvature_1_m, sol.axial_force_n
        )
    return out


def calibrate(
    targets: CalibrationTargets,
    params=None,
    *,
    initial: Calibration | None = None,
    cells_per_section: int | None = None,
    verbose: bool = False,
    friction_score=None,
    orientation: str = "vertical",
) -> CalibrationResult:
    """Fit the twin's free parameters to measured targets (``scipy.optimize.least_squares``).

    Mechanics first (support mass, housing stiffness and base factor, strip and housing damping, cable stiffness)
    against the release tests' wn and zeta (relative residuals in units of 1 %) and the deflections (in units of
    the reading resolution); a parameter no given target identifies keeps its initial value (:data:`MECHANICS`).
    Then, with the mechanics fixed, each channel's gain and offset by linear least squares against its gauge-volt
    line over the sweep; noise levels are copied from the targets when given; last the cable-guide friction, from
    a measured actuated repeatability (closed form) or, failing that, from the actuated test corr2 through
    ``friction_score`` (a 1-D root find, :func:`~flexdigit.calibrate.friction.fit_level`). With neither,
    ``initial``'s value is kept.

    Parameters
    ----------
    targets : CalibrationTargets
        E.g. :meth:`CalibrationTargets.from_thesis` or :meth:`CalibrationTargets.from_records`.
    params : RigParams, optional
    initial : Calibration, optional
        Starting point and the values of everything not fitted (default: the nominal :class:`Calibration` on the
        thesis rig, :func:`~flexdigit.twin.digit_calibration.calibration_for` on another digit).
    cells_per_section : int
        Resolution of the digit model the calibration is for.
    verbose : bool
        Log the residual table at INFO (else at DEBUG) on the ``flexdigit.calibrate.twin_fit`` logger; the library
        prints nothing (``result.table()`` gives the same table).
    orientation : {"vertical", "hanging", "horizontal"}
        How the digit was mounted for the release tests, sweep and deflections: tip up as the thesis's (3.1.2,
        3.4.3); a digit that buckles so was recorded hanging.
    friction_score : callable, optional
        ``friction_score(calibration) -> corr2``: the thesis pipeline's actuated test corr2 on a twin with that
        calibration (e.g. :func:`flexdigit.tactile.thesis_experiments.actuated_corr2_score`, its mean over 8 seeded
        repetitions of the experiment: one repetition scatters by about 0.02); needed only for
        ``targets.actuated_test_corr2``.

    Returns
    -------
    CalibrationResult
    """
    params = params or RigParams()
    if initial is None:  # the nominal calibration is the thesis rig's; another digit starts from it scaled to it
        initial = Calibration() if params.is_thesis_rig() else calibration_for(params.digit_only())
    cal, fitted, (cost, success, message), notes = _fit_mechanics(
        params, initial, targets, cells_per_section, orientation
    )
    r = model_response(params, cal, targets, cells_per_section=cells_per_section, orientation=orientation)
    cal, sweep_rows, copied, gain_notes = _fit_channels(cal, targets, r, params)
    notes += gain_notes
    cal, friction_rows = _fit_friction(params, cal, targets, cells_per_section, friction_score)
    if targets.sweep_commands is not None:
        fitted += ["channel_gain", "channel_offset_v"]
    fitted += copied
    if friction_rows:
        fitted.append("cable_friction_ratio")
    rows = _mechanics_rows(targets, r) + sweep_rows + friction_rows
    result = CalibrationResult(cal, rows, cost, success, message, fitted, targets, notes)
    _log.log(logging.INFO if verbose else logging.DEBUG, "calibration residuals:\n%s", result.table())
    return result


def _deflection_weight(t: CalibrationTargets) -> np.ndarray | None:
    """The weight of each measured deflection (gauge x command), None without deflections."""
    return np.asarray(t.deflection_weight, dtype=float) if t.deflection_mm is not None else None


#: The order in which the mechanics are tried for the fit when the records cannot tell some apart: the first of
#: two parameters one record moves alike is fitted, the other kept (a housed release test alone has one wn for the
#: supports' mass and the housing's stiffness: the housing, the part no scale weighs, is fitted; one zeta for the
#: strip's and the housing's damping: the housing's, which dominates it).
PRIORITY = (
    "housing_ei_n_m2",
    "housing_beta_s",
    "support_mass_kg",
    "strip_beta_s",
    "cable_stiffness_n_m",
    "housing_base_factor",
)
#: A parameter is fitted only if changing it by a factor e moves the scaled residuals (units: 1 % of a wn or zeta,
#: a deflection's resolution) by at least this much in a direction the parameters already fitted cannot follow...
IDENTIFIED_MIN = 1.0
#: ... and that direction is at least this share of its whole effect (else the two are nearly one parameter: their
#: fitted values would trade against each other by 1 / share times the records' noise).
IDENTIFIED_SHARE = 0.05
#: Scaled residuals (units as above) under which a fit that ran out of evaluations has still met every target.
MET = 0.01
#: What record gives each target (what an ill-posed fit is missing).
_RECORD = {
    "bare_wn_rad_s": "a bare release test (--release-bare)",
    "housing_wn_rad_s": "a housed release test (--release-housed)",
    "bare_zeta": "a bare release test (--release-bare)",
    "housing_zeta": "a housed release test (--release-housed)",
    "deflection_mm": "a deflection table (--deflections)",
}


def _mechanics_start(cal0: Calibration, t: CalibrationTargets) -> tuple[np.ndarray, np.ndarray, np.ndarray, list]:
    """Start point and bounds (log scale) of the mechanics, and which of them the given targets bear on.

    The supports' masses and the housing's stiffnesses are scales on ``cal0``'s values (their ratios kept: one
    wn cannot tell one support's mass from another's), the base factor a scale on ``cal0``'s base-to-section
    ratio; the dampings and the cable stiffness are absolute. A parameter no given target bears on is pinned
    (:data:`MECHANICS`).
    """
    masses = np.maximum(np.asarray(cal0.support_mass_kg, dtype=float), 1e-12)
    eis = np.maximum(np.asarray(cal0.housing_ei_n_m2, dtype=float), 1e-8)
    base0 = eis[0] / eis[-1]
    x0 = np.array(
        [
            0.0,
            0.0,
            0.0,
            np.log(max(cal0.strip_beta_s, 1e-8)),
            np.log(max(cal0.housing_beta_s, 1e-8)),
            np.log(cal0.cable_stiffness_n_m),
        ]
    )
    lower = np.array(
        [
            np.log(1e-4 / masses.min()),
            np.log(1e-5 / eis[1:].min()) if eis.size > 1 else np.log(1e-5 / eis[0]),
            np.log(0.2 / base0),
            np.log(1e-7),
            np.log(1e-6),
            np.log(2e3),
        ]
    )
    upper = np.array(
        [
            np.log(0.5 / masses.max()),
            np.log(1.0 / eis[1:].max()) if eis.size > 1 else np.log(1.0 / eis[0]),
            np.log(200.0 / base0),
            0.0,
            0.0,
            np.log(2e6),
        ]
    )
    lower, upper = np.minimum(lower, x0), np.maximum(upper, x0)  # a start outside the plausible box stays possible
    given = {name for name, value in vars(t).items() if value is not None}
    weight = _deflection_weight(t)
    if weight is None or not np.any(weight > 0):
        given.discard("deflection_mm")
    free = [any(target in given for target in MECHANICS[name]) for name in MECHANICS]
    return x0, lower, upper, free


def _unpacker(cal0: Calibration, sections: int):
    """``x`` (log scales and values, :func:`_mechanics_start`) -> the calibration it stands for."""
    masses = np.asarray(cal0.support_mass_kg, dtype=float)
    eis = np.maximum(np.asarray(cal0.housing_ei_n_m2, dtype=float), 1e-8)

    def unpack(x):
        m, ei, base, bs, bh, kc = np.exp(x)
        housing = eis * ei
        housing[0] *= base  # the base section's clamp factor, on its own
        return cal0.replace(
            support_mass_kg=tuple(float(v) for v in masses * m),
            housing_ei_n_m2=tuple(float(v) for v in housing[:sections]),
            strip_beta_s=bs,
            housing_beta_s=bh,
            cable_stiffness_n_m=kc,
        )

    return unpack


def _identified(resid, x0: np.ndarray, candidates: list[int]) -> tuple[list[int], dict[int, int | None]]:
    """Which of the candidate mechanics the targets tell apart (:data:`PRIORITY`, :data:`IDENTIFIED_MIN`,
    :data:`IDENTIFIED_SHARE`), from the scaled residuals' finite-difference Jacobian at the start: the chosen
    indices, and for each one left out the chosen one it cannot be told from (None: it moves nothing)."""
    f0 = resid(x0)
    if not np.all(np.isfinite(f0)):
        raise ParameterError(
            "The starting calibration's twin has no finite modes or deflections as mounted (does the digit buckle "
            "in that orientation? give --orientation hanging, or --initial FILE)"
        )
    step = 1e-3
    columns = {}
    for k in candidates:
        x = x0.copy()
        x[k] += step
        columns[k] = (resid(x) - f0) / step
    names = list(MECHANICS)
    order = sorted(candidates, key=lambda k: PRIORITY.index(names[k]))
    chosen: list[int] = []
    left: dict[int, int | None] = {}
    for k in order:
        col = columns[k]
        if chosen:
            basis = np.column_stack([columns[j] for j in chosen])
            coef, *_ = np.linalg.lstsq(basis, col, rcond=None)
            ortho = col - basis @ coef
        else:
            coef, ortho = np.zeros(0), col
        norm, rest = float(np.linalg.norm(col)), float(np.linalg.norm(ortho))
        if rest >= IDENTIFIED_MIN and rest >= IDENTIFIED_SHARE * norm:
            chosen.append(k)
        else:
            left[k] = chosen[int(np.argmax(np.abs(coef)))] if norm >= IDENTIFIED_MIN and chosen else None
    return sorted(chosen), left


def _fit_mechanics(
    params, cal0: Calibration, t: CalibrationTargets, cells_per_section: int, orientation: str = "vertical"
) -> tuple[Calibration, list[str], tuple[float, bool, str], list[str]]:
    """The mechanics fitted to the wn, zeta and deflection targets: calibration, names fitted, solver outcome, and
    the notes on what the records could not tell apart (kept at ``cal0``'s values)."""
    from scipy.optimize import least_squares

    sections = params.geometry.section_count
    unpack = _unpacker(cal0, sections)
    weight = _deflection_weight(t)

    def resid(x):
        r = model_response(params, unpack(x), t, cells_per_section=cells_per_section, orientation=orientation)
        out = []
        for key in ("bare_wn", "bare_zeta", "housing_wn", "housing_zeta"):
            target = getattr(t, key + ("_rad_s" if key.endswith("wn") else ""))
            if target is not None:
                out.append((r[key] / target - 1.0) / 0.01)
        if weight is not None:
            diff = (r["deflection_mm"] - np.asarray(t.deflection_mm)) / t.deflection_resolution_mm
            out.extend((diff * weight)[weight > 0].tolist())
        return np.array(out)

    x0, lower, upper, free = _mechanics_start(cal0, t)
    names = list(MECHANICS)
    if sections == 1:  # one section: its housing is the base's, the base factor is no separate parameter
        free[names.index("housing_base_factor")] = False
    candidates = [k for k, is_free in enumerate(free) if is_free]
    if not candidates:
        return cal0, [], (0.0, True, "no mechanical target: mechanics kept"), []
    chosen, left = _identified(resid, x0, candidates)
    notes = [_kept_note(names[k], None if j is None else names[j], t) for k, j in left.items()]
    if not chosen:
        return cal0, [], (0.0, True, "the records move no mechanical parameter: mechanics kept"), notes

    def sub(z):
        x = x0.copy()
        x[chosen] = z
        return x

    fit = least_squares(
        lambda z: resid(sub(z)),
        np.clip(x0[chosen], lower[chosen], upper[chosen]),
        bounds=(lower[chosen], upper[chosen]),
        x_scale=1.0,
        xtol=1e-10,
        ftol=1e-10,
        gtol=1e-10,
        max_nfev=100 * (len(chosen) + 1),
    )
    success, message = bool(fit.success), str(fit.message)
    if not success and fit.fun.size and float(np.max(np.abs(fit.fun))) < MET:
        success, message = True, f"every target met within {MET:g} of its scale ({fit.nfev} evaluations)"
    fitted = [names[k] for k in chosen if names[k] != "housing_base_factor"]
    return unpack(sub(fit.x)), fitted, (float(fit.cost), success, message), notes


def _kept_note(name: str, like: str | None, t: CalibrationTargets) -> str:
    """One line: a mechanical parameter kept at its starting value, why, and the record that would fit it."""
    given = {key for key, value in vars(t).items() if value is not None}
    missing = sorted({_RECORD[target] for target in MECHANICS[name] if target not in given and target in _RECORD})
    why = f"these records cannot tell it from {like}" if like is not None else "these records hardly move it"
    give = f"; {' or '.join(missing)} would fit it" if missing else ""
    return f"kept {name} at its starting value: {why}{give}"


#: A channel's gain is refused (kept at its starting value, said in a note) when the sweep tells it to no better
#: than this relative standard error (the issue's 5 %): a gauge that hardly reads in the sweep, or whose drift
#: swamps its line. A geared servo's sweep over the thesis's 8..43 turns the tip a gear ratio less far: its lines
#: are that much shallower against the same drift (six-gauges-geared, 4:1: 4.3-6.6 %; four_sections_geared_eight,
#: 3:1: gauges 1-2 7 %; the thesis rig 0.6-0.8 %). With the twin's true mechanics its gains scatter as stated
#: (RMS 5.8 % over 4 seeds x 6 gauges against 5.5 % stated; no drift, within 0.12 %): no bias, the drift's random
#: tilt, which 25 % let through as fitted values 10-17 % off (2 sd).
GAIN_UNDETERMINED = 0.05
#: Relative standard errors of the gains above this are reported in a note (the sweep's noise and drift on them).
GAIN_REPORTED = 0.02
#: How long a sweep holds each command, s (the thesis's settled readings, ``simulate sweep``'s default 3 s settle
#: and 20 readings at 100 Hz): the time over which the gauges' random-walk drift bends its line.
SWEEP_S_PER_COMMAND = 3.2


def _wider_sweep(params, commands: np.ndarray, se: float) -> str:
    """The note's advice: a sweep as far in tip rotation as the thesis's 8..43 where this digit's commands turn its
    tip less far (a geared servo, a fine step; :func:`~flexdigit.palpation.palpation.command_scale`), and what it
    would tell the gain to (the drift's tilt: the relative error falls as the root of the commands swept, each held
    as long); where the sweep already spans that far, that more commands or a steadier gauge would."""
    if params is None:
        return ""
    lo, span = int(commands.min()), float(np.ptp(commands))
    wanted = min(int(round(span * command_scale(params))), int(params.actuator.command_max) - lo)
    if wanted <= span * 1.2:
        return "; a sweep over more commands, or a gauge that drifts less, would tell it"
    return (
        f"; a sweep over {lo}..{lo + wanted} (as far in tip rotation as the thesis rig's 8..43) would tell it to "
        f"about +-{100 * se * math.sqrt(span / wanted):.1f} %"
    )


def _fit_channels(
    cal: Calibration, t: CalibrationTargets, r: dict, params=None
) -> tuple[Calibration, list[dict[str, Any]], list[str], list[str]]:
    """Each channel's gain and offset fitted to its sweep line (linear least squares), the noise levels copied.

    A gain's relative standard error is its line's slope's (``t.sweep_slope_se_v_per_command``): one the sweep
    cannot tell to :data:`GAIN_UNDETERMINED` is kept at its starting value. Returns the calibration, the sweep's
    residual rows, the names of the noise levels copied and the notes (gains uncertain or kept).
    """
    gains, offsets = list(cal.channel_gain), list(cal.channel_offset_v)
    rows: list[dict[str, Any]] = []
    notes: list[str] = []
    if t.sweep_commands is not None:
        cmds = np.asarray(t.sweep_commands, dtype=float)
        uncertain = []
        for ch in range(r["sweep_unit_v"].shape[1]):
            line = t.sweep_slopes_v_per_command[ch] * cmds + t.sweep_offsets_v[ch]
            design = np.column_stack([r["sweep_unit_v"][:, ch], np.ones_like(cmds)])
            (g, o), *_ = np.linalg.lstsq(design, line, rcond=None)
            se = _gain_relative_se(t, ch, _drift(cal, t, ch))
            if se > GAIN_UNDETERMINED:
                notes.append(
                    f"kept channel_gain of gauge {ch + 1} at its starting value {gains[ch]:.4g}: the sweep "
                    f"determines it only to +-{100 * se:.0f} % (its line's slope "
                    f"{t.sweep_slopes_v_per_command[ch]:.3g} V/command against the scatter and drift of its "
                    f"readings; at most {100 * GAIN_UNDETERMINED:.0f} % is fitted){_wider_sweep(params, cmds, se)}"
                )
                g = gains[ch]
                o = float(np.mean(line - g * r["sweep_unit_v"][:, ch]))
            elif se > GAIN_REPORTED:
                uncertain.append(f"gauge {ch + 1} +-{100 * se:.0f} %")
            gains[ch], offsets[ch] = float(g), float(o)
            model = g * r["sweep_unit_v"][:, ch] + o
            slope, intercept = np.polyfit(cmds, model, 1)
            rows.append(
                dict(
                    target=f"sweep slope gauge {ch + 1}{_as_thesis(ch)}",
                    measured=t.sweep_slopes_v_per_command[ch],
                    twin=float(slope),
                    unit="V/command",
                )
            )
            rows.append(
                dict(
                    target=f"sweep offset gauge {ch + 1}{_as_thesis(ch)}",
                    measured=t.sweep_offsets_v[ch],
                    twin=float(intercept),
                    unit="V",
                )
            )
        if uncertain:
            notes.append("channel_gain standard errors from the sweep's scatter and drift: " + ", ".join(uncertain))
    changes: dict[str, Any] = {"channel_gain": tuple(gains), "channel_offset_v": tuple(offsets)}
    if t.noise_white_v is not None:
        changes["noise_white_v"] = tuple(float(v) for v in t.noise_white_v)
    if t.noise_drift_v_per_sqrt_s is not None:
        changes["noise_drift_v_per_sqrt_s"] = tuple(float(v) for v in t.noise_drift_v_per_sqrt_s)
    copied = [name for name in ("noise_white_v", "noise_drift_v_per_sqrt_s") if name in changes]
    return cal.replace(**changes), rows, copied, notes


def _drift(cal: Calibration, t: CalibrationTargets, channel: int) -> float:
    """A channel's random-walk drift rate, V/sqrt(s): measured at rest when given, else the calibration's."""
    rates = t.noise_drift_v_per_sqrt_s if t.noise_drift_v_per_sqrt_s is not None else cal.noise_drift_v_per_sqrt_s
    return float(rates[channel]) if channel < len(rates) else 0.0


def _gain_relative_se(t: CalibrationTargets, channel: int, drift_v_per_sqrt_s: float = 0.0) -> float:
    """A channel's gain's relative standard error: its sweep slope's, from the readings' scatter about the line
    and the drift over the sweep (a random walk of rate ``s`` over ``T`` tilts a least-squares line by
    ``s sqrt(6 / (5 T))`` V/s, :data:`SWEEP_S_PER_COMMAND` s a command), added in quadrature."""
    slope = float(t.sweep_slopes_v_per_command[channel])
    scatter = 0.0
    if t.sweep_slope_se_v_per_command is not None:
        scatter = float(t.sweep_slope_se_v_per_command[channel])
        scatter = scatter if np.isfinite(scatter) else 0.0
    commands = np.asarray(t.sweep_commands, dtype=float)
    span = float(commands.max() - commands.min())
    duration_s = SWEEP_S_PER_COMMAND * commands.size
    tilt = drift_v_per_sqrt_s * np.sqrt(1.2 / duration_s) * duration_s / span if span > 0 else 0.0
    se = float(np.hypot(scatter, tilt))
    return se / abs(slope) if slope != 0 else float("inf")


def _as_thesis(channel: int) -> str:
    """The thesis's gauge-volt line a channel's sweep line compares with (E 3.20-3.22), for its three gauges."""
    return f" (as E 3.2{channel})" if channel < 3 else ""


def _fit_friction(
    params, cal: Calibration, t: CalibrationTargets, cells_per_section: int, friction_score
) -> tuple[Calibration, list[dict[str, Any]]]:
    """The cable-guide friction: from the actuated repeatability (closed form), else the actuated test corr2."""
    friction_rows: list[dict[str, Any]] = []
    if t.actuated_repeatability_v is not None:
        if t.actuated_repeatability_command is None:
            raise ParameterError(
                "The 'actuated_repeatability_command' parameter of CalibrationTargets must be given with "
                "'actuated_repeatability_v'. Got None."
            )
        ratio = friction_ratio_from_repeatability(
            params, cal, t.actuated_repeatability_command, t.actuated_repeatability_v, cells_per_section
        )
        cal = cal.replace(cable_friction_ratio=ratio)
        model = actuated_rest_sd_v(params, cal, t.actuated_repeatability_command, cells_per_section)
        for ch, (meas, got) in enumerate(zip(t.actuated_repeatability_v, model, strict=True)):
            friction_rows.append(
                dict(
                    target=f"actuated repeatability gauge {ch + 1} @ {t.actuated_repeatability_command}",
                    measured=float(meas),
                    twin=float(got),
                    unit="V",
                )
            )
    elif t.actuated_test_corr2 is not None and friction_score is not None:
        base = cal
        ratio = fit_level(lambda r: friction_score(base.replace(cable_friction_ratio=r)), t.actuated_test_corr2)
        cal = cal.replace(cable_friction_ratio=ratio)
        friction_rows.append(
            dict(target="actuated test corr2 (7.5)", measured=t.actuated_test_corr2, twin=friction_score(cal), unit="")
        )
    return cal, friction_rows


def _mechanics_rows(t: CalibrationTargets, r: dict) -> list[dict[str, Any]]:
    """The residual rows of the mechanics: wn and zeta (scale 1 %), deflections (scale: the reading resolution)."""
    head = []
    for key, label, unit in (
        ("bare_wn", "wn without housing (as table 3.1)", "rad/s"),
        ("bare_zeta", "zeta without housing (as table 3.1)", ""),
        ("housing_wn", "wn with housing (as table 3.2)", "rad/s"),
        ("housing_zeta", "zeta with housing (as table 3.2)", ""),
    ):
        target = getattr(t, key + ("_rad_s" if key.endswith("wn") else ""))
        if target is not None:
            head.append(dict(target=label, measured=float(target), twin=r[key], unit=unit, scale=0.01 * float(target)))
    weight = _deflection_weight(t)
    if weight is not None:
        for g in range(weight.shape[0]):
            for c, cmd in enumerate(t.deflection_commands):
                if weight[g, c] > 0:
                    head.append(
                        dict(
                            target=f"deflection gauge {g + 1} @ {cmd} (as table 3.6)",
                            measured=float(t.deflection_mm[g][c]),
                            twin=float(r["deflection_mm"][g, c]),
                            unit="mm",
                            scale=float(t.deflection_resolution_mm),
                        )
                    )
    return head


def calibrate_to_thesis(params=None, *, verbose: bool = False) -> CalibrationResult:
    """The packaged default: :func:`calibrate` on the thesis's targets, the friction by the actuated corr2.

    The friction's only evidence is the thesis network's actuated test corr2 (7.5), scored through the tactile
    pipeline averaged over 8 seeded repetitions (:func:`flexdigit.tactile.thesis_experiments.actuated_corr2_score`):
    minutes of CPU. ``flexdigit calibrate --thesis`` runs it.
    """

    def score(calibration: Calibration) -> float:
        return actuated_corr2_score(calibration, params=params)

    return calibrate(CalibrationTargets.from_thesis(), params, verbose=verbose, friction_score=score)


#: ``[fit] source`` of a calibration fitted to the thesis (the packaged default's).
THESIS_SOURCE = (
    "calibrate(CalibrationTargets.from_thesis(), friction_score=actuated_corr2_score) with RigParams() "
    "defaults, cells_per_section=3"
)
