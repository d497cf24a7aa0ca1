"""``flexdigit reproduce``: the main job, the whole thesis on the twin, as a report."""

from __future__ import annotations

import argparse
import sys

from flexdigit._command import CommandResult, add_command
from flexdigit._validation import SEED, Flag


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = add_command(
        subparsers,
        "reproduce",
        _reproduce,
        help="reproduce the thesis end to end on the twin and write a report",
    )
    parser.add_argument("--out", default="report", help="output folder (default: report/)")
    parser.add_argument("--seed", type=Flag(SEED), default=0, help="seed of every random stream (default 0)")
    parser.add_argument("--params", help="rig parameter TOML (default: the thesis rig)")
    parser.add_argument("--calibration", metavar="FILE", help="twin calibration TOML (default: fitted to the thesis)")
    parser.add_argument("--fast", action="store_true", help="smaller sweeps, for a quick look")
    parser.add_argument(
        "--workers",
        type=int,
        help="chapters built at once, one process each (default: one per core; 1: in this process, one by one)",
    )
    parser.add_argument("--force", action="store_true", help="overwrite a report already in --out")


def _reproduce(args: argparse.Namespace) -> CommandResult:
    from flexdigit.errors import ParameterError
    from flexdigit.params import RigParams, load_params
    from flexdigit.report.build import check_report_dir, reproduce

    if args.workers is not None and args.workers < 1:
        raise ParameterError(f"--workers must be a positive integer. Got {args.workers} instead.")
    if args.workers is not None:
        from flexdigit._system import check_workers
        from flexdigit.report.build import CHAPTER_BYTES

        check_workers(args.workers, "--workers", CHAPTER_BYTES)
    check_report_dir(args.out, force=args.force)  # before the chapters run (minutes), not after
    params = load_params(args.params) if args.params else RigParams()

    def progress(name: str, title: str, seconds: float) -> None:
        if not args.json:
            print(f"  {title} done in {seconds:.1f} s", file=sys.stderr, flush=True)

    run = {"params": params, "seed": args.seed, "fast": args.fast, "progress": progress, "workers": args.workers}
    run["force"] = args.force  # checked above; the chapters' own files are then ours to replace
    if args.calibration:  # every twin of every chapter on the user's calibration (flexdigit calibrate's file)
        from flexdigit.twin.calibration import load_calibration_record, use_calibration

        calibration, fit = load_calibration_record(args.calibration)
        with use_calibration(calibration, source=str(args.calibration), fit=fit):
            summary = reproduce(args.out, **run)  # the workers get the calibration from reproduce
    else:
        summary = reproduce(args.out, **run)
    lines = [
        f"report written to {summary.out_dir / 'index.html'} and {summary.out_dir / 'results.json'}",
        f"{summary.entries} entries: " + ", ".join(f"{n} {s}" for s, n in summary.counts.items()),
    ]
    lines += [f"chapter {name} FAILED: {error}" for name, error in summary.failed.items()]
    return CommandResult(data=summary, text="\n".join(lines), exit_code=1 if summary.failed else 0)
