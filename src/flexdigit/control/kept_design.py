"""A digit's 20 ms design kept in a file, so that a run need not search its weights again.

``flexdigit run --params D.toml`` designs the digit's controller before every run
(:func:`~flexdigit.control.design20ms.digit_design_20ms`): on a digit other than the thesis rig that is a search of
48-240 weight candidates on its linearised chain, 0.1-0.25 s of CPU (0.02 s on the thesis rig, whose weights are
chapter 5's). The search's outcome is its weights; the rest of the design (the model, one LQR and one Kalman
predictor) is cheap. So a kept design is the weights the search chose, with what they were chosen for:

- the digit: the fingerprint of its description (:func:`flexdigit._json.fingerprint` of ``RigParams.to_dict()``:
  the values, not the file's bytes, so a comment or a reordered key does not matter; any changed value does);
- the twin calibration its model was linearised with (its fingerprint; the thesis's scaled to the digit unless a
  calibration was given);
- how the digit was mounted and the loop's period;
- the model's rotation per command, to which the weights' command terms are scaled.

A run with the file (``flexdigit run --params D.toml --controller ctrl.json``) checks all four against its own and
refuses a mismatch in one line (before the rig moves for the digit and the file's format, after the rotation map
for the rest), then designs with the kept weights, rescaled to the map's measured rotation per command as the
search rescales its candidates (:meth:`~flexdigit.control.design20ms.Weights.for_digit`). With the same rotation
per command the design is the searched one to the bit; with the map's measured one it is the one the search's
same candidate gives (the search itself could pick another candidate there: a kept design is a choice kept).

The file is JSON (:data:`FORMAT`), written atomically and never over an existing file without ``force``.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, fields
from pathlib import Path

from flexdigit._io import atomic_write, read_text
from flexdigit._json import fingerprint
from flexdigit.control.design20ms import Weights, digit_design_20ms_summary
from flexdigit.errors import DataFileError, DesignError, ParameterError
from flexdigit.params import RigParams
from flexdigit.twin.digit import ORIENTATIONS
from flexdigit.twin.digit_calibration import twin_calibration

__all__ = ["KeptDesign", "FORMAT", "keep_design", "write_kept_design", "read_kept_design"]

#: The ``format`` of a kept design's JSON.
FORMAT = "flexdigit-20ms-design-1"
_EXPECTED = (
    "expected a kept 20 ms design (flexdigit design 20ms --params D.toml --out FILE): format, params_fingerprint, "
    "calibration_fingerprint, orientation, period_s, deg_per_command, weights"
)


@dataclass(frozen=True)
class KeptDesign:
    """The weights of a digit's 20 ms design and what they were chosen for (module docstring).

    Attributes
    ----------
    params_fingerprint, calibration_fingerprint : str
        Of the digit's description and of the twin calibration its model used.
    orientation : str
        How the digit was mounted for the design.
    period_s : float
        The loop's sample period, s.
    deg_per_command : float
        The design model's rotation per command, deg (the weights' command terms are scaled to it).
    weights : Weights
        The searched (or, on the thesis rig, chapter 5's) weights.
    search : dict or None
        The search's worst linear figures when it was made (``flexdigit design 20ms --json``'s ``search``).
    params_file : str or None
        Where the description was read from (for the reader; the fingerprint is what is checked).
    source : str or None
        The file this design was read from (named in refusals); not part of the design.
    """

    params_fingerprint: str
    calibration_fingerprint: str
    orientation: str
    period_s: float
    deg_per_command: float
    weights: Weights
    search: dict | None = None
    params_file: str | None = None
    source: str | None = field(default=None, compare=False)

    def check(self, params: RigParams, calibration=None, *, orientation: str, period_s: float, source=None) -> None:
        """Refuse, in one line naming the file, a digit, calibration, mount or period other than the design's."""
        source = source or self.source or ""
        where = f"{source}: " if source else ""
        self.check_digit(params, source=source)
        cal = calibration_fingerprint(params, calibration)
        if cal != self.calibration_fingerprint:
            raise ParameterError(
                f"{where}designed with another twin calibration (fingerprint {self.calibration_fingerprint}, this "
                f"run's {cal}); design it with the run's --calibration"
            )
        if orientation != self.orientation:
            raise ParameterError(
                f"{where}designed for the digit mounted {self.orientation}, this run's is {orientation}; design it "
                f"with --orientation {orientation}"
            )
        if not math.isclose(period_s, self.period_s, rel_tol=1e-9, abs_tol=0.0):
            raise ParameterError(
                f"{where}designed for a {self.period_s * 1000:g} ms period, this run's is {period_s * 1000:g} ms; "
                f"design it with --period {period_s:g}"
            )

    def check_digit(self, params: RigParams | None, *, source=None) -> None:
        """Refuse, in one line naming the file, a digit other than the design's (its description's fingerprint)."""
        source = source or self.source or "the kept design"
        given = params_fingerprint(params)
        if given != self.params_fingerprint:
            of = f" of {self.params_file}" if self.params_file else ""
            raise ParameterError(
                f"{source}: a design for another digit (params fingerprint {self.params_fingerprint}{of}, this "
                f"digit's {given}); design it again: flexdigit design 20ms --params FILE --out {source} --force"
            )

    def to_dict(self) -> dict:
        return {
            "format": FORMAT,
            "params_fingerprint": self.params_fingerprint,
            "params_file": self.params_file,
            "calibration_fingerprint": self.calibration_fingerprint,
            "orientation": self.orientation,
            "period_s": self.period_s,
            "deg_per_command": self.deg_per_command,
            "weights": dict(self.weights.__dict__),
            "search": self.search,
        }


def params_fingerprint(params: RigParams | None) -> str:
    """The fingerprint of a digit's description (the thesis rig's for None)."""
    return fingerprint((params or RigParams()).to_dict())


def calibration_fingerprint(params: RigParams | None, calibration=None) -> str:
    """The fingerprint of the twin calibration a digit's design model uses: ``calibration``, or the one the twin
    gets for the digit by default (:func:`~flexdigit.twin.digit_calibration.twin_calibration`)."""
    cal = calibration if calibration is not None else twin_calibration(params or RigParams())
    return fingerprint(cal.to_dict())


def keep_design(
    params: RigParams | None = None,
    calibration=None,
    *,
    orientation: str = "vertical",
    period_s: float | None = None,
    summary: dict | None = None,
    params_file: str | None = None,
) -> KeptDesign:
    """The kept design of a digit: its weights searched now, or taken from ``summary`` (what
    :func:`~flexdigit.control.design20ms.digit_design_20ms_summary` returned for the same arguments: ``flexdigit
    design 20ms --out`` designs once).

    Examples
    --------
    >>> k = keep_design()  # the thesis rig: chapter 5's weights
    >>> k.weights == Weights(), k.period_s, round(k.deg_per_command, 3)
    (True, 0.02, 1.735)
    """
    params = params or RigParams()
    if summary is None:
        summary = digit_design_20ms_summary(params, period_s=period_s, calibration=calibration, orientation=orientation)
    return KeptDesign(
        params_fingerprint=params_fingerprint(params),
        calibration_fingerprint=calibration_fingerprint(params, calibration),
        orientation=orientation,
        period_s=float(summary["period_s"]),
        deg_per_command=float(summary["deg_per_command"]),
        weights=Weights(**summary["weights"]),
        search=summary.get("search"),
        params_file=params_file,
    )


def write_kept_design(kept: KeptDesign, path: str | Path, *, force: bool = False) -> Path:
    """Write ``kept`` as JSON to ``path`` (atomic; an existing file only with ``force``)."""
    with atomic_write(path, "w", force=force) as fh:
        json.dump(kept.to_dict(), fh, indent=2)
        fh.write("\n")
    return Path(path)


def read_kept_design(path: str | Path) -> KeptDesign:
    """Read a kept design (:meth:`KeptDesign.check_digit` then says whether it is a digit's).

    Raises
    ------
    DataFileError
        Naming the file and the key that is missing or wrong.
    """
    source = str(path)
    try:
        data = json.loads(read_text(path, "a kept 20 ms design JSON"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise DataFileError(f"{source}: not JSON ({exc}); {_EXPECTED}") from None
    except RecursionError:
        raise DataFileError(f"{source}: JSON nested too deep; {_EXPECTED}") from None
    return _from_dict(data, source)


def _from_dict(data, source: str) -> KeptDesign:
    if not isinstance(data, dict):
        raise DataFileError(f"{source}: not a kept design; {_EXPECTED}")
    if data.get("format") != FORMAT:
        raise DataFileError(f"{source}: format {data.get('format')!r}; this flexdigit reads {FORMAT!r}")
    known = {"format", "params_fingerprint", "params_file", "calibration_fingerprint", "orientation", "period_s"}
    known |= {"deg_per_command", "weights", "search"}
    unknown = sorted(set(data) - known)
    if unknown:
        raise DataFileError(f"{source}: unknown key {unknown[0]!r}; {_EXPECTED}")
    for key in sorted(known - {"params_file", "search"}):
        if key not in data:
            raise DataFileError(f"{source}: no {key!r}; {_EXPECTED}")

    def bad(key, expected):
        raise DataFileError(f"{source}: {key!r} must be {expected}. Got {data[key]!r:.80} instead.")

    for key in ("params_fingerprint", "calibration_fingerprint"):
        value = data[key]
        if not (isinstance(value, str) and len(value) == 16 and all(c in "0123456789abcdef" for c in value)):
            bad(key, "16 hex digits")
    if data["orientation"] not in ORIENTATIONS:
        bad("orientation", "one of " + ", ".join(ORIENTATIONS))
    for key in ("period_s", "deg_per_command"):
        value = data[key]
        if isinstance(value, bool) or not isinstance(value, int | float) or not (math.isfinite(value) and value > 0):
            bad(key, "a positive number")
    names = [f.name for f in fields(Weights)]
    w = data["weights"]
    if not isinstance(w, dict) or sorted(w) != sorted(names):
        bad("weights", "a table of " + ", ".join(names))
    if any(isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v) for v in w.values()):
        bad("weights", "finite numbers")
    try:
        weights = Weights(**{k: float(v) for k, v in w.items()})
    except DesignError as exc:
        raise DataFileError(f"{source}: 'weights': {exc}") from None
    search = data.get("search")
    if search is not None and not isinstance(search, dict):
        bad("search", "a table or null")
    params_file = data.get("params_file")
    if params_file is not None and not isinstance(params_file, str):
        bad("params_file", "a string or null")
    return KeptDesign(
        data["params_fingerprint"],
        data["calibration_fingerprint"],
        data["orientation"],
        float(data["period_s"]),
        float(data["deg_per_command"]),
        weights,
        search,
        params_file,
        source,
    )
