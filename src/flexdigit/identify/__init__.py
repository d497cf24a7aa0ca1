"""System identification (thesis 3.1.2, 3.2.4, 3.4): from a release or step record to a validated model.

- :mod:`~flexdigit.identify.timeseries`: recordings from CSV/Parquet (``read_timeseries``), the twin's tables
  (``series_from_table``) or arrays, with errors naming file, column and line;
- :mod:`~flexdigit.identify.response`: %OS, peak/rise/2 % settling time, damped frequency, log decrement, and the
  thesis's zeta(%OS), wn = 4/(zeta Ts) with the bias of the latter;
- :mod:`~flexdigit.identify.fit`: least-squares second-order fit with confidence intervals (``SecondOrderFit``),
  ARX (``fit_arx``), straight lines of 3.4 (``fit_linear``);
- :mod:`~flexdigit.identify.filters`: the SVD and FFT filters of 3.2.4 and zero-phase Butterworth;
- :mod:`~flexdigit.identify.scores`: MATLAB's ``corr2`` and the NRMSE fit;
- :mod:`~flexdigit.identify.identification`: ``identify(series, "release" | "step", method="thesis" | "lsq" | "arx")``.

The submodules are imported on demand (``flexdigit --help`` stays fast).
"""
