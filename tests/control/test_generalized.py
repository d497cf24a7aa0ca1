"""The generalized plant of thesis 4.4 and the weight validation."""

import control as ct
import numpy as np
import pytest

from flexdigit.control.generalized import filter_weight, mixed_sensitivity_plant, regularise, thesis_generalized_plant
from flexdigit.errors import DesignError

# printed plant of thesis 3.5 / 4.2, typed here only as an independent oracle for the LFT algebra
G_PRINTED = ct.tf([48.7], [1, 23.65, 537.3, 2616, 4.354e4])

# Tolerances, each with the reason for its size
LFT_RTOL = 1e-10  # the state-space LFT against the transfer-function products at one frequency: rounding only
EXACT_RTOL = 1e-12  # a block that is 1 by construction
PRINTED_4_DECIMALS_ATOL = 1e-4  # 2 pi 5 = 31.4159, printed to 4 decimals
PRINTED_DB_ATOL = 0.01  # the printed -29.9474 dB is |F| on the plot's grid, 0.0044 dB from the DC peak


def test_thesis_P_blocks_equal_F_S_structure():
    # 4.4: z = F (w - G u), y = w - G u; check every block against the transfer functions at a test frequency
    F = filter_weight(5.0)
    P = thesis_generalized_plant(G_PRINTED, F)
    s = 7.0j
    H = P(s)
    g, f = G_PRINTED(s), F(s)
    np.testing.assert_allclose(H[0, 0], f, rtol=LFT_RTOL)
    np.testing.assert_allclose(H[0, 1], -f * g, rtol=LFT_RTOL)
    np.testing.assert_allclose(H[1, 0], 1.0, rtol=EXACT_RTOL)
    np.testing.assert_allclose(H[1, 1], -g, rtol=LFT_RTOL)
    # D12 = 0: the singular problem the issue describes
    assert P.D[0, 1] == 0.0


def test_filter_weight_5hz_is_thesis_F():
    # 4.3: F(s) = 1/(s + 31.4159), peak -29.9474 dB
    F = filter_weight(5.0)
    assert F.den[0][0][1] == pytest.approx(31.4159, abs=PRINTED_4_DECIMALS_ATOL)
    # ours is -29.9430 dB at DC: the thesis read its plot at a grid point, 0.004 dB lower
    assert 20 * np.log10(abs(F(0))) == pytest.approx(-29.9474, abs=PRINTED_DB_ATOL)


def test_regularise_adds_eps_rows():
    P = regularise(thesis_generalized_plant(G_PRINTED, filter_weight(5.0)), 1e-3, 1e-2)
    assert (P.ninputs, P.noutputs) == (3, 3)
    assert P.D[1, 2] == pytest.approx(1e-3)  # eps_u on u in the second z row
    assert P.D[2, 1] == pytest.approx(1e-2)  # eps_noise on y


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"w1": ct.tf([1, 0, 0], [1, 1])}, "proper"),
        ({"w1": ct.tf([1], [1, -1])}, "stable weight"),
        ({"w1": ct.tf([[[1]], [[1]]], [[[1, 1]], [[1, 2]]])}, "single-input single-output"),
        ({}, "at least one"),
    ],
)
def test_bad_weights_raise_design_error(kwargs, match):
    with pytest.raises(DesignError, match=match):
        mixed_sensitivity_plant(G_PRINTED, **kwargs)


def test_unstable_thesis_filter_rejected():
    with pytest.raises(DesignError, match="stable weight"):
        thesis_generalized_plant(G_PRINTED, ct.tf([1], [1, -3]))
