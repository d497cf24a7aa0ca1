"""Noise filters for identification records (thesis 3.2.4): the SVD and FFT filters, and zero-phase Butterworth.

The thesis filtered its noisy servo step responses two ways (3.2.4, all in MATLAB during acquisition):

- an **FFT filter** keeping ``N`` harmonics. Its trade-off, as the thesis describes it: with ``N`` too large the
  noise is not filtered; with ``N`` too low the truncated Fourier series adds its own sinusoidal ripple (Gibbs
  ringing, worst at the ends of a non-periodic record such as a step), "making the plot even more irregular than
  the original";
- an **SVD filter** (singular spectrum analysis): the record is embedded in a Hankel (trajectory) matrix, only
  the leading singular values are kept ("in our case the 2nd largest", i.e. rank 2, the rank of one damped
  sinusoid), and the matrix is turned back into a series by averaging its anti-diagonals. The thesis found it
  the better of the two: it smooths without losing the signal. Its parameters are the rank (too low drops part of
  the signal: a step on an offset is rank 3; too high lets noise back in) and the window length.

Both treat the samples as uniformly spaced. :func:`butter_filter` (zero-phase Butterworth, ``scipy.signal``'s
``sosfiltfilt``) is the sensible default: no phase lag, no end ringing, one physical parameter (the cut-off).

Examples
--------
>>> t = np.linspace(0, 5, 2501)
>>> clean = np.exp(-0.9 * t) * np.cos(13.1 * t)
>>> noisy = clean + np.random.default_rng(0).normal(0, 0.05, t.size)
>>> noise_reduction(clean, noisy, svd_filter(noisy, rank=2)) > 0.9
True
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from scipy import signal
from threadpoolctl import threadpool_limits

from flexdigit._validation import check_array, check_int, check_positive
from flexdigit.errors import DataFileError

__all__ = [
    "FILTERS",
    "svd_filter",
    "singular_spectrum",
    "fft_filter",
    "butter_filter",
    "default_cutoff_hz",
    "apply_filter",
    "noise_reduction",
]

#: The filters by name, as the CLI and :func:`apply_filter` know them.
FILTERS = ("butter", "svd", "fft", "none")


def svd_filter(y, rank: int = 2, window: int | None = None) -> np.ndarray:
    """SVD (singular-spectrum) filter of 3.2.4: keep the ``rank`` leading singular values of the Hankel matrix.

    Parameters
    ----------
    y : array_like
        Uniformly sampled signal, at least 4 samples.
    rank : int
        Number of leading singular values kept (thesis: 2). A damped sinusoid is rank 2, plus an offset rank 3.
    window : int, optional
        Rows of the trajectory matrix ``L`` (default ``min(n // 2, 256)``): longer windows separate signal from
        noise better and cost ``O(L^2 n)``.

    Returns
    -------
    ndarray
        The filtered signal, same length.

    Examples
    --------
    >>> np.allclose(svd_filter(np.cos(0.3 * np.arange(50)), rank=2), np.cos(0.3 * np.arange(50)))
    True
    """
    x = check_array(y, "y", "svd_filter", ndim=1, min_length=4, error=DataFileError)
    n = x.size
    L = min(n // 2, 256) if window is None else check_int(window, "window", "svd_filter", low=2, high=n - 1)
    r = check_int(rank, "rank", "svd_filter", low=1, high=min(L, n - L + 1))
    trajectory = np.ascontiguousarray(np.lib.stride_tricks.sliding_window_view(x, n - L + 1))  # L x K Hankel
    # the r leading left singular vectors are the leading eigenvectors of the L x L lag covariance X X^T (basic
    # SSA): far cheaper than a full SVD of X, and only those r are needed
    with threadpool_limits(1):  # a few-hundred-square problem: threads only add contention on a busy machine
        _, vectors = np.linalg.eigh(trajectory @ trajectory.T)  # ascending eigenvalues
    u = vectors[:, L - r :]
    low_rank = u @ (u.T @ trajectory)  # projection onto the leading r-dimensional subspace
    return _diagonal_average(low_rank)


def singular_spectrum(y, window: int | None = None) -> np.ndarray:
    """Singular values of the Hankel matrix :func:`svd_filter` truncates, largest first (for choosing ``rank``)."""
    x = check_array(y, "y", "singular_spectrum", ndim=1, min_length=4, error=DataFileError)
    L = min(x.size // 2, 256) if window is None else check_int(window, "window", low=2, high=x.size - 1)
    return np.linalg.svd(np.lib.stride_tricks.sliding_window_view(x, x.size - L + 1), compute_uv=False)


def _diagonal_average(matrix: np.ndarray) -> np.ndarray:
    """Hankelisation: the series whose sample ``k`` is the mean of the anti-diagonal ``i + j = k``."""
    rows, cols = matrix.shape
    index = (np.arange(rows)[:, None] + np.arange(cols)[None, :]).ravel()
    sums = np.bincount(index, weights=matrix.ravel(), minlength=rows + cols - 1)
    counts = np.bincount(index, minlength=rows + cols - 1)
    return sums / counts


def fft_filter(y, harmonics: int, *, detrend: bool = False) -> np.ndarray:
    """FFT filter of 3.2.4: keep the mean and the ``harmonics`` lowest harmonics of the record.

    Parameters
    ----------
    y : array_like
        Uniformly sampled signal.
    harmonics : int
        ``N``, the number of harmonics of ``1 / record length`` kept (the thesis's MATLAB "N" parameter).
    detrend : bool
        Remove the straight line through the end points first and add it back after, which makes the record
        periodic and removes most of the end ringing (not in the thesis; off by default).

    Returns
    -------
    ndarray

    Examples
    --------
    >>> k = np.arange(64)
    >>> np.allclose(fft_filter(np.sin(2 * np.pi * 3 * k / 64) + np.sin(2 * np.pi * 20 * k / 64), 5),
    ...             np.sin(2 * np.pi * 3 * k / 64))
    True
    """
    x = check_array(y, "y", "fft_filter", ndim=1, min_length=4, error=DataFileError)
    n_keep = check_int(harmonics, "harmonics", "fft_filter", low=0)
    trend = np.zeros_like(x)
    if detrend:
        trend = np.linspace(x[0], x[-1], x.size)
    spectrum = np.fft.rfft(x - trend)
    spectrum[n_keep + 1 :] = 0.0
    return np.fft.irfft(spectrum, n=x.size) + trend


def butter_filter(y, sample_rate_hz: float, cutoff_hz: float, order: int = 4) -> np.ndarray:
    """Zero-phase low-pass Butterworth filter (``scipy.signal.butter`` + ``sosfiltfilt``).

    Parameters
    ----------
    y : array_like
        Uniformly sampled signal.
    sample_rate_hz, cutoff_hz : float
        Sampling rate and -3 dB cut-off (Hz; the cut-off is below Nyquist). Filtering forward and backward
        squares the magnitude response (-6 dB at the cut-off) and cancels the phase.
    order : int
        Butterworth order (of one pass).

    Examples
    --------
    >>> t = np.arange(0, 2, 1e-3)
    >>> out = butter_filter(np.sin(2 * np.pi * t) + np.sin(2 * np.pi * 100 * t), 1000, 10)
    >>> bool(np.max(np.abs(out - np.sin(2 * np.pi * t))[200:-200]) < 0.01)
    True
    """
    x = check_array(y, "y", "butter_filter", ndim=1, min_length=4, error=DataFileError)
    fs = check_positive(sample_rate_hz, "sample_rate_hz", "butter_filter")
    fc = check_positive(cutoff_hz, "cutoff_hz", "butter_filter", high=fs / 2, high_open=True)
    n = check_int(order, "order", "butter_filter", low=1, high=12)
    sos, zi = _butter_design(n, fc, fs)
    pad = min(x.size - 1, 3 * (2 * len(sos) + 1) * 10)
    # scipy.signal.sosfiltfilt (padtype "odd") on 1-D x, step for step, with the design and its initial state
    # cached: an identification filters at the same few cut-offs hundreds of times, and designing was 2/3 of a call
    ext = np.concatenate((2 * x[:1] - x[pad:0:-1], x, 2 * x[-1:] - x[-2 : -(pad + 2) : -1])) if pad else x
    y, _ = signal.sosfilt(sos, ext, zi=zi * ext[0])
    y, _ = signal.sosfilt(sos, y[::-1], zi=zi * y[-1])
    y = y[::-1]
    return y[pad:-pad].copy() if pad else y.copy()


@lru_cache(maxsize=256)
def _butter_design(order: int, cutoff_hz: float, sample_rate_hz: float):
    """A low-pass Butterworth's second-order sections and their step-response initial state (shared: never
    modify them; sosfilt needs the sections writable)."""
    sos = signal.butter(order, cutoff_hz, btype="low", fs=sample_rate_hz, output="sos")
    return sos, signal.sosfilt_zi(sos)


def default_cutoff_hz(t_s, y) -> float:
    """A Butterworth cut-off for a release or step record: 5 x its dominant frequency, at least 20 / duration.

    The dominant frequency is the peak of the Hann-windowed spectrum of ``y - final value``; the result is kept
    below 0.4 x the sampling rate (Hz).
    """
    t = np.asarray(t_s, dtype=float)
    x = np.asarray(y, dtype=float)
    fs = (t.size - 1) / (t[-1] - t[0])
    dev = x - np.mean(x[-max(3, x.size // 10) :])
    spec = np.abs(np.fft.rfft(dev * np.hanning(x.size)))
    freqs = np.fft.rfftfreq(x.size, 1.0 / fs)
    f_peak = float(freqs[1 + int(np.argmax(spec[1:]))]) if spec.size > 1 else 0.0
    return float(min(0.4 * fs, max(5.0 * f_peak, 20.0 / (t[-1] - t[0]))))


def apply_filter(t_s, y, method: str = "butter", **options) -> np.ndarray:
    """Filter ``y`` by name: ``"butter"`` (``cutoff_hz``, ``order``), ``"svd"`` (``rank``, ``window``),
    ``"fft"`` (``harmonics``, ``detrend``) or ``"none"``.

    Defaults: Butterworth at :func:`default_cutoff_hz`; SVD rank 3 (a response on an offset); FFT 20 harmonics.
    """
    if method not in FILTERS:
        raise ValueError(f"The 'filter' parameter must be one of {', '.join(map(repr, FILTERS))}. Got {method!r}.")
    if method == "none":
        return np.asarray(y, dtype=float).copy()
    if method == "svd":
        return svd_filter(y, rank=options.get("rank", 3), window=options.get("window"))
    if method == "fft":
        return fft_filter(y, options.get("harmonics", 20), detrend=options.get("detrend", False))
    t = np.asarray(t_s, dtype=float)
    fs = (t.size - 1) / (t[-1] - t[0])
    cutoff = options.get("cutoff_hz") or default_cutoff_hz(t, y)
    return butter_filter(y, fs, cutoff, order=options.get("order", 4))


def noise_reduction(clean, noisy, filtered) -> float:
    """Fraction of the noise power a filter removed: ``1 - mean((filtered - clean)^2) / mean((noisy - clean)^2)``.

    Counts signal distortion as remaining noise, so a filter that flattens the signal scores badly too.
    """
    c = np.asarray(clean, dtype=float)
    before = np.mean((np.asarray(noisy, dtype=float) - c) ** 2)
    after = np.mean((np.asarray(filtered, dtype=float) - c) ** 2)
    return float(1.0 - after / before)
