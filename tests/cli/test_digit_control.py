"""Issue 24, the control side: every test digit goes through ``params``, ``design 20ms`` and ``run`` from the command
line (no Python written by a user), and its 30 deg step on the twin settles in < 1 s with < 10 % overshoot and the
true tip rotation within 2 % of the setpoint; with two cables -30 deg too. The held rotation is checked against an
independent reference: the static elastica (``tests/oracles.py``, ``solve_bvp``) of the digit under the cable
shortening of the commands the loop ended on.

Beyond ``tests/digits.py``: digits drawn from a seed (1-8 sections, 1-8 gauges, 0.15-0.5 m, quarter/half/full
bridges, one cable or a pair, a geared servo), as the acceptance digits are unseen; each step on two twin seeds.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from digits import DIGITS, random_digit, write_digit
from flexdigit.cli import main
from flexdigit.params import RigParams, load_params
from flexdigit.twin.digit_calibration import twin_calibration
from oracles import digit_contact_bvp, thesis_digit_segments

# issue 24's figures for the 30 deg step (true rotation, on the twin)
SETTLING_S = 1.0
OVERSHOOT_PERCENT = 10.0
FINAL_FRACTION = 0.02
# The held rotation against the elastica of the commands held: the twin's default 3 cells per section bend
# 0.3-2.7 % off the elastica (docs/digits.md; 0.1 % at 27 cells), the dithered command averages to within 0.1
# command over the last 0.5 s, the servo's quantum there is ~1.7 deg: 4 % of 30 deg (1.2 deg) bounds them all.
ELASTICA_FRACTION = 0.04
RUN_S = "2.5"


def _random_digit(seed: int) -> dict:
    """A consistent description drawn from ``seed``: sections, lengths, gauges on the free strip, bridge, cables."""
    rng = np.random.default_rng(seed)
    sections = int(rng.integers(1, 6))
    length = float(rng.uniform(0.15, 0.40))
    pitch = length / sections
    support = min(0.01, 0.2 * pitch)
    strip_section = round(pitch - support, 4)
    gauges = int(rng.integers(1, 9))
    # gauges spread over the sections' free strips, never two at one place
    slots = [(k, j) for k in range(sections) for j in range(8)]
    chosen = sorted(rng.choice(len(slots), size=gauges, replace=False))
    positions = []
    for index in chosen:
        k, j = slots[index]
        start = k * pitch + support / 2
        positions.append(round(start + (j + 0.5) / 8 * strip_section, 4))
    digit = {
        "geometry": {
            "section_count": sections,
            "section_length_m": strip_section,
            "strip_length_m": round(sections * strip_section, 6),
            "digit_length_m": round(sections * strip_section + sections * support, 6),
            "gauge_positions_m": sorted(positions),
        },
        "sensors": {"bridge": str(rng.choice(["quarter", "half", "full"])), "adc_channels": list(range(gauges))},
    }
    if rng.random() < 0.5:
        digit["cables"] = {"count": 2, "pretension_n": round(float(rng.uniform(1.0, 5.0)), 2)}
    if rng.random() < 0.5:
        digit["actuator"] = {"gear_ratio": float(rng.choice([2.0, 4.0]))}
    return digit


# tests/digits.py's random_digit (1-8 sections, 0.15-0.5 m, 1-8 gauges, any bridge, one cable or a pair, gear
# 1-4): 6 a 0.43 m single geared cable (hung: it nearly buckles tip up), 9 7 sections geared (hung); 11 (8 sections,
# 0.43 m, a geared pair), 18 (8 sections, 0.47 m, a pair) and 21 (6 sections, 0.44 m, a pair), all hung: nearly
# undamped (zeta 0.02 with the cable taut) while the scaled calibration kept the thesis's relaxation times, they
# settle since a digit keeps the thesis rig's modal damping (twin.digit_calibration; docs/digits.md); 23 (one
# 0.475 m section, 4 gauges, hung), which overshot 21 % while its design model dropped its 200 rad/s mode (above
# the loop's Nyquist frequency, matched at DC: the model's gauges led the twin's, control.digit_model); 4
# (6 sections, 0.38 m, a pair, 3 quarter bridges, tip up), whose map held the true rotation 0.58 deg short of +30 on
# seed 0 (29.42 deg): its sweep's gauge drift and a 5-reading tare (0.25 deg of noise on its three coarse gauges),
# until the sweep was referenced to straight and the tare read a window at rest (rig.rotation); 8 (one 0.38 m
# section, 3 quarter bridges, a pair: 0.67 deg of noise a reading through the map), whose search found no weights
# under the noise limits and ran the noisiest: 5 of its 6 steps (+-30, seeds 0-2) left the 2 % band after 1 s, until
# the search went on to quieter observers where its grid has none (design20ms.QUIET_*); 37 (2 sections, 0.155 m, 3
# full bridges, geared), whose `run` exited 2 with an internal error: python-control refused its Kalman predictor's
# process covariance, asymmetric by roundoff (design20ms._predictor_gain).
RANDOM = {f"random-{seed}": random_digit(seed) for seed in (4, 6, 8, 9, 11, 18, 21, 23, 37)}
SEEDED = {**{f"seeded-{seed}": _random_digit(seed) for seed in (3, 11)}, **RANDOM}
ALL = {**DIGITS, **SEEDED}
#: The twin's seeds each test digit's step is run with (the sweep's twin takes the next one): two, so a design that
#: settles on one seed's noise by luck does not pass (seed 2 found one-section at 2.1 s and the 0.5 m digit at 1.6 s).
RUN_SEEDS = ("0", "2")
#: Runs known to miss the settling, with why; each must still miss it (so that a fix removes it from here). The
#: one-section digit's seed 2 was one (30.65 deg at 2.05 s): its dithered command (one quantum, 1.67 deg) toggling
#: through the serial board, which reads one frame in 25 twice, kicked its tip out of the band; the dither now counts
#: the board's pulses (``Rig.command_pulses``, tests/rig/test_board_pulses.py) and it settles in 0.22 s.
KNOWN_MISSES: dict[tuple[str, float, str], str] = {}


def _write(name: str, directory) -> object:
    if name in DIGITS:
        return write_digit(name, directory)
    import tomli_w

    path = directory / f"{name}.toml"
    path.write_text(tomli_w.dumps(SEEDED[name]))
    return path


def _cli(argv, capsys) -> tuple[int, dict]:
    code = main([*argv, "--json"])
    out = capsys.readouterr().out
    return code, json.loads(out)


def _setpoints(params: RigParams) -> list[float]:
    return [30.0, -30.0] if params.cables.count == 2 else [30.0]


def _held_elastica_deg(params: RigParams, orientation: str, commands) -> float:
    """Tip rotation (deg) of the elastica of the digit (tests/oracles.py) under the cable shortening of the mean
    command held: ``r_M / n (theta(c) - theta(straight))`` (E 3.11), self-weight as mounted."""
    from flexdigit.twin.twin import cable_shortening_m

    cal = twin_calibration(params)
    shortening = cable_shortening_m(float(np.mean(commands)), params)
    segments, supports = thesis_digit_segments(params, cal)
    gravity = {"vertical": (-9.80665, 0.0), "hanging": (9.80665, 0.0), "horizontal": (0.0, -9.80665)}[orientation]
    pair = params.cables.count == 2
    ref = digit_contact_bvp(
        segments,
        strip_mass_per_m=params.material.strip_density_kg_m3 * params.geometry.cross_section_m2,
        point_masses=dict(zip(supports, cal.support_mass_kg, strict=True)),
        gravity_ab=gravity,
        eccentricity_m=params.geometry.cable_eccentricity_m,
        cable_stiffness_n_m=cal.cable_stiffness_n_m,
        cable_shortening_m=float(shortening),
        cable_pretension_m=params.cables.pretension_n / cal.cable_stiffness_n_m if pair else None,
        tol=1e-6,
        max_nodes=20_000,
    )
    assert ref.converged, ref.message
    return math.degrees(float(ref.theta[-1]))


@pytest.mark.slow
@pytest.mark.parametrize("name", list(ALL))
def test_params_design_and_run_on_the_digit(name, tmp_path, capsys):
    path = _write(name, tmp_path)
    code, checked = _cli(["params", str(path)], capsys)
    assert code == 0, checked
    params = load_params(path)
    kept = tmp_path / "ctrl.json"
    design_argv = ["design", "20ms", "--params", str(path), "--out", str(kept)]
    code, design = _cli(design_argv, capsys)
    if code == 2:  # a digit that buckles tip up is refused, naming the fix: then it is designed hanging
        assert "buckles" in design["error"]
        code, design = _cli([*design_argv, "--orientation", "hanging"], capsys)
    assert code == 0, design
    assert design["stable"]
    assert design["closed_loop_pole_radius"] < 1.0
    seeds = RUN_SEEDS if name in DIGITS else RUN_SEEDS[:1]  # the drawn digits on one seed: the suite stays short
    for k, (setpoint, seed) in enumerate((s, seed) for s in _setpoints(params) for seed in seeds):
        log = tmp_path / f"run{setpoint:+g}-{seed}.jsonl"
        argv = ["run", "--params", str(path), f"--setpoint-deg={setpoint:g}", "--duration", RUN_S, "--seed", seed]
        # the first run searches the digit's weights itself, as a user's who never ran design; the others run the
        # design kept above (the same weights: tests/cli/test_kept_design_cli.py), not searching again
        controller = ["--controller", str(kept)] if k else []
        # the rotation map is swept on a twin of the next seed (cli/run.py), the same map for +30 and -30 on one
        # seed: the first run of a seed saves it, a pair's -30 loads it (--rotation-map) instead of sweeping the
        # same twin again (~60 simulated s, most of a run's time), the map and the run as they would be
        rotation_map = ["--rotation-map", str(tmp_path / f"map-{seed}.json")]
        code, run = _cli([*argv, *controller, *rotation_map, "--log", str(log)], capsys)
        assert code == 0, run
        assert run["status"] == "completed"
        assert run["controller_file"] == (str(kept) if k else None)
        true = run["step_metrics"]["true"]
        assert true["overshoot_percent"] < OVERSHOOT_PERCENT
        assert abs(run["true_final_rotation_deg"] - setpoint) < FINAL_FRACTION * abs(setpoint)
        if (name, setpoint, seed) in KNOWN_MISSES:
            settled = true["settling_time_s"]
            assert settled is None or settled >= SETTLING_S, f"settles now: remove {name} seed {seed} from KNOWN_MISSES"
        else:
            assert true["settling_time_s"] is not None
            assert true["settling_time_s"] < SETTLING_S
        # the log says how the command drives the cable(s)
        header = json.loads(log.read_text().splitlines()[0])
        assert header["cables"]["count"] == params.cables.count
        assert run["cables"] == header["cables"]
        # the held rotation is the elastica's under the commands held (an independent solution of the mechanics)
        samples = [json.loads(line) for line in log.read_text().splitlines()[1:] if '"k"' in line]
        held = [s["command"] for s in samples if s["t"] >= samples[-1]["t"] - 0.5]
        reference = _held_elastica_deg(params, run["rig"]["orientation"], held)
        assert abs(run["true_final_rotation_deg"] - reference) < ELASTICA_FRACTION * abs(setpoint)


def test_a_setpoint_beyond_the_servos_reach_is_refused_in_one_line(tmp_path, capsys, work_must_not_start):
    """A pair geared 20:1 (the largest plausible reduction) turns 0.087 deg a command: 127 commands either side of
    straight reach +-11.0 deg, so -30 deg is refused before the twin moves, naming the reach."""
    import tomli_w

    from flexdigit.twin.twin import Twin

    work_must_not_start(Twin, "advance")
    geared_pair = tmp_path / "g.toml"
    geared_pair.write_text(
        tomli_w.dumps({"cables": {"count": 2, "pretension_n": 3.0}, "actuator": {"gear_ratio": 20.0}})
    )
    code, out = _cli(["run", "--params", str(geared_pair), "--setpoint-deg=-30"], capsys)
    assert code == 2
    assert "--setpoint-deg -30" in out["error"]
    assert "reaches -11.0 to 11.0 deg" in out["error"]


def test_run_says_what_its_design_misses_in_one_line(capsys):
    """``run``'s design warnings (a command too coarse for the 2 % band: tests/control/test_coarse_step.py) go to
    stderr as one line each and into ``--json``'s ``design_warnings``; any other warning goes on as it came."""
    import warnings

    from flexdigit.cli.run import _design_warnings
    from flexdigit.errors import DesignWarning

    with pytest.warns(UserWarning, match="something else"):
        with _design_warnings() as said:
            warnings.warn("design: one frame of one command moves the tip 0.62 deg", DesignWarning, stacklevel=1)
            warnings.warn("something else", UserWarning, stacklevel=1)
    assert said == ["design: one frame of one command moves the tip 0.62 deg"]
    said_on_stderr = "flexdigit run: warning: design: one frame of one command moves the tip 0.62 deg\n"
    assert capsys.readouterr().err == said_on_stderr  # prefixed as the command's errors are
