"""``flexdigit palpate``: press the digit into tissue and say how stiff it is (issue 13)."""

from __future__ import annotations

import argparse

from flexdigit._command import CommandResult, add_command, digit_name
from flexdigit._plot import add_plot_flag
from flexdigit._validation import SEED, Flag

#: Largest chi^2 per degree of freedom a palpation fit may leave and still be reported.
MAX_CHI2_PER_DOF = 25.0
#: A sweep's modulus uncertain by more than this fraction of itself is no measurement (a digit that barely presses
#: the tissue fits a near-zero modulus at a made-up gap: 1.7 +- 2.4 N/m^2 for a true 1000); a sweep that presses
#: it measures within a few per cent (soft-block on the thesis rig: 994 +- 18).
MAX_MODULUS_REL_SD = 0.5


def register(subparsers: argparse._SubParsersAction) -> None:
    p = add_command(
        subparsers,
        "palpate",
        _palpate,
        help="palpate tissue beside the digit: stiffness from a command sweep, a scan for an inclusion, force control",
    )
    from flexdigit.cli._formats import epilog

    p.epilog = epilog("tissue", "palpation")
    p.add_argument("--tissue", required=True, help="a tissue TOML file or a built-in (soft-block, nodule-phantom, ...)")
    p.add_argument("--protocol", default=None, help="a protocol TOML file or a built-in: sweep (default), scan, hold")
    p.add_argument("--backend", default="sim", help="rig URL (default: sim, the digital twin)")
    p.add_argument(
        "--seed",
        type=Flag(SEED),
        default=None,
        help="seed of the twin's noise (sim backends; default 0, or the URL's seed=)",
    )
    p.add_argument("--params", metavar="FILE", help="the digit's parameters TOML (default: the thesis rig)")
    p.add_argument(
        "--calibration", metavar="FILE", help="twin calibration TOML (default: the thesis's, scaled to the digit)"
    )
    p.add_argument("--log", default=None, help="JSON-lines log of every loop sample (scan: one file per offset)")
    p.add_argument("--out", default=None, help="write the result as JSON to this file")
    p.add_argument("--force", action="store_true", help="overwrite --out / --log / --plot if they exist")
    add_plot_flag(p, "force against indentation (sweep), the stiffness map (scan) or the force over time (hold)")


def _sim_options(backend: str, kind: str, seed: int | None, params, calibration, orientation: str) -> dict:
    from flexdigit.palpation.palpation import twin_step_s
    from flexdigit.rig.base import parse_rig_url, seed_option

    url = parse_rig_url(backend)
    options = seed_option(backend, seed)  # --seed only when given: the URL's seed= is not overridden by a default
    if url.scheme.startswith("sim") and "dt_s" not in url.options:
        orientation = url.options.get("orientation", orientation)
        options["dt_s"] = twin_step_s(kind, params, calibration, orientation)
    return options


def _palpate(args: argparse.Namespace) -> CommandResult:
    from flexdigit._io import check_output
    from flexdigit.palpation.palpation_files import load_palpation_protocol, load_tissue

    tissue, info = load_tissue(args.tissue)
    plan = load_palpation_protocol(args.protocol)
    kind = "force" if plan.force else ("scan" if plan.scan else "sweep")
    from flexdigit._plot import check_plot

    out = check_output(args.out, force=args.force) if args.out else None
    check_plot(args.plot, "palpate", force=args.force)
    logs = _log_paths(args.log, plan, args.force)
    sim, rig, calibration = _palpation_rig(args, info, kind)
    settings = rig.settings()  # what was used (the URL's seed, or --seed, or the default): reported
    log_mode = "replace" if args.force else "new"  # the logs were checked above, before the rig moved
    try:
        tissue, laid = _digit_tissue(tissue, info, rig.params)
        if laid and plan.scan and plan.builtin:
            plan = _scan_laid_out(plan, rig.params)
            logs = _log_paths(args.log, plan, args.force)  # one per offset, named by the offsets laid out
        plan = _laid_out(plan, rig, calibration, tissue.side, info.source)
        if kind == "force":
            data, text, fig = _force(rig, tissue, plan, logs[0], log_mode)
        elif kind == "scan":
            data, text, fig = _scan(rig, tissue, plan, logs, log_mode, calibration)
        else:
            data, text, fig = _sweep(
                rig, tissue, plan, logs[0], log_mode, tissue.modulus_n_m2 if sim else None, calibration
            )
    finally:
        rig.close()
    data = {"kind": kind, "tissue": _tissue_dict(tissue, info), "backend": args.backend, "rig": settings, **data}
    if laid:
        data["tissue"]["laid_out"] = laid
        text += f"\n{laid}"
    if settings.get("orientation") == "hanging":
        text += "\nmounted tip down (hanging): this digit buckles tip up (as `flexdigit run --params` mounts it)"
    if sim:
        data["truth"] = {
            "gap_mm": 1000 * tissue.gap_m,
            "modulus_n_m2": tissue.modulus_n_m2,
            "exponent": tissue.exponent,
        }
    return CommandResult(data=data, text=text + _save_outputs(args, data, fig, out))


def _digit_tissue(tissue, info, params):
    """``(tissue, note)``: a built-in tissue laid out beside the digit (palpation.digit_tissue; the note says how,
    "" on the thesis rig), or a file's tissue as it is, refused in one line naming the file if it lies past the
    digit's tip (palpation.check_tissue_reach)."""
    from flexdigit.errors import DataFileError, ParameterError
    from flexdigit.palpation.palpation import check_tissue_reach, digit_tissue, tissue_scale

    if info.builtin:
        laid = digit_tissue(tissue, params)
        if laid is tissue:
            return tissue, ""
        scale = tissue_scale(params)
        return laid, (
            f"built-in {info.name} laid out beside this {1000 * params.geometry.digit_length_m:g} mm digit: its "
            f"place and gap scaled by {scale:.3g} from the thesis rig's 270 mm (start {1000 * laid.start_m:.1f} mm, "
            f"gap {1000 * laid.gap_m:.1f} mm); modulus as written"
        )
    try:
        check_tissue_reach(tissue, params)
    except ParameterError as exc:
        raise DataFileError(f"{info.source}: key 'tissue.start_mm': {exc}") from None
    return tissue, ""


def _scan_laid_out(plan, params):
    """The built-in scan beside a built-in tissue laid out for the digit (palpation.digit_scan)."""
    from dataclasses import replace

    from flexdigit.palpation.palpation import digit_scan

    return replace(plan, scan=digit_scan(plan.scan, params))


def _laid_out(plan, rig, calibration, side: str, tissue_source: str):
    """The protocol on the rig's digit: the built-in sweep's thesis commands (and those a file leaves out) from its
    straight command towards the tissue, as far in tip rotation, each plateau settling as much longer as the digit
    rings (palpation.digit_protocol); a file's own commands checked to press towards the tissue
    (palpation.check_sweep_commands). One line naming the file if not."""
    from dataclasses import replace

    from flexdigit.errors import DataFileError, ParameterError
    from flexdigit.palpation.contact_estimation import ContactGaugeModel
    from flexdigit.palpation.palpation import check_sweep_commands, digit_protocol, towards

    params = rig.params
    try:
        sign = towards(params, side)
    except ParameterError as exc:
        raise DataFileError(f"{tissue_source}: key 'tissue.side': {exc}") from None
    if plan.force:
        if sign < 0:
            raise DataFileError(
                f"{tissue_source}: key 'tissue.side' = 'opposite': force control presses the digit towards its cable "
                "side (commands above straight); an antagonistic pair's other side is not held yet"
            )
        return plan
    try:
        model = ContactGaugeModel(params, calibration, orientation=_orientation(rig))
        sweep = digit_protocol(plan.sweep, params, side, laid_out=plan.laid_out, model=model)
        check_sweep_commands(sweep, params, side)
    except ParameterError as exc:
        raise DataFileError(f"{plan.source}: [sweep] {exc}") from None
    return replace(plan, sweep=sweep)


def _palpation_rig(args: argparse.Namespace, info, kind: str):
    """``(sim, rig, calibration)``: the rig of ``--backend`` for ``--params``, its twin placing the tissue (which
    the twin needs placed: gap and modulus), and the calibration of the twin and the gauge model."""
    from flexdigit.errors import DataFileError
    from flexdigit.params import RigParams, load_params
    from flexdigit.rig.base import open_rig
    from flexdigit.twin.digit_calibration import twin_calibration

    sim = args.backend.split(":")[0].split("?")[0].startswith("sim")
    if sim and not info.placed_on_twin:
        raise DataFileError(
            f"{info.source}: keys 'tissue.gap_mm' and 'tissue.modulus_n_m2' are needed on the twin (they place the "
            "tissue there; palpation then estimates them)"
        )
    params = load_params(args.params) if args.params else RigParams()
    calibration = twin_calibration(params, args.calibration)  # the twin's (sim) and the gauge model's
    mount = {}
    if sim and args.params and "orientation" not in _url_options(args.backend):
        from flexdigit.control.design20ms import digit_mount

        # a digit that buckles tip up hangs, as `run --params` mounts it (said in the output): tip up its twin
        # sagged off its straight command and the gauge model's statics did not converge (69 warnings, > 6 min)
        if digit_mount(params, calibration) == "hanging":
            mount["orientation"] = "hanging"
    options = (
        _sim_options(args.backend, kind, args.seed, params, calibration, mount.get("orientation", "vertical")) | mount
    )
    if sim and (args.params or args.calibration):
        options["calibration"] = calibration
    rig = open_rig(args.backend, params, **options)
    return sim, rig, calibration


def _url_options(backend: str) -> dict:
    from flexdigit.rig.base import rig_url_options

    return rig_url_options(backend)[1]


def _save_outputs(args: argparse.Namespace, data: dict, fig, out) -> str:
    """Save ``--plot`` and ``--out`` (atomic, refusing to overwrite without ``--force``); the lines saying so."""
    from flexdigit._io import atomic_write
    from flexdigit._json import to_jsonable

    text = f"\non digit {digit_name(args.params)} ({args.params})" if args.params else ""
    if args.plot:
        from flexdigit._plot import save_plot

        figure = fig()
        if args.params:  # whose digit: the --params file's stem before the first title
            ax = next((a for a in figure.axes if a.get_title()), None)
            if ax is not None:
                ax.set_title(f"digit {digit_name(args.params)}: {ax.get_title()}", fontsize=ax.title.get_fontsize())
        data["plot"] = str(save_plot(figure, args.plot, "palpate", force=args.force))
        text += f"\nplot -> {args.plot}"
    if out is not None:
        import json

        with atomic_write(out, "w", force=args.force) as fh:
            json.dump(to_jsonable(data), fh, indent=2)
        text += f"\nwritten to {out}"
    return text


def _orientation(rig) -> str:
    """How the digit is mounted: the twin's (``sim?orientation=hanging``: a long digit buckles tip up), else the
    thesis's upright mounting."""
    return rig.settings().get("orientation") or "vertical"


def _log_paths(log, plan, force):
    from pathlib import Path

    from flexdigit._io import check_output

    if log is None:
        return [None] * (len(plan.scan["offsets_m"]) if plan.scan else 1)
    if not plan.scan:
        return [check_output(log, force=force)]
    base = Path(log)
    return [
        check_output(base.with_name(f"{base.stem}.offset{1000 * d:+.0f}mm{base.suffix}"), force=force)
        for d in plan.scan["offsets_m"]
    ]


def _tissue_dict(tissue, info) -> dict:
    return {
        "name": info.name,
        "source": info.source,
        "side": tissue.side,
        "start_mm": 1000 * tissue.start_m,
        "end_mm": 1000 * tissue.end_m,
        "inclusions": [
            {"centre_mm": 1000 * i.centre_m, "width_mm": 1000 * i.width_m, "ratio": i.ratio} for i in tissue.inclusions
        ],
    }


def _refuse_poor_fit(fit, what: str, max_rel_sd: float | None = None) -> None:
    from flexdigit.errors import DataFileError

    per_dof = fit.chi2 / max(fit.dof, 1)
    if not fit.converged or per_dof > MAX_CHI2_PER_DOF:
        raise DataFileError(
            f"{what}: the gauges do not fit the tissue model (chi2/dof = {per_dof:.1f}, converged = {fit.converged}): "
            "check where the tissue lies ('start_mm', 'end_mm', 'side') and let each plateau settle longer "
            "('settle_s'); no stiffness reported"
        )
    if max_rel_sd is not None and not fit.modulus_sd_n_m2 <= max_rel_sd * fit.modulus_n_m2:
        raise DataFileError(
            f"{what}: the modulus is not determined ({fit.modulus_n_m2:.3g} +- {fit.modulus_sd_n_m2:.2g}, more than "
            f"{max_rel_sd:.0%} of itself): the digit barely presses the tissue; sweep to higher commands "
            "('commands') or place the tissue nearer; no stiffness reported"
        )


def _refuse_untouched(curve) -> None:
    """One line if the digit reached the tissue on fewer than 3 plateaus (a stiffness needs 3)."""
    import numpy as np

    from flexdigit.errors import DataFileError

    touching = int(np.count_nonzero(curve["indentation_m"] > 0))
    if touching < 3:
        raise DataFileError(
            f"palpation: the digit reached the tissue on {touching} of {len(curve['command'])} plateaus (3 "
            "needed for a stiffness): sweep to higher commands ('commands') or place the tissue nearer"
        )


def _refuse_sweep(result) -> None:
    """One line if the sweep's fit is poor, its modulus undetermined or the tissue barely reached; where the climb
    stopped short of an ADC rail (palpation._Staircase), the likelier reason, said on the same line."""
    from flexdigit.errors import DataFileError

    try:
        _refuse_poor_fit(result.fit, "palpation", MAX_MODULUS_REL_SD)
        _refuse_untouched(result.curve)
    except DataFileError as exc:
        if not result.record.capped:
            raise
        raise DataFileError(f"{exc}; the sweep {result.record.capped}") from None


def _held(sweep, result):
    """The sweep as its plateaus held it: the protocol, or, where the climb stopped short of a rail, its commands as
    sent (the Cramer-Rao bound of what was measured)."""
    if not result.record.capped:
        return sweep
    from dataclasses import replace

    return replace(sweep, commands=tuple(int(c) for c in result.record.command[1:-1]))


def _sweep(rig, tissue, plan, log, log_mode, true_modulus=None, calibration=None):
    from flexdigit.palpation.contact_estimation import ContactGaugeModel
    from flexdigit.palpation.palpation import palpate, stiffness_bound

    model = ContactGaugeModel(rig.params, calibration, orientation=_orientation(rig))
    result = palpate(rig, tissue, plan.sweep, model=model, log_path=log, log_mode=log_mode, drift=True)
    _refuse_sweep(result)
    hunt = plan.sweep.model == "hunt-crossley"
    bound = stiffness_bound(model, result.fit.tissue, _held(plan.sweep, result), fit_exponent=hunt, drift=True)
    data = _sweep_data(result, plan, bound, tissue)
    summary = data["result"]
    f = result.fit
    lines = [
        f"palpation of {tissue.side}-side tissue at {1000 * tissue.start_m:g}-{1000 * tissue.end_m:g} mm, "
        f"{len(plan.sweep.commands)} plateaus ({plan.sweep.model})",
        f"  modulus   {f.modulus_n_m2:9.1f} +- {f.modulus_sd_n_m2:.1f} "
        + (
            f"N/m^2 ({f.stiffness_n_m_per_cm:.2f} N/m per cm; Cramer-Rao sd {bound['modulus_n_m2']:.1f} N/m^2)"
            if plan.sweep.model == "linear"
            else f"N/m^{1 + f.exponent:.2f} (k of k delta^n; Cramer-Rao sd {bound['modulus_n_m2']:.1f} "
            f"N/m^{1 + f.exponent:.2f})"
        ),
        f"  gap       {1000 * f.gap_m:9.3f} +- {1000 * f.gap_sd_m:.3f} mm",
        f"  lumped    {result.lumped_stiffness_n_m:9.2f} N/m (force against deepest indentation)",
        f"  chi2/dof  {summary['chi2_per_dof']:9.2f}",
        _force_read_line(result.curve),
    ]
    if plan.sweep.model == "hunt-crossley":
        lines.insert(3, f"  exponent  {f.exponent:9.3f} +- {f.exponent_sd:.3f}")
    if result.record.capped:  # a gauge neared an ADC rail: the climb stopped there, said (palpation._Staircase)
        lines.append(f"  sweep     {result.record.capped}")

    def figure():
        from flexdigit.palpation.palpation_plot import indentation_figure

        title = f"palpation of {tissue.side}-side tissue ({plan.sweep.model})"
        return indentation_figure(result, true_modulus_n_m2=true_modulus, title=title)

    return data, "\n".join(lines), figure


def _force_read_line(curve) -> str:
    """The text's line on the curve's forces from the gauges: on how many plateaus one was read, and where not."""
    read = curve["force_read"]
    missing = [int(c) for c in curve["command"][~read]]
    line = f"  force     read from the gauges on {int(read.sum())} of {read.size} plateaus"
    if missing:
        line += f"; no force read at commands {missing} (no contact seen, or its sd infinite or over the value)"
    return line


def _sweep_data(result, plan, bound, tissue) -> dict:
    """``palpate --json`` of a sweep: the protocol, the fit, its Cramer-Rao bound and the curve, in mm."""
    summary = result.summary()
    data = {
        "protocol": {
            "commands": list(plan.sweep.commands),
            "settle_s": plan.sweep.settle_s,
            "return_settle_s": plan.sweep.return_settle_s,
            "tare_command": plan.sweep.tare_command,
            "readings": plan.sweep.readings,
            **({"capped": result.record.capped} if result.record.capped else {}),
        },
        "result": summary,
        "cramer_rao": {"gap_mm": 1000 * bound["gap_m"], "modulus_n_m2": bound["modulus_n_m2"]},
        "curve": {
            "command": result.curve["command"].tolist(),
            "force_n": result.curve["force_n"].tolist(),
            "force_sd_n": result.curve["force_sd_n"].tolist(),
            "force_read": result.curve["force_read"].tolist(),
            "indentation_mm": (1000 * result.curve["indentation_m"]).tolist(),
            "model_force_n": result.curve["model_force_n"].tolist(),
            **({"true_force_n": result.curve["true_force_n"].tolist()} if "true_force_n" in result.curve else {}),
            **({"force_refused": result.curve["force_refused"]} if "force_refused" in result.curve else {}),
        },
    }
    if "true_force_n" in result.curve:
        data["modulus_rel_error"] = summary["modulus_n_m2"] / tissue.modulus_n_m2 - 1
    return data


def _scan(rig, tissue, plan, logs, log_mode, calibration=None):
    from flexdigit.palpation.contact_estimation import ContactGaugeModel
    from flexdigit.palpation.palpation import scan

    result = scan(
        rig,
        tissue,
        plan.scan["offsets_m"],
        plan.sweep,
        model=ContactGaugeModel(rig.params, calibration, orientation=_orientation(rig)),
        inclusion_width_m=plan.scan["inclusion_width_m"],
        log_paths=logs,
        log_mode=log_mode,
    )
    for fit in result.local:
        _refuse_poor_fit(fit, "scan")
    inc = result.inclusion
    data = _scan_data(result, tissue, plan.scan["offsets_m"])
    text = (
        f"scan of {len(plan.scan['offsets_m'])} offsets: inclusion {1000 * inc['centre_m']:.1f} +- "
        f"{1000 * inc['centre_sd_m']:.1f} mm into the tissue, {inc['ratio']:.2f} +- {inc['ratio_sd']:.2f} x stiffer "
        f"(base {inc['modulus_n_m2']:.0f} N/m^2)"
    )

    def figure():
        from flexdigit.palpation.palpation_plot import scan_figure

        true_centre = data["inclusion"].get("true_centre_in_tissue_mm")
        return scan_figure(result, true_centre_mm=true_centre, title=f"scan of {len(result.records)} offsets")

    return data, text, figure


def _scan_data(result, tissue, offsets_m) -> dict:
    """``palpate --json`` of a scan: the stiffness map and the inclusion found, in mm (the truth on the twin)."""
    inc = result.inclusion
    data = {
        "offsets_mm": [1000 * d for d in offsets_m],
        "map": {
            "position_in_tissue_mm": (1000 * result.map_position_m).tolist(),
            "modulus_n_m2": result.map_modulus_n_m2.tolist(),
            "modulus_sd_n_m2": result.map_modulus_sd_n_m2.tolist(),
        },
        "inclusion": {
            "centre_in_tissue_mm": 1000 * inc["centre_m"],
            "centre_sd_mm": 1000 * inc["centre_sd_m"],
            "ratio": inc["ratio"],
            "ratio_sd": inc["ratio_sd"],
            "modulus_n_m2": inc["modulus_n_m2"],
            "width_mm": 1000 * inc["width_m"],
            "chi2_per_dof": inc["chi2_per_dof"],
        },
    }
    if tissue.inclusions:
        true = tissue.inclusions[0]
        data["inclusion"]["true_centre_in_tissue_mm"] = 1000 * (true.centre_m - tissue.start_m)
        data["inclusion"]["true_ratio"] = true.ratio
    return data


#: A hold whose read force is uncertain by more than this fraction of the setpoint says so (the issue's 10 %).
HOLD_TOLERANCE = 0.10


def _uncertainty_data(held) -> dict:
    """``palpate --json`` of how far the gauges' force estimate can be trusted over the hold (1 sd, N) and, where it
    is more than :data:`HOLD_TOLERANCE` of the setpoint, the reason in one line."""
    import math

    sd = held.region.get("held_force_sd_n", math.nan)
    if not math.isfinite(sd):
        return {}
    data = {"estimate_sd_n": sd}
    if sd > HOLD_TOLERANCE * held.setpoint_n:
        data["estimate_note"] = (
            f"the force read is uncertain by {1000 * sd:.0f} mN (1 sd: the tare's noise and the gauges' drift over "
            f"the hold), more than {HOLD_TOLERANCE:.0%} of the {held.setpoint_n:g} N setpoint: one reading tells this "
            f"contact's force to {1000 * held.region['force_sd_n']:.0f} mN"
        )
    return data


def _place_data(held) -> dict:
    """``palpate --json`` of a hold's contact place: where it was looked for, the estimate over the figures' window
    (null where the gauges cannot tell it, with the reason), and on the twin the true centroid and the error."""
    import math

    def mm(x):
        return None if x is None or not math.isfinite(x) else 1000 * x

    region = held.region
    searched = region.get("region_m")
    data = {
        "searched_mm": None if searched is None else [1000 * searched[0], 1000 * searched[1]],
        "narrowed": bool(region.get("narrowed", False)),
        "told": bool(region.get("place_told", False)),
        "reason": region.get("reason", ""),
        "steady_mm": mm(held.steady_place_m),
    }
    if held.true_place_m is not None:
        data["true_steady_mm"] = mm(held.true_steady_place_m)
        both = data["steady_mm"] is not None and data["true_steady_mm"] is not None
        data["error_mm"] = data["steady_mm"] - data["true_steady_mm"] if both else None
    return data


def _force(rig, tissue, plan, log, log_mode):
    from flexdigit._command import said_warnings
    from flexdigit.errors import DesignWarning
    from flexdigit.palpation.palpation import hold_force

    f = plan.force
    # a tissue past the tip was refused before the rig moved (_digit_tissue: palpation.check_tissue_reach)
    rig.place_tissue(tissue)
    end = min(tissue.end_m, rig.params.geometry.digit_length_m)
    with said_warnings("palpate", DesignWarning) as design_warnings:  # a command too coarse for the setpoint
        held = hold_force(
            rig,
            f["setpoint_n"],
            duration_s=f["duration_s"],
            gain=f["gain"],
            approach_rate=f["approach_rate"],
            side=tissue.side,
            region_m=(max(tissue.start_m, 0.0), end),
            log_path=log,
            log_mode=log_mode,
            refuse_uncertain=True,  # a force read uncertain by more than 5 % of the setpoint: refused before moving
        )
    unreached = held.unreached()
    if unreached:  # never a success that touched nothing: the digit relaxed, one line, exit 2
        from flexdigit.errors import RigError

        straight = rig.relax()
        raise RigError(f"hold: {unreached}; digit relaxed to command {straight}")
    data, text = _hold_data(held)
    data["design_warnings"] = design_warnings

    def figure():
        from flexdigit.palpation.palpation_plot import hold_figure

        return hold_figure(held, title=f"force control at {held.setpoint_n:g} N")

    return data, text, figure


def _limit_data(held) -> dict:
    """``palpate --json``'s ``limit_note``: why a hold ended short, in one line: no contact seen (the approach did
    not reach the body), or the loop at its highest command
    (:meth:`~flexdigit.palpation.palpation.ForceHold.limit_reached`)."""
    if not held.touched and held.command.size:
        return {
            "limit_note": f"no contact seen in the hold: the approach reached command {int(held.command[-1])} at "
            f"{held.approach_rate:g} commands/s; hold longer ('duration_s') or place the body nearer"
        }
    if not held.limit_reached():
        return {}
    top = held.region["command_range"][1]
    return {
        "limit_note": f"the loop reached its highest command ({top}: the thesis rig's 60 in tip rotation) short of "
        f"{held.setpoint_n:g} N: the digit does not press that hard there; place the body nearer"
    }


def _band_data(held) -> dict:
    """``palpate --json`` of the 10 % band: whether the overshoot stayed within it (over it: flagged, never a
    success, and why, :meth:`~flexdigit.palpation.palpation.ForceHold.over_band`), and what the hold measured before
    it pressed (``coarse_command``, :func:`~flexdigit.palpation.palpation.hold_coarseness`: the lone step's ring,
    the force a command presses, the least setpoint it can hold within the band)."""
    over, coarse = held.over_band(), held.region.get("coarse_command", {})
    return {
        "within_band": not over,
        **({"over_band_note": over} if over else {}),
        "over_band_tag": " (OVER the 10 % band)" if over else "",
        "coarse_command": coarse,
        # how the command is rounded: the sigma-delta, or the integer within integer_band of it where a lone
        # one-frame step rings the force more than 10 % (palpation.quantiser_band; ring NaN: not measured)
        "integer_band": held.region.get("integer_band", 0.0),
        "lone_step_ring_n": held.region.get("lone_step_ring_n", coarse.get("lone_step_ring_n")),
    }


def _decisions_line(data: dict) -> str:
    """The text's line on what the estimates of the figures' window decided (the force held follows it)."""
    counts = data["decisions"]
    said = ", ".join(f"{kind} {n}" for kind, n in counts.items() if n)
    average = data["average_readings"]
    each = "each reading" if average == 1 else f"the mean of each {average} readings"
    return f"contact decided on {each} over the last window: {said or 'no estimate'}"


def _decisions_data(held) -> dict:
    """``palpate --json`` of a hold's contact decisions: how many of the window's estimates decided each kind, and
    the decision's chi^2 threshold, raised past what the digit's free motion reads (``palpation.free_motion_chi2``)."""
    return {
        "decisions": held.decisions(),
        "free_motion_chi2": held.region.get("free_motion_chi2"),
        "detect_chi2": held.region.get("detect_chi2"),
    }


def _hold_data(held) -> tuple[dict, str]:
    """``palpate --json`` of a hold and its text: the figures, the contact place, the estimate's uncertainty."""
    data = {
        "setpoint_n": held.setpoint_n,
        "steady_force_n": held.steady_force_n,
        "steady_error": held.steady_error,
        "steady_ripple_n": held.steady_ripple_n,
        "overshoot": held.overshoot,
        **_band_data(held),
        "settling_s": held.settling_s,
        # within 10 % over the whole figures' window: only then is "steady" a steady state
        "settled": held.settled(),
        **({"settle_note": held.settle_note()} if not held.settled() else {}),
        "status": held.status,
        "scored_on": "true contact force (twin)" if held.true_force_n is not None else "estimated force",
        "contact_place": _place_data(held),
        # how many of the last window's estimates decided each kind of contact (the force follows the decision)
        **_decisions_data(held),
        "average_readings": held.region.get("average_readings", 1),
        **_limit_data(held),
        "tare_readings": held.region.get("tare_readings"),
        **_uncertainty_data(held),
        "time_s": held.time_s.tolist(),
        "command": held.command.tolist(),
        "force_n": held.force_n.tolist(),
        "decision": [] if held.kind is None else held.kind.tolist(),
        **({"true_force_n": held.true_force_n.tolist()} if held.true_force_n is not None else {}),
    }
    place = data["contact_place"]
    text = (
        f"held {held.setpoint_n:g} N: steady {held.steady_force_n:.4f} N ({100 * held.steady_error:+.1f} %), ripple "
        f"{held.steady_ripple_n * 1000:.1f} mN, overshoot {100 * held.overshoot:.1f} %{data['over_band_tag']}, "
        + (f"within 10 % after {held.settling_s:.2f} s" if data["settled"] else "NOT settled")
        + f" ({data['scored_on']})\n"
        + "".join(f"{data[note]}\n" for note in ("over_band_note", "settle_note") if note in data)
        + (f"contact at {place['steady_mm']:.1f} mm" if place["steady_mm"] is not None else "contact place: not told")
        + f" ({place['reason']})\n"
        + _decisions_line(data)
        + (f"\n{data['limit_note']}" if "limit_note" in data else "")
        + (f"\n{data['estimate_note']}" if "estimate_note" in data else "")
    )
    return data, text
