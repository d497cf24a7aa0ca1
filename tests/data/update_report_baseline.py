"""Rewrite tests/data/report_fast_baseline.json from ``flexdigit reproduce --fast`` (seed 0) of this checkout.

The chapter tests check that every entry of the fast report is as the baseline has it (``oracles.
assert_entries_unchanged``): a refactor must leave the numbers alone. When a change is meant to move them (a new
calibration, a better fit), run this (a few minutes, under the heavy lock), look at the diff of the baseline, and
commit it with the change that explains it::

    flock /work/locks/heavy.lock .venv/bin/python tests/data/update_report_baseline.py
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

BASELINE = Path(__file__).with_name("report_fast_baseline.json")


def main() -> int:
    from flexdigit.report.build import reproduce

    out = Path(tempfile.mkdtemp()) / "report"
    summary = reproduce(out, fast=True)
    if summary.failed:
        print(f"chapters failed, baseline not written: {sorted(summary.failed)}", file=sys.stderr)
        return 1
    document = json.loads((out / "results.json").read_text())
    baseline = {e["key"]: [e["status"], e["ours"], e["chapter"]] for e in document["entries"]}
    lines = [f"{json.dumps(k)}: {json.dumps(v)}" for k, v in sorted(baseline.items())]  # one entry a line: diffable
    BASELINE.write_text("{\n" + ",\n".join(lines) + "\n}\n")
    print(f"wrote {BASELINE}: {len(baseline)} entries")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
