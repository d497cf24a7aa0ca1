"""One rig to evaluate in a study: its parameters, its twin calibration and an optional antagonistic cable.

Its own module, below both :mod:`~flexdigit.studies.spec` (which makes parameter sets from a spec) and
:mod:`~flexdigit.studies.metrics` (which scores them), so that neither imports the other to get it.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

from flexdigit._repr import differences, summary
from flexdigit.params import RigParams
from flexdigit.twin.calibration import Calibration
from flexdigit.twin.digit_calibration import twin_calibration

__all__ = ["ParameterSet"]


@dataclass(frozen=True)
class ParameterSet:
    """One rig to evaluate: its parameters, its twin calibration and, for designs beyond the thesis, a second
    antagonistic cable (its pretension in N, both cables; None: the thesis's single cable, 2.1).

    The calibration left out is the twin's one default for ``params``
    (:func:`~flexdigit.twin.digit_calibration.twin_calibration`: the packaged thesis fit for the thesis rig, the
    thesis's scaled to another digit), as ``Twin(params)`` and the commands take it.

    Examples
    --------
    >>> from flexdigit.params import Geometry
    >>> from flexdigit.twin.calibration import default_calibration
    >>> ParameterSet().calibration == default_calibration()
    True
    >>> len(ParameterSet(RigParams(geometry=Geometry(gauge_positions_m=(0.045, 0.135)))).calibration.channel_gain)
    2
    """

    params: RigParams = field(default_factory=RigParams)
    calibration: Calibration = None  # type: ignore[assignment]  # None: twin_calibration(params)
    antagonist_pretension_n: float | None = None

    def __post_init__(self) -> None:
        if self.calibration is None:
            object.__setattr__(self, "calibration", twin_calibration(self.params))

    def description(self) -> RigParams:
        """The rig as a parameter file describes it (issue 24: one description for the study and the commands):
        the antagonistic pair, if any, in ``[cables]``.

        Examples
        --------
        >>> ParameterSet(antagonist_pretension_n=5.0).description().cables.count
        2
        """
        pre = self.antagonist_pretension_n
        cables = (
            self.params.cables if pre is None else dataclasses.replace(self.params.cables, count=2, pretension_n=pre)
        )
        return self.params.replace(cables=cables)

    @property
    def pair_pretension_n(self) -> float | None:
        """The antagonistic pair's pretension (N) this rig runs with, None for a single cable: the study's
        ``antagonist_pretension_n`` if set, else the pair its parameters describe (``[cables] count = 2``), so a
        digit's own description reaches the batched twin as it reaches the scalar one.

        Examples
        --------
        >>> from flexdigit.params import Cables
        >>> ParameterSet(RigParams(cables=Cables(count=2, pretension_n=3.0))).pair_pretension_n
        3.0
        >>> ParameterSet().pair_pretension_n is None
        True
        """
        cables = self.description().cables
        return float(cables.pretension_n) if cables.count == 2 else None

    def __repr__(self) -> str:
        return summary(
            self,
            antagonist_pretension_n=self.antagonist_pretension_n,
            **differences(self.params, RigParams()),
            **{"calibration." + k: v for k, v in differences(self.calibration, twin_calibration(self.params)).items()},
        )
