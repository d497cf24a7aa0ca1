"""Run every benchmark module and print one table (``make bench``).

Each module in :data:`MODULES` exposes ``run() -> list[dict]`` with keys ``name``, ``value``, ``unit``,
``goal`` (text, may be empty) and ``note``. Peers (PyElastica, plain hinfsyn) are timed in the same run.

``--out FILE`` also writes the rows as JSON with where and when they were measured (``make bench`` writes
``benchmarks/results.json``); the documentation's benchmark page is generated from that file (``docs/_ext``), so no
figure is copied by hand.
"""

from __future__ import annotations

import argparse
import importlib
import json
import os
import platform
import subprocess
import sys
import time
from datetime import UTC, datetime
from pathlib import Path

MODULES: tuple[str, ...] = (
    "benchmarks.bench_cli",
    "benchmarks.bench_control",
    "benchmarks.bench_twin",
    "benchmarks.bench_digits",
    "benchmarks.bench_cells",
    "benchmarks.bench_resolution",
    "benchmarks.bench_unequal",
    "benchmarks.bench_digitshape",
    "benchmarks.bench_digitctl2",
    "benchmarks.bench_damping",
    "benchmarks.bench_designunequal",
    "benchmarks.bench_noisy",
    "benchmarks.bench_stepfix",
    "benchmarks.bench_map",
    "benchmarks.bench_tdcr",
    "benchmarks.bench_tdcrcli",
    "benchmarks.bench_tdcrfix",
    "benchmarks.bench_identify",
    "benchmarks.bench_rig",
    "benchmarks.bench_tactile",
    "benchmarks.bench_digittac",
    "benchmarks.bench_bayes",
    "benchmarks.bench_netfix",
    "benchmarks.bench_bayes2",
    "benchmarks.bench_calibrate",
    "benchmarks.bench_calfix",
    "benchmarks.bench_live",
    "benchmarks.bench_livegauges",
    "benchmarks.bench_studies",
    "benchmarks.bench_dask",
    "benchmarks.bench_report",
    "benchmarks.bench_palpation",
    "benchmarks.bench_force",
    "benchmarks.bench_palp2",
    "benchmarks.bench_forcecal",
    "benchmarks.bench_board",
    "benchmarks.bench_digitboard",
    "benchmarks.bench_board8",
    "benchmarks.bench_resources",
    "benchmarks.bench_plots",
    "benchmarks.bench_plots2",
    "benchmarks.bench_suitetime",
)
#: Run only when named (``python -m benchmarks bench_converged``): half an hour of CPU.
ON_REQUEST: tuple[str, ...] = ("benchmarks.bench_converged",)


def run_context() -> dict:
    """Where and when the rows were measured: the figures are indicative, so the page says of what run they are."""
    try:
        commit = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, check=True
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        commit = ""
    return {
        "date_utc": datetime.now(UTC).strftime("%Y-%m-%d %H:%M"),
        "commit": commit,
        "cpu_count": os.cpu_count(),
        "load_average_1min": os.getloadavg()[0],
        "python": platform.python_version(),
        "machine": platform.machine(),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks")
    parser.add_argument("only", nargs="*", help="run only these modules (e.g. bench_twin, or twin)")
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--out", type=Path, help="also write the rows and the run's context as JSON to this file")
    parser.add_argument("--force", action="store_true", help="replace an existing --out file")
    args = parser.parse_args(argv)
    if args.out is not None:
        from flexdigit._io import check_output

        try:
            check_output(args.out, force=args.force)  # before the minutes of measuring, not after
        except OSError as exc:  # flexdigit's OutputError: one line naming the file
            print(f"python -m benchmarks: {exc}", file=sys.stderr)
            return 2
    rows = []
    for name in MODULES + ON_REQUEST:
        short = name.rsplit(".", 1)[-1]
        named = short in args.only or short.removeprefix("bench_") in args.only
        if (args.only and not named) or (name in ON_REQUEST and not named):
            continue
        start = time.perf_counter()
        print(f"running {name} ...", file=sys.stderr, flush=True)
        for row in importlib.import_module(name).run():
            rows.append({"module": name.rsplit(".", 1)[-1], **row})
        print(f"  {time.perf_counter() - start:.1f} s", file=sys.stderr, flush=True)
    if args.out is not None:
        from flexdigit._io import atomic_write

        with atomic_write(args.out, "w", force=args.force) as fh:
            json.dump({"context": run_context(), "rows": rows}, fh, indent=2)
            fh.write("\n")
    if args.json:
        json.dump(rows, sys.stdout, indent=2)
        print()
        return 0
    print(f"| {'benchmark':<58} | {'value':>12} | {'unit':<10} | {'goal':<14} |")
    print(f"|{'-' * 60}|{'-' * 14}|{'-' * 12}|{'-' * 16}|")
    for row in rows:
        print(f"| {row['name']:<58} | {row['value']:>12.4g} | {row['unit']:<10} | {row.get('goal', ''):<14} |")
        if row.get("note"):
            print(f"|   {row['note']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
