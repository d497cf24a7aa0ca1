"""The cable-guide friction's level from a measured repeatability (closed form), and a 1-D level fit to a score.

The friction (:mod:`flexdigit.twin.sensors`) scatters the actuated gauges by ``ratio * u_k`` per gauge, ``u_k`` the
spread at ratio 1 from the twin's static model, independent of the white noise ``w_k``. A rig's repeated readings
of the unloaded actuated digit, tapped before each, therefore fix the ratio in closed form
(:func:`friction_ratio_from_repeatability`); without them the thesis's only evidence is its actuated network's
corr2, matched by :func:`fit_level` on a score the caller supplies (the tactile pipeline).
"""

from __future__ import annotations

import numpy as np

from flexdigit._validation import check_array, check_real
from flexdigit.errors import ParameterError
from flexdigit.twin.calibration import Calibration
from flexdigit.twin.twin import friction_sd_v, static_gauges_v

__all__ = ["LEVEL_XTOL", "fit_level", "actuated_rest_sd_v", "friction_ratio_from_repeatability"]

#: The friction fit's tolerance on the ratio (absolute): Brent's method returns a level within it of a crossing.
LEVEL_XTOL = 1e-4


def fit_level(score, target: float, bracket: tuple[float, float] = (0.0, 0.3), xtol: float = LEVEL_XTOL) -> float:
    """The level ``x`` in ``bracket`` where ``score(x) = target``: a 1-D root find (Brent's method).

    For a noise level against a score that falls as the noise grows (corr2). ``score`` should be deterministic
    (seeded) so the root is; a score that is noisy in ``x`` gives one of its crossings.

    Raises
    ------
    ParameterError
        If ``target`` is not between the scores at the bracket's ends.

    Examples
    --------
    >>> round(fit_level(lambda x: 1.0 - x**2, 0.96), 4)
    0.2
    """
    from scipy.optimize import brentq

    lo, hi = (float(v) for v in bracket)
    target = check_real(target, "target", "fit_level")
    f_lo, f_hi = score(lo) - target, score(hi) - target
    if f_lo * f_hi > 0:
        raise ParameterError(
            f"The 'target' parameter of fit_level must lie between the scores at the bracket's ends "
            f"({f_lo + target:.4g} at {lo:g}, {f_hi + target:.4g} at {hi:g}). Got {target!r} instead."
        )
    if f_lo == 0:
        return lo
    if f_hi == 0:
        return hi
    return float(brentq(lambda x: score(x) - target, lo, hi, xtol=xtol))


def _rest_friction_sd_v(params, calibration: Calibration, command: int, cells_per_section: int) -> np.ndarray:
    """Cable-guide friction's standard deviation (V, per gauge) of the unloaded horizontal digit at ``command``."""
    _, sol = static_gauges_v(
        [0.0],
        [0.0],
        [command],
        params=params,
        calibration=calibration,
        cells_per_section=cells_per_section,
        adc=False,
        return_solution=True,
    )
    return friction_sd_v(sol, params, calibration, cells_per_section=cells_per_section)[0]


def actuated_rest_sd_v(
    params, calibration: Calibration, command: int, cells_per_section: int | None = None
) -> np.ndarray:
    """Standard deviation (V, per gauge) of one reading of the unloaded digit, horizontal, held at ``command``.

    White noise and cable-guide friction, independent (:mod:`flexdigit.twin.sensors`); drift left out (a
    repeatability record spans seconds).
    """
    friction = _rest_friction_sd_v(params, calibration, command, cells_per_section)
    return np.sqrt(np.asarray(calibration.noise_white_v) ** 2 + friction**2)


def friction_ratio_from_repeatability(
    params, calibration: Calibration, command: int, sd_v, cells_per_section: int | None = None
) -> float:
    """``cable_friction_ratio`` from the measured spread of the unloaded actuated digit's readings (closed form).

    The friction's standard deviation is proportional to the ratio, ``s_k = ratio * u_k`` per gauge, and adds to
    the white noise ``w_k`` in variance, so the least-squares ratio over the gauges is
    ``sqrt(sum u_k^2 (sd_k^2 - w_k^2) / sum u_k^4)`` (0 if the spread is no more than the white noise).
    """
    sd = check_array(sd_v, "actuated_repeatability_v", "CalibrationTargets", ndim=1, low=0)
    u = _rest_friction_sd_v(params, calibration.replace(cable_friction_ratio=1.0), command, cells_per_section)
    if sd.size != u.size:
        raise ParameterError(
            f"The 'actuated_repeatability_v' parameter of CalibrationTargets must have {u.size} values (one per "
            f"gauge). Got {sd.size}."
        )
    excess = sd**2 - np.asarray(calibration.noise_white_v, dtype=float) ** 2
    ratio2 = float(np.sum(u**2 * excess) / np.sum(u**4)) if np.sum(u**4) > 0 else 0.0
    return float(min(np.sqrt(max(ratio2, 0.0)), 1.0))
