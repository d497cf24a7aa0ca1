"""The twin's free parameters (:class:`Calibration`), their TOML file, and the packaged default fitted to the thesis.

What the thesis fixes and what it leaves free
---------------------------------------------
Geometry, E, gauge factor, gains and the servo are in :class:`flexdigit.params.RigParams`. Not measured in the
thesis, so fitted (by :mod:`flexdigit.calibrate`, a layer above the twin and the tactile package):

- ``support_mass_kg``: the nylon supports' masses (one value for the three: a single frequency identifies one
  mass), from the bare release tests' wn (table 3.1);
- ``housing_ei_n_m2``: the housing's bending stiffness per section, a uniform value from the housed release tests'
  wn (table 3.2) times a base-section factor from the measured deflections (table 3.6: gauge 1 bends far less than
  a uniform strip would, 3.4.1);
- ``strip_beta_s``, ``housing_beta_s``: stiffness-proportional damping of strip and housing, from the zetas of
  tables 3.1 and 3.2;
- ``cable_stiffness_n_m``: the cable's compliance, from the same deflections;
- ``channel_gain``, ``channel_offset_v``: per-channel factor on ``amplifier_gain * excitation`` and offset, from the
  gauge-volt lines E 3.20-3.22 (the excitation voltage is not given; see ``params.sensors.excitation_v``);
- noise levels, when a record of the resting rig is given (the thesis gives none: defaults are assumptions);
- ``cable_friction_ratio``: the cable-guide friction that only acts when the cable is taut
  (:mod:`flexdigit.twin.sensors`), from a measured repeatability of the actuated gauges or, as the thesis gives
  nothing else, from the actuated experiment's test corr2 (0.8998, 7.5).

Assumptions kept fixed (not identifiable from the thesis's data): the housing's mass (0: its effect on the housed
frequency is folded into the fitted housing stiffness), the digit mounted tip up for the release tests and the
sweep (2.2.4).

The file
--------
A calibration file is TOML with a ``[calibration]`` table holding every key of :class:`Calibration` (SI units, one
value per support, section or gauge where the key is a list), and optionally the ``[fit]`` table the fit wrote
(targets and residuals, for the record). It is validated on load like a parameter file: an unknown key, a missing
key, a value of the wrong type or out of its range stops with one line naming the file and the key. A *partial*
file says so explicitly with ``based_on = "default"`` at the top: the keys it leaves out are then the packaged
default's.

The packaged default (``default_calibration.toml``) is regenerated with
``flexdigit calibrate --thesis --out src/flexdigit/twin/default_calibration.toml --force``; a test re-runs the fit
and compares. :func:`use_calibration` makes another calibration the default for a block of code (what
``flexdigit reproduce --calibration FILE`` does), as :func:`sklearn.config_context` does for scikit-learn's settings.

Examples
--------
>>> cal = default_calibration()
>>> round(cal.support_mass_kg[0] * 1e3, 2)     # g, fitted to table 3.1's wn
8.39
>>> with use_calibration(cal.replace(strip_beta_s=1e-3)):
...     default_calibration().strip_beta_s
0.001
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import tomllib
from collections.abc import Iterator
from dataclasses import dataclass
from importlib import resources
from numbers import Real
from pathlib import Path
from typing import Any

from flexdigit._io import atomic_write, read_text, refuse_special
from flexdigit._repr import fields_summary
from flexdigit._validation import check_array, check_real
from flexdigit.errors import DataFileError, ParameterError

__all__ = [
    "DEFAULT_FILE",
    "BASED_ON",
    "FIELDS",
    "Calibration",
    "load_calibration",
    "load_calibration_record",
    "save_calibration",
    "packaged_calibration",
    "default_calibration",
    "default_calibration_source",
    "default_fit_record",
    "use_calibration",
]

DEFAULT_FILE = "default_calibration.toml"
#: The value of ``based_on`` that makes a file partial (its missing keys from the packaged default).
BASED_ON = ("default",)

#: Every field's kind and allowed range, declared once: ``(kind, low, high, low_open, unit)``, kind ``"support"``,
#: ``"section"`` or ``"gauge"`` for one value per support, section or gauge, ``"scalar"`` for one value. The upper
#: bounds are far beyond any plausible rig (a 1 kg support on a 0.2 g/mm strip, a gauge noise the size of the ADC
#: range): they catch a unit slip (g for kg, mV for V), not a fit's choice.
FIELDS: dict[str, tuple[str, float | None, float | None, bool, str]] = {
    "support_mass_kg": ("support", 0.0, 1.0, False, "kg"),
    "housing_ei_n_m2": ("section", 0.0, 10.0, False, "N m^2"),
    "strip_beta_s": ("scalar", 0.0, 1.0, False, "s"),
    "housing_beta_s": ("scalar", 0.0, 1.0, False, "s"),
    "cable_stiffness_n_m": ("scalar", 0.0, 1e9, True, "N/m"),
    "housing_mass_kg": ("scalar", 0.0, 1.0, False, "kg"),
    "channel_gain": ("gauge", 0.0, 1e3, True, ""),
    "channel_offset_v": ("gauge", -10.0, 10.0, False, "V"),
    "noise_white_v": ("gauge", 0.0, 5.0, False, "V"),
    "noise_drift_v_per_sqrt_s": ("gauge", 0.0, 5.0, False, "V/sqrt(s)"),
    "pot_noise_v": ("scalar", 0.0, 5.0, False, "V"),
    "cable_friction_ratio": ("scalar", 0.0, 1.0, False, ""),
}


@dataclass(frozen=True)
class Calibration:
    """The twin's fitted parameters (see the module docstring); SI units.

    Attributes
    ----------
    support_mass_kg : tuple of float
        Masses of the supports at 90, 180, 270 mm (kg).
    housing_ei_n_m2 : tuple of float
        Housing bending stiffness per section, base first (N m^2).
    strip_beta_s, housing_beta_s : float
        Stiffness-proportional damping (s): ``c = beta k``.
    cable_stiffness_n_m : float
        Tension-only cable stiffness (N/m). Assumption: 20 lb steel trace wire, ~0.35 m.
    housing_mass_kg : float
        Housing mass spread over the flexible strip (kg). Assumption: 0.
    channel_gain : tuple of float
        Per-channel factor on ``amplifier_gain_v_per_v * excitation_v``.
    channel_offset_v : tuple of float
        Per-channel output offset (V).
    noise_white_v : tuple of float
        White noise per gauge sample, standard deviation (V).
    noise_drift_v_per_sqrt_s : tuple of float
        Random-walk drift per gauge channel (V / sqrt(s)).
    pot_noise_v : float
        White noise on the potentiometer channel (V).
    cable_friction_ratio : float
        Cable-guide friction, taut cable only: standard deviation of the share of the cable tension gained or lost
        across the guides before each gauge's section (dimensionless, 0..1; 0 = none), drawn afresh whenever the
        cable is jolted in its guides (a weight hung, lifted or re-hung) and held otherwise. Each gauge's section
        then carries the extra bending moment ``ratio * e * T * xi`` (``xi`` standard normal, independent per
        gauge), zero when the cable is slack (:mod:`flexdigit.twin.sensors`).
    """

    support_mass_kg: tuple[float, ...] = (0.01, 0.01, 0.01)
    housing_ei_n_m2: tuple[float, ...] = (0.01, 0.01, 0.01)
    strip_beta_s: float = 5e-4
    housing_beta_s: float = 0.01
    cable_stiffness_n_m: float = 3.0e4
    housing_mass_kg: float = 0.0
    channel_gain: tuple[float, ...] = (0.1, 0.1, 0.1)
    channel_offset_v: tuple[float, ...] = (0.0, 0.0, 0.0)
    noise_white_v: tuple[float, ...] = (0.002, 0.002, 0.002)
    noise_drift_v_per_sqrt_s: tuple[float, ...] = (2e-4, 2e-4, 2e-4)
    pot_noise_v: float = 0.005
    cable_friction_ratio: float = 0.0

    #: every field to 4 significant digits, a few lines (issue 23: the generated repr printed 17 digits a float)
    __repr__ = fields_summary

    def __post_init__(self) -> None:
        owner = type(self).__name__
        lengths: dict[str, tuple[str, int]] = {}
        for name, (kind, low, high, low_open, _) in FIELDS.items():
            value = getattr(self, name)
            if kind == "scalar":
                object.__setattr__(self, name, check_real(value, name, owner, low=low, high=high, low_open=low_open))
                continue
            arr = check_array(value, name, owner, ndim=1, min_length=1, low=low, high=high, low_open=low_open)
            object.__setattr__(self, name, tuple(float(v) for v in arr))
            group = "gauge" if kind == "gauge" else "support"  # a support ends each section: as many of both
            first, size = lengths.setdefault(group, (name, arr.size))
            if size != arr.size:
                raise ParameterError(
                    f"The '{name}' parameter of {owner} has {arr.size} values but '{first}' has {size} values, one "
                    f"per {kind}: every per-{kind} key needs as many. Got {arr.tolist()!r}."
                )

    def replace(self, **changes: Any) -> Calibration:
        """A copy with some fields changed."""
        return dataclasses.replace(self, **changes)

    def to_dict(self) -> dict[str, Any]:
        return {k: list(v) if isinstance(v, tuple) else v for k, v in dataclasses.asdict(self).items()}

    @classmethod
    def from_dict(cls, data: dict[str, Any], source: str = "calibration", *, base: Calibration | None = None):
        """Build from a dict (a TOML ``[calibration]`` table), validated like a file.

        Every key is required unless ``base`` is given, whose values fill the keys ``data`` leaves out. An unknown
        or missing key, a value of the wrong type or out of range raises :class:`~flexdigit.errors.DataFileError`
        naming ``source`` and the key.
        """
        allowed = list(FIELDS)
        if not isinstance(data, dict):
            raise DataFileError(f"{source}: [calibration] must be a table of keys. Got {data!r} instead.")
        bad = [k for k in data if k not in FIELDS]
        if bad:
            raise DataFileError(f"{source}: unknown key {bad[0]!r} in [calibration]; expected " + ", ".join(allowed))
        missing = [k for k in allowed if k not in data]
        if missing and base is None:
            raise DataFileError(
                f"{source}: [calibration] lacks key '{missing[0]}' ({len(missing)} missing in all): a calibration "
                f'file lists every key, or says based_on = "default" to take the missing ones from the packaged '
                "default"
            )
        values = {}
        for key, value in data.items():
            kind, low, high, low_open, unit = FIELDS[key]
            values[key] = _typed(value, key, kind, unit, source)
        merged = {**(base.to_dict() if base is not None else {}), **values}
        try:
            return cls(**merged)
        except ParameterError as exc:
            raise DataFileError(f"{source}: {exc}") from None


def _typed(value: object, key: str, kind: str, unit: str, source: str):
    """The value of one key with its TOML type checked (a number, or a list of numbers); ranges are the class's."""
    unit_text = f" ({unit})" if unit else ""

    def is_number(v: object) -> bool:
        return isinstance(v, Real) and not isinstance(v, bool)

    if kind == "scalar":
        if not is_number(value):
            raise DataFileError(f"{source}: key '{key}' must be a number{unit_text}. Got {value!r} instead.")
        if not math.isfinite(float(value)):
            raise DataFileError(f"{source}: key '{key}' must be a finite number{unit_text}. Got {value!r} instead.")
        return float(value)
    if not isinstance(value, list) or not value or not all(is_number(v) for v in value):
        raise DataFileError(
            f"{source}: key '{key}' must be a list of numbers{unit_text}, one per {kind}. Got {value!r} instead."
        )
    return tuple(float(v) for v in value)


def load_calibration(path: str | Path) -> Calibration:
    """Read and validate a calibration TOML (see the module docstring for the file).

    Raises
    ------
    DataFileError
        Naming the file and the key: not TOML, no ``[calibration]`` table, an unknown or missing key, a value of
        the wrong type or out of range.
    FileNotFoundError
        If the file does not exist.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "cal.toml"
    >>> _ = path.write_text('based_on = "default"\\n[calibration]\\nstrip_beta_s = 6.5e-4\\n')
    >>> load_calibration(path).strip_beta_s
    0.00065
    """
    data = _read_toml(Path(path))
    return _from_document(data, str(path))


def load_calibration_record(path: str | Path) -> tuple[Calibration, dict[str, Any]]:
    """The calibration of a file and its ``[fit]`` table (empty when the file has none)."""
    data = _read_toml(Path(path))
    return _from_document(data, str(path)), dict(data.get("fit", {}))


def _read_toml(path: Path) -> dict:
    if not path.exists():
        raise FileNotFoundError(2, "No such file", str(path))
    refuse_special(path, "a calibration TOML")
    if not path.is_file():
        raise DataFileError(f"{path}: not a file (a directory?); expected a calibration TOML")
    try:
        return tomllib.loads(read_text(path, "a calibration TOML"))
    except (tomllib.TOMLDecodeError, RecursionError) as exc:  # RecursionError: nested past the parser
        raise DataFileError(f"{path}: not valid TOML ({exc})") from None
    except UnicodeDecodeError as exc:
        raise DataFileError(f"{path}: not a text TOML file (byte {exc.start} is not UTF-8)") from None


def _from_document(data: dict, source: str) -> Calibration:
    bad = [k for k in data if k not in ("based_on", "calibration", "fit")]
    if bad:
        raise DataFileError(f"{source}: unknown key {bad[0]!r}; expected based_on, [calibration] and [fit]")
    if "calibration" not in data:
        raise DataFileError(f"{source}: no [calibration] table")
    based_on = data.get("based_on")
    if based_on is not None and based_on not in BASED_ON:
        raise DataFileError(
            f"{source}: key 'based_on' must be one of " + ", ".join(repr(b) for b in BASED_ON) + f". Got {based_on!r}"
        )
    base = packaged_calibration() if based_on is not None else None
    return Calibration.from_dict(data["calibration"], source=source, base=base)


def save_calibration(
    calibration: Calibration, path: str | Path, fit: dict | None = None, *, force: bool = False, header: str = ""
) -> Path:
    """Write a calibration (and optionally its fit record: targets, residuals) as TOML, atomically.

    An existing file is refused unless ``force`` (:mod:`flexdigit._io`).
    """
    import tomli_w

    doc: dict[str, Any] = {"calibration": calibration.to_dict()}
    if fit:
        doc["fit"] = fit
    text = header or "# flexdigit twin calibration (SI units), written by flexdigit calibrate.\n"
    with atomic_write(path, "w", force=force) as fh:
        fh.write(text + tomli_w.dumps(doc))
    return Path(path)


_PACKAGED: Calibration | None = None
#: The calibrations :func:`use_calibration` blocks set, innermost last: (calibration, source, fit record).
_ACTIVE: list[tuple[Calibration, str, dict]] = []


def packaged_calibration() -> Calibration:
    """The packaged calibration fitted to the thesis (``default_calibration.toml``); cached."""
    global _PACKAGED
    if _PACKAGED is None:
        with resources.files(__package__).joinpath(DEFAULT_FILE).open("rb") as fh:
            data = tomllib.load(fh)
        _PACKAGED = Calibration.from_dict(data["calibration"], source=DEFAULT_FILE)
    return _PACKAGED


def default_calibration() -> Calibration:
    """The calibration the twin uses when none is passed: the packaged thesis fit, or the one a
    :func:`use_calibration` block set."""
    return _ACTIVE[-1][0] if _ACTIVE else packaged_calibration()


def default_calibration_source() -> str:
    """Where :func:`default_calibration` comes from: ``"packaged"`` or the name given to :func:`use_calibration`."""
    return _ACTIVE[-1][1] if _ACTIVE else "packaged"


def default_fit_record() -> dict[str, Any]:
    """The ``[fit]`` table of :func:`default_calibration` (targets, model values, residuals): the packaged file's,
    or the one given to :func:`use_calibration` (empty if none)."""
    if _ACTIVE:
        return dict(_ACTIVE[-1][2])
    with resources.files(__package__).joinpath(DEFAULT_FILE).open("rb") as fh:
        return tomllib.load(fh).get("fit", {})


@contextlib.contextmanager
def use_calibration(calibration: Calibration, source: str = "user", fit: dict | None = None) -> Iterator[Calibration]:
    """Make ``calibration`` the twin's default inside the block: every twin, record and study built without an
    explicit calibration uses it, and :func:`default_fit_record` returns ``fit``. The previous default comes back
    when the block ends, also on an error.

    Process-wide, not per thread: a report's chapters and their worker threads all see it (worker processes do
    not: pass the calibration to them).
    """
    if not isinstance(calibration, Calibration):
        raise ParameterError(
            f"The 'calibration' parameter of use_calibration must be a Calibration. Got {type(calibration).__name__}."
        )
    _ACTIVE.append((calibration, str(source), dict(fit or {})))
    try:
        yield calibration
    finally:
        _ACTIVE.pop()
