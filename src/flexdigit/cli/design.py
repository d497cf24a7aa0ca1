"""``flexdigit design ...``: H-infinity designs of thesis chapter 4 and the mixed-sensitivity design.

* ``flexdigit design hinf --filter-hz F [--plant printed|consistent] [--eps E] [--margin M]``
* ``flexdigit design sweep --filters 0.5,5,39,50``
* ``flexdigit design mixsyn [--bandwidth W] [--w-command C] [--w-disturbance D] [--s-peak M]``
* ``flexdigit design 20ms [--params FILE] [--calibration FILE] [--out ctrl.json]``: the 20 ms discrete design
  (5.2-5.3); ``--out`` keeps it (:mod:`flexdigit.control.kept_design`) for ``flexdigit run --params FILE
  --controller ctrl.json``, which then does not search the digit's weights again

``hinf`` and ``20ms`` take ``--params FILE`` (and ``--calibration FILE``): the design is then on that digit's plant,
built the thesis's way from its components (servo, cable, the digit's own mode from its twin, gauge chain;
:func:`flexdigit.control.thesis_designs.digit_plant`, :func:`flexdigit.control.design20ms.digit_design_20ms`), and
a design that does not stabilise it is refused in one line (exit 2).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from flexdigit._command import CommandResult, add_command
from flexdigit._plot import add_plot_flag
from flexdigit._validation import SEED, Flag, Plausible

# The design flags' plausible ranges (flexdigit._validation.Flag refuses the rest in one line naming the flag). The
# library's own declarations (control.mixsyn, control.synthesis) say what is possible; these what is sensible to ask
# of a digit sampled every 20 ms.
#: The error filter's cut-off: the thesis tried 0.5 to 50 Hz (4.7); 0.01 Hz to 1 kHz brackets any rig's loop.
FILTER_HZ = Plausible("Hz", 0.01, 1000.0, "an error-filter cut-off: the thesis tried 0.5 to 50 Hz")


def register(subparsers) -> None:
    parser = subparsers.add_parser("design", help="H-infinity and mixed-sensitivity controller design (ch. 4)")
    sub = parser.add_subparsers(title="design commands", metavar="KIND")
    parser.set_defaults(
        func=lambda args: CommandResult(data=None, text=parser.format_help(), exit_code=2), command_name="design"
    )
    p = add_command(sub, "hinf", _hinf, help="the thesis's H-infinity design (4.4) for one error-filter cut-off")
    p.add_argument("--filter-hz", type=Flag(FILTER_HZ), required=True, help="cut-off of F(s) = 1/(s + 2 pi f), Hz")
    p.add_argument(
        "--plant",
        choices=("printed", "consistent"),
        default="printed",
        help="printed: the thesis's G(s) of 3.5 as printed; consistent: its unit-correct rebuild",
    )
    _add_digit_flags(p)
    p.add_argument(
        "--eps",
        type=Flag(Plausible("", 0.0, 1e3, "a regularisation weight eps_u: the thesis's are near 1e-3")),
        default=None,
        help="regularisation eps_u (default: fitted to the thesis)",
    )
    p.add_argument(
        "--margin",
        type=Flag(Plausible("", 0.0, 100.0, "a gamma margin: a fraction above the optimal gamma")),
        default=None,
        help="gamma margin (default: fitted to the thesis)",
    )
    _plot_flags(p)
    p = add_command(sub, "sweep", _sweep, help="the filter sweep of 4.7 (additive tolerance per cut-off)")
    p.add_argument(
        "--filters", type=Flag(FILTER_HZ, many=True), default="0.5,5,39,50", help="comma-separated cut-offs in Hz"
    )
    add_plot_flag(p, "||T_pq|| and the additive tolerance against the cut-off, the thesis's printed values beside")
    p.add_argument("--force", action="store_true", help="overwrite an existing --plot file")
    p = add_command(sub, "mixsyn", _mixsyn, help="integral mixed-sensitivity design on the consistent plant")
    p.add_argument(
        "--bandwidth",
        type=Flag(Plausible("rad/s", 0.01, 1e4, "a loop bandwidth: the digit's mode is 13 rad/s, the loop 314")),
        default=None,
        help="W1 bandwidth, rad/s",
    )
    p.add_argument(
        "--s-peak",
        type=Flag(Plausible("", 1.0, 10.0, "a sensitivity peak of 0 to 20 dB; 2 (6 dB) is the usual")),
        default=None,
        help="allowed |S| peak",
    )
    p.add_argument(
        "--w-command",
        type=Flag(Plausible("1/command", 1e-9, 1e6, "a weight on the command, positive")),
        default=None,
        help="weight on the command, 1/command",
    )
    p.add_argument(
        "--w-disturbance",
        type=Flag(Plausible("commands", 0.0, 1e6, "an input-disturbance weight")),
        default=None,
        help="input-disturbance weight, commands",
    )
    p.add_argument("--seed", type=Flag(SEED), default=0, help="Monte Carlo seed")
    _plot_flags(p)
    p = add_command(sub, "20ms", _twenty_ms, help="the 20 ms discrete design (5.2-5.3) for the thesis rig or --params")
    p.add_argument(
        "--period",
        type=Flag(Plausible("s", 1e-4, 1.0, "a loop period of 0.1 ms to 1 s")),
        default=None,
        help="sample period, s (default the digit's serial period, 20 ms)",
    )
    _add_digit_flags(p)
    p.add_argument(
        "--out",
        default=None,
        metavar="FILE",
        help="keep the design (JSON, the digit's fingerprint in it) for: flexdigit run --params FILE --controller OUT",
    )
    p.add_argument("--force", action="store_true", help="overwrite an existing --out (and --plot) file")
    add_plot_flag(p, "the linear 30 deg step (tip rotation and command) and the loop's frequency response")
    from flexdigit.cli._formats import epilog

    p.epilog = epilog("kept_design")


def _add_digit_flags(p) -> None:
    p.add_argument("--params", default=None, metavar="FILE", help="the digit's parameters TOML (default: thesis rig)")
    p.add_argument(
        "--calibration", default=None, metavar="FILE", help="its twin calibration TOML (default: scaled to --params)"
    )
    p.add_argument(
        "--orientation",
        choices=("vertical", "hanging", "horizontal"),
        default=None,
        help="how the digit is mounted (its mode and stability depend on it; default tip up, or hanging for a "
        "--params digit that buckles tip up, as flexdigit run mounts it)",
    )


def _digit(args):
    """``(params, calibration)`` of ``--params`` / ``--calibration`` (None, None: the thesis rig's design)."""
    from flexdigit.params import load_params
    from flexdigit.twin.calibration import load_calibration

    params = load_params(args.params) if args.params else None
    calibration = load_calibration(args.calibration) if args.calibration else None
    if calibration is not None and params is None:
        from flexdigit.params import RigParams

        params = RigParams()
    args.mount_note = ""
    if args.orientation is None:  # as run and collect mount the digit (control.digit_mount), said in the output
        from flexdigit.control.design20ms import digit_mount

        args.orientation = "vertical" if params is None else digit_mount(params, calibration)
        if args.orientation == "hanging":
            args.mount_note = (
                "mount: hanging (tip down): tip up this digit buckles under its own weight (as run and collect hang it)"
            )
    return params, calibration


def _with_mount(args, result: CommandResult) -> CommandResult:
    """The result, with the line that says the digit was hung (when :func:`_digit` chose so)."""
    if getattr(args, "mount_note", ""):
        result.text += "\n" + args.mount_note
        result.data["orientation"] = args.orientation
    return result


def _plot_flags(p) -> None:
    add_plot_flag(p, "the closed loop's step (output and command) and the Bode plot of L, S and T")
    p.add_argument("--force", action="store_true", help="overwrite an existing --plot file")


def _save_plot(args, plant, controller, unit: str, title: str):
    """``--plot``: the design's step and Bode figure (:func:`flexdigit.control.design_plot.design_figure`)."""
    from flexdigit._plot import save_plot
    from flexdigit.control.design_plot import design_figure

    fig = design_figure(plant, controller, output_unit=unit, title=title)
    return str(save_plot(fig, args.plot, "design", force=args.force))


def _design_summary(filter_hz: float, plant_variant: str = "printed", eps=None, margin=None, parts=None) -> dict:
    import control as ct
    import numpy as np

    from flexdigit.control.analysis import additive_tolerance, hinf_norm, loop_maps, step_metrics
    from flexdigit.control.thesis_designs import is_open_loop, sorted_poles, thesis_design
    from flexdigit.models.plant import build_plant

    plant = build_plant(plant_variant).tf
    d = thesis_design(filter_hz, plant, eps_u=eps, margin=margin)
    K = d.controller
    if parts is not None:  # --plot draws the plant and controller designed here
        parts.update(plant=plant, controller=K)
    maps = loop_maps(plant, K)
    tzw, wzw = hinf_norm(maps.T_zw, "T_zw")
    tol = additive_tolerance(plant, K)
    tf = ct.tf(K)
    return {
        "filter_hz": filter_hz,
        "plant": plant_variant,
        "gamma_opt": d.gamma_opt,
        "gamma": d.gamma,
        "margin": d.margin,
        "controller_num": np.asarray(tf.num[0][0]).tolist(),
        "controller_den": np.asarray(tf.den[0][0]).tolist(),
        "controller_poles": sorted_poles(np.linalg.eigvals(K.A)).tolist(),
        "controller_zeros": sorted_poles(ct.zeros(K)).tolist(),
        "tzw_peak_db": 20 * np.log10(tzw),
        "tzw_peak_rad_s": wzw,
        "tpq_peak_db": tol["tpq_db"],
        "additive_tolerance_m_per_command": tol["tolerance"],
        "additive_tolerance_relative_percent": tol["tolerance_relative_percent"],
        "thesis_arithmetic_percent": tol["thesis_arithmetic_percent"],
        "open_loop": is_open_loop(d.gamma_opt, filter_hz),
        "tuw_step_peak": step_metrics(maps.T_uw, t_final=3.0)["peak"],
        "tyw_settling_s": step_metrics(maps.T_yw, t_final=3.0)["settling_time_s"],
    }


def _hinf(args: argparse.Namespace) -> CommandResult:
    from flexdigit._plot import check_plot

    check_plot(args.plot, "design", force=args.force)
    params, calibration = _digit(args)
    if params is not None:
        return _with_mount(args, _hinf_digit(args, params, calibration))
    parts: dict = {}
    s = _design_summary(args.filter_hz, args.plant, args.eps, args.margin, parts)
    if args.plot:
        title = f"H-inf design, filter {args.filter_hz:g} Hz, {args.plant} plant (thesis 4.4)"
        s["plot"] = _save_plot(args, parts["plant"], parts["controller"], "m", title)
    text = (
        f"H-inf design, F(s) = 1/(s + {2 * 3.141592653589793 * args.filter_hz:.4f}), {args.plant} plant\n"
        f"  gamma_opt {s['gamma_opt']:.6g}, central controller at {s['gamma']:.6g} (margin {s['margin']:.3g})\n"
        f"  K(s) num {[float(f'{c:.4g}') for c in s['controller_num']]}\n"
        f"       den {[float(f'{c:.4g}') for c in s['controller_den']]}\n"
        f"  ||T_zw|| {s['tzw_peak_db']:.4f} dB at {s['tzw_peak_rad_s']:.3f} rad/s; ||T_pq|| {s['tpq_peak_db']:.2f} dB\n"
        f"  additive tolerance {s['additive_tolerance_m_per_command']:.4g} m/command "
        f"({s['additive_tolerance_relative_percent']:.3g} % of |G(0)|; thesis arithmetic 100/dB = "
        f"{s['thesis_arithmetic_percent']:.3g} %)\n"
        + (_OPEN_LOOP_TEXT if s["open_loop"] else "")
        + f"  T_uw step peak {s['tuw_step_peak']:.4g} commands/m; T_yw settling {s['tyw_settling_s']:.3f} s"
        + (f"\n  plot -> {s['plot']}" if args.plot else "")
    )
    return CommandResult(data=s, text=text)


def _hinf_digit(args, params, calibration) -> CommandResult:
    """``design hinf --params``: 4.4's design on the digit's own plant (gauge-1 deflection, m per command)."""
    import math

    from flexdigit.control.thesis_designs import digit_hinf_summary

    summary = digit_hinf_summary(
        args.filter_hz, params, calibration, orientation=args.orientation, eps_u=args.eps, margin=args.margin
    )
    data = {"params": args.params, **summary}
    eps_from = "given" if args.eps is not None else "the thesis's, scaled to this |G(0)|"
    if args.plot:  # the plant and the controller the design reported, as transfer functions
        import control as ct

        plant = ct.tf(data["plant_num"], data["plant_den"])
        controller = ct.tf(data["controller_num"], data["controller_den"])
        title = f"H-inf design on {Path(args.params).name}, filter {args.filter_hz:g} Hz (thesis 4.4)"
        data["plot"] = _save_plot(args, plant, controller, "m", title)
    text = (
        f"H-inf design on {args.params}: F(s) = 1/(s + {2 * math.pi * args.filter_hz:.4f}), the digit's plant from "
        f"its components (gauge-1 deflection, {data['plant_dc_gain_m_per_command'] * 1e3:.4g} mm per command; E(s) "
        f"wn {data['digit_wn_rad_s']:.4g} rad/s from its twin)\n"
        f"  gamma_opt {data['gamma_opt']:.6g}, central controller at {data['gamma']:.6g} (margin "
        f"{data['margin']:.3g}); closed loop stable\n"
        f"  ||T_zw|| {data['tzw_peak_db']:.4f} dB at {data['tzw_peak_rad_s']:.3f} rad/s; ||T_pq|| "
        f"{data['tpq_peak_db']:.2f} dB; eps_u {data['eps_u']:.4g} ({eps_from})\n"
        f"  additive tolerance {_tolerance_text(data)}\n"
        f"  T_yw settling {data['tyw_settling_s']:.3f} s; thesis columns not applicable"
        + (f"\n  plot -> {data['plot']}" if args.plot else "")
    )
    return CommandResult(data=data, text=text)


#: What ``design hinf`` says of a design whose gamma_opt is ||F||_inf (docs/guide/control.md, "Design on your digit").
_OPEN_LOOP_TEXT = (
    "  (open loop: gamma_opt is ||F||_inf = 1/(2 pi f_c), the cost of K = 0: this design barely feeds back, and its "
    "tolerance says only that; not a robustness figure)\n"
)


def _tolerance_text(data: dict) -> str:
    """The digit design's additive tolerance, or why it is not given (the open-loop design)."""
    if data["additive_tolerance_m_per_command"] is None:
        return data["additive_tolerance_note"]
    return (
        f"{data['additive_tolerance_m_per_command']:.4g} m/command ({data['additive_tolerance_relative_percent']:.3g} "
        f"% of |G(0)|; loop gain at DC {data['loop_gain_dc']:.3g})"
    )


def _twenty_ms(args: argparse.Namespace) -> CommandResult:
    """``design 20ms``: the discrete design the loop runs (``flexdigit run --controller digital20``)."""
    from flexdigit._io import check_output
    from flexdigit._plot import check_plot
    from flexdigit.control.design20ms import digit_design_20ms_summary

    if args.out is not None:
        check_output(args.out, force=args.force)  # before the search, not after it
    check_plot(args.plot, "design", force=args.force)
    params, calibration = _digit(args)
    summary = digit_design_20ms_summary(
        params, period_s=args.period, calibration=calibration, orientation=args.orientation
    )
    data = {"params": args.params, **summary, "out": _keep(args, params, calibration, summary)}
    data["plot"] = _twenty_ms_plot(args, params, calibration, summary)
    step, digit, search = data["linear_step_30deg"], data["model"], data["search"]
    model = (
        "servo x rotation per command (5.3)"
        if digit is None
        else "servo x the twin's chain linearised at "
        f"{digit['operating_deg']:.0f} deg, cable(s) taut, {args.orientation}: modes "
        + ", ".join(f"{w:.3g}" for w in digit["modes_wn_rad_s"])
        + f" rad/s kept, {len(digit['truncated_wn_rad_s'])} above Nyquist truncated"
    )
    text = (
        f"20 ms design{' on ' + args.params if args.params else ''}: {model}; {data['deg_per_command']:.4g} deg a "
        f"command, {data['delay_samples']} sample(s) of delay, period {data['period_s'] * 1000:g} ms\n"
        f"  nominal loop poles inside |z| <= {data['closed_loop_pole_radius']:.4f} (stable); linear 30 deg step: "
        f"settling {step['settling_time_s']:.3f} s, overshoot {step['overshoot_percent']:.2f} %\n"
    )
    if search is not None:
        text += (
            f"  weights searched ({search['candidates']} candidates, plant gain x "
            f"{min(search['gain_errors']):g}-{max(search['gain_errors']):g}): worst settling "
            f"{search['worst_settling_time_s']:.3f} s, overshoot {search['worst_overshoot_percent']:.2f} %, noise "
            f"{search['noise_sd_deg']:.3f} deg\n"
        )
        if not search["meets"]:
            text += f"  NOT meeting issue 24's step figures on its model: {search['failing']}\n"
    where = f" --params {args.params}" if args.params else ""
    kept = f" --controller {data['out']}" if data["out"] else ""
    text += f"  {'kept in ' + data['out'] + '; ' if kept else ''}the loop on the twin: flexdigit run{where}{kept}"
    text += " --setpoint-deg 30" + (f"\n  plot -> {data['plot']}" if data["plot"] else "")
    return _with_mount(args, CommandResult(data=data, text=text))


def _twenty_ms_plot(args, params, calibration, summary: dict) -> str | None:
    """``design 20ms --plot``: the design of ``summary`` (its weights, no search again) drawn by
    :func:`flexdigit.control.design_plot.twenty_ms_figure`; None without ``--plot``."""
    if args.plot is None:
        return None
    import warnings

    from flexdigit._plot import save_plot
    from flexdigit.control.design20ms import Weights, digit_design_20ms
    from flexdigit.control.design_plot import twenty_ms_figure
    from flexdigit.errors import DesignWarning

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DesignWarning)  # said in the command's text
        design = digit_design_20ms(
            params, period_s=summary["period_s"], calibration=calibration, orientation=args.orientation,
            weights=Weights(**summary["weights"]),
        )  # fmt: skip
    digit = Path(args.params).stem if args.params else "the thesis rig"
    title = f"20 ms design on {digit} ({args.orientation}; thesis 5.2-5.3)"
    return str(save_plot(twenty_ms_figure(design, title=title), args.plot, "design", force=args.force))


def _keep(args, params, calibration, summary: dict) -> str | None:
    """``design 20ms --out``: the design kept for ``run --controller FILE`` (its weights, the digit's
    fingerprint); None without ``--out``."""
    if args.out is None:
        return None
    from flexdigit.control.kept_design import keep_design, write_kept_design

    kept = keep_design(params, calibration, orientation=args.orientation, summary=summary, params_file=args.params)
    return str(write_kept_design(kept, args.out, force=args.force))


def _sweep(args: argparse.Namespace) -> CommandResult:
    from flexdigit._plot import check_plot
    from flexdigit.reference import thesis_value

    check_plot(args.plot, "design", force=args.force)
    printed = thesis_value("hinf.additive_tolerance_percent")
    rows = []
    lines = [
        "  f (Hz) | ||T_pq|| dB | thesis % | 100/dB at 10x gain | 1/||T_pq|| % of |G(0)| | T_uw step peak (commands/m)",
    ]
    for f in args.filters:
        s = _design_summary(f)
        key = f"{f:g}Hz".replace(".", "p") if f"{f:g}Hz" not in printed else f"{f:g}Hz"
        s["thesis_percent"] = printed.get(key)
        rows.append(s)
        thesis_text = f"{s['thesis_percent']:.4g}" if s["thesis_percent"] is not None else "-"
        # the thesis's reading, 100 / (||T_pq|| in dB), with the printed controllers' 10x gain (+20 dB)
        s["thesis_arithmetic_printed_gain_percent"] = 100 / (s["tpq_peak_db"] + 20) if s["tpq_peak_db"] > -20 else None
        shifted = s["thesis_arithmetic_printed_gain_percent"]
        lines.append(
            f"  {f:6g} | {s['tpq_peak_db']:11.2f} | {thesis_text:>8} | "
            f"{shifted if shifted is not None else float('nan'):18.3g} | "
            f"{s['additive_tolerance_relative_percent']:22.4g} | {s['tuw_step_peak']:.4g}"
        )
    if args.plot:
        lines.append(f"  plot -> {_sweep_plot(args, rows)}")
    return CommandResult(data=rows, text="\n".join(lines))


def _sweep_plot(args, rows: list[dict]) -> str:
    """``design sweep --plot``: :func:`flexdigit.control.design_plot.sweep_figure` of the rows printed."""
    from flexdigit._plot import save_plot
    from flexdigit.control.design_plot import sweep_figure

    columns = ("filter_hz", "tpq_peak_db", "additive_tolerance_relative_percent", "thesis_percent")
    columns += ("thesis_arithmetic_printed_gain_percent",)
    fig = sweep_figure(*([r[c] for r in rows] for c in columns))
    return str(save_plot(fig, args.plot, "design", force=args.force))


def _mixsyn(args: argparse.Namespace) -> CommandResult:
    import dataclasses

    import numpy as np

    from flexdigit._plot import check_plot
    from flexdigit.control.mixsyn import MixsynSpec, mixsyn_on_the_digit

    check_plot(args.plot, "design", force=args.force)
    flags = {"bandwidth_rad_s": args.bandwidth, "s_peak": args.s_peak, "w_command": args.w_command}
    flags["w_disturbance"] = args.w_disturbance
    spec = MixsynSpec(**{k: v for k, v in flags.items() if v is not None})
    d, req = mixsyn_on_the_digit(spec, seed=args.seed)
    data = {
        "spec": dataclasses.asdict(spec),
        "gamma": d.hinf.gamma,
        "controller_num": np.asarray(d.controller.num[0][0]).tolist(),
        "controller_den": np.asarray(d.controller.den[0][0]).tolist(),
        "requirements": req,
    }
    if args.plot:
        from flexdigit.models.plant import build_plant

        title = f"mixed-sensitivity design, consistent plant (beam rotation), order {d.order}"
        plant = build_plant("consistent", output="tip_rotation_rad")  # the plant mixsyn_on_the_digit designs for
        data["plot"] = _save_plot(args, plant.tf, d.controller, "rad", title)
    if not req.get("stable"):
        return CommandResult(data=data, text="mixsyn: the nominal closed loop is unstable", exit_code=1)
    mc = req["monte_carlo"]
    text = (
        f"mixed-sensitivity design on the consistent plant (beam rotation, rad), order {d.order}, "
        f"gamma {d.hinf.gamma:.4g}\n"
        f"  (i)   30 deg step: command {req['command_min']:+.2f} .. {req['command_max']:+.2f} servo commands about "
        f"8 (window {req['command_window']}): {'ok' if req['req_i_command_ok'] else 'FAIL'}\n"
        f"  (ii)  |S(0)| = {req['sensitivity_dc']:.2e}: {'ok' if req['req_ii_integral'] else 'FAIL'}\n"
        f"  (iii) min closed-loop damping {req['min_damping']:.3f}: {'ok' if req['req_iii_damping'] else 'FAIL'}\n"
        f"  (iv)  gain x0.7..1.3, beam wn x0.8..1.2: grid {'stable' if req['grid_stable'] else 'UNSTABLE'}, "
        f"Monte Carlo {mc['stable_fraction'] * 100:.1f} % of {mc['n']} stable (seed {args.seed}); "
        f"small-gain certificate on {req['small_gain_boxes']} sub-boxes: peak {req['small_gain_partition_peak']:.3f} "
        f"({'certified' if req['req_iv_small_gain'] else 'NOT certified'}); one-box unstructured |T| l = "
        f"{req['small_gain_peak']:.3g}\n"
        f"  settling {req['settling_time_s']:.2f} s, overshoot {req['overshoot_percent']:.1f} %"
        + (f"\n  plot -> {data['plot']}" if args.plot else "")
    )
    return CommandResult(data=data, text=text, exit_code=0 if req["all_met"] else 1)
