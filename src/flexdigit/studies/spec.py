"""Uncertain parameters: a TOML that gives a distribution or a range to any field of the rig and the calibration.

The thesis's first item of future work (chapter 8) is "a sensitivity and stability analysis ... into the effects of
all system parameters"; 2.1 asks what the digit's size does to its stiffness and stability. A study spec says
which fields of :class:`~flexdigit.params.RigParams` and :class:`~flexdigit.twin.calibration.Calibration` are
uncertain and how, one table per field::

    [study]
    name = "thesis-tolerances"
    seed = 0
    metrics = ["release_wn_rad_s", "rotation_gain_deg_per_command"]

    [parameters.geometry.strip_thickness_m]     # 0.015 in feeler stock
    distribution = "uniform"
    delta = 0.0127e-3                           # nominal +- 0.0127 mm
    source = "shim-stock thickness tolerance, +-0.0005 in (datasheet class)"

    [parameters.calibration.housing_ei_n_m2]    # a tuple field: one factor moves every element
    distribution = "normal"
    relative_sd = 0.08

    [parameters.geometry.gauge_positions_m.0]   # one element of a tuple field
    distribution = "uniform"
    delta = 1e-3

Distributions (the nominal value is the baseline rig's, :attr:`UncertainParameter.nominal`):

- ``uniform``: ``low`` and ``high``, or ``relative`` (nominal x (1 +- r)), or ``delta`` (nominal +- d);
- ``triangular``: the same bounds, peak at ``mode`` (default the nominal value);
- ``normal``: ``sd`` or ``relative_sd``, mean ``mean`` (default nominal), optionally truncated to ``low``/``high``;
- ``lognormal``: ``sigma_log`` (standard deviation of the log), median ``median`` (default nominal).

A tuple field without an element index is moved as a whole by one factor (nominal 1), so only the relative forms
apply to it. Everything is checked when the spec is read, like a parameter file: an unknown section, field or key,
an empty range, a distribution whose range reaches values the field refuses (a negative stiffness, a thickness of
0), each a one-line :class:`~flexdigit.errors.ParameterError` naming the file and the key. The declared constraints
live in the dataclasses themselves: a range is checked by building the rig at its two ends (six standard
deviations out for an unbounded normal), so the spec never restates them.

Examples
--------
>>> spec = spec_from_toml('''
... [parameters.material.youngs_modulus_pa]
... distribution = "uniform"
... low = 195e9
... high = 215e9
... ''')
>>> p = spec.parameters[0]
>>> p.name, float(p.ppf(0.5))
('material.youngs_modulus_pa', 205000000000.0)
>>> spec.parameter_set({"material.youngs_modulus_pa": 2.0e11}).params.material.youngs_modulus_pa
200000000000.0
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import re
import tomllib
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats

from flexdigit._io import read_text, refuse_special
from flexdigit._repr import summary
from flexdigit.errors import DataFileError, ParameterError
from flexdigit.params import RigParams, load_params
from flexdigit.studies.metrics import METRICS, UserMetric, checked_value
from flexdigit.studies.parameter_set import ParameterSet
from flexdigit.twin.calibration import load_calibration

__all__ = [
    "shipped_specs",
    "DISTRIBUTIONS",
    "ParameterSet",
    "UncertainParameter",
    "StudySpec",
    "load_spec",
    "spec_from_toml",
    "SHIPPED_SPECS",
]

#: Keys each distribution takes (besides ``distribution`` and ``source``); alternatives are listed in order.
DISTRIBUTIONS: dict[str, tuple[str, ...]] = {
    "uniform": ("low", "high", "relative", "delta"),
    "triangular": ("low", "high", "relative", "delta", "mode"),
    "normal": ("mean", "sd", "relative_sd", "low", "high"),
    "lognormal": ("median", "sigma_log"),
}
#: How far an unbounded distribution's range is checked against the field's constraints (standard deviations).
CHECK_SIGMAS = 6.0
_LOG_MAX_FLOAT = math.log(np.finfo(float).max)  # math.exp beyond it raises OverflowError
SECTIONS = ("geometry", "material", "sensors", "actuator", "dynamics", "calibration")
#: Specs shipped with flexdigit (``flexdigit study sensitivity thesis-tolerances``).
SHIPPED_SPECS = ("thesis-tolerances", "thesis-design", "thesis-taper")


@dataclass(frozen=True)
class UncertainParameter:
    """One uncertain field (or element of a tuple field, or a factor on a whole tuple field).

    Attributes
    ----------
    name : str
        ``section.field``, ``section.field[k]`` (element ``k``) or ``section.field[*]`` (a factor on every element).
    section, field : str
    element : int or None
        The tuple element (0-based); None for a scalar field or a whole-tuple factor.
    distribution : str
        One of :data:`DISTRIBUTIONS`.
    nominal : float
        The baseline's value (1 for a whole-tuple factor).
    low, high : float
        The support (may be infinite for ``normal`` and ``lognormal``).
    shape : dict
        The distribution's other numbers (``mean``, ``sd``, ``mode``, ``median``, ``sigma_log``).
    source : str
        Where the tolerance comes from (datasheet class, thesis text, engineering judgement).
    """

    name: str
    section: str
    field: str
    element: int | None
    distribution: str
    nominal: float
    low: float
    high: float
    shape: dict = field(default_factory=dict)
    source: str = ""

    @property
    def is_factor(self) -> bool:
        """True for a factor on a whole tuple field."""
        return self.name.endswith("[*]")

    def ppf(self, u) -> np.ndarray:
        """Values at probabilities ``u`` in (0, 1) (the inverse CDF): how unit-cube samples become values."""
        u = np.asarray(u, dtype=float)
        lo, hi = self.low, self.high
        if self.distribution == "uniform":
            return lo + u * (hi - lo)
        if self.distribution == "triangular":
            c = (self.shape["mode"] - lo) / (hi - lo)
            return stats.triang.ppf(u, c, loc=lo, scale=hi - lo)
        if self.distribution == "normal":
            mean, sd = self.shape["mean"], self.shape["sd"]
            if math.isinf(lo) and math.isinf(hi):
                return stats.norm.ppf(u, loc=mean, scale=sd)
            return stats.truncnorm.ppf(u, (lo - mean) / sd, (hi - mean) / sd, loc=mean, scale=sd)
        return self.shape["median"] * np.exp(self.shape["sigma_log"] * stats.norm.ppf(u))  # lognormal

    def check_range(self) -> tuple[float, float]:
        """The two values checked against the field's constraints: the support's ends, or six sigmas out."""
        lo, hi = self.low, self.high
        if self.distribution == "normal":
            mean, sd = self.shape["mean"], self.shape["sd"]
            lo = max(lo, mean - CHECK_SIGMAS * sd)
            hi = min(hi, mean + CHECK_SIGMAS * sd)
        elif self.distribution == "lognormal":
            spread = CHECK_SIGMAS * self.shape["sigma_log"]
            lo = self.shape["median"] * math.exp(-spread)
            hi = self.shape["median"] * (math.exp(spread) if spread < _LOG_MAX_FLOAT else math.inf)
        return lo, hi

    def describe(self) -> str:
        """A short description such as ``uniform [0.368, 0.394] mm``-like text (SI units)."""
        if self.distribution in ("uniform", "triangular"):
            return f"{self.distribution} [{self.low:.6g}, {self.high:.6g}]"
        if self.distribution == "normal":
            text = f"normal mean {self.shape['mean']:.6g} sd {self.shape['sd']:.6g}"
            if math.isfinite(self.low) or math.isfinite(self.high):
                text += f" truncated to [{self.low:.6g}, {self.high:.6g}]"
            return text
        return f"lognormal median {self.shape['median']:.6g} sigma_log {self.shape['sigma_log']:.6g}"


@dataclass(frozen=True)
class StudySpec:
    """A parsed study spec: uncertain parameters, the study's settings and the baseline rig.

    Attributes
    ----------
    name : str
    seed : int
    parameters : tuple of UncertainParameter
    metrics : tuple of str
        Metric names (:data:`flexdigit.studies.metrics.METRICS`); empty means the study's default set.
    settings : dict
        The other tables (``[sensitivity]``, ``[design]``), as read; each study validates its own.
    baseline : ParameterSet
    source : str
        The file (or ``"spec"``) named in error messages.
    user_metrics : tuple of UserMetric
        The spec's own metrics (``[metrics.NAME]``: ``function = "module:function"`` of a parameter set and its
        ``unit``), run after the built-in ones the study computes.
    """

    name: str
    seed: int
    parameters: tuple[UncertainParameter, ...]
    metrics: tuple[str, ...]
    settings: dict
    baseline: ParameterSet
    source: str = "spec"
    user_metrics: tuple = ()

    @property
    def names(self) -> list[str]:
        return [p.name for p in self.parameters]

    def __repr__(self) -> str:
        # the study at a glance (issue 23: the generated repr printed every parameter's source, 5,700 characters)
        return summary(
            self,
            name=self.name,
            seed=self.seed,
            parameters=self.names,
            metrics=self.metrics,
            settings=list(self.settings),
            source=self.source,
        )

    def study_metrics(self, default) -> tuple[str, ...]:
        """The metrics a study computes: ``[study] metrics`` (or ``default``), then the spec's own not listed."""
        listed = tuple(self.metrics or default)
        return listed + tuple(u.name for u in self.user_metrics if u.name not in listed)

    def fingerprint(self) -> str:
        """A hash of everything that decides the study's numbers (not the file's comments or layout)."""
        doc = {
            "name": self.name,
            "seed": self.seed,
            "metrics": list(self.metrics),
            "settings": self.settings,
            "parameters": [dataclasses.asdict(p) for p in self.parameters],
            "baseline": {"params": self.baseline.params.to_dict(), "calibration": self.baseline.calibration.to_dict()},
        }
        if self.user_metrics:  # (absent otherwise: the fingerprints of specs without them stay as they were)
            doc["user_metrics"] = [[u.name, u.function, u.unit] for u in self.user_metrics]
        text = json.dumps(doc, sort_keys=True, default=repr)
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    def values_from_unit(self, u) -> np.ndarray:
        """Map unit-cube samples (n, d) to parameter values (n, d) column by column."""
        u = np.atleast_2d(np.asarray(u, dtype=float))
        if u.shape[1] != len(self.parameters):
            raise ParameterError(
                f"{self.source}: samples have {u.shape[1]} columns for {len(self.parameters)} parameters"
            )
        return np.column_stack([p.ppf(u[:, j]) for j, p in enumerate(self.parameters)])

    def parameter_set(self, values, label: str = "sample") -> ParameterSet:
        """The baseline rig with the uncertain fields set to ``values`` (a mapping name -> value, or a row).

        Raises
        ------
        ParameterError
            Naming ``label`` and the field, if the rig refuses a value (e.g. a gauge beyond the tip).
        """
        if not isinstance(values, dict):
            row = np.asarray(values, dtype=float).reshape(-1)
            values = dict(zip(self.names, row, strict=True))
        return apply_values(self.baseline, self.parameters, values, label)


# --------------------------------------------------------------------------------------------------- applying
def apply_values(baseline: ParameterSet, parameters, values: dict, label: str) -> ParameterSet:
    """``baseline`` with each parameter's value set (see :meth:`StudySpec.parameter_set`).

    Only the sections a parameter touches are rebuilt (``dataclasses.replace``), so their own validation runs and
    the rest is reused: a few hundred microseconds a row, not the milliseconds of a round trip through a dict.
    A section rebuilt with the same values as a recent row is that row's (frozen, already validated): in a
    Saltelli design most rows move one parameter, so most of their sections repeat another row's.
    """
    changes: dict[str, dict] = {}
    for p in parameters:
        value = float(values[p.name])
        section = baseline.calibration if p.section == "calibration" else getattr(baseline.params, p.section)
        fields = changes.setdefault(p.section, {})
        current = fields.get(p.field, getattr(section, p.field))
        if p.is_factor:
            fields[p.field] = tuple(float(v) * value for v in current)
        elif p.element is not None:
            current = list(current)
            current[p.element] = value
            fields[p.field] = tuple(current)
        else:
            fields[p.field] = value
    where = "calibration"
    try:
        calibration = baseline.calibration
        if "calibration" in changes:
            calibration = _replaced(calibration, tuple(changes.pop("calibration").items()))
        sections = {}
        for where, kw in changes.items():
            sections[where] = _replaced(getattr(baseline.params, where), tuple(kw.items()))
        where = "rig"
        params = dataclasses.replace(baseline.params, **sections) if sections else baseline.params
    except (ParameterError, DataFileError, TypeError) as exc:
        raise ParameterError(f"{label}: [{where}] {exc}") from None
    return ParameterSet(params, calibration, baseline.antagonist_pretension_n)


@lru_cache(maxsize=4096)
def _replaced(section, changes: tuple):
    """``dataclasses.replace(section, **dict(changes))``, remembered (a refused value raises and is not)."""
    return dataclasses.replace(section, **dict(changes))


# --------------------------------------------------------------------------------------------------- reading
def load_spec(
    name_or_path: str | Path,
    *,
    baseline: ParameterSet | None = None,
    fields: tuple[str, ...] | None = None,
    scaled: bool = False,
) -> StudySpec:
    """Read a study spec: a file, or the name of a shipped one (:data:`SHIPPED_SPECS`).

    ``baseline``: the rig the spec's tolerances are taken about (a digit's description and calibration), instead of
    the spec's ``[study] params`` / ``calibration`` (refused if it names them too) or the thesis rig; its
    relative and ``delta`` ranges are then about that rig's values. ``fields``: keep only these
    ``[parameters.SECTION.FIELD]`` tables (``"section.field"``), e.g. the ones that apply to such a rig (the thesis
    rig's three gauge positions do not to a digit of one gauge). ``scaled`` (with ``baseline``): the spec's absolute
    values of a real field (``low``, ``high``, ``mode``, ``mean``, ``sd``, ``median``), set about the spec's own rig,
    are multiplied by the baseline's value over that rig's: the same relative spread about the baseline (the thesis
    steel's 195-215 GPa becomes +-4.9 % about a PEEK strip's modulus, not a steel range it cannot take).

    Raises
    ------
    ParameterError
        Naming the file and the key, for anything the spec gets wrong.
    FileNotFoundError
        If there is no such file and no shipped spec of that name.
    """
    text_name = str(name_or_path)
    path = Path(name_or_path)
    if not path.exists() and text_name in SHIPPED_SPECS:
        from importlib import resources

        ref = resources.files("flexdigit.studies").joinpath("specs").joinpath(f"{text_name}.toml")
        text, source = ref.read_text(), f"{text_name}.toml"
        return spec_from_toml(text, source=source, baseline=baseline, fields=fields, scaled=scaled)
    if path.is_dir():
        raise IsADirectoryError(f"{path}: is a directory, not a study spec")
    text = read_text(path, "a study spec TOML")  # binary garbage: named, not a codec error
    return spec_from_toml(text, source=str(path), base_dir=path.parent, baseline=baseline, fields=fields, scaled=scaled)


def shipped_specs() -> dict[str, str]:
    """The shipped study specs (:data:`SHIPPED_SPECS`), each with its kind and one-line description."""
    import tomllib
    from importlib import resources

    out = {}
    for name in SHIPPED_SPECS:
        text = resources.files("flexdigit.studies").joinpath("specs").joinpath(f"{name}.toml").read_text()
        doc = tomllib.loads(text)
        kind = "design" if "design" in doc else "sensitivity"
        out[name] = f"{kind} study: {doc.get('study', {}).get('description', '')}".rstrip(": ")
    return out


def spec_from_toml(
    text: str,
    source: str = "spec",
    base_dir: Path | None = None,
    baseline: ParameterSet | None = None,
    fields: tuple[str, ...] | None = None,
    scaled: bool = False,
) -> StudySpec:
    """Parse a study spec from TOML text (see the module docstring); errors name ``source`` and the key.
    ``baseline``: the rig to take the tolerances about; ``fields``: the parameter tables kept; ``scaled``: its
    absolute values scaled to the baseline (:func:`load_spec`)."""
    try:
        doc = tomllib.loads(text)
    except (tomllib.TOMLDecodeError, RecursionError) as exc:  # RecursionError: nested past the parser
        raise ParameterError(f"{source}: not valid TOML ({exc})") from None
    table = doc.get("parameters")
    if fields is not None and isinstance(table, dict):
        keep = set(fields)
        doc["parameters"] = {
            s: {f: e for f, e in t.items() if f"{s}.{f}" in keep} if isinstance(t, dict) else t
            for s, t in table.items()
        }
    known = {"study", "parameters", "sensitivity", "design", "metrics"}
    unknown = sorted(set(doc) - known)
    if unknown:
        raise ParameterError(
            f"{source}: unknown table {unknown[0]!r}; expected " + ", ".join(f"[{k}]" for k in sorted(known))
        )
    study = _table(doc.get("study", {}), "[study]", source)
    bad = sorted(set(study) - {"name", "seed", "metrics", "params", "calibration", "description"})
    if bad:
        raise ParameterError(
            f"{source}: unknown key {bad[0]!r} in [study]; expected name, seed, metrics, params, calibration, "
            "description"
        )
    name = study.get("name", Path(source).stem)
    if not isinstance(name, str) or not name:
        raise ParameterError(f"{source}: [study] name must be a non-empty string. Got {name!r} instead.")
    seed = study.get("seed", 0)
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ParameterError(f"{source}: [study] seed must be an integer >= 0. Got {seed!r} instead.")
    metrics = study.get("metrics", [])
    if not isinstance(metrics, list) or not all(isinstance(m, str) for m in metrics):
        raise ParameterError(f"{source}: [study] metrics must be a list of metric names. Got {metrics!r} instead.")
    if baseline is None:
        baseline = _baseline(study, source, base_dir)
    elif "params" in study or "calibration" in study:
        named = "params" if "params" in study else "calibration"
        raise ParameterError(
            f"{source}: [study] {named} names the baseline rig, and another was given: give the baseline one way"
        )
    elif scaled and isinstance(doc.get("parameters"), dict):
        doc["parameters"] = _scaled_to(doc["parameters"], _baseline(study, source, base_dir), baseline)
    user_metrics = _user_metrics(doc.get("metrics", {}), baseline, source)
    if metrics:
        known_metrics = [*METRICS, *(u.name for u in user_metrics)]
        for m in metrics:
            if m not in known_metrics:
                raise ParameterError(
                    f"{source}: [study] metrics: unknown metric {m!r}; expected one of " + ", ".join(known_metrics)
                )
        if len(set(metrics)) != len(metrics):
            raise ParameterError(f"{source}: [study] metrics lists a metric twice: {metrics!r}")
    parameters = _parameters(doc.get("parameters", {}), baseline, source)
    if not parameters and "design" not in doc:
        raise ParameterError(f"{source}: no [parameters.SECTION.FIELD] tables: nothing is uncertain")
    names = [p.name for p in parameters]
    for p in parameters:
        if p.is_factor and any(q.startswith(f"{p.section}.{p.field}[") and q != p.name for q in names):
            raise ParameterError(
                f"{source}: [parameters.{p.section}.{p.field}] gives the whole field a factor and also one of its "
                "elements a distribution; give either the factor or the elements"
            )
    settings = {k: _table(doc[k], f"[{k}]", source) for k in ("sensitivity", "design") if k in doc}
    return StudySpec(name, seed, tuple(parameters), tuple(metrics), settings, baseline, source, user_metrics)


def _user_metrics(table, baseline: ParameterSet, source: str) -> tuple:
    """The spec's own metrics, ``[metrics.NAME]`` with ``function = "module:function"`` (of a parameter set),
    ``unit`` and an optional ``description``: each imported and run once on the baseline rig here, so a missing
    module, a name that is not a function or a function that returns no number is one line naming its key now,
    not a column of failed rows later."""
    table = _table(table, "[metrics]", source)
    out = []
    for name, entry in table.items():
        where = f"{source}: [metrics.{name}]"
        if not re.fullmatch(r"[A-Za-z_]\w*", name) or name in METRICS:
            raise ParameterError(
                f"{where}: a metric's name must be a new identifier (letters, digits, _; the unit in it), not one of "
                "the built-in metrics"
            )
        entry = _table(entry, f"[metrics.{name}]", source)
        unknown = sorted(set(entry) - {"function", "unit", "description"})
        if unknown:
            raise ParameterError(f"{where}: unknown key {unknown[0]!r}; expected function, unit, description")
        for key in ("function", "unit"):
            if not isinstance(entry.get(key), str) or not entry[key]:
                raise ParameterError(f"{where} {key}: a non-empty string is required. Got {entry.get(key)!r}")
        description = entry.get("description", "")
        if not isinstance(description, str):
            raise ParameterError(f"{where} description: a string is required. Got {description!r}")
        user = UserMetric(name, entry["function"], entry["unit"], description, where)
        func = user.resolve()
        try:
            value = func(baseline)
        except Exception as exc:  # noqa: BLE001 - the user's function failing on the baseline, said in one line
            raise ParameterError(
                f"{where} function: {user.function} raised on the baseline rig: "
                + f"{type(exc).__name__}: {exc}".splitlines()[0]
            ) from None
        checked_value(value, user)
        out.append(user)
    return tuple(out)


def _table(value, where: str, source: str) -> dict:
    if not isinstance(value, dict):
        raise ParameterError(f"{source}: {where} must be a table of keys. Got {value!r} instead.")
    return value


#: The absolute values of a distribution that :func:`_scaled_to` carries to another rig (``delta`` stays: a
#: manufacturing tolerance is a length, whatever the part's size).
SCALED_KEYS = ("low", "high", "mode", "mean", "sd", "median")


def _scaled_to(table: dict, own: ParameterSet, other: ParameterSet) -> dict:
    """``[parameters]`` with each real field's absolute values times ``other``'s value over ``own``'s (the rig the
    spec was written about); the rest as read, for :func:`read_parameters` to check."""
    out = {}
    for section, entries in table.items():
        if section not in SECTIONS or not isinstance(entries, dict):
            out[section] = entries
            continue
        mine, theirs = _fields(section, own), _fields(section, other)
        out[section] = dict(entries)
        for name, entry in entries.items():
            a, b = mine.get(name), theirs.get(name)
            if not (isinstance(entry, dict) and isinstance(a, float) and isinstance(b, float) and a != 0.0):
                continue
            ratio = b / a
            scaled = {k: v * ratio if k in SCALED_KEYS and isinstance(v, float) else v for k, v in entry.items()}
            if ratio != 1.0 and any(k in SCALED_KEYS for k in entry):
                note = f"scaled x{ratio:.4g} to this rig's {b:.6g}"
                scaled["source"] = f"{entry['source']} ({note})" if isinstance(entry.get("source"), str) else note
            out[section][name] = scaled
    return out


def _baseline(study: dict, source: str, base_dir: Path | None) -> ParameterSet:
    """The spec's baseline rig: ``[study] params`` (the thesis rig) and ``calibration`` (default: the twin's one
    default for that digit, :func:`~flexdigit.twin.digit_calibration.twin_calibration`)."""
    params, calibration = RigParams(), None
    for key, loader in (("params", load_params), ("calibration", load_calibration)):
        if key not in study:
            continue
        value = study[key]
        if not isinstance(value, str):
            raise ParameterError(f"{source}: [study] {key} must be a file name. Got {value!r} instead.")
        path = Path(value) if base_dir is None or Path(value).is_absolute() else base_dir / value
        refuse_special(path, f"the [study] {key} file of {source}")
        if not path.is_file():
            raise ParameterError(f"{source}: [study] {key}: no such file {str(path)!r}")
        try:
            loaded = loader(path)
        except (ParameterError, DataFileError) as exc:
            raise ParameterError(f"{source}: [study] {key}: {exc}") from None
        if key == "params":
            params = loaded
        else:
            calibration = loaded
    return ParameterSet(params, calibration)


def _fields(section: str, baseline: ParameterSet) -> dict[str, Any]:
    if section == "calibration":
        return baseline.calibration.to_dict()
    return baseline.params.to_dict()[section]


def _parameters(table, baseline: ParameterSet, source: str) -> list[UncertainParameter]:
    """A rig spec's uncertain parameters (:func:`read_parameters` on the baseline rig's sections)."""

    def check(p: UncertainParameter, end: float) -> None:
        try:
            apply_values(baseline, [p], {p.name: end}, f"{source}: {_where(p)}")
        except ParameterError as exc:
            raise ParameterError(
                f"{exc} (the {p.distribution} range of {_where(p)} reaches {end:.6g}, which the field refuses)"
            ) from None

    return read_parameters(table, SECTIONS, lambda section: _fields(section, baseline), check, source)


def read_parameters(table, sections, fields, check, source: str) -> list[UncertainParameter]:
    """The uncertain parameters of a spec's ``[parameters.SECTION.FIELD]`` tables, a rig's or a robot's
    (:mod:`flexdigit.studies.robot_study`): a real field, an element of a list field (``.K``) or a factor on the
    whole list (a ``distribution`` at the field's level), each range checked at both ends.

    Parameters
    ----------
    table : dict
        The ``[parameters]`` table as read.
    sections : sequence of str
        The sections a spec may name.
    fields : callable
        ``fields(section)``: the section's fields and their nominal values.
    check : callable
        ``check(parameter, value)``: builds the baseline with the parameter at ``value`` (an end of its range),
        raising :class:`~flexdigit.errors.ParameterError` naming the key where the field refuses it.
    source : str
        The file named in error messages.
    """
    table = _table(table, "[parameters]", source)
    out: list[UncertainParameter] = []
    for section, entries in table.items():
        if section not in sections:
            raise ParameterError(
                f"{source}: unknown section {section!r} in [parameters]; expected one of "
                + ", ".join(f"[parameters.{s}]" for s in sections)
            )
        entries = _table(entries, f"[parameters.{section}]", source)
        allowed = fields(section)
        for name, entry in entries.items():
            where = f"[parameters.{section}.{name}]"
            if name not in allowed:
                raise ParameterError(
                    f"{source}: unknown field {name!r} in [parameters.{section}]; expected one of " + ", ".join(allowed)
                )
            out += _field_parameters(section, name, allowed[name], _table(entry, where, source), source)
    for p in out:
        for end in p.check_range():
            if not math.isfinite(end):  # a spread too wide for floats: every sample would be 0 or inf
                raise ParameterError(
                    f"{source}: {_where(p)}: the {p.distribution} range reaches {end:g} at {CHECK_SIGMAS:g} sigmas; "
                    "give a spread whose range is finite"
                )
            check(p, end)
    return out


def _field_parameters(section: str, name: str, nominal, entry: dict, source: str) -> list[UncertainParameter]:
    """One ``[parameters.SECTION.NAME]`` table's parameters: the field's, a factor on a list, or its elements'."""
    where = f"[parameters.{section}.{name}]"
    if isinstance(nominal, bool) or isinstance(nominal, (str, int)):
        raise ParameterError(
            f"{source}: {where}: the field is {type(nominal).__name__}-valued ({nominal!r}); only real-valued "
            "fields can be uncertain (a design study varies the others)"
        )
    if not isinstance(nominal, list):
        return [_parameter(section, name, None, float(nominal), entry, where, source)]
    if not all(isinstance(v, float) for v in nominal):
        raise ParameterError(f"{source}: {where}: only real-valued fields can be uncertain")
    if "distribution" in entry:  # a factor on the whole list
        return [_parameter(section, name, None, 1.0, entry, where, source, factor=True)]
    out = []
    for key, sub in entry.items():
        if not (key.isascii() and key.isdigit() and int(key) < len(nominal)):  # int("²") fails
            raise ParameterError(
                f"{source}: {where}: expected 'distribution' (one factor on every element) or element "
                f"tables 0..{len(nominal) - 1}. Got key {key!r} instead."
            )
        k = int(key)
        sub_where = f"[parameters.{section}.{name}.{k}]"
        out.append(_parameter(section, name, k, nominal[k], _table(sub, sub_where, source), sub_where, source))
    return out


def _where(p: UncertainParameter) -> str:
    tail = f".{p.element}" if p.element is not None else ""
    return f"[parameters.{p.section}.{p.field}{tail}]"


def _number(entry: dict, key: str, where: str, source: str, positive: bool = False) -> float:
    value = entry[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ParameterError(f"{source}: {where} {key} must be a finite number. Got {value!r} instead.")
    if positive and value <= 0:
        raise ParameterError(f"{source}: {where} {key} must be > 0. Got {value!r} instead.")
    return float(value)


def _parameter(section, name, element, nominal, entry, where, source, factor=False) -> UncertainParameter:
    dist = entry.get("distribution")
    if not isinstance(dist, str) or dist not in DISTRIBUTIONS:
        raise ParameterError(
            f"{source}: {where} distribution must be one of "
            + ", ".join(repr(d) for d in DISTRIBUTIONS)
            + f". Got {dist!r} instead."
        )
    keys = set(entry) - {"distribution", "source"}
    bad = sorted(keys - set(DISTRIBUTIONS[dist]))
    if bad:
        raise ParameterError(
            f"{source}: {where}: unknown key {bad[0]!r} for a {dist} distribution; expected "
            + ", ".join(DISTRIBUTIONS[dist])
        )
    text = entry.get("source", "")
    if not isinstance(text, str):
        raise ParameterError(f"{source}: {where} source must be a string. Got {text!r} instead.")
    if factor:
        absolute = sorted(keys & {"low", "high", "mean", "sd", "median", "delta", "mode"})
        if absolute:
            raise ParameterError(
                f"{source}: {where}: a whole tuple field is moved by one factor (nominal 1): give 'relative' or "
                f"'relative_sd' (or 'sigma_log'), or one table per element. Got '{absolute[0]}' instead."
            )
    num = {k: _number(entry, k, where, source) for k in keys}
    shape: dict[str, float] = {}
    lo, hi = -math.inf, math.inf
    if dist in ("uniform", "triangular"):
        forms = [f for f in (("low", "high"), ("relative",), ("delta",)) if any(k in num for k in f)]
        if len(forms) != 1 or (forms[0] == ("low", "high") and not {"low", "high"} <= set(num)):
            raise ParameterError(
                f"{source}: {where}: a {dist} distribution needs 'low' and 'high', or 'relative', or 'delta' "
                f"(exactly one form). Got {sorted(keys - {'mode'})} instead."
            )
        if "relative" in num:
            r = _number(entry, "relative", where, source, positive=True)
            lo, hi = sorted((nominal * (1 - r), nominal * (1 + r)))
        elif "delta" in num:
            d = _number(entry, "delta", where, source, positive=True)
            lo, hi = nominal - d, nominal + d
        else:
            lo, hi = num["low"], num["high"]
        if not lo < hi:
            raise ParameterError(f"{source}: {where}: empty range: low {lo:.6g} must be below high {hi:.6g}")
        if dist == "triangular":
            mode = num.get("mode", nominal)
            if not lo <= mode <= hi:
                raise ParameterError(f"{source}: {where}: mode {mode:.6g} must lie in [{lo:.6g}, {hi:.6g}]")
            shape["mode"] = mode
    elif dist == "normal":
        if ("sd" in num) == ("relative_sd" in num):
            raise ParameterError(f"{source}: {where}: a normal distribution needs 'sd' or 'relative_sd' (one of them)")
        mean = num.get("mean", nominal)
        sd = (
            _number(entry, "sd", where, source, positive=True)
            if "sd" in num
            else _number(entry, "relative_sd", where, source, positive=True) * abs(mean)
        )
        if sd <= 0:
            raise ParameterError(f"{source}: {where}: relative_sd of a zero mean gives no spread; give 'sd'")
        lo, hi = num.get("low", -math.inf), num.get("high", math.inf)
        if not lo < hi:
            raise ParameterError(f"{source}: {where}: empty range: low {lo:.6g} must be below high {hi:.6g}")
        if not lo <= mean <= hi:
            raise ParameterError(f"{source}: {where}: mean {mean:.6g} must lie in the truncation [{lo:.6g}, {hi:.6g}]")
        shape.update(mean=mean, sd=sd)
    else:  # lognormal
        if "sigma_log" not in num:
            raise ParameterError(f"{source}: {where}: a lognormal distribution needs 'sigma_log'")
        sigma = _number(entry, "sigma_log", where, source, positive=True)
        median = num.get("median", nominal)
        if median <= 0:
            raise ParameterError(f"{source}: {where}: a lognormal median must be > 0. Got {median!r} instead.")
        shape.update(median=median, sigma_log=sigma)
        lo, hi = 0.0, math.inf
    label = f"{section}.{name}" + ("[*]" if factor else f"[{element}]" if element is not None else "")
    return UncertainParameter(label, section, name, element, dist, float(nominal), lo, hi, shape, text)
