"""scikit-learn's estimator contract for flexdigit's estimators, with declared parameter validation.

:class:`Estimator` is scikit-learn's ``BaseEstimator`` (``get_params``/``set_params``, cloning, use in a
``Pipeline`` or ``GridSearchCV``) whose ``_parameter_constraints`` are flexdigit's declared constraints
(:mod:`flexdigit._validation`): ``__init__`` only stores its keyword arguments, ``fit`` calls
:meth:`Estimator._validate_params` first, sets attributes ending in ``_`` and returns ``self``; ``predict`` on an
unfitted estimator raises scikit-learn's :class:`~sklearn.exceptions.NotFittedError` (a ``ValueError``) through
:func:`~sklearn.utils.validation.check_is_fitted`. Every subclass is registered for the declared-validation test.
"""

from __future__ import annotations

from sklearn.base import BaseEstimator
from sklearn.exceptions import NotFittedError
from sklearn.utils.validation import check_is_fitted

from flexdigit._validation import check_params, declare

__all__ = ["Estimator", "NotFittedError", "check_is_fitted"]


class Estimator(BaseEstimator):
    """Base of flexdigit's estimators: scikit-learn's ``BaseEstimator`` plus declared parameter validation."""

    _parameter_constraints: dict = {}

    def __init_subclass__(cls, **kwargs) -> None:
        super().__init_subclass__(**kwargs)
        if cls.__dict__.get("_parameter_constraints"):
            declare(cls)

    def _validate_params(self) -> None:
        """Check the constructor's parameters against ``_parameter_constraints`` (call it first in ``fit``)."""
        check_params(self.get_params(deep=False), self._parameter_constraints, type(self).__name__)
