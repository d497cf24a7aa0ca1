"""What the twin is calibrated to: the thesis's figures, or a user's rig records reduced to the same targets.

:class:`CalibrationTargets` holds the figures :func:`flexdigit.calibrate.twin_fit.calibrate` fits: the release tests'
wn and zeta bare and housed (tables 3.1, 3.2), the actuation sweep's straight lines (E 3.20-3.22), deflections at
the gauges (table 3.6), noise levels and the actuated repeatability. :meth:`CalibrationTargets.from_thesis` reads
them as printed; :meth:`CalibrationTargets.from_records` reduces a rig's records to them, the release tests through
:func:`flexdigit.identify.identification.identify` (``method="lsq"``), the same fitter ``flexdigit identify
release`` and the report use, so one record gives one answer everywhere.

Examples
--------
>>> t = CalibrationTargets.from_thesis()
>>> t.bare_wn_rad_s, t.housing_zeta              # tables 3.1 and 3.2, as printed
(10.16271, 0.06791)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from flexdigit._repr import fields_summary
from flexdigit._validation import check_array, check_int, check_param
from flexdigit.errors import DataFileError
from flexdigit.identify.identification import identify
from flexdigit.identify.timeseries import TimeSeries
from flexdigit.reference import thesis_value
from flexdigit.rig.rotation_reference import READING_RESOLUTION_MM

__all__ = ["CalibrationTargets", "release_figures", "sweep_lines", "noise_from_record", "MODE_RTOL"]

#: How far a channel's identified wn may lie from the best-fitting channel's and still count as the same mode: the
#: gauges of one release test agree to 0.2 %; a gauge near the tip reads so little of the first mode that its fit
#: (2-3 %) can lock on another at 4x its wn (seven_sections_450mm's gauge 4), and it must not move the medians.
MODE_RTOL = 0.1


@dataclass(frozen=True)
class CalibrationTargets:
    """What the twin is fitted to. Any field may be None (then that part is not fitted).

    Attributes
    ----------
    bare_wn_rad_s, bare_zeta : float
        First-mode natural frequency and damping of the digit without housing, cable removed (table 3.1).
    housing_wn_rad_s, housing_zeta : float
        The same with the housing (table 3.2).
    sweep_commands : tuple of int
        Commands of the static actuation sweep (E 3.20-3.22: 8..43).
    sweep_slopes_v_per_command, sweep_offsets_v : tuple of float
        Per-channel straight-line fit ``V = slope * command + offset`` of the gauge voltages over the sweep.
    sweep_slope_se_v_per_command : tuple of float, optional
        Each slope's standard error, from the scatter of the per-command means about the line (the readings'
        drift and noise): what a channel's fitted gain is known to (:func:`sweep_lines`).
    deflection_commands : tuple of int
        Commands at which deflections were read (table 3.6: 8..24).
    deflection_mm : tuple of tuple of float
        Deflection at each gauge position (rows: gauges 1..3, columns: commands), mm.
    deflection_weight : tuple of tuple of float
        Weight of each deflection in the fit (0: ignore it).
    deflection_resolution_mm : float
        Reading resolution, the residual scale (0.5 mm in 3.4.1).
    noise_white_v, noise_drift_v_per_sqrt_s : tuple of float
        Measured noise levels, if any.
    actuated_repeatability_v : tuple of float, optional
        Measured standard deviation (V, per gauge) of repeated readings of the unloaded digit lying horizontal
        (cable side up) and held at ``actuated_repeatability_command``, the digit tapped before each reading so
        the cable settles afresh in its guides (readings after one tap share one friction state): fixes
        ``cable_friction_ratio`` in closed form
        (:func:`flexdigit.calibrate.friction.friction_ratio_from_repeatability`).
        Preferred over ``actuated_test_corr2`` when given.
    actuated_repeatability_command : int, optional
        The command of that record.
    actuated_test_corr2 : float, optional
        Test corr2 of the thesis pipeline on the actuated experiment (0.8998, 7.5: the only evidence the thesis
        gives of the actuated noise); fitted with a score function passed to
        :func:`~flexdigit.calibrate.twin_fit.calibrate`.
    """

    bare_wn_rad_s: float | None = None
    bare_zeta: float | None = None
    housing_wn_rad_s: float | None = None
    housing_zeta: float | None = None
    sweep_commands: tuple[int, ...] | None = None
    sweep_slopes_v_per_command: tuple[float, ...] | None = None
    sweep_offsets_v: tuple[float, ...] | None = None
    sweep_slope_se_v_per_command: tuple[float, ...] | None = None
    deflection_commands: tuple[int, ...] | None = None
    deflection_mm: tuple[tuple[float, ...], ...] | None = None
    deflection_weight: tuple[tuple[float, ...], ...] | None = None
    deflection_resolution_mm: float = 0.5
    noise_white_v: tuple[float, ...] | None = None
    noise_drift_v_per_sqrt_s: tuple[float, ...] | None = None
    actuated_repeatability_v: tuple[float, ...] | None = None
    actuated_repeatability_command: int | None = None
    actuated_test_corr2: float | None = None

    def to_dict(self) -> dict[str, Any]:
        """The targets given (None fields left out), lists for tuples: the ``[fit.targets]`` of a calibration file."""
        out = {}
        for name in self.__dataclass_fields__:
            value = getattr(self, name)
            if value is not None:
                out[name] = _plain(value)
        return out

    @classmethod
    def from_thesis(cls) -> CalibrationTargets:
        """Tables 3.1, 3.2, 3.6, E 3.20-3.22 and the actuated test corr2 of 7.5 as printed (``reference/thesis.toml``).

        Table 3.6 enters where the thesis's own model (table 3.4, E 3.15) agrees with it within the 0.5 mm reading
        resolution (3.4.1 blames the other readings on that resolution and, for gauge 1, on the single-section
        model); elsewhere the readings scatter by up to 3 mm between consecutive commands, which no smooth
        model follows.
        """
        bare = "digit.release_tests_without_housing"
        house = "digit.release_tests_with_housing"
        conv = "conversion"
        commands = tuple(int(c) for c in thesis_value(f"{conv}.table_3_4_commands"))
        measured = np.array([thesis_value(f"{conv}.table_3_6_y_sg{k}_mm") for k in (1, 2, 3)], dtype=float)
        theory = np.array([thesis_value(f"{conv}.table_3_4_y_sg{k}_mm") for k in (1, 2, 3)], dtype=float)
        resolution = 0.5  # mm, 3.4.1
        weight = (np.abs(measured - theory) <= resolution).astype(float)
        weight[:, np.array(commands) == int(thesis_value("actuator.equilibrium_command"))] = 0.0  # 0 = 0 trivially
        fits = thesis_value(f"{conv}.v_sg_fit")
        lo, hi = thesis_value("actuator.operating_commands")
        return cls(
            bare_wn_rad_s=float(thesis_value(f"{bare}.wn_avg_rad_s")),
            bare_zeta=float(thesis_value(f"{bare}.zeta_avg")),
            housing_wn_rad_s=float(thesis_value(f"{house}.wn_avg_rad_s")),
            housing_zeta=float(thesis_value(f"{house}.zeta_avg")),
            sweep_commands=tuple(range(int(lo), int(hi) + 1)),
            sweep_slopes_v_per_command=tuple(float(f["slope"]) for f in fits),
            sweep_offsets_v=tuple(float(f["offset"]) for f in fits),
            deflection_commands=commands,
            deflection_mm=tuple(tuple(row) for row in measured.tolist()),
            deflection_weight=tuple(tuple(row) for row in weight.tolist()),
            actuated_test_corr2=float(thesis_value("tactile.actuated.test_corr2")),
        )

    @classmethod
    def from_records(
        cls,
        *,
        release_bare=None,
        release_housing=None,
        sweep=None,
        deflections=None,
        rest=None,
        actuated_rest=None,
        deflection_resolution_mm: float = 0.5,
    ) -> CalibrationTargets:
        """Targets from a real rig's records (what a user with hardware passes to ``calibrate``).

        Parameters
        ----------
        release_bare, release_housing : TimeSeries or sequence of TimeSeries, optional
            Release tests (3.1.2): every gauge channel of every test, each identified by
            :func:`release_figures` (``identify``'s lsq fit); wn and zeta are the medians.
        sweep : (commands, volts (N, 3)), optional
            Settled gauge voltages at each command (several readings a command allowed): a straight line per
            channel.
        deflections : (commands, mm (3, N)), optional
            Deflections read at the gauge positions; NaN for a reading not taken (weight 0, the others 1).
        rest : (time_s, volts (N, 3)), optional
            The resting rig: white noise and drift per channel (:func:`noise_from_record`).
        actuated_rest : (command, volts (N, 3)), optional
            Repeated readings of the unloaded digit lying horizontal, held at one command and tapped before each
            reading: their standard deviation per channel is the actuated repeatability (``cable_friction_ratio``).
        deflection_resolution_mm : float
            The deflections' reading resolution (their residual scale in the fit).
        """
        resolution = check_param(deflection_resolution_mm, READING_RESOLUTION_MM, "deflection_resolution_mm", "Targets")
        kw: dict[str, Any] = {"deflection_resolution_mm": resolution}
        for name, rec in (("bare", release_bare), ("housing", release_housing)):
            if rec is not None:
                figures = release_figures(rec)
                kw[f"{name}_wn_rad_s"], kw[f"{name}_zeta"] = figures["wn_rad_s"], figures["zeta"]
        if sweep is not None:
            kw.update(sweep_lines(*sweep))
        if deflections is not None:
            cmds = check_array(deflections[0], "deflection commands", "CalibrationTargets", ndim=1, min_length=1)
            mm = check_array(deflections[1], "deflections", "CalibrationTargets", shape=(None, cmds.size), finite=False)
            if np.any(np.isinf(mm)):
                raise DataFileError("The 'deflections' of CalibrationTargets must be finite or NaN (not read).")
            weight = np.isfinite(mm).astype(float)
            kw["deflection_commands"] = tuple(int(c) for c in cmds)
            kw["deflection_mm"] = tuple(tuple(r) for r in np.nan_to_num(mm).tolist())
            kw["deflection_weight"] = tuple(tuple(r) for r in weight.tolist())
        if rest is not None:
            white, drift = noise_from_record(*rest)
            kw["noise_white_v"] = tuple(float(v) for v in white)
            kw["noise_drift_v_per_sqrt_s"] = tuple(float(v) for v in drift)
        if actuated_rest is not None:
            command = check_int(actuated_rest[0], "actuated_rest command", "CalibrationTargets", low=0, high=254)
            volts = check_array(actuated_rest[1], "actuated_rest volts", "CalibrationTargets", ndim=2, min_length=3)
            kw["actuated_repeatability_command"] = command
            kw["actuated_repeatability_v"] = tuple(float(v) for v in np.std(volts, axis=0, ddof=1))
        return cls(**kw)

    __repr__ = fields_summary


def _plain(value):
    if isinstance(value, tuple | list):
        return [_plain(v) for v in value]
    return value


def release_figures(records) -> dict[str, Any]:
    """wn and zeta of release tests: each record identified by ``identify(..., "release", method="lsq")``.

    Parameters
    ----------
    records : TimeSeries, (time_s, volts) or a sequence of them
        One channel of one release test each (every gauge of every test, typically).

    Returns
    -------
    dict
        ``wn_rad_s`` and ``zeta``: the medians over the records identified at the best-fitting record's mode
        (within :data:`MODE_RTOL` of its wn; one gauge alone scatters: gauge 3, nearest the tip, sees the smallest
        strain); ``fits``: their :class:`~flexdigit.identify.identification.Identification`; ``skipped``: the
        records ``identify`` refused or identified at another mode (``record`` and ``reason``, a one-line
        message), left out of the medians.

    Raises
    ------
    DataFileError
        When no record can be identified, with ``identify``'s reason for the first.
    """
    if isinstance(records, TimeSeries) or (
        isinstance(records, tuple) and len(records) == 2 and not isinstance(records[0], TimeSeries)
    ):
        records = [records]
    series = []
    for k, rec in enumerate(records):
        if isinstance(rec, TimeSeries):
            series.append(rec)
        else:
            series.append(TimeSeries.from_arrays(rec[0], rec[1], channel=f"record {k + 1}", source="release"))
    if not series:
        raise DataFileError("release_figures needs at least one release record")
    fits, skipped = [], []
    for s in series:
        try:
            fits.append((s.name, identify(s, "release", method="lsq")))
        except DataFileError as exc:  # one gauge's channel may be too weak to identify; the others still count
            skipped.append({"record": s.name, "reason": str(exc)})
    if not fits:
        raise DataFileError(
            f"no release record could be identified ({len(skipped)} tried); the first: {skipped[0]['reason']}"
        )
    best = max((f for _, f in fits), key=lambda f: f.fit_percent)
    for name, f in fits:
        if abs(f.wn_rad_s / best.wn_rad_s - 1) > MODE_RTOL:
            skipped.append({"record": name, "reason": _another_mode(name, f, best)})
    fits = [f for _, f in fits if abs(f.wn_rad_s / best.wn_rad_s - 1) <= MODE_RTOL]
    return {
        "wn_rad_s": float(np.median([f.wn_rad_s for f in fits])),
        "zeta": float(np.median([f.zeta for f in fits])),
        "fits": fits,
        "skipped": skipped,
    }


def _another_mode(name: str, fit, best) -> str:
    return (
        f"{name}: identified at wn {fit.wn_rad_s:.4g} rad/s (fit {fit.fit_percent:.1f} %), another mode than the "
        f"best-fitting channel's {best.wn_rad_s:.4g} rad/s (fit {best.fit_percent:.1f} %): left out of the medians"
    )


def sweep_lines(commands, volts) -> dict[str, tuple]:
    """Per-channel straight line ``V = slope * command + offset`` through a sweep (E 3.20-3.22).

    Returns the ``sweep_*`` fields of :class:`CalibrationTargets`: the distinct commands, slopes, offsets and the
    slopes' standard errors.
    """
    cmds = check_array(commands, "sweep commands", "CalibrationTargets", ndim=1, min_length=2)
    v = check_array(volts, "sweep volts", "CalibrationTargets", shape=(cmds.size, None))
    distinct = np.unique(cmds)
    if distinct.size < 2:
        raise DataFileError(
            f"The 'sweep commands' of CalibrationTargets must hold at least two different commands. Got {distinct}."
        )
    coef = np.polyfit(cmds, v, 1)
    # the slope's standard error from the per-command means' scatter about the line: readings at one command share
    # its drift, so the means, not the readings, are the independent samples (an underestimate when the drift
    # wanders over several commands; 0 dof with two commands: no estimate, NaN)
    means = np.array([v[cmds == c].mean(axis=0) for c in distinct])
    scatter = means - (np.outer(distinct, coef[0]) + coef[1])
    dof = distinct.size - 2
    sd = np.sqrt(np.sum(scatter**2, axis=0) / dof) if dof > 0 else np.full(v.shape[1], np.nan)
    se = sd / np.sqrt(np.sum((distinct - distinct.mean()) ** 2))
    return {
        "sweep_commands": tuple(int(c) for c in distinct),
        "sweep_slopes_v_per_command": tuple(float(x) for x in coef[0]),
        "sweep_offsets_v": tuple(float(x) for x in coef[1]),
        "sweep_slope_se_v_per_command": tuple(float(x) for x in se),
    }


def noise_from_record(time_s, volts) -> tuple[np.ndarray, np.ndarray]:
    """White-noise sigma (V) and random-walk drift rate (V/sqrt(s)) per channel of a resting record.

    White noise from the first differences (``std(diff)/sqrt(2)``); drift from the variance of 1 s block means
    growing linearly with lag (a random walk), after removing the white part.
    """
    t = check_array(time_s, "time_s", "noise_from_record", ndim=1, min_length=16)
    v = check_array(volts, "volts", "noise_from_record", shape=(t.size, None))
    white = np.std(np.diff(v, axis=0), axis=0) / np.sqrt(2.0)
    dt = float(np.mean(np.diff(t)))
    block = max(1, int(round(1.0 / dt)))
    nb = v.shape[0] // block
    if nb < 3:
        return white, np.zeros(v.shape[1])
    means = v[: nb * block].reshape(nb, block, -1).mean(axis=1)
    steps = np.diff(means, axis=0)
    var = np.maximum(np.var(steps, axis=0) - 2 * white**2 / block, 0.0)
    drift = np.sqrt(var / (block * dt))
    return white, drift
