"""The cost of a finer twin (issue 24, a description's ``[twin]`` table, ``flexdigit.twin.resolution``): the run
twin's real-time factor at the default resolution and at the ``[twin] max_cell_length_m`` that meets 0.1 % of the
elastica (docs/digits.md, "The twin's resolution"), timed as :func:`benchmarks._common.realtime_factor`
times them, the cells coming from the description (not passed); and what ``flexdigit params FILE``'s error
estimate costs (two static solves and, where the default misses 0.1 %, the search for the setting).

``python -m benchmarks resolution``
"""

from __future__ import annotations

from benchmarks._common import ONE_LONG_SECTION, best_of, realtime_factor

#: (name, description, orientation, the max_cell_length_m meeting 0.1 %: docs/digits.md's table)
DIGITS = (
    ("thesis rig", {}, "vertical", 0.014),
    ("one 0.39 m section", ONE_LONG_SECTION, "hanging", 0.018),
)


def run() -> list[dict]:
    from flexdigit.params import RigParams
    from flexdigit.twin.resolution import resolution_for, static_error

    rows = []
    for name, description, orientation, cell_m in DIGITS:
        fine = {**description, "twin": {"max_cell_length_m": cell_m}}
        for label, data in (("default", description), (f"[twin] max_cell_length_m = {cell_m}", fine)):
            factor, springs, elapsed = realtime_factor(data, orientation, None)
            error = static_error(RigParams.from_dict(data))
            rows.append(
                {
                    "name": f"run twin real-time factor, {name}, {label}",
                    "value": factor,
                    "unit": "x",
                    "goal": ">= 1 (the loop)",
                    "note": f"{springs} springs, {orientation}; 10 s in {elapsed:.3f} s (best of 3); static error "
                    f"{100 * error.tip_load:.3g} % tip load, {100 * error.cable:.3g} % cable",
                }
            )
        params = RigParams.from_dict(description)
        static_error(params)  # the derived calibration, cached as in a command
        rows.append(
            {
                "name": f"static error estimate (params FILE), {name}",
                "value": 1e3 * best_of(lambda p=params: static_error(p), 5),
                "unit": "ms",
                "goal": "",
                "note": "two static solves, at the cells and at 3x (best of 5)",
            }
        )
        rows.append(
            {
                "name": f"setting for 0.1 % (resolution_for), {name}",
                "value": 1e3 * best_of(lambda p=params: resolution_for(p), 5),
                "unit": "ms",
                "goal": "",
                "note": "the h^2 law's guess, checked by the estimate (best of 5)",
            }
        )
    return rows
