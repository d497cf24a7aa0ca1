"""Your digit beside the thesis rig (issue 24): the twin's real-time factor and its static load cases per second,
for the thesis rig (3 sections, 3 gauges) and the 8-gauge, 5-section, 0.5 m digit of ``tests/digits.py``, timed in
the same run.

- Real-time factor: the twin as ``flexdigit run`` drives it (the ``sim`` backend's 2 ms step, read every 20 ms
  serial frame, a command every 5th frame of a slow ramp over 30 commands from the straight one), 10 simulated
  seconds, best of 3 on fresh twins. The 0.5 m digit hangs tip down (tip up it buckles under its supports' weight,
  docs/digits.md), the thesis rig stands tip up as in the thesis; both with their cable.
- Static cases per second: 5,000 random load cases (one weight of 7.5-37.5 g anywhere along the digit, commands
  straight / +10 / +20), one batched :func:`~flexdigit.twin.twin.static_gauges_v` call, horizontal (chapters 6-7).
- The report of the 0.5 m digit: ``flexdigit reproduce --fast --params D.toml --workers 1`` (every chapter, one
  process), wall time of the command a user runs, interpreter start-up included.

``python -m benchmarks bench_digits``
"""

from __future__ import annotations

import time

import numpy as np

from benchmarks._common import FIVE_SECTIONS_EIGHT_GAUGES, realtime_factor

DIGITS = {"thesis rig (3 sections, 3 gauges)": ({}, "vertical"), "5 sections, 8 gauges, 0.5 m": (
    FIVE_SECTIONS_EIGHT_GAUGES, "hanging")}  # fmt: skip


def _params(description: dict):
    from flexdigit.params import RigParams

    return RigParams.from_dict(description)


def bench_static(description: dict, cases: int = 5_000) -> tuple:
    """Static load cases per second of a digit, one batched call; ``(rate, elapsed)``."""
    from flexdigit.twin.twin import static_gauges_v

    params = _params(description)
    rng = np.random.default_rng(0)
    length = params.geometry.digit_length_m
    masses = rng.choice([0.0075, 0.0125, 0.025, 0.0375], cases)
    positions = rng.uniform(0.1 * length, length, cases)
    commands = params.actuator.equilibrium_command + rng.choice([0, 10, 20], cases)
    static_gauges_v(masses[:10], positions[:10], commands[:10], params=params)  # warm the chain's cache
    start = time.perf_counter()
    static_gauges_v(masses, positions, commands, params=params, seed=0)
    elapsed = time.perf_counter() - start
    return cases / elapsed, elapsed


def speed_rows(digits: dict) -> list[dict]:
    """The twin's real-time factor, then its static load cases per second, of each ``name: (description,
    orientation)`` in ``digits``, timed in this run (shared with :mod:`benchmarks.bench_unequal`)."""
    rows = []
    for name, (description, orientation) in digits.items():
        factor, springs, elapsed = realtime_factor(description, orientation)
        rows.append(
            {
                "name": f"run twin real-time factor, {name}",
                "value": factor,
                "unit": "x",
                "goal": ">= 1 (the loop)",
                "note": f"2 ms step read each 20 ms frame, {orientation}; 10 s in {elapsed:.3f} s (best of 3), "
                f"{springs} springs",
            }
        )
    for name, (description, _) in digits.items():
        rate, elapsed = bench_static(description)
        rows.append(
            {
                "name": f"static load cases per second, {name}",
                "value": rate,
                "unit": "cases/s",
                "goal": "",
                "note": f"5000 cases (one weight, three commands) in {elapsed:.3f} s, batched, horizontal",
            }
        )
    return rows


def run() -> list[dict]:
    rows = speed_rows(DIGITS)
    wall, entries = bench_report(FIVE_SECTIONS_EIGHT_GAUGES)
    rows.append(
        {
            "name": "reproduce --fast --params, 5 sections, 8 gauges, 0.5 m",
            "value": wall,
            "unit": "s",
            "goal": "",
            "note": f"{entries} entries, every chapter in one process (--workers 1), exit 0",
        }
    )
    return rows


def bench_report(description: dict) -> tuple[float, int]:
    """Wall time (s) of ``flexdigit reproduce --fast --params`` on the digit, and its report's entries."""
    import json
    import subprocess
    import sys
    import tempfile
    from pathlib import Path

    import tomli_w

    folder = Path(tempfile.mkdtemp())
    (folder / "digit.toml").write_text(tomli_w.dumps(description))
    command = ["reproduce", "--fast", "--params", str(folder / "digit.toml"), "--out", str(folder / "report")]
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "flexdigit.cli", *command, "--workers", "1"], check=True)
    wall = time.perf_counter() - start
    return wall, len(json.loads((folder / "report" / "results.json").read_text())["entries"])
