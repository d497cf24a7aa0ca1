"""The cost of the twin's default resolution (issue 24, ``flexdigit.twin.digit.default_cells``): the run twin's
real-time factor of long digits at the old 3 cells per section and at the default (cells no longer than
``MAX_CELL_LENGTH_M``), timed in the same run as :func:`benchmarks.bench_digits.bench_realtime` times them (2 ms
step, read every 20 ms frame, a slow ramp, 10 simulated s, best of 3; the long digits hang tip down).

- One 0.39 m section (the campaign's digit 2, ``tests/digit_campaign.py``, written out: benchmarks do not import
  the tests): 3 springs before, 15 now.
- 5 sections of 90 mm, 8 gauges, 0.5 m (``tests/digits.py``): 15 springs before, 25 now.
- The thesis rig: 9 springs either way (the same chain).

``python -m benchmarks bench_cells``
"""

from __future__ import annotations

import time

from benchmarks._common import FIVE_SECTIONS_EIGHT_GAUGES, ONE_LONG_SECTION

DIGITS = {
    "thesis rig": ({}, "vertical"),
    "one 0.39 m section": (ONE_LONG_SECTION, "hanging"),
    "5 sections, 8 gauges, 0.5 m": (FIVE_SECTIONS_EIGHT_GAUGES, "hanging"),
}


def realtime_factor(description: dict, orientation: str, cells, sim_seconds: float = 10.0, repeats: int = 3):
    """``(factor, springs, elapsed)`` of the run twin at ``cells`` per section (None: the default)."""
    from flexdigit.params import RigParams
    from flexdigit.rig.backends.sim_backend import DEFAULT_TWIN_DT_S
    from flexdigit.twin.twin import Twin

    params = RigParams.from_dict(description)
    straight = params.actuator.equilibrium_command
    ramp = list(range(straight, straight + 31)) + list(range(straight + 29, straight, -1))

    def once() -> tuple[float, int]:
        twin = Twin(params, seed=0, orientation=orientation, dt_s=DEFAULT_TWIN_DT_S, cells_per_section=cells)
        frame = params.actuator.serial_period_s
        start = time.perf_counter()
        for k in range(int(round(sim_seconds / frame))):
            if k % 5 == 0:
                twin.command(ramp[(k // 5) % len(ramp)])
            twin.advance(frame)
            twin.read()
        return time.perf_counter() - start, twin.chain.n

    elapsed, springs = min(once() for _ in range(repeats))
    return sim_seconds / elapsed, springs, elapsed


def run() -> list[dict]:
    rows = []
    for name, (description, orientation) in DIGITS.items():
        for label, cells in (("3 cells per section (before)", 3), ("default cells (now)", None)):
            factor, springs, elapsed = realtime_factor(description, orientation, cells)
            rows.append(
                {
                    "name": f"run twin real-time factor, {name}, {label}",
                    "value": factor,
                    "unit": "x",
                    "goal": ">= 1 (the loop)",
                    "note": f"{springs} springs, {orientation}; 10 s in {elapsed:.3f} s (best of 3)",
                }
            )
    return rows
