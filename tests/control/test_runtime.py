"""The runtime controller against python-control's simulation, and its saturation, quantisation, anti-windup and
bumpless start."""

from __future__ import annotations

import control as ct
import numpy as np
import pytest

from flexdigit.control.runtime import RuntimeController
from flexdigit.errors import DesignError, ParameterError
from flexdigit.reference import thesis_value

T = 0.02
K39 = ct.tf(thesis_value("hinf.k_39hz_num"), thesis_value("hinf.k_39hz_den"))


def test_unsaturated_unquantised_matches_forced_response():
    Kd = ct.sample_system(K39, T, "tustin")
    c = RuntimeController(Kd, quantise=False)
    rng = np.random.default_rng(0)
    e = rng.normal(0, 2.0, 200)
    _, v = ct.forced_response(Kd, np.arange(200) * T, e)  # oracle: python-control
    assert np.all(np.abs(v) < 8)  # stays inside 0..254 around the equilibrium 8: no saturation in play
    ours = c.simulate(e, np.zeros(200))
    np.testing.assert_allclose(ours, 8 + v, rtol=1e-9, atol=1e-9)


def test_two_input_form_is_r_and_y():
    Kd = ct.ss(ct.tf([[[1.5], [-0.5]]], [[[1.0], [1.0]]], T))
    c = RuntimeController(Kd, quantise=False)
    assert c.update(4.0, 2.0) == pytest.approx(8 + 1.5 * 4 - 0.5 * 2)


def test_saturates_to_0_254_integers_and_never_255():
    c = RuntimeController(ct.tf([1.0], [1.0], T))
    out = c.simulate(np.linspace(-400, 400, 801), np.zeros(801))
    assert out.min() == 0
    assert out.max() == 254
    assert out.dtype.kind == "i"
    assert 255 not in out
    # inside the range it is the nearest integer to 8 + e
    e = np.linspace(-7.9, 240.0, 301)
    np.testing.assert_array_equal(c.simulate(e, np.zeros_like(e)), np.round(8 + e).astype(int))


def _pi(kp=2.0, ki=5.0):
    # x+ = x + ki T e ; v = x + kp e  (a discrete PI)
    return ct.ss([[1.0]], [[ki * T]], [[1.0]], [[kp]], T)


def test_back_calculation_stops_windup():
    e = np.r_[np.full(100, 300.0), np.full(100, -1.0)]
    pi = _pi(kp=0.5)
    plain = RuntimeController(pi).simulate(e, np.zeros_like(e))
    aw = RuntimeController(pi, antiwindup="back_calculation", aw_gain=[1.0]).simulate(e, np.zeros_like(e))
    # without anti-windup the integrator holds 100 * 5 * 0.02 * 300 = 3000 commands: saturated for ~3e4 samples
    assert np.all(plain[100:] == 254)
    # back-calculation with L = 1 keeps the state at what the applied 254 needs: x = 254 - 8 - 0.5 * 300 + 0.1 * 300
    # = 126, so after the error flips the command is 8 + 126 - 0.5 = 133.5 -> 134 (round half to even), then falls
    assert aw[100] == 134
    assert aw[199] < aw[100]
    # feeding the rounding error back as well makes the integrator track the rounded command: it stalls
    stall = RuntimeController(pi, antiwindup="back_calculation", aw_gain=[1.0], aw_quantisation=True)
    out = stall.simulate(e, np.zeros_like(e))
    assert out[100] == 134
    assert np.all(out[100:] == 134)


def test_clamp_freezes_the_integrator_while_saturated():
    e = np.r_[np.full(100, 300.0), np.full(20, -1.0)]
    out = RuntimeController(_pi(kp=0.5), antiwindup="clamp").simulate(e, np.zeros_like(e))
    assert out[99] == 254
    assert out[100] < 254


def test_bumpless_start_from_the_command_in_force():
    c = RuntimeController(ct.sample_system(K39, T, "tustin"))
    c.reset(20)
    assert c.update(0.0, 0.0) == 20  # zero error: no jump
    c.reset()
    assert c.update(0.0, 0.0) == 8
    assert np.all(c.state == 0)


@pytest.mark.filterwarnings("ignore:overflow encountered")
def test_bad_systems_and_options():
    with pytest.raises(DesignError, match="discrete"):
        RuntimeController(K39)
    with pytest.raises(ParameterError, match="aw_gain"):
        RuntimeController(_pi(), antiwindup="back_calculation")
    with pytest.raises(ParameterError, match="aw_gain"):
        RuntimeController(_pi(), antiwindup="back_calculation", aw_gain=[1.0, 2.0])
    unstable = RuntimeController(ct.ss([[2.0]], [[1.0]], [[1.0]], [[0.0]], T), quantise=False)
    with pytest.raises(DesignError, match="diverged"):
        for _ in range(2000):
            unstable.update(1.0, 0.0)
