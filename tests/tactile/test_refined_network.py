"""Issue 24's network ratio on a digit that resolves positions far finer than its protocol's step, collected with
``collect --refine`` (:meth:`flexdigit.tactile.protocols.Protocol.refined`): docs/guide/tactile.md, "Issue 24's
ratio"."""

from pathlib import Path

import numpy as np
import pytest

from flexdigit.cli import main
from flexdigit.params import load_params
from flexdigit.tactile.dataset import load_dataset
from flexdigit.tactile.localisation import position_bayes_rmse_m, readings_gauge_model, train_network
from flexdigit.tactile.position_floor import NETWORK_RATIO_MAX
from flexdigit.twin.digit_calibration import twin_calibration

DIGIT = Path(__file__).parents[1] / "data" / "handmade_digits2" / "unequal_three_two_in_one.toml"

#: The network's size and tolerance the full sweep chose on twin seed 0's refined run (45, 1e-8: 0.668 mm; a
#: 20-node network at the same tolerance read 0.642 mm there): fixed here, the sweep is minutes
HIDDEN, TOL = 20, 1e-8
#: Monte Carlo readings per setting of the drift-counted limit (``train --bayes-limit`` draws 4000): a fifth, the
#: limit's cost being its draws over every setting of the run; its scatter over the test settings ~1 %
SAMPLES = 800


@pytest.mark.slow
def test_a_refined_protocol_brings_a_fine_digits_network_within_the_issue_bound(tmp_path):
    """unequal_three_two_in_one (limit ~0.75 mm; thesis-6.1's step 14 mm on its 0.39 m): on thesis-6.1 as scaled
    its network read 1.38 x the drift-counted limit (twin seed 0), tested 29 mm from its training positions at a
    gauge it passes. Refined x4 (3.6 mm steps, 7 readings a position), on twin seed 1 (not the run the docs' table
    and HIDDEN come from), it is within the issue's 1.3 (seed 0, swept: 0.60)."""
    data = tmp_path / "d.parquet"
    argv = ["collect", "thesis-6.1", "--refine", "4", "--seed", "1", "--params", str(DIGIT), "--out", str(data)]
    assert main([*argv, "--no-progress"]) == 0
    dataset = load_dataset(data)
    result, rows, _, _ = train_network(dataset, "position", hidden=HIDDEN, tol=TOL, split="positions")
    rmse_m = float(np.sqrt(np.mean((result.y_pred - result.y_test) ** 2)))
    params = load_params(DIGIT)
    model = readings_gauge_model(params, twin_calibration(params, None))
    limit_m = position_bayes_rmse_m(model, dataset, rows[result.split.test], samples=SAMPLES, drift=True)
    assert rmse_m / limit_m <= NETWORK_RATIO_MAX, (rmse_m, limit_m)
