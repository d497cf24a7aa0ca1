"""The digit's centre line from the three gauges and the servo command, with its uncertainty (thesis 1.1, 3.3-3.4).

:mod:`~flexdigit.shape.shape` holds the estimator; the live page and the report show it.
"""
