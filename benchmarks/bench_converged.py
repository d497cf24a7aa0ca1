"""The studies of issue 27's "converged by default", each run once as a user runs it (the command line, a local
Dask cluster of 2 workers on this 2-core machine): the shipped thesis-tolerances study at N = 1024 (first and total
order, all 18 parameters), the second-order study at N = 256, and the design study's full 2,916 designs.

Half an hour of CPU: not in ``make bench``'s default set; run it alone, under the machine's heavy-job lock::

    flock /work/locks/heavy.lock python -m benchmarks bench_converged --json

Figures: wall time per study (goal <= 600 s for the first two) and the CPU seconds it took, how many metrics the
convergence check passed (no Sobol S1 or ST moving by more than the spec's 0.05 between N and 2N), each metric's
largest move, and the machine's load average before and after (other jobs share the 2 cores: a loaded machine
runs longer). The second-order study's S1 and ST are the mean over both halves of its design
(``flexdigit.studies.sensitivity.averaged_sobol_indices``), the first-order study's SALib's own.
``FLEXDIGIT_BENCH_OUT`` keeps the studies' directories (default: a temporary directory, removed).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

STUDIES = (
    ("thesis-tolerances, N = 1024, first and total order", ["sensitivity", "thesis-tolerances", "--n", "1024"]),
    ("thesis-tolerances, N = 256, second order", ["sensitivity", "thesis-tolerances", "--n", "256", "--second-order"]),
    ("thesis-design, all 2916 designs", ["design", "thesis-design", "--samples", "0"]),
)


def _study(label: str, argv: list[str], out: Path) -> list[dict]:
    load = os.getloadavg()[0]
    cmd = [sys.executable, "-m", "flexdigit.cli", "study", *argv, "--out", str(out), "--workers", "2", "--force"]
    cpu_before = _children_cpu_s()
    start = time.perf_counter()
    done = subprocess.run([*cmd, "--no-progress", "--json"], capture_output=True, text=True)
    wall = time.perf_counter() - start
    cpu = _children_cpu_s() - cpu_before
    note = (
        f"load average {load:.2f} before, {os.getloadavg()[0]:.2f} after; CPU {cpu:.0f} s (the CLI and its "
        f"workers, user + system); exit {done.returncode}"
    )
    rows = [{"name": f"study {label}: wall time", "value": wall, "unit": "s", "goal": "<= 600", "note": note}]
    if done.returncode != 0:
        rows[0]["note"] += ": " + (done.stderr.strip().splitlines() or ["?"])[-1]
        return rows
    summary = json.loads(done.stdout)
    if argv[0] == "design":
        rows[0]["note"] += f"; {summary['candidates']} designs, {len(summary['pareto_front'])} on the front, " + (
            f"{len(summary['failed'])} failed"
        )
        return rows
    conv = {m: e.get("convergence", {}) for m, e in summary["metrics"].items()}
    passed = [m for m, c in conv.items() if c.get("converged")]
    moves = ", ".join(f"{m} {c.get('max_change', float('nan')):.3f}" for m, c in conv.items())
    rows[0]["note"] += f"; {summary['evaluations']} evaluations"
    rows.append(
        {
            "name": f"study {label}: metrics converged",
            "value": len(passed),
            "unit": f"of {len(conv)}",
            "goal": f"{len(conv)}",
            "note": f"largest move of S1/ST between N and 2N: {moves}",
        }
    )
    return rows


def _children_cpu_s() -> float:
    """CPU seconds (user + system) of the finished child processes and theirs: the CLI and its Dask workers (a
    loaded machine stretches the wall time, not this)."""
    import resource

    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def run() -> list[dict]:
    keep = os.environ.get("FLEXDIGIT_BENCH_OUT")
    rows: list[dict] = []
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(keep) if keep else Path(tmp)
        base.mkdir(parents=True, exist_ok=True)
        for i, (label, argv) in enumerate(STUDIES):
            rows += _study(label, argv, base / f"study-{i}")
    return rows
