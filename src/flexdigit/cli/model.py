"""``flexdigit model``: the component models and the plant G(s) of thesis 3.5, printed or unit-consistent."""

from __future__ import annotations

import argparse

from flexdigit._command import CommandResult, add_command


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = add_command(
        subparsers,
        "model",
        _model,
        help="show the component models and the plant G(s): poles, zeros, DC gain, ranks, minimum phase",
    )
    parser.add_argument(
        "--variant",
        default="printed",
        choices=("printed", "consistent"),
        help="'printed' (the thesis's G(s), default) or 'consistent' (unit-correct chain)",
    )
    parser.add_argument(
        "--output",
        default="deflection_sg1_m",
        help="plant output, e.g. deflection_sg1_m (default), tip_rotation_rad, gauge_v_sg1 (consistent only)",
    )
    parser.add_argument(
        "--gains",
        default="cable",
        choices=("cable", "measured"),
        help="consistent variant: 'cable' (default) or 'measured'",
    )
    parser.add_argument("--params", metavar="FILE", help="rig parameters TOML (default: the thesis rig)")
    parser.add_argument("--explain", action="store_true", help="also list the printed-vs-consistent discrepancies")


def _model(args: argparse.Namespace) -> CommandResult:
    from flexdigit.models.plant import build_plant, closed_loop_printed_k1, explain_discrepancies
    from flexdigit.models.polytf import PolyTF
    from flexdigit.params import RigParams, load_params

    # python-control is never imported here: it costs 2 s of start-up (see flexdigit.models.polytf)
    params = load_params(args.params) if args.params else RigParams()
    params, derived = _digit_dynamics(params)
    plant = build_plant(args.variant, params, output=args.output, gains=args.gains)
    summary = plant.summary()
    components = {}
    for name, value in plant.factors.items():
        if isinstance(value, PolyTF):
            components[name] = {"num": value.num.tolist(), "den": value.den.tolist()}
        else:
            components[name] = float(value)
    notes = list(plant.notes)
    if derived:
        d = params.dynamics
        notes.append(
            f"E(s) of this digit from its twin's release mode (no [dynamics] in the file): wn {d.wn_housing_rad_s:.4g} "
            f"rad/s, zeta {d.zeta_housing:.4g} housed (the thesis's tables are its rig's alone)"
        )
    data = {"plant": summary, "components": components, "notes": notes}
    if plant.variant == "printed":
        k1 = closed_loop_printed_k1()
        cl = plant.closed_loop_poly(k1).normalised()
        data["closed_loop"] = {"k1": k1, "num": cl.num.tolist(), "den": cl.den.tolist(), "poles": _sorted_poles(cl)}
    if args.explain:
        data["discrepancies"] = explain_discrepancies(params)
    return CommandResult(data=data, text=_text(data))


def _digit_dynamics(params):
    """``(params, derived)``: a digit other than the thesis rig whose file gives no ``[dynamics]`` gets its twin's
    release mode (:func:`flexdigit.twin.twin.release_dynamics`) for its E(s); else the params as they are."""
    import dataclasses

    from flexdigit.params import DigitDynamics

    if params.is_thesis_rig() or params.dynamics != DigitDynamics():
        return params, False
    from flexdigit.errors import DesignError
    from flexdigit.twin.twin import release_dynamics

    try:
        dynamics = release_dynamics(params)
    except DesignError:  # tip up it buckles: its mode hanging tip down, as simulate release --orientation hanging
        dynamics = release_dynamics(params, orientation="hanging")
    return dataclasses.replace(params, dynamics=dynamics), True


def _sorted_poles(tf):
    import numpy as np

    p = np.asarray(tf.poles(), dtype=complex)
    return p[np.lexsort((p.imag, p.real))]


def _poly(coefs) -> str:
    n = len(coefs) - 1
    terms = []
    for i, c in enumerate(coefs):
        power = n - i
        var = "" if power == 0 else ("s" if power == 1 else f"s^{power}")
        terms.append(f"{c:.6g}{(' ' + var) if var else ''}")
    return " + ".join(terms)


def _complex(z) -> str:
    return f"{z.real:.5g}{z.imag:+.5g}j"


def _text(data: dict) -> str:
    p = data["plant"]
    lines = [
        f"plant ({p['variant']}): {p['input_unit']} -> {p['output']} [{p['output_unit']}]",
        f"  G(s) = ({_poly(p['num'])}) / ({_poly(p['den'])})",
        "  poles (rad/s): " + ", ".join(_complex(z) for z in p["poles"]),
        "  zeros (rad/s): " + (", ".join(_complex(z) for z in p["zeros"]) or "none"),
        f"  DC gain: {p['dc_gain']:.6g} {p['output_unit']} per command",
        f"  controllability rank {p['controllability_rank']}, observability rank {p['observability_rank']} "
        f"(order {p['order']})",
        f"  stable: {p['stable']}, minimum phase: {p['minimum_phase']}",
        "components:",
    ]
    for name, value in data["components"].items():
        if isinstance(value, dict):
            lines.append(f"  {name} = ({_poly(value['num'])}) / ({_poly(value['den'])})")
        else:
            lines.append(f"  {name} = {value:.6g}")
    if "closed_loop" in data:
        cl = data["closed_loop"]
        lines.append(f"closed loop with K1 = {cl['k1']:.5g} (table 4.1):")
        lines.append(f"  T(s) = ({_poly(cl['num'])}) / ({_poly(cl['den'])})")
        lines.append("  poles (rad/s): " + ", ".join(_complex(z) for z in cl["poles"]))
    lines.extend(f"note: {n}" for n in data["notes"])
    for item in data.get("discrepancies", []):
        lines.append(item)
    return "\n".join(lines)
