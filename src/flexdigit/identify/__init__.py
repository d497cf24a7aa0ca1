"""System identification (thesis 3.1.2, 3.2.4, 3.4): from a release or step record to a validated model.

- :mod:`~flexdigit.identify.timeseries`: recordings from CSV/Parquet (``read_timeseries``; other rigs' layouts:
  delimiters, decimal commas, units in brackets), the twin's tables (``series_from_table``) or arrays, with
  errors naming file, column and line;
- :mod:`~flexdigit.identify.events`: the step or release instant found from the record, its spikes, mains hum and
  noise, and the problems that make it unfit to identify (``survey``);
- :mod:`~flexdigit.identify.response`: %OS, peak/rise/2 % settling time, damped frequency, log decrement, and the
  thesis's zeta(%OS), wn = 4/(zeta Ts) with the bias of the latter;
- :mod:`~flexdigit.identify.fit`: second-order fit, robust to spikes, with a drift and confidence intervals
  (``SecondOrderFit``), ARX (``fit_arx``), straight lines of 3.4 (``fit_linear``);
- :mod:`~flexdigit.identify.filters`: the SVD and FFT filters of 3.2.4 and zero-phase Butterworth;
- :mod:`~flexdigit.identify.scores`: MATLAB's ``corr2``, the NRMSE fit, the Ljung-Box test;
- :mod:`~flexdigit.identify.quality`: how far a fit can be trusted (misfit, whiteness, clipping, second steps);
- :mod:`~flexdigit.identify.identification`: ``identify(series, "release" | "step", method="thesis" | "lsq" | "arx")``.

The submodules are imported on demand (``flexdigit --help`` stays fast).
"""

from flexdigit._lazy import lazy_exports

#: Public names and the module each lives in, imported on first use (PEP 562): importing the package loads
#: none of its modules, so `flexdigit --help` stays fast; `dir()` lists them all the same.
__getattr__, __all__ = lazy_exports(
    __name__,
    {
        "TimeSeries": "flexdigit.identify.timeseries",
        "read_timeseries": "flexdigit.identify.timeseries",
        "series_from_table": "flexdigit.identify.timeseries",
        "Survey": "flexdigit.identify.events",
        "survey": "flexdigit.identify.events",
        "find_spikes": "flexdigit.identify.events",
        "remove_hum": "flexdigit.identify.events",
        "ResponseFeatures": "flexdigit.identify.response",
        "analyze_response": "flexdigit.identify.response",
        "zeta_from_overshoot": "flexdigit.identify.response",
        "wn_from_settling_time": "flexdigit.identify.response",
        "NoOscillationError": "flexdigit.identify.response",
        "SecondOrderFit": "flexdigit.identify.fit",
        "ARXModel": "flexdigit.identify.fit",
        "fit_arx": "flexdigit.identify.fit",
        "LinearRelation": "flexdigit.identify.fit",
        "fit_linear": "flexdigit.identify.fit",
        "svd_filter": "flexdigit.identify.filters",
        "fft_filter": "flexdigit.identify.filters",
        "butter_filter": "flexdigit.identify.filters",
        "apply_filter": "flexdigit.identify.filters",
        "corr2": "flexdigit.identify.scores",
        "nrmse_fit": "flexdigit.identify.scores",
        "ljung_box": "flexdigit.identify.scores",
        "FitQuality": "flexdigit.identify.quality",
        "assess": "flexdigit.identify.quality",
        "Identification": "flexdigit.identify.identification",
        "identify": "flexdigit.identify.identification",
        "fit_figure": "flexdigit.identify.fit_plot",
        "average_runs": "flexdigit.identify.identification",
        "twin_identification": "flexdigit.identify.chapter3_identification",
        "noisy_records_study": "flexdigit.identify.chapter3_identification",
        "Chapter3IdentifyStudy": "flexdigit.identify.chapter3_identification",
        "chapter3_identify_study": "flexdigit.identify.chapter3_identification",
    },
)
