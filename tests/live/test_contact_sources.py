"""The live page's contact sources without a server: the beam inversion's and a trained network's (--model)."""

import numpy as np
import pytest

from flexdigit.errors import ParameterError
from flexdigit.live.session import BeamContact, NetworkContact
from flexdigit.shape.shape import ShapeEstimator
from flexdigit.tactile.model_io import save_model
from flexdigit.tactile.pipeline import ThesisNetwork
from flexdigit.twin import static_gauges_v


@pytest.fixture(scope="module")
def network_file(tmp_path_factory):
    # a position network trained on the non-actuated twin beyond gauge 2 (where one reading places a load)
    positions = np.tile(np.linspace(0.15, 0.27, 13), 6)
    volts = static_gauges_v(np.full(positions.size, 0.025), positions, seed=4)
    net = ThesisNetwork(hidden=6, epochs=8).fit(volts, 0.27 - positions)  # the thesis's target: m from the tip
    rmse_mm = 1e3 * float(np.sqrt(np.mean((net.predict(volts) - (0.27 - positions)) ** 2)))
    path = tmp_path_factory.mktemp("model") / "position.model.json"
    save_model(path, net, target="position", inputs=["gauge1_v", "gauge2_v", "gauge3_v"],
               meta={"scores": {"rmse_mm": rmse_mm}})  # fmt: skip
    return path, rmse_mm


def test_a_trained_network_places_the_load_with_its_test_rmse_as_band(network_file):
    path, rmse_mm = network_file
    source = NetworkContact(path, 0.27)
    volts = static_gauges_v([0.025], [0.21])
    shape = ShapeEstimator(orientation="horizontal", cable=False).estimate(volts)
    out = source.estimate(volts[0], None, shape)
    assert out["contact"]
    assert abs(out["position_from_base_m"] - 0.21) < 0.01
    assert out["position_sd_m"] == pytest.approx(rmse_mm / 1e3)
    bare = ShapeEstimator(orientation="horizontal", cable=False).estimate(static_gauges_v([0.0], [0.0]))
    assert not source.estimate(static_gauges_v([0.0], [0.0])[0], None, bare)["contact"]  # contact: beam inversion


def test_a_model_of_another_target_is_refused(network_file, tmp_path):
    path, _ = network_file
    other = tmp_path / "contact.model.json"
    other.write_text(path.read_text().replace('"target": "position"', '"target": "contact"'))
    with pytest.raises(ParameterError, match="'position' model"):
        NetworkContact(other, 0.27)


def test_the_beam_contact_says_when_it_cannot_place_a_load():
    est = ShapeEstimator(orientation="horizontal", cable=False, n_average=10)
    located = BeamContact().estimate(None, None, est.estimate(static_gauges_v([0.025], [0.22])))
    assert located["located"]
    assert abs(located["position_from_base_m"] - 0.22) < 0.005
    confounded = BeamContact().estimate(None, None, est.estimate(static_gauges_v([0.025], [0.10])))
    assert confounded["contact"]
    assert not confounded["located"]  # between gauges 1 and 2
