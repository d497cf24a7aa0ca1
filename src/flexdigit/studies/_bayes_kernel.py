"""The Bayes position limit's Monte Carlo scoring (:func:`flexdigit.studies.metrics.bayes_limits`), compiled.

numba, because the limit scores 24,000 draws against 49 settings per rig: numpy builds a (draws, settings,
gauges) array of residuals and a (draws, settings) array of exponentials per setting (~50 ms a rig, the study's
largest cost); here one pass per draw keeps the residuals in registers, scores only the settings near enough to
matter (:func:`_near_settings`, about 10 of the 49) and skips the exponentials below half an ulp of their sums
(:data:`NEGLIGIBLE`). The same Bayes estimate as
:func:`flexdigit.tactile.bounds.protocol_limits` (the posterior mean over the loaded settings, normalised as it
normalises), its sums in another order: ``tests/studies/test_metrics.py`` holds the two together.
"""

from __future__ import annotations

import numba
import numpy as np

from flexdigit import _numba_cache

_numba_cache.install()  # the machine code kept per user by source text (flexdigit/_numba_cache.py)

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
    near = np.empty(k_settings, dtype=np.int64)
    out = np.empty(n_drawn)
    for i in range(n_drawn):
        j = drawn[i]
        n_near = _near_settings(mean, sigma, log_norm, eps[i], j, near)
        acc = 0.0
        for s in range(samples):
            for d in range(dim):
                v[d] = mean[j, d] + sigma[j, d] * eps[i, s, d]
            best = -np.inf
            best_loaded = -np.inf
            for t in range(n_near):
                k = near[t]
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
            for t in range(n_near):
                k = near[t]
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


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _near_settings(mean, sigma, log_norm, eps, j, near):
    """The settings that can matter to a reading drawn at setting ``j`` with any of the draws ``eps`` (S, D): the
    others' log posterior is below the true setting's by more than :data:`NEGLIGIBLE` for every draw, so they are
    never the largest term and never summed (the same terms skipped as when all are scored; the same numbers).

    With ``|eps| <= r`` over the draws, the true setting scores at least ``log_norm_j - r^2 / 2``; setting k at
    most ``log_norm_k - (max(0, d_jk - g_jk r))^2 / 2``, ``d_jk`` the distance of the two mean readings in k's noise
    and ``g_jk = max_d sigma_jd / sigma_kd`` (the triangle inequality in k's whitened metric). Fills ``near`` and
    returns how many."""
    k_settings, dim = mean.shape
    r = 0.0
    for s in range(eps.shape[0]):
        e2 = 0.0
        for d in range(dim):
            e2 += eps[s, d] * eps[s, d]
        r = max(r, np.sqrt(e2))
    floor = log_norm[j] - 0.5 * r * r - NEGLIGIBLE
    count = 0
    for k in range(k_settings):
        dist2 = 0.0
        gain = 0.0
        for d in range(dim):
            z = (mean[j, d] - mean[k, d]) / sigma[k, d]
            dist2 += z * z
            gain = max(gain, sigma[j, d] / sigma[k, d])
        gap = max(0.0, np.sqrt(dist2) - gain * r)
        if k == j or log_norm[k] - 0.5 * gap * gap >= floor - 1e-9 * abs(floor):
            near[count] = k
            count += 1
    return count
