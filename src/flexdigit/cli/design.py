"""``flexdigit design ...``: H-infinity designs of thesis chapter 4 and the mixed-sensitivity design.

* ``flexdigit design hinf --filter-hz F [--plant printed|consistent] [--eps E] [--margin M]``
* ``flexdigit design sweep --filters 0.5,5,39,50``
* ``flexdigit design mixsyn [--bandwidth W] [--w-command C] [--w-disturbance D] [--s-peak M]``
"""

from __future__ import annotations

import argparse

from flexdigit._command import CommandResult, add_command
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
    p.add_argument("--plant", choices=("printed", "consistent"), default="printed")
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
    p = add_command(sub, "sweep", _sweep, help="the filter sweep of 4.7 (additive tolerance per cut-off)")
    p.add_argument(
        "--filters", type=Flag(FILTER_HZ, many=True), default="0.5,5,39,50", help="comma-separated cut-offs in Hz"
    )
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


def _design_summary(filter_hz: float, plant_variant: str = "printed", eps=None, margin=None) -> dict:
    import control as ct
    import numpy as np

    from flexdigit.control.analysis import additive_tolerance, hinf_norm, loop_maps, step_metrics
    from flexdigit.control.thesis_designs import sorted_poles, thesis_design
    from flexdigit.models.plant import build_plant

    plant = build_plant(plant_variant).tf
    d = thesis_design(filter_hz, plant, eps_u=eps, margin=margin)
    K = d.controller
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
        "tuw_step_peak": step_metrics(maps.T_uw, t_final=3.0)["peak"],
        "tyw_settling_s": step_metrics(maps.T_yw, t_final=3.0)["settling_time_s"],
    }


def _hinf(args: argparse.Namespace) -> CommandResult:
    s = _design_summary(args.filter_hz, args.plant, args.eps, args.margin)
    text = (
        f"H-inf design, F(s) = 1/(s + {2 * 3.141592653589793 * args.filter_hz:.4f}), {args.plant} plant\n"
        f"  gamma_opt {s['gamma_opt']:.6g}, central controller at {s['gamma']:.6g} (margin {s['margin']:.3g})\n"
        f"  K(s) num {[float(f'{c:.4g}') for c in s['controller_num']]}\n"
        f"       den {[float(f'{c:.4g}') for c in s['controller_den']]}\n"
        f"  ||T_zw|| {s['tzw_peak_db']:.4f} dB at {s['tzw_peak_rad_s']:.3f} rad/s; ||T_pq|| {s['tpq_peak_db']:.2f} dB\n"
        f"  additive tolerance {s['additive_tolerance_m_per_command']:.4g} m/command "
        f"({s['additive_tolerance_relative_percent']:.3g} % of |G(0)|; thesis arithmetic 100/dB = "
        f"{s['thesis_arithmetic_percent']:.3g} %)\n"
        f"  T_uw step peak {s['tuw_step_peak']:.4g} commands/m; T_yw settling {s['tyw_settling_s']:.3f} s"
    )
    return CommandResult(data=s, text=text)


def _sweep(args: argparse.Namespace) -> CommandResult:
    from flexdigit.reference import thesis_value

    printed = thesis_value("hinf.additive_tolerance_percent")
    rows = []
    lines = [
        "  f (Hz) | ||T_pq|| dB | thesis % | 100/dB at 10x gain | 1/||T_pq|| % of |G(0)| | T_uw step peak",
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
    return CommandResult(data=rows, text="\n".join(lines))


def _mixsyn(args: argparse.Namespace) -> CommandResult:
    import dataclasses

    import numpy as np

    from flexdigit.control.mixsyn import MixsynSpec, mixsyn_on_the_digit

    flags = {
        "bandwidth_rad_s": args.bandwidth,
        "s_peak": args.s_peak,
        "w_command": args.w_command,
        "w_disturbance": args.w_disturbance,
    }
    spec = MixsynSpec(**{k: v for k, v in flags.items() if v is not None})
    d, req = mixsyn_on_the_digit(spec, seed=args.seed)
    data = {
        "spec": dataclasses.asdict(spec),
        "gamma": d.hinf.gamma,
        "controller_num": np.asarray(d.controller.num[0][0]).tolist(),
        "controller_den": np.asarray(d.controller.den[0][0]).tolist(),
        "requirements": req,
    }
    if not req.get("stable"):
        return CommandResult(data=data, text="mixsyn: the nominal closed loop is unstable", exit_code=1)
    mc = req["monte_carlo"]
    text = (
        f"mixed-sensitivity design on the consistent plant (beam rotation, rad), order {d.order}, "
        f"gamma {d.hinf.gamma:.4g}\n"
        f"  (i)   30 deg step: command {req['command_min']:+.2f} .. {req['command_max']:+.2f} about 8 "
        f"(window {req['command_window']}): {'ok' if req['req_i_command_ok'] else 'FAIL'}\n"
        f"  (ii)  |S(0)| = {req['sensitivity_dc']:.2e}: {'ok' if req['req_ii_integral'] else 'FAIL'}\n"
        f"  (iii) min closed-loop damping {req['min_damping']:.3f}: {'ok' if req['req_iii_damping'] else 'FAIL'}\n"
        f"  (iv)  gain x0.7..1.3, beam wn x0.8..1.2: grid {'stable' if req['grid_stable'] else 'UNSTABLE'}, "
        f"Monte Carlo {mc['stable_fraction'] * 100:.1f} % of {mc['n']} stable (seed {args.seed}); "
        f"small-gain certificate on {req['small_gain_boxes']} sub-boxes: peak {req['small_gain_partition_peak']:.3f} "
        f"({'certified' if req['req_iv_small_gain'] else 'NOT certified'}); one-box unstructured |T| l = "
        f"{req['small_gain_peak']:.3g}\n"
        f"  settling {req['settling_time_s']:.2f} s, overshoot {req['overshoot_percent']:.1f} %"
    )
    return CommandResult(data=data, text=text, exit_code=0 if req["all_met"] else 1)
