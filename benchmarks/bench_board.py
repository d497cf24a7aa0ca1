"""The controller on the board (issue 25): cycles of one control update on the emulated ATmega328P, the shortest
period that leaves half the CPU idle, the servo pulse's resolution, and the 30 deg step on the board against
flexdigit's Python loop on the twin.

- ``update cycles``: the largest width of the pulse the firmware raises on PD7 around ``fd_ctrl_update`` (simavr
  counts cycles exactly), over a run of setpoint steps that also saturates the command both ways (30, 90, -40,
  10 deg over 4 s at 2 ms: 2000 updates). Observed worst case, not a static bound: avr-gcc's soft float and
  64-bit multiply take data-dependent time.
- ``idle``: the share of the board's cycles its CPU sleeps (the firmware sleeps whenever it has nothing to do; the
  harness counts the slept cycles) over 1 s of a 30 deg step held by the loop on the board, at each period dividing
  the servo's 20 ms frame, float and fixed point; beside it, the same image with the host commanding (no update).
  Everything the board does counts: the update, the map, the interrupts, formatting and sending the stream's lines.
- ``shortest period``: the smallest of those periods whose measured idle share is >= 50 %.
- ``step``: settling (2 %), overshoot and steady-state error of the twin's true rotation, the loop on the board
  (hil://) against ``flexdigit run --backend "sim?servo_drive=timer"`` (same design, period and rotation map, its
  twin's servo driven as the board's Timer1 drives it): the like-for-like reference. Typical figures over
  STEP_SEEDS noise seeds, as tests/firmware/test_board.py compares them: the median settling time (bimodal by
  seed: a peak near the 2 % band), the mean overshoot and steady-state error. At 20 ms, 5 ms and SHORTEST_SUSTAINED.

Needs the AVR toolchain and libsimavr (``make avr``); the images are built as ``make firmware`` builds them.
"""

from __future__ import annotations

import io
import json
import os
import subprocess
import sys
import tempfile
from contextlib import redirect_stdout
from pathlib import Path

FIRMWARE = Path(__file__).resolve().parents[1] / "firmware"
F_CPU_HZ = 16e6
PERIODS_S = (0.001, 0.002, 0.004, 0.005, 0.010, 0.020)
STEP_SEEDS = range(8)
#: The shortest period the board sustains, (s, format): the shortest dividing the 20 ms frame at which each
#: period's update runs in its period with idle to spare (the idle rows: ~31 % at 2 ms; at 1 ms 1-2.5 %, while
#: formatting one stream line takes ~1.3 ms of CPU, longer than the period). The step comparison's third period.
SHORTEST_SUSTAINED = (0.002, "fixed")
#: The idle share the issue asks the shortest period to leave.
IDLE_GOAL = 0.5
STEP_KEYS = (("settling_time_s", "s", "median"), ("overshoot_percent", "%", "mean"), ("final_error_deg", "deg", "mean"))


def _rotation_map(root: Path) -> Path:
    """The map every image is exported with and the Python loop runs on (the export's default: the twin, seed 0)."""
    from flexdigit.rig.base import open_rig
    from flexdigit.rig.rotation import calibrate_rotation, save_rotation_map

    path = root / "rotation-map.json"
    if not path.exists():
        with open_rig("sim") as rig:
            save_rotation_map(calibrate_rotation(rig), path)
    return path


def _build(root: Path, period_s: float, fmt: str) -> Path:
    import flexdigit

    out = root / f"{fmt}-{int(round(period_s * 1e6))}"
    src = str(Path(flexdigit.__file__).resolve().parents[1])
    env = dict(os.environ, PYTHONPATH=src + os.pathsep + os.environ.get("PYTHONPATH", ""))
    subprocess.run(
        ["make", "-s", "-C", str(FIRMWARE), f"BUILD={out}", f"PERIOD_S={period_s}", f"FORMAT={fmt}",
         f"MAP={_rotation_map(root)}", f"FLEXDIGIT={sys.executable} -m flexdigit.cli"],
        check=True, env=env, capture_output=True,
    )  # fmt: skip
    return out / "flexdigit_board.elf"


def _update_cycles(elf: Path) -> int:
    from flexdigit.rig.base import open_rig

    rig = open_rig(f"hil://{elf}", mode="board", setpoint_deg=30.0)
    try:
        for setpoint in (30.0, 90.0, -40.0, 10.0):
            rig.set_setpoint(setpoint)
            rig.wait(1.0)
        return rig.exec_max_cycles
    finally:
        rig.close()


def _idle_shares(elf: Path) -> dict[str, float]:
    """The share of cycles the board's CPU sleeps over 1 s (after 0.2 s), with the host commanding (``host``: no
    update runs) and with the loop on the board holding a 30 deg step (``board``)."""
    from flexdigit.rig.base import open_rig

    shares = {}
    for mode in ("host", "board"):
        rig = open_rig(f"hil://{elf}", mode=mode, setpoint_deg=30.0)
        try:
            rig.wait(0.2)
            cycles, idle = rig.board_cycles, rig.idle_cycles
            rig.wait(1.0)
            shares[mode] = (rig.idle_cycles - idle) / (rig.board_cycles - cycles)
        finally:
            rig.close()
    return shares


def _step(elf: Path, seed: int) -> dict:
    from flexdigit.rig.backends.hil_backend import run_on_board
    from flexdigit.rig.base import open_rig
    from flexdigit.rig.step_test import step_metrics

    rig = open_rig(f"hil://{elf}?seed={seed}", mode="board", setpoint_deg=30.0)
    try:
        run = run_on_board(rig, 30.0, 3.0)
    finally:
        rig.close()
    return step_metrics(run.time_s, run.true_rotation_deg, 30.0, 0.0, 1.735).to_dict()


def _python_step(period_s: float, seed: int, rotation_map: Path) -> dict:
    """The Python loop on the twin, its servo driven as the board drives it (the like-for-like reference)."""
    from flexdigit.cli import main

    buf = io.StringIO()
    with redirect_stdout(buf):
        main(["run", "--backend", f"sim?seed={seed}&servo_drive=timer", "--setpoint-deg", "30", "--duration", "3",
              "--period", str(period_s), "--rotation-map", str(rotation_map), "--json"])  # fmt: skip
    return json.loads(buf.getvalue())["step_metrics"]["true"]


def _typical(figures: list[dict]) -> dict:
    import numpy as np

    return {key: float(getattr(np, how)([f[key] for f in figures])) for key, _, how in STEP_KEYS}


def run() -> list[dict]:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        for fmt in ("float", "fixed"):
            cycles = _update_cycles(_build(root, 0.002, fmt))
            rows.append({"name": f"board: one control update, {fmt} (20 ms design at 2 ms, 4 states)",
                         "value": cycles, "unit": "cycles", "goal": "",
                         "note": f"{cycles / F_CPU_HZ * 1e6:.0f} us at 16 MHz; worst observed over 2000 updates "
                                 "incl. saturation both ways (simavr)"})  # fmt: skip
            idle = {}
            for period_s in PERIODS_S:
                shares = _idle_shares(_build(root, period_s, fmt))
                idle[period_s] = shares["board"]
                rows.append({"name": f"board: CPU idle, loop on the board at {period_s * 1e3:g} ms ({fmt})",
                             "value": shares["board"] * 100, "unit": "%", "goal": "",
                             "note": f"host commanding (no update): {shares['host'] * 100:.1f} %; slept cycles over "
                                     "1 s of a 30 deg step (simavr)"})  # fmt: skip
            shortest = min((p for p in PERIODS_S if idle[p] >= IDLE_GOAL), default=float("nan"))
            rows.append({"name": f"board: shortest period with >= 50 % idle, {fmt}", "value": shortest * 1e3,
                         "unit": "ms", "goal": "",
                         "note": "periods dividing the servo's 20 ms frame; the CPU's slept cycles, all its work "
                                 "counted"})  # fmt: skip
        rows.append({"name": "board: servo command step (Timer1, 0.5 us ticks over 1-2 ms)", "value": 2000 / 254,
                     "unit": "x finer", "goal": "",
                     "note": "2000 pulse widths over the range against the serial board's 254 commands"})  # fmt: skip
        for period_s, fmt in ((0.020, "float"), (0.005, "float"), SHORTEST_SUSTAINED):
            elf = _build(root, period_s, fmt)
            board = _typical([_step(elf, seed) for seed in STEP_SEEDS])
            python = _typical([_python_step(period_s, seed, _rotation_map(root)) for seed in STEP_SEEDS])
            for key, unit, how in STEP_KEYS:
                rows.append({"name": f"board vs python loop, {period_s * 1e3:g} ms ({fmt}): {key}",
                             "value": board[key], "unit": unit, "goal": "",
                             "note": f"python loop on the twin: {python[key]:.4g}; {how} over "
                                     f"{len(STEP_SEEDS)} seeds",
                             "period_ms": period_s * 1e3, "format": fmt, "figure": key,
                             "reference": python[key]})  # fmt: skip
    return rows


#: The issue's criteria, board against the Python loop, per figure: (kind, tolerance).
CRITERIA = {
    "settling_time_s": ("fraction", 0.05),
    "overshoot_percent": ("points", 1.0),
    "final_error_deg": ("abs", 0.2),
}


def markdown(rows: list[dict]) -> str:
    """The step table and the timing figures of docs/board.md, from :func:`run`'s rows (or their JSON)."""
    lines = ["| period (format) | figure | board (hil://) | Python loop | difference | criterion | met |",
             "|---|---|---|---|---|---|---|"]  # fmt: skip
    for row in rows:
        if "figure" not in row:
            continue
        kind, tolerance = CRITERIA[row["figure"]]
        diff = row["value"] - row["reference"]
        if kind == "fraction":
            shown, limit, met = (
                f"{diff / row['reference'] * 100:+.1f} %",
                f"within {tolerance * 100:g} %",
                abs(diff) <= tolerance * row["reference"],
            )
        else:
            unit = "points" if kind == "points" else row["unit"]
            shown, limit, met = f"{diff:+.2f} {unit}", f"within {tolerance:g} {unit}", abs(diff) <= tolerance
        lines.append(f"| {row['period_ms']:g} ms ({row['format']}) | {row['figure']} | {row['value']:.3f} | "
                     f"{row['reference']:.3f} | {shown} | {limit} | {'yes' if met else 'NO'} |")  # fmt: skip
    lines += ["", "| figure | value | unit | note |", "|---|---|---|---|"]
    lines += [f"| {r['name']} | {_shown(r)} | {r['unit']} | {r['note']} |" for r in rows if "figure" not in r]
    return "\n".join(lines)


def _shown(row: dict) -> str:
    """A figure as the table shows it: cycles whole (51008, not 5.101e+04), the rest to 4 significant digits."""
    return f"{row['value']:.0f}" if row["unit"] == "cycles" else f"{row['value']:.4g}"


if __name__ == "__main__":  # python benchmarks/bench_board.py [--markdown] [ROWS.json]
    if "--markdown" in sys.argv:
        given = [a for a in sys.argv[1:] if a != "--markdown"]
        print(markdown(json.loads(Path(given[0]).read_text()) if given else run()))
    else:
        print(json.dumps(run(), indent=2))
