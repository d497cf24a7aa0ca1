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
