"""The sweep's modulus sd is honest over seeds on the two digits whose `flexdigit palpate` sat 2.2-2.9 sd off at
seeds 0 and 2 (issue 24; stop 35's note read them as "the drift-weighted sd ~2x low").

The sweeps are drawn as the twin draws them: the static contact's gauges (the fit's own model, whose plateaus the
dynamic twin's settle to within 0.07 mV on both digits, a sixth of one plateau's white noise) read through the
twin's own sensor chain (:class:`flexdigit.twin.sensors.SensorChain`: per 20 ms reading its white noise and
random-walk drift, seeded as ``flexdigit palpate --seed S`` seeds the twin) and averaged as ``run_sweep`` averages
them. Seeds 0..9 give the command's own z-scores within 0.05 (two_sections_half seed 0: 2.94 here and there).

Why those sweeps sat off: chance, twice the same. The twin draws the same normals for one seed on any two-gauge
digit, so the two digits' seed 0 (and seed 2) are one draw each, not two; both digits' z-scores run 2.9, -0.8,
2.2 | 2.3, 1.3, 2.9 at seeds 0-2. Over 300 seeds (100..399) two_sections_half's z has rms 1.03, 96 % within 2 sd.

Bounds (``N`` = :data:`SEEDS` independent standard normal z-scores, each bound passed by chance with probability
under 1e-3): ``sum z^2`` is chi^2 with N dof, so the rms lies in :data:`Z_RMS` (its 0.05 % and 99.95 % points);
the count outside 2 sd is binomial(N, 0.0455): more than :data:`MOST_OUTSIDE` has probability < 1e-3; the mean
z is normal with sd ``1 / sqrt(N)``: :data:`MEAN_Z` is 3.3 of those. An sd 2x too small (rms 2) fails the first;
so does the white noise's sd alone (``drift=False``: rms 2.41 and 1.66 on these draws).

The same disease, found here, in what the sweep derives from the fit: the lumped slope's sd counted the plateaus'
forces as independent (z to 35: the fitted gap and drift are one error shared by all) and each force's sd its
white noise alone (z rms 2.1: the walk about the fitted line is not white). Both now carry the shared part.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from flexdigit.control.design20ms import digit_mount
from flexdigit.palpation.contact_estimation import ContactGaugeModel
from flexdigit.palpation.palpation import (
    PalpationProtocol,
    SweepRecord,
    _deepest,
    _walk,
    _walk_widening,
    analyse,
    digit_protocol,
    digit_tissue,
    fit_tissue,
)
from flexdigit.palpation.palpation_files import load_tissue
from flexdigit.params import load_params
from flexdigit.twin.digit_calibration import twin_calibration
from flexdigit.twin.sensors import SensorChain

HANDMADE = Path(__file__).parents[1] / "data" / "handmade_digits"
#: The command's seeds 0..29 (seeds 0 and 2 among them).
SEEDS = 30
Z_RMS = (0.60, 1.44)
MOST_OUTSIDE = 6
MEAN_Z = 3.3 / math.sqrt(SEEDS)
#: The lumped slope's seeds (each sweep's force estimates cost ~1 s) and its rms bounds (chi^2, 8 dof, 1e-3)
LUMPED_SEEDS = 8
LUMPED_Z_RMS = (0.30, 1.87)
#: soft-block's modulus (N/m^2), from src/flexdigit/palpation/palpation_data/soft-block.toml
SOFT_BLOCK_N_M2 = 1000.0
#: How the command lays the built-in sweep out on a digit (flexdigit.cli.palpate._laid_out)
LAID_OUT = ("commands", "tare_command", "settle_s")


def _digit(name: str):
    """``(model, tissue, protocol)`` as ``flexdigit palpate --tissue soft-block --params NAME`` sets them up."""
    params = load_params(HANDMADE / f"{name}.toml")
    calibration = twin_calibration(params)
    model = ContactGaugeModel(params, calibration, orientation=digit_mount(params, calibration))
    tissue = digit_tissue(load_tissue("soft-block")[0], params)
    assert tissue.modulus_n_m2 == SOFT_BLOCK_N_M2
    return model, tissue, digit_protocol(PalpationProtocol(), params, laid_out=LAID_OUT, model=model)


def _twin_read_sweep(model, tissue, protocol: PalpationProtocol, seed: int) -> SweepRecord:
    """The plateau means of a sweep whose every 20 ms reading goes through the twin's sensor chain."""
    sequence = np.array([protocol.tare_command, *protocol.commands, protocol.tare_command])
    clean = model.tissue_solution(tissue, sequence)[1]
    times = protocol.period_s * np.arange(round(protocol.duration_s / protocol.period_s))
    plateau = np.minimum((times // protocol.plateau_s).astype(int), sequence.size - 1)
    chain = SensorChain(model.params, model.calibration, np.random.default_rng(seed))
    gauges, _ = chain.sample_series(clean[plateau], times, np.zeros(times.size))
    rows = [np.flatnonzero(plateau == j)[-protocol.readings :] for j in range(sequence.size)]
    means = np.array([gauges[r].mean(axis=0) for r in rows])
    tare = np.zeros(sequence.size, dtype=bool)
    tare[[0, -1]] = True
    return SweepRecord(sequence, np.array([times[r].mean() for r in rows]), means, tare, protocol.readings, {})


@pytest.mark.slow
@pytest.mark.parametrize("name", ["two_sections_half", "nitinol_unequal_supports"])
def test_over_seeds_the_modulus_error_is_a_standard_normal_in_its_own_sd(name):
    model, tissue, protocol = _digit(name)
    z = []
    for seed in range(SEEDS):
        fit = fit_tissue(_twin_read_sweep(model, tissue, protocol, seed), model, tissue, drift=True)
        z.append((fit.modulus_n_m2 - SOFT_BLOCK_N_M2) / fit.modulus_sd_n_m2)
    z = np.array(z)
    assert Z_RMS[0] < float(np.sqrt(np.mean(z**2))) < Z_RMS[1], z.round(2)
    assert np.count_nonzero(np.abs(z) > 2) <= MOST_OUTSIDE, z.round(2)
    assert abs(float(z.mean())) < MEAN_Z, z.round(2)


@pytest.mark.slow
def test_the_lumped_slopes_and_each_forces_sd_carry_the_shared_errors():
    # the truth: the twin's tissue's own force against its deepest indentation, on the plateaus and weights the
    # measured slope used; the forces' scatter alone claimed 0.023 N/m where seeds 0-9 scattered 0.35 (z to 35)
    model, tissue, protocol = _digit("two_sections_half")
    white_v = np.asarray(model.noise_v) / math.sqrt(protocol.readings)
    z, forces = [], []
    for seed in range(LUMPED_SEEDS):
        result = analyse(_twin_read_sweep(model, tissue, protocol, seed), tissue, protocol, model, drift=True)
        curve = result.curve
        touching = (curve["indentation_m"] > 0) & curve["force_read"]
        sol = model.tissue_solution(tissue, curve["command"])[0]
        true_force = -tissue.sign * sol.contact_force_n
        forces.append(((curve["force_n"] - true_force) / curve["force_sd_n"])[curve["force_read"]])
        # the slope weighs each plateau by its force's white-noise sd: the sd before the walk widened it
        white = curve["force_sd_n"] / _walk_widening(result.record.time_s, _walk(model), white_v)[1:-1]
        weights = 1.0 / white[touching] ** 2
        depth = _deepest(model, tissue, sol.static.psi_rad)[touching]
        truth = np.sum(weights * depth * true_force[touching]) / np.sum(weights * depth**2)
        z.append((result.lumped_stiffness_n_m - truth) / result.lumped_stiffness_sd_n_m)
    z = np.array(z)
    # each plateau's force against the twin's: an sd of white noise alone put them at rms 2.2 (seeds 0-9 of the
    # command); the plateaus of one sweep share their walk, so only the seeds count as independent (bound as above)
    force_rms = float(np.sqrt(np.mean(np.concatenate(forces) ** 2)))
    assert LUMPED_Z_RMS[0] < force_rms < LUMPED_Z_RMS[1], force_rms  # before: 2.14
    assert LUMPED_Z_RMS[0] < float(np.sqrt(np.mean(z**2))) < LUMPED_Z_RMS[1], z.round(2)  # before: 18.6
