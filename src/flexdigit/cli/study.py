"""``flexdigit study sensitivity|design SPEC.toml --out DIR``: studies at scale from the shell."""

from __future__ import annotations

import argparse
from numbers import Integral

from flexdigit._command import CommandResult, add_command
from flexdigit._plot import add_plot_flag
from flexdigit._validation import Flag, Interval, Plausible


def register(subparsers: argparse._SubParsersAction) -> None:
    p = add_command(
        subparsers,
        "study",
        _study,
        help="sensitivity (Morris, Sobol) or design study (Pareto front) over a spec, on Dask",
        description="Run a study spec (a TOML file, or a shipped one: thesis-tolerances, thesis-design, "
        "thesis-taper) on a local Dask cluster (one worker per core) or an existing one; rerunning with the same "
        "--out resumes it.",
    )
    from flexdigit.cli._formats import epilog

    p.epilog = epilog("spec")
    p.add_argument("kind", choices=("sensitivity", "design"), help="which study")
    p.add_argument("spec", help="study spec TOML, or a shipped name (thesis-tolerances, thesis-design, thesis-taper)")
    p.add_argument("--out", required=True, help="directory for the journal, tables and figures (created)")
    p.add_argument("--scheduler", default=None, help="an existing Dask scheduler, tcp://HOST:PORT")
    p.add_argument("--workers", type=int, default=None, help="local Dask workers (default: one per core; 0: no Dask)")
    p.add_argument(  # the spec's own bounds (sobol_n 4..2**20, a power of 2) are checked with the spec
        "--n",
        type=Flag(Interval(Integral, 1, 2**20)),
        default=None,
        help="sensitivity: Sobol base samples N (a power of 2)",
    )
    p.add_argument("--second-order", action="store_true", help="sensitivity: also second-order indices S2")
    _add_design_flags(p)
    p.add_argument(
        "--force", action="store_true", help="start over: replace the journal and outputs in --out (and --plot)"
    )
    add_plot_flag(
        p,
        "the study's main result: a sensitivity study's Sobol indices (one metric's S1 and ST, or the total-index "
        "map of several), a design study's Pareto front",
    )
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")


def _add_design_flags(p) -> None:
    """The flags of ``study design`` alone."""
    p.add_argument(
        "--samples",
        type=Flag(Plausible("", 0, 1_000_000, "candidate designs: a million twin evaluations is days", integer=True)),
        default=None,
        help="design: candidate designs to evaluate (0: all)",
    )
    p.add_argument(
        "--export",
        type=Flag(Interval(Integral, 0, 10**7)),
        default=None,
        metavar="K",
        help="design: write the rig description (params TOML) of design K on the Pareto front (finishing the study "
        "first; a finished one is read, not rerun)",
    )
    p.add_argument(
        "--export-to", metavar="FILE", default=None, help="where --export writes (default OUT/design-K.toml)"
    )


def _study(args: argparse.Namespace) -> CommandResult:
    from pathlib import Path

    from flexdigit.errors import ParameterError
    from flexdigit.studies.execution import parse_scheduler

    if args.workers is not None and args.workers < 0:
        raise ParameterError(f"--workers must be >= 0 (0: no Dask). Got {args.workers} instead.")
    if args.workers is not None and args.scheduler is None:
        from flexdigit._system import check_workers
        from flexdigit.studies.execution import WORKER_BYTES

        check_workers(args.workers, "--workers", WORKER_BYTES)
    if args.scheduler is not None:
        parse_scheduler(args.scheduler)
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise NotADirectoryError(f"{out}: --out must be a directory")
    if not out.parent.is_dir():
        raise FileNotFoundError(f"{out}: the directory {out.parent} does not exist")
    if args.kind == "sensitivity" and (args.export is not None or args.export_to is not None):
        raise ParameterError("--export K is for design studies (flexdigit study design SPEC --out DIR --export K)")
    from flexdigit._plot import check_plot

    check_plot(args.plot, "study", force=args.force)
    spec = _load(args)
    if args.kind == "sensitivity":
        return _sensitivity(args, spec, out)
    return _design(args, spec, out)


def _load(args: argparse.Namespace):
    """The spec: a rig's (:func:`~flexdigit.studies.spec.load_spec`) or, when its [study] names a robot, a tendon
    robot's (:mod:`flexdigit.studies.robot_study`: sensitivity only)."""
    from flexdigit.errors import ParameterError
    from flexdigit.studies.robot_study import is_robot_spec, load_robot_spec
    from flexdigit.studies.spec import load_spec

    if not is_robot_spec(args.spec):
        return load_spec(args.spec)
    if args.kind != "sensitivity":
        raise ParameterError(f"{args.spec}: a robot study spec ([study] robot) runs as a sensitivity study only")
    return load_robot_spec(args.spec)


def _run(args, out, run, settings, write):
    """Run a study in ``out`` (created), write its files, return ``(result, summary)``.

    A finished study is refused (before any work) unless some of its tasks failed (a worker died): a rerun then
    computes those rows again and rewrites the outputs; or unless it is asked for ``--export`` or ``--plot``: its
    journal is then read, nothing computed again, its files left as they are."""
    from flexdigit.errors import OutputExistsError
    from flexdigit.studies.execution import retry_rows

    done = out / "summary.json"
    retry = done.exists() and not args.force and retry_rows(out) > 0
    asks = getattr(args, "export", None) is not None or args.plot is not None  # of the finished study: read it
    reading = done.exists() and not args.force and not retry and asks
    if done.exists() and not args.force and not retry and not reading:
        raise OutputExistsError(f"{done}: this study has finished in {out}; pass --force to run it again")
    from flexdigit._io import output_lock
    from flexdigit.studies.execution import JOURNAL_NAME

    out.mkdir(exist_ok=True)
    with output_lock(out / JOURNAL_NAME):  # a second study into this --out is refused, never mixed with this one
        result = run(
            args.spec_obj,
            out,
            settings=settings,
            workers=args.workers,
            scheduler=args.scheduler,
            force=args.force,
            progress=not args.no_progress,
        )
        # a finished study read for --export or --plot: its journal gave every row, its files stay as they are
        paths = {} if reading else write(result, out, force=args.force or retry)
    summary = result.summary()
    summary["files"] = {k: str(v) for k, v in paths.items()}
    return result, summary


def _sensitivity(args, spec, out) -> CommandResult:
    from flexdigit.studies.sensitivity import SensitivitySettings, run_sensitivity, write_outputs

    overrides = {"sobol_n": args.n, "second_order": True if args.second_order else None}
    args.spec_obj = spec
    result, summary = _run(args, out, run_sensitivity, SensitivitySettings.from_spec(spec, **overrides), write_outputs)
    lines = [f"{spec.name}: {summary['evaluations']} evaluations of {len(spec.parameters)} parameters -> {out}"]
    for metric, entry in summary["metrics"].items():
        if metric in result.refused:
            lines.append(f"  {metric}: no indices: {result.refused[metric]}")
            continue
        conv = entry.get("convergence", {})
        top = entry.get("ranking", [])[:3]
        sob = entry.get("sobol", {})
        ranked = ", ".join(f"{n} ST {sob[n]['ST']:.2f}+-{sob[n]['ST_conf']:.2f}" for n in top)
        flag = "converged" if conv.get("converged") else f"NOT converged (moved {conv.get('max_change', 0):.3f})"
        lines.append(f"  {metric}: {ranked} [{flag}]")
    if result.failed_rows:
        lines.append(f"  {len(result.failed_rows)} rows failed (listed in summary.json)")
    if args.plot and result.sobol:
        from flexdigit.studies.figures import sensitivity_figure

        summary["plot"] = _save_plot(args, sensitivity_figure(result))
        lines.append(f"  plot -> {summary['plot']}")
    elif args.plot:
        lines.append("  no plot: no metric has indices")
    return CommandResult(data=summary, text="\n".join(lines))


def _save_plot(args, fig) -> str:
    from flexdigit._plot import save_plot

    return str(save_plot(fig, args.plot, "study", force=args.force))


def _design(args, spec, out) -> CommandResult:
    from flexdigit.studies.design_study import DesignSettings, run_design, write_design_outputs

    args.spec_obj = spec
    settings = DesignSettings.from_spec(spec, samples=args.samples)
    target = args.export_to or out / f"design-{args.export}.toml"
    if args.export is not None and (args.export_to is not None or out.is_dir()):
        from flexdigit._io import check_output

        # before the study runs (hours, for a big one), not after; and --force would also run it again
        check_output(target, force=args.force, hint="(which also runs the study again) or give --export-to FILE")
    result, summary = _run(args, out, run_design, settings, write_design_outputs)
    text = result.text()
    if args.plot:
        from flexdigit.studies.design_study import design_pareto_figure
        from flexdigit.studies.figures import with_subject

        summary["plot"] = _save_plot(args, with_subject(design_pareto_figure(result), spec))
        text += f"\nplot -> {summary['plot']}"
    if args.export is not None:
        from flexdigit.studies.design_study import export_design

        target = export_design(result, args.export, target, force=args.force)
        summary["exported"] = {"design": args.export, "params": str(target)}
        text += f"\ndesign {args.export}'s rig description written to {target} (flexdigit params {target})"
    return CommandResult(data=summary, text=text)
