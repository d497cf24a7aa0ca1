"""Issue 11 item 5: on twins that differ from the nominal one, a map calibrated against measured deflections holds
the true tip rotation within 2 % of a 30 deg setpoint.

The "rig" is a twin whose calibration is perturbed as the issue says (housing 30 % softer, support masses x1.5,
strip damping x0.3) and in ways of our choosing that a real rig differs by (channel gains, cable stiffness, a
stiffer base section). The "user" measures deflections with a ruler at the gauges (45, 135, 225 mm, as table 3.6)
and at the tip, read to 0.5 mm, on that digit at rest: computed from a fine model of it (21 springs per section:
a continuous strip; the twin's 3 per section are exact for the tip rotation but 11 % off for a deflection between
its springs). The map is fitted to the rotations those deflections give (``rotations_from_deflections``) and the
gauge readings of a sweep on the rig (settling detected), then the 20 ms loop runs a 30 deg step and the twin's
TRUE tip rotation is scored. The map calibrated on the nominal twin (what ``run`` did before) is run beside it:
it misses by up to 10 % where the channel gains differ.

Measured (seed 0): measured map 29.44-30.40 deg on every twin (2 % is 0.6 deg; one command is 1.7 deg, so the loop
can only land on the command whose rotation is nearest); nominal map 26.94 deg (gains x1.12), 28.62 (mixed gains).
The issue's 32-33.8 deg for the first three perturbations does not reproduce with the present map (the
Gauss-Markov map, commit a0bd467): those twins bend the same way per gauge volt as the nominal one (30.31-30.40).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from flexdigit.rig.backends.sim_backend import SimRig
from flexdigit.rig.rotation import calibrate_rotation
from flexdigit.rig.rotation_reference import read_reference
from flexdigit.rig.step_test import step_test
from flexdigit.twin.calibration import default_calibration, save_calibration
from flexdigit.twin.twin import Twin

pytestmark = pytest.mark.slow

SETPOINT_DEG = 30.0
#: the issue's criterion: the true rotation within 2 % of the setpoint
TOLERANCE_DEG = 0.02 * SETPOINT_DEG
POINTS_MM = (45, 135, 225, 270)
COMMANDS = tuple(range(8, 33, 3))


def _scaled(name: str, factor) -> tuple:
    cal = default_calibration()
    factors = np.broadcast_to(factor, (len(getattr(cal, name)),))
    return tuple(float(v * f) for v, f in zip(getattr(cal, name), factors, strict=True))


def perturbed(name: str):
    cal = default_calibration()
    return {
        "housing 30 % softer": lambda: cal.replace(housing_ei_n_m2=_scaled("housing_ei_n_m2", 0.7)),
        "support masses x1.5": lambda: cal.replace(support_mass_kg=_scaled("support_mass_kg", 1.5)),
        "strip damping x0.3": lambda: cal.replace(strip_beta_s=0.3 * cal.strip_beta_s),
        "channel gains x1.12": lambda: cal.replace(channel_gain=_scaled("channel_gain", 1.12)),
        "channel gains x0.9/1.1/1.05": lambda: cal.replace(channel_gain=_scaled("channel_gain", (0.9, 1.1, 1.05))),
        "cable stiffness x0.5": lambda: cal.replace(cable_stiffness_n_m=0.5 * cal.cable_stiffness_n_m),
        "base section x1.6 stiffer": lambda: cal.replace(housing_ei_n_m2=_scaled("housing_ei_n_m2", (1.6, 1, 1))),
    }[name]()


CASES = [
    "housing 30 % softer",
    "support masses x1.5",
    "strip damping x0.3",
    "channel gains x1.12",
    "channel gains x0.9/1.1/1.05",
    "cable stiffness x0.5",
    "base section x1.6 stiffer",
]


def ruler_file(tmp_path, calibration) -> str:
    """What a user with a ruler writes down: deflections at the gauges and the tip, to 0.5 mm, per command."""
    lines = ["command," + ",".join(f"deflection_mm_at_{p}mm" for p in POINTS_MM)]
    for command in COMMANDS:
        digit = Twin(calibration=calibration, command=command, cells_per_section=21)  # at rest at the command
        mm = np.round(digit.deflection_m(np.array(POINTS_MM) / 1000) * 2000) / 2
        lines.append(f"{command}," + ",".join(f"{v:g}" for v in mm))
    path = tmp_path / "ruler.csv"
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture(scope="module")
def nominal_map():
    return calibrate_rotation(SimRig(seed=1))  # what run did before: the nominal twin's map


@pytest.mark.parametrize("seed", [0, 3])
@pytest.mark.parametrize("case", CASES)
def test_measured_deflections_give_a_map_that_holds_the_setpoint(tmp_path, nominal_map, case, seed):
    cal = perturbed(case)
    reference = read_reference(ruler_file(tmp_path, cal))
    est = calibrate_rotation(SimRig(seed=seed + 1, calibration=cal), reference=reference)
    st = step_test(SimRig(seed=seed, calibration=cal), "digital20", step_deg=SETPOINT_DEG, estimator=est)
    assert st.result.ok
    assert st.metrics.bounded
    assert abs(st.metrics.final_error_deg) < TOLERANCE_DEG, case
    # the map's own claim: the uncertainty it states at the setpoint is small and covers its error
    assert est.uncertainty_deg(SETPOINT_DEG) < 0.3  # measured 0.19 deg
    # every sweep reading waited for the digit to settle, judged from the readings (1.4-3.0 s measured)
    assert all(0.5 < t < 10 for t in est.settle_time_s_)
    if case.startswith("channel gains"):
        # the nominal twin's map reads these gauges wrong: the loop ends more than a command away
        before = step_test(SimRig(seed=seed, calibration=cal), "digital20", estimator=nominal_map)
        assert abs(before.metrics.final_error_deg) > 1.0


def test_run_json_states_the_map_it_used(tmp_path, capsys):
    from flexdigit.cli import main

    cal = perturbed("channel gains x1.12")
    twin_toml = save_calibration(cal, tmp_path / "rig.toml")
    ruler = ruler_file(tmp_path, cal)
    argv = ["run", "--json", "--calibration", str(twin_toml), "--map-from", str(ruler)]
    argv += ["--rotation-map", str(tmp_path / "map.json"), "--setpoint-deg", "30", "--duration", "3"]
    assert main(argv) == 0
    data = json.loads(capsys.readouterr().out)
    used = data["rotation_map"]
    assert "deflections measured on the rig" in used["source"]
    assert str(ruler) in used["source"]
    assert used["file"] == str(tmp_path / "map.json")
    assert used["commands"] == list(COMMANDS)
    assert 0 < used["uncertainty_deg"] < 0.3
    assert abs(data["true_final_rotation_deg"] - 30) < TOLERANCE_DEG
    # the map is saved; a second run loads it (and says so) without a sweep
    assert main(argv[:4] + argv[6:]) == 0
    again = json.loads(capsys.readouterr().out)["rotation_map"]
    assert "loaded from" in again["source"]
    assert again["uncertainty_deg"] == pytest.approx(used["uncertainty_deg"])
    # making a map over an existing file is refused before any work, unless --force
    assert main(argv) == 2
    assert "pass --force" in capsys.readouterr().err
