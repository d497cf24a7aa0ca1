"""Records of a rig with known parameters: a twin with a perturbed calibration, written as a user's files.

For trying ``flexdigit calibrate`` without a rig, and for checking it: the "rig" is the twin with issue 11's
perturbation of the packaged calibration (housing stiffness +15 %, strip damping x2, channel gains +10 % / -10 % /
+10 %), and :func:`make_records` writes its release tests, actuation sweep, deflection table and actuated-rest
readings with a plain ``csv`` writer in layouts flexdigit does not write itself (millivolts and milliseconds under
``sgN`` names, a ``;``-separated sweep, a tab-separated deflection table, CRLF line ends). The answer is the
perturbed calibration.

Examples
--------
>>> import tempfile, pathlib
>>> from flexdigit.twin.calibration import packaged_calibration
>>> truth = perturbed(packaged_calibration())
>>> round(truth.strip_beta_s / packaged_calibration().strip_beta_s, 6)
2.0
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flexdigit._io import atomic_write
from flexdigit._repr import summary
from flexdigit.params import RigParams
from flexdigit.twin import records as ex
from flexdigit.twin.calibration import Calibration
from flexdigit.twin.twin import Twin

__all__ = [
    "GAIN_FACTORS",
    "RELEASE",
    "DEFLECTION_RESOLUTION_MM",
    "DEFLECTION_COMMANDS",
    "ACTUATED_COMMAND",
    "ACTUATED_READINGS",
    "perturbed",
    "write_csv",
    "RigRecords",
    "make_records",
]

GAIN_FACTORS = (1.10, 0.90, 1.10)
#: Release tests as the report runs them: 30 s bare (time constant 1/(zeta wn) = 20 s at the doubled damping),
#: 8 s housed, at 500 Hz
RELEASE = {"bare": (False, 30.0), "housed": (True, 8.0)}
#: Deflections read like a camera's (0.1 mm), at every fifth command over the operating range
DEFLECTION_RESOLUTION_MM = 0.1
DEFLECTION_COMMANDS = tuple(range(8, 44, 5))
#: Tapped readings of the unloaded digit held at command 30
ACTUATED_COMMAND = 30
ACTUATED_READINGS = 400


def perturbed(base: Calibration) -> Calibration:
    """``base`` with issue 11's perturbation: housing stiffness +15 %, strip damping x2, gains +-10 %."""
    return base.replace(
        housing_ei_n_m2=tuple(1.15 * v for v in base.housing_ei_n_m2),
        strip_beta_s=2.0 * base.strip_beta_s,
        channel_gain=tuple(f * g for f, g in zip(GAIN_FACTORS, base.channel_gain, strict=True)),
    )


def write_csv(path: Path, header, rows, delimiter=",", decimal=".") -> Path:
    """A table as a spreadsheet would export it (CRLF line ends, ``repr`` floats with the given decimal mark)."""

    def cell(v):
        if isinstance(v, float | np.floating):
            text = repr(float(v))
            return text.replace(".", decimal) if decimal != "." else text
        return str(v)

    with atomic_write(path, "w", force=True, newline="") as fh:  # synthetic records are made again at will
        writer = csv.writer(fh, delimiter=delimiter, lineterminator="\r\n")
        writer.writerow(header)
        writer.writerows([[cell(v) for v in row] for row in rows])
    return path


@dataclass
class RigRecords:
    """The files :func:`make_records` wrote (``bare``, ``housed``, ``sweep``, ``deflections``, ``actuated``), the
    calibration that made them and the seed of each."""

    truth: Calibration
    files: dict[str, Path]
    seeds: dict[str, int]

    def __repr__(self) -> str:
        return summary(self, files=list(self.files), seeds=list(self.seeds.values()))


def make_records(folder: Path, truth: Calibration, seed: int = 4) -> RigRecords:
    """The perturbed rig's release tests, sweep, deflection table and actuated-rest readings as files."""
    params = RigParams()
    files, seeds = {}, {}
    for k, (name, (housing, duration)) in enumerate(RELEASE.items()):
        seeds[name] = seed + k
        rec = ex.release_test(
            housing=housing, duration_s=duration, sample_rate_hz=500, calibration=truth, seed=seeds[name]
        )
        columns = [rec.column("time_s") * 1e3] + [rec.column(f"gauge{g}_v") * 1e3 for g in (1, 2, 3)]
        files[name] = write_csv(
            folder / f"release_{name}.csv", ["time_ms", "sg1_mv", "sg2_mv", "sg3_mv"], zip(*columns, strict=True)
        )
    seeds["sweep"] = seed + 2
    sweep = ex.actuation_sweep(range(8, 44), settle_s=2.5, samples=12, calibration=truth, seed=seeds["sweep"])
    columns = [sweep.column("command").astype(int)] + [sweep.column(f"gauge{g}_v") for g in (1, 2, 3)]
    files["sweep"] = write_csv(
        folder / "sweep.csv",
        ["command", "gauge1_v", "gauge2_v", "gauge3_v"],
        zip(*columns, strict=True),
        delimiter=";",
    )
    rows = []
    for command in DEFLECTION_COMMANDS:
        y_mm = Twin(params, truth, command=command).deflection_m(params.geometry.gauge_positions_m) * 1e3
        rows.append(
            [command] + [float(np.round(v / DEFLECTION_RESOLUTION_MM) * DEFLECTION_RESOLUTION_MM) for v in y_mm]
        )
    header = ["command", "y1_mm", "y2_mm", "y3_mm"]
    files["deflections"] = write_csv(folder / "deflections.tsv", header, rows, delimiter="\t")
    seeds["actuated"] = seed + 3
    twin = Twin(params, truth, seed=seeds["actuated"], orientation="horizontal", command=ACTUATED_COMMAND)
    rows = []
    for _ in range(ACTUATED_READINGS):
        twin.advance(0.02)
        twin.disturb()  # a tap: the cable settles afresh in its guides
        rows.append([ACTUATED_COMMAND] + [float(v) for v in twin.read()[0]])
    files["actuated"] = write_csv(folder / "actuated.csv", ["command", "gauge1_v", "gauge2_v", "gauge3_v"], rows)
    return RigRecords(truth, files, seeds)
