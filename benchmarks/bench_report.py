"""``flexdigit reproduce``: the whole report on the twin (goal <= 60 s on the 2-core machine), and each chapter.

One full run (not ``--fast``) with the default workers (one process per core; chapters are handed out longest
first), through the command a user runs, so interpreter start-up and imports count. Each chapter's seconds are
its own build time inside its worker: they add up to more than the wall time, since chapters run side by side.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

GOAL_S = 60.0


def run() -> list[dict]:
    out = Path(tempfile.mkdtemp()) / "report"
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "flexdigit.cli", "reproduce", "--out", str(out)], check=True)
    wall = time.perf_counter() - start
    document = json.loads((out / "results.json").read_text())
    rows = [
        {
            "name": f"flexdigit reproduce, full report ({len(document['entries'])} entries)",
            "value": wall,
            "unit": "s",
            "goal": f"<= {GOAL_S:g} s",
            "note": "wall time of the command, default workers",
        }
    ]
    cpu = sum(c["cpu_seconds"] for c in document["chapters"])
    rows[0]["note"] += f"; {cpu:.0f} s of CPU in the chapters (60 s on 2 cores needs about 115)"
    for chapter in document["chapters"]:
        rows.append(
            {
                "name": f"  chapter {chapter['slug']}",
                "value": chapter["seconds"],
                "unit": "s",
                "goal": "",
                "note": f"its build time in its worker; {chapter['cpu_seconds']:.1f} s of CPU",
            }
        )
    return rows
