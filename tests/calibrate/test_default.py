"""The packaged default calibration against the thesis (tables 3.1, 3.2, 3.6, E 3.20-3.22), and its re-fit.

The release tests and the sweep are run as experiments on the twin (through the sensor chain, with noise) and
analysed like measurements, with the reduction ``flexdigit calibrate`` applies to a rig's records (identify's lsq
fit per gauge, the median over the gauges), so the check covers the dynamics, the servo and the sensors, not only
the fit. Tolerances from issue 3: wn and zeta within 3 %, gauge-volt slopes within 5 %, deflections within the
0.5 mm reading resolution where the thesis's own model agrees with its measurement.
"""

import dataclasses

import numpy as np
import pytest

from flexdigit.calibrate.friction import LEVEL_XTOL
from flexdigit.calibrate.targets import CalibrationTargets, release_figures
from flexdigit.calibrate.twin_fit import calibrate
from flexdigit.identify.timeseries import series_from_table
from flexdigit.reference import thesis_value
from flexdigit.tactile.thesis_experiments import actuated_corr2_score
from flexdigit.twin import records as ex
from flexdigit.twin.calibration import default_fit_record, packaged_calibration

pytestmark = pytest.mark.blas  # run again under other OpenBLAS kernels by `make test` (docs/guide/reliability.md)

RELEASE_RTOL = 0.03
SLOPE_RTOL = 0.05
DEFLECTION_ABS_MM = 0.5
#: The re-fit must land on the packaged values (the fit is deterministic on one machine: fixed tolerances, seeded
#: scores); across BLAS kernels its flattest direction, the cable stiffness, lands 1.5e-5 apart (SkylakeX against
#: Haswell, measured at 9f1cdf6): 1e-4, six times that spread
REFIT_RTOL = 1e-4

#: The re-fit's friction ratio must cross the thesis's corr2 within this many LEVEL_XTOL (1e-4) of the packaged
#: one. The score is 8 trained networks' corr2, and training amplifies rounding: under the Haswell, SkylakeX,
#: Nehalem and Prescott BLAS kernels its mean at one ratio differs by up to 3.1e-4 (ratios packaged +- 2..20
#: LEVEL_XTOL measured), and within one kernel it is not monotone over 2 LEVEL_XTOL (by 2e-4), while its slope is
#: only 2.5e-4 per LEVEL_XTOL: at +- 2 LEVEL_XTOL the crossing sat 1.1e-4 inside the noise (and outside it on
#: another machine, 0.90002 at + 2). At +- 10 the scores are 0.9016 and 0.8964-0.8967 on all four kernels, clear of
#: 0.8998 by 1.8e-3, 6x the kernels' spread; and 1e-3 of ratio is still a third of what the evidence fixes
#: (8 seeds scattering by 0.02 in corr2: a standard error of 0.007, 30 LEVEL_XTOL of ratio).
FRICTION_BRACKET_XTOLS = 10

#: Record lengths of the simulated release tests (s), as the report uses them: the bare digit's amplitude decays
#: with a time constant 1/(zeta wn) = 39 s, so a 12 s record holds too little decay for a zeta to survive the
#: noise (median over the gauges off by up to 3.1 % over 20 seeds at 12 s, 0.6-1.6 % at 30 s); the housed one's
#: is 1.1 s, and 8 s holds all of it.
RELEASE_DURATION_S = {False: 30.0, True: 8.0}


@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.parametrize(
    ("housing", "table"),
    [pytest.param(False, "without_housing", marks=pytest.mark.slow), (True, "with_housing")],
)
def test_release_tests_reproduce_tables_3_1_and_3_2(housing, table, seed):
    # wn and zeta are the medians over the gauges, as the report and flexdigit calibrate take them: gauge 3
    # (nearest the tip, the smallest strain: ~14 mV of swing over 2 mV of white noise and drift) alone scatters by
    # +-5 % even on 30 s records. Several seeds, so a pass is not seed luck.
    res = ex.release_test(housing=housing, duration_s=RELEASE_DURATION_S[housing], sample_rate_hz=500, seed=seed)
    figures = release_figures([series_from_table(res, f"gauge{gauge}") for gauge in (1, 2, 3)])
    assert figures["wn_rad_s"] == pytest.approx(
        thesis_value(f"digit.release_tests_{table}.wn_avg_rad_s"), rel=RELEASE_RTOL
    )
    assert figures["zeta"] == pytest.approx(thesis_value(f"digit.release_tests_{table}.zeta_avg"), rel=RELEASE_RTOL)
    for fit in figures["fits"]:  # wn is set by the mechanics: every gauge identified sees it
        assert fit.wn_rad_s == pytest.approx(figures["wn_rad_s"], rel=0.01), fit.channel


def test_actuation_sweep_reproduces_e_3_20_to_3_22():
    res = ex.actuation_sweep(settle_s=2.5, samples=5, seed=2)
    commands = res.column("command")
    for gauge, fit in enumerate(thesis_value("conversion.v_sg_fit"), start=1):
        slope, offset = np.polyfit(commands, res.column(f"gauge{gauge}_v"), 1)
        assert slope == pytest.approx(fit["slope"], rel=SLOPE_RTOL)
        assert offset == pytest.approx(fit["offset"], abs=0.02)


def test_deflections_match_table_3_6_where_the_thesis_model_agrees():
    from flexdigit.params import RigParams
    from flexdigit.twin.twin import Twin

    targets = CalibrationTargets.from_thesis()
    weight = np.array(targets.deflection_weight)
    measured = np.array(targets.deflection_mm)
    assert weight.sum() >= 15  # 19 readings of table 3.6 are within 0.5 mm of table 3.4
    p = RigParams()
    for c, command in enumerate(targets.deflection_commands):
        if not weight[:, c].any():
            continue
        twin = Twin(seed=0, command=command)
        y_mm = twin.deflection_m(p.geometry.gauge_positions_m) * 1e3
        for g in range(3):
            if weight[g, c]:
                assert y_mm[g] == pytest.approx(measured[g, c], abs=DEFLECTION_ABS_MM), (g + 1, command)


@pytest.mark.slow
def test_recalibrating_reproduces_the_packaged_default():
    # Everything but the friction is fitted before it and does not depend on it: re-fitted exactly (seconds).
    targets = CalibrationTargets.from_thesis()
    mechanics = calibrate(dataclasses.replace(targets, actuated_test_corr2=None))
    default = packaged_calibration()
    for name, value in default.to_dict().items():
        if name != "cable_friction_ratio":
            np.testing.assert_allclose(
                getattr(mechanics.calibration, name), value, rtol=REFIT_RTOL, atol=1e-12, err_msg=name
            )
    # The friction's only evidence is the thesis's actuated corr2, scored by the tactile pipeline (8 seeded runs of
    # the experiment per score). Brent's method returns a ratio within LEVEL_XTOL of a crossing of the target, so
    # the packaged ratio is the re-fit's answer when the score crosses 0.8998 near it: two scores instead of the
    # ten of a full root find (flexdigit calibrate --thesis runs that). How near: FRICTION_BRACKET_XTOLS.
    ratio = default.cable_friction_ratio
    step = FRICTION_BRACKET_XTOLS * LEVEL_XTOL
    below = actuated_corr2_score(mechanics.calibration.replace(cable_friction_ratio=ratio - step))
    above = actuated_corr2_score(mechanics.calibration.replace(cable_friction_ratio=ratio + step))
    assert below >= targets.actuated_test_corr2 >= above  # corr2 falls as the friction grows
    assert len(default_fit_record()["residuals"]) == len(mechanics.residuals) + 1  # + the corr2 row
