"""A digit of issue 24 on the board (``python -m benchmarks digitboard``): its image built for it (``make firmware
PARAMS=D.toml``), its control update's cycles on the emulated ATmega328P, the time from the control tick to the
command being ready (its G conversions and the update) against the pulse's delay, and its 30 deg step with the loop
on the board (the twin's true rotation, a few noise seeds).

Digits: tests/digits.py's ``six-gauges-geared`` (6 gauges: the most the Uno reads) and ``four-sections-two-cables``
(4 gauges, a cable pair: +30 and -30 deg). The update's cycles are the widest PD7 pulse the firmware raises around
``fd_ctrl_update`` over setpoint steps that saturate the command both ways (observed worst case: avr-gcc's soft
float takes data-dependent time). The ready time adds the tick's G conversions (13 ADC clocks of 8 us each: 104 us,
ATmega328P datasheet 24.4) and the map; the rotation map's ~2G float operations are not in the PD7 pulse, so the
margin is given against the pulse's delay less the conversions and the update.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
from pathlib import Path

FIRMWARE = Path(__file__).resolve().parents[1] / "firmware"
F_CPU_HZ = 16e6
#: One ADC conversion at the firmware's 125 kHz ADC clock: 13 clocks (datasheet 24.4).
CONVERSION_S = 13 / 125e3
DIGITS = (("six-gauges-geared", (30.0,)), ("four-sections-two-cables", (30.0, -30.0)))
STEP_SEEDS = range(3)


def _build(root: Path, name: str) -> tuple[Path, Path]:
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    import flexdigit
    from digits import write_digit

    params = write_digit(name, root)
    out = root / name
    src = str(Path(flexdigit.__file__).resolve().parents[1])
    env = dict(os.environ, PYTHONPATH=src + os.pathsep + os.environ.get("PYTHONPATH", ""))
    subprocess.run(
        ["make", "-s", "-C", str(FIRMWARE), f"BUILD={out}", f"PARAMS={params}",
         f"FLEXDIGIT={sys.executable} -m flexdigit.cli"],
        check=True, env=env, capture_output=True,
    )  # fmt: skip
    return out / "flexdigit_board.elf", params


def _twin_options(params) -> dict:
    from flexdigit.twin.digit_calibration import twin_calibration

    return {"calibration": twin_calibration(params)}


def _update_cycles(elf: Path, params, setpoints) -> int:
    from flexdigit.rig.base import open_rig

    rig = open_rig(f"hil://{elf}", params, mode="board", setpoint_deg=setpoints[0], **_twin_options(params))
    try:
        for setpoint in (*setpoints, 90.0, -60.0, 10.0):
            rig.set_setpoint(setpoint)
            rig.wait(1.0)
        return rig.exec_max_cycles
    finally:
        rig.close()


def _step(elf: Path, params, setpoint: float, seed: int) -> dict:
    from flexdigit.rig.step_test import board_step_test

    run = board_step_test(f"hil://{elf}", setpoint, 2.0, seed=seed, params=params, twin_options=_twin_options(params))
    return {**run["step_metrics"]["true"], "final_deg": run["true_final_rotation_deg"]}


def run() -> list[dict]:
    import numpy as np

    from flexdigit.params import load_params

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        for name, setpoints in DIGITS:
            elf, path = _build(root, name)
            params = load_params(path)
            gauges = len(params.geometry.gauge_positions_m)
            header = (elf.parent / "ctrl.h").read_text()
            states = int(header.split("_NSTATES ")[1].split()[0])
            cycles = _update_cycles(elf, params, setpoints)
            ready_s = gauges * CONVERSION_S + cycles / F_CPU_HZ
            rows.append({"name": f"digit board: one control update, {name} ({states} states, float)",
                         "value": cycles, "unit": "cycles", "goal": "",
                         "note": f"{cycles / F_CPU_HZ * 1e6:.0f} us at 16 MHz; worst observed (simavr)"})  # fmt: skip
            rows.append({"name": f"digit board: tick to command ready, {name} ({gauges} gauges)",
                         "value": ready_s * 1e3, "unit": "ms", "goal": "< 5 ms",
                         "note": f"{gauges} conversions of 104 us + the update; the pulse starts 5 ms after the "
                                 "tick (make firmware PARAMS=...: PULSE_DELAY_MS=5)"})  # fmt: skip
            for setpoint in setpoints:
                figures = [_step(elf, params, setpoint, seed) for seed in STEP_SEEDS]
                for key, unit, how, goal in (
                    ("settling_time_s", "s", "max", "< 1 s"),
                    ("overshoot_percent", "%", "max", "< 10 %"),
                    ("final_deg", "deg", "mean", f"{setpoint:+g} within 2 %"),
                ):
                    value = float(getattr(np, how)([f[key] for f in figures]))
                    rows.append({"name": f"digit board: {name} {setpoint:+g} deg step, {key}", "value": value,
                                 "unit": unit, "goal": goal,
                                 "note": f"{how} over {len(STEP_SEEDS)} seeds; the twin's true rotation, loop on "
                                         "the board (hil://, 20 ms)"})  # fmt: skip
    return rows


if __name__ == "__main__":
    import json

    print(json.dumps(run(), indent=2))
