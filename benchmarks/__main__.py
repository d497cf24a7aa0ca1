"""Run every benchmark module and print one table (``make bench``).

Each module in :data:`MODULES` exposes ``run() -> list[dict]`` with keys ``name``, ``value``, ``unit``,
``goal`` (text, may be empty) and ``note``. Peers (PyElastica, plain hinfsyn) are timed in the same run.
"""

from __future__ import annotations

import argparse
import importlib
import json
import sys
import time

MODULES: tuple[str, ...] = (
    "benchmarks.bench_cli",
    "benchmarks.bench_control",
    "benchmarks.bench_twin",
    "benchmarks.bench_digits",
    "benchmarks.bench_tdcr",
    "benchmarks.bench_identify",
    "benchmarks.bench_rig",
    "benchmarks.bench_tactile",
    "benchmarks.bench_calibrate",
    "benchmarks.bench_live",
    "benchmarks.bench_studies",
    "benchmarks.bench_report",
    "benchmarks.bench_palpation",
    "benchmarks.bench_board",
    "benchmarks.bench_resources",
)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks")
    parser.add_argument("only", nargs="*", help="run only these modules (e.g. bench_twin)")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    rows = []
    for name in MODULES:
        if args.only and name.rsplit(".", 1)[-1] not in args.only:
            continue
        start = time.perf_counter()
        print(f"running {name} ...", file=sys.stderr, flush=True)
        for row in importlib.import_module(name).run():
            rows.append({"module": name.rsplit(".", 1)[-1], **row})
        print(f"  {time.perf_counter() - start:.1f} s", file=sys.stderr, flush=True)
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
