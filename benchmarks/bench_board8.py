"""A digit of 8 gauges on the board (``python -m benchmarks board8``, issue 24 item 5): the ATmega328P's ADC6 and
ADC7 (a Nano or Pro Mini; simavr emulates them), the cost of its control update, the CPU left at the shortest
periods its image can run, and its 30 deg step on the board against flexdigit's Python loop on the twin.

The digit: tests/digits.py's ``five-sections-eight-gauges`` (five 90 mm sections, 0.5 m, 8 full bridges; its 20 ms
design, 29 controller states with the setpoint shaper's delay line). Measured as benchmarks/bench_board.py measures
the thesis rig's images (its ``markdown`` renders these rows too):

- ``update cycles``: the widest PD7 pulse around ``fd_ctrl_update`` over setpoint steps that saturate the command
  both ways (30, 90, -60, 10 deg, 1 s each at 20 ms), float32 and fixed point (observed worst case);
- ``idle``: the share of the board's cycles its CPU sleeps over 1 s of a 30 deg step held by the loop on the board,
  at each period dividing the servo's 20 ms frame that the image can run: the servo pulse starts PULSE_DELAY_MS
  (5 ms) after the control tick, once the tick's 8 conversions (0.83 ms) and the update (~3.2 ms) are done, and
  must start inside the period, so 10 and 20 ms; beside it, the same image with the host commanding;
- ``step``: the loop on the board (hil://) against ``flexdigit run --params D --backend
  "sim?servo_drive=timer&pulse_delay_ms=5"`` (same design, period and rotation map, its servo driven as the image's
  Timer1 drives it), typical figures over STEP_SEEDS as tests/firmware/test_eight_gauges.py compares them.

Needs the AVR toolchain and libsimavr (``make avr``).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path

from benchmarks.bench_board import STEP_KEYS, _typical

FIRMWARE = Path(__file__).resolve().parents[1] / "firmware"
TESTS = Path(__file__).resolve().parents[1] / "tests"
F_CPU_HZ = 16e6
DIGIT = "five-sections-eight-gauges"
#: The periods dividing the servo's 20 ms frame longer than the image's 5 ms pulse delay.
PERIODS_S = (0.010, 0.020)
PULSE_DELAY_MS = 5
STEP_SEEDS = range(8)
IDLE_GOAL = 0.5


def _digit(root: Path) -> tuple[Path, Path]:
    """The digit's file and its rotation map (calibrated on its twin, mounted as the export mounts it)."""
    sys.path.insert(0, str(TESTS))
    from digits import write_digit
    from flexdigit.control.design20ms import digit_mount
    from flexdigit.params import load_params
    from flexdigit.rig.base import open_rig
    from flexdigit.rig.rotation import calibrate_rotation, save_rotation_map
    from flexdigit.twin.digit_calibration import twin_calibration

    params, rotation_map = root / f"{DIGIT}.toml", root / "rotation-map.json"
    if not rotation_map.exists():
        write_digit(DIGIT, root)
        p = load_params(params)
        calibration = twin_calibration(p)
        with open_rig("sim", p, calibration=calibration, orientation=digit_mount(p, calibration)) as rig:
            save_rotation_map(calibrate_rotation(rig), rotation_map)
    return params, rotation_map


def _build(root: Path, period_s: float, fmt: str) -> Path:
    import flexdigit

    params, rotation_map = _digit(root)
    out = root / f"{fmt}-{int(round(period_s * 1e6))}"
    src = str(Path(flexdigit.__file__).resolve().parents[1])
    env = dict(os.environ, PYTHONPATH=src + os.pathsep + os.environ.get("PYTHONPATH", ""))
    subprocess.run(
        ["make", "-s", "-C", str(FIRMWARE), f"BUILD={out}", f"PERIOD_S={period_s}", f"FORMAT={fmt}",
         f"PARAMS={params}", f"MAP={rotation_map}", f"FLEXDIGIT={sys.executable} -m flexdigit.cli"],
        check=True, env=env, capture_output=True,
    )  # fmt: skip
    return out / "flexdigit_board.elf"


def _open(root: Path, elf: Path, **options):
    from flexdigit.params import load_params
    from flexdigit.rig.base import open_rig
    from flexdigit.twin.digit_calibration import twin_calibration

    p = load_params(_digit(root)[0])
    return open_rig(f"hil://{elf}", p, calibration=twin_calibration(p), **options)


def _update_cycles(root: Path, elf: Path) -> int:
    rig = _open(root, elf, mode="board", setpoint_deg=30.0)
    try:
        for setpoint in (30.0, 90.0, -60.0, 10.0):
            rig.set_setpoint(setpoint)
            rig.wait(1.0)
        return rig.exec_max_cycles
    finally:
        rig.close()


def _idle_shares(root: Path, elf: Path) -> dict[str, float]:
    shares = {}
    for mode in ("host", "board"):
        rig = _open(root, elf, mode=mode, setpoint_deg=30.0)
        try:
            rig.wait(0.2)
            cycles, idle = rig.board_cycles, rig.idle_cycles
            rig.wait(1.0)
            shares[mode] = (rig.idle_cycles - idle) / (rig.board_cycles - cycles)
        finally:
            rig.close()
    return shares


def _steps(root: Path, elf: Path, seed: int) -> tuple[dict, dict]:
    """One seed: the loop on the board and the Python loop on the twin (the test's helpers' CLI runs)."""
    sys.path.insert(0, str(TESTS))
    from firmware.board_helpers import board_step, python_step

    params, rotation_map = _digit(root)
    return board_step(elf, seed, params), python_step(0.020, seed, rotation_map, params, PULSE_DELAY_MS)


def run() -> list[dict]:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        for fmt in ("float", "fixed"):
            cycles = _update_cycles(root, _build(root, 0.020, fmt))
            rows.append({"name": f"board, 8 gauges: one control update, {fmt} (20 ms digit design, 29 states)",
                         "value": cycles, "unit": "cycles", "goal": "",
                         "note": f"{cycles / F_CPU_HZ * 1e3:.2f} ms at 16 MHz; worst observed over 4 s of steps "
                                 "incl. saturation both ways (simavr)"})  # fmt: skip
            idle = {}
            for period_s in PERIODS_S:
                shares = _idle_shares(root, _build(root, period_s, fmt))
                idle[period_s] = shares["board"]
                rows.append({"name": f"board, 8 gauges: CPU idle, loop on the board at {period_s * 1e3:g} ms ({fmt})",
                             "value": shares["board"] * 100, "unit": "%", "goal": "",
                             "note": f"host commanding (no update): {shares['host'] * 100:.1f} %; slept cycles over "
                                     "1 s of a 30 deg step (simavr)"})  # fmt: skip
            shortest = min((p for p in PERIODS_S if idle[p] >= IDLE_GOAL), default=float("nan"))
            rows.append({"name": f"board, 8 gauges: shortest period with >= 50 % idle, {fmt}",
                         "value": shortest * 1e3, "unit": "ms", "goal": "",
                         "note": f"periods dividing 20 ms past the {PULSE_DELAY_MS} ms pulse delay: 10 and 20 ms; "
                                 "the CPU's slept cycles, all its work counted"})  # fmt: skip
        elf = _build(root, 0.020, "float")
        pairs = [_steps(root, elf, seed) for seed in STEP_SEEDS]
        board, python = _typical([b for b, _ in pairs]), _typical([p for _, p in pairs])
        for key, unit, how in STEP_KEYS:
            rows.append({"name": f"board vs python loop, 8 gauges, 20 ms (float): {key}",
                         "value": board[key], "unit": unit, "goal": "",
                         "note": f"python loop on the twin: {python[key]:.4g}; {how} over {len(STEP_SEEDS)} seeds",
                         "period_ms": 20.0, "format": "float, 8 gauges", "figure": key,
                         "reference": python[key]})  # fmt: skip
    return rows


if __name__ == "__main__":  # python benchmarks/bench_board8.py [--markdown] [ROWS.json]
    import json

    from benchmarks.bench_board import markdown

    if "--markdown" in sys.argv:
        given = [a for a in sys.argv[1:] if a != "--markdown"]
        print(markdown(json.loads(Path(given[0]).read_text()) if given else run()))
    else:
        print(json.dumps(run(), indent=2))
