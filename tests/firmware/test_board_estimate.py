"""The board streams its rotation estimate (issue 24 item 5): each line of the loop on the board carries, after the
gauges' counts and the command, the rotation its update was fed (its map's reading of those counts less its tare),
in micro-degrees; ``run --on-board --log`` records it as ``y`` (tests/firmware/test_on_board_log.py).

Reference: flexdigit's Python map (:class:`~flexdigit.control.c_export.RotationMap`, float64, the very map the image
was exported with) of the same streamed counts, less the tare the board announced. The board computes the map in
float32, in both number formats (the fixed-point export quantises the controller, not the map), so the two differ
by float32 rounding, bounded (Higham, *Accuracy and Stability of Numerical Algorithms*, 2002, 3.1: a sum of n
products in floating point is within gamma_n = n u / (1 - n u) of the sum of their magnitudes; u = 2^-24) by:

- the map: G products and G additions, with the coefficients and the offset rounded to float32 (the export's
  literals): (G + 2) u (sum |c_i g_i| + |offset|); the gauge volts are exact in float32 (a count + 1/2, x 5/1024);
- the tare's subtraction: u |map - tare|; the tare line (micro-degrees, truncated by the board: 1e-6 deg, and its
  product by 1e6 rounded in float32: u |tare|); the field's rounding to the micro-degree (0.5e-6 deg) and its
  product by 1e6 in float32 (u |estimate|).
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from flexdigit.params import load_params
from flexdigit.twin.digit_calibration import twin_calibration

from .board_helpers import gauges_volts, python_estimates, watch_board

#: float32's unit roundoff.
U32 = 2.0**-24
#: The board's micro-degree fields: the estimate rounded (0.5e-6 deg), the tare truncated (1e-6 deg).
FIELD_DEG = 1.5e-6


def _bound_deg(rotation, samples, tare_deg: float, estimates: np.ndarray) -> np.ndarray:
    """The float32 bound of the module docstring, per sample, deg."""
    g = len(rotation.coef)
    terms = np.array([np.abs(np.multiply(rotation.coef, gauges_volts(s))).sum() for s in samples])
    return (g + 2) * U32 * (terms + abs(rotation.offset)) + U32 * (2 * np.abs(estimates) + abs(tare_deg)) + FIELD_DEG


def _check(rotation, board, tare: float) -> np.ndarray:
    streamed = np.array([s.rotation_deg for s in board], dtype=float)
    python = python_estimates(rotation, board, tare)
    bound = _bound_deg(rotation, board, tare, python)
    assert np.all(np.abs(streamed - python) <= bound), float(np.max(np.abs(streamed - python) - bound))
    return streamed


@pytest.mark.slow
def test_an_eight_gauge_boards_estimate_is_the_python_maps(mapped_digit_firmware):
    from flexdigit.cli.export import _digit_export_design

    elf, path, rotation_map = mapped_digit_firmware(8)
    params = load_params(path)
    _, board, tare = watch_board(elf, params, 30.0, 1.5, calibration=twin_calibration(params))
    options = SimpleNamespace(calibration=None, rotation_map=rotation_map, no_rotation_map=False, params=path)
    _, _, rotation, _, _ = _digit_export_design(params, 0.020, options)  # the map the image was exported with
    streamed = _check(rotation, board, tare)
    assert len(board) >= 70
    assert streamed.max() > 25.0  # the step was watched, not only the rest


@pytest.mark.slow
def test_a_fixed_point_boards_estimate_is_the_python_maps(firmware, rotation_map):
    from flexdigit.cli.export import _export_design

    elf = firmware(0.020, "fixed")
    _, board, tare = watch_board(elf, None, 20.0, 1.5)
    options = SimpleNamespace(no_rotation_map=False, rotation_map=rotation_map)
    _, _, rotation, _, _ = _export_design("digital20", 0.020, options)
    streamed = _check(rotation, board, tare)
    assert streamed.max() > 15.0
