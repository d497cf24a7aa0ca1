"""The Bayes position limit's Monte Carlo scoring (:func:`flexdigit.studies.metrics.bayes_limits`), compiled.

numba, because the limit scores 24,000 draws against 49 settings per rig: numpy builds a (draws, settings,
gauges) array of residuals and a (draws, settings) array of exponentials per setting (~50 ms a rig, the study's
largest cost); here one pass per draw keeps the residuals in registers and skips the exponentials that are zero
below half an ulp of their sums (:data:`NEGLIGIBLE`). The same Bayes estimate as
:func:`flexdigit.tactile.bounds.protocol_limits` (the posterior mean over the loaded settings, normalised as it
normalises), its sums in another order: ``tests/studies/test_metrics.py`` holds the two together.
"""

from __future__ import annotations

import numba
import numpy as np

__all__ = ["position_mse_m2"]

#: A posterior term below exp(-NEGLIGIBLE) = 4e-18 of the largest (>= 1 after scaling) is under half an ulp of the
#: sum: skipping its exponential changes the sum by at most that, per term
NEGLIGIBLE = 40.0


@numba.njit(cache=True, nogil=True, error_model="numpy")
def position_mse_m2(mean, sigma, a, loaded, log_prior, eps, drawn):
    """Mean squared error (m^2) of the Bayes position estimate of readings drawn at the settings ``drawn``.

    Parameters
    ----------
    mean, sigma : (K, D) the noise-free readings and their standard deviations, the K settings of one command
    a : (K,) positions (m); loaded : (K,) bool, a load hangs (the estimate averages over these)
    log_prior : (K,) log of each setting's frequency
    eps : (L, S, D) standard normal draws of the L settings ``drawn`` (indices into the K)
    """
    k_settings, dim = mean.shape
    n_drawn, samples, _ = eps.shape
    inv = 1.0 / sigma
    log_norm = np.empty(k_settings)
    for k in range(k_settings):
        s = 0.0
        for d in range(dim):
            s += np.log(sigma[k, d])
        log_norm[k] = log_prior[k] - s
    lp = np.empty(k_settings)
    v = np.empty(dim)
    out = np.empty(n_drawn)
    for i in range(n_drawn):
        j = drawn[i]
        acc = 0.0
        for s in range(samples):
            for d in range(dim):
                v[d] = mean[j, d] + sigma[j, d] * eps[i, s, d]
            best = -np.inf
            best_loaded = -np.inf
            for k in range(k_settings):
                q = 0.0
                for d in range(dim):
                    z = (v[d] - mean[k, d]) * inv[k, d]
                    q += z * z
                lp[k] = log_norm[k] - 0.5 * q
                best = max(best, lp[k])
                if loaded[k]:
                    best_loaded = max(best_loaded, lp[k])
            # sums relative to their largest term; a term below e^-NEGLIGIBLE of it changes no digit of the sum
            total = 0.0
            total_loaded = 0.0
            moment = 0.0
            for k in range(k_settings):
                if lp[k] - best > -NEGLIGIBLE:
                    total += np.exp(lp[k] - best)
                if loaded[k] and lp[k] - best_loaded > -NEGLIGIBLE:
                    e = np.exp(lp[k] - best_loaded)
                    total_loaded += e
                    moment += e * a[k]
            share = total_loaded * np.exp(best_loaded - best) / total  # the loaded settings' posterior
            estimate = moment / total_loaded * min(1.0, share / 1e-300)  # protocol_limits' floor on the share
            acc += (estimate - a[j]) ** 2
        out[i] = acc / samples
    return out
