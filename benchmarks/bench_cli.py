"""Start-up of the ``flexdigit`` command: ``--help`` (goal <= 0.3 s, issue 23), ``--version``, ``params`` and
``model`` (goal <= 0.5 s each).

Each is a fresh process (``python -m flexdigit.cli ...`` from this interpreter), best of 5: the figure a user
waits for. Sub-command modules only register their options; the libraries a command needs (python-control,
scipy, cvxpy, scikit-learn, matplotlib) are imported when it runs, and ``model`` needs none of them (the plant is
numpy polynomials, :mod:`flexdigit.models.polytf`). Also, for information, ``import control`` and
``import numpy`` alone in a fresh process: the floor of a command that needs them.
"""

from __future__ import annotations

import subprocess
import sys
import time

REPEATS = 5
GOAL_S = 0.5
#: ``flexdigit --help``: what every user waits for first (issue 23's "Done when": <= 0.3 s).
HELP_GOAL_S = 0.3


def _best_of(argv: list[str], repeats: int = REPEATS) -> float:
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        subprocess.run(argv, check=True, capture_output=True)
        best = min(best, time.perf_counter() - start)
    return best


def run() -> list[dict]:
    rows = []
    cli = [sys.executable, "-m", "flexdigit.cli"]
    for args in (["--help"], ["--version"], ["params"], ["model"], ["model", "--variant", "consistent", "--explain"]):
        rows.append(
            {
                "name": "flexdigit " + " ".join(args),
                "value": _best_of(cli + args),
                "unit": "s",
                "goal": f"<= {HELP_GOAL_S if args == ['--help'] else GOAL_S} s",
                "note": f"fresh process, best of {REPEATS}",
            }
        )
    for module in ("numpy", "control"):
        rows.append(
            {
                "name": f"python -c 'import {module}' (floor, for information)",
                "value": _best_of([sys.executable, "-c", f"import {module}"]),
                "unit": "s",
                "goal": "",
                "note": "",
            }
        )
    return rows
