"""Tactile readings from another rig: a foreign table mapped onto a flexdigit dataset (``flexdigit dataset import``).

A user's file has its own column names and units: gauge volts or millivolts, grams or kilograms, a position in
millimetres measured from the clamp... A :class:`ColumnMap` (command-line flags or a small TOML) says which
column is what and in which unit; :func:`import_readings` reads the file (:mod:`flexdigit._table`: delimiter
detected, byte-order mark, CRLF, quoted headers, comment lines; extra columns ignored), converts everything to SI,
checks every cell, and returns a :class:`~flexdigit.tactile.dataset.Dataset` that ``train``, ``predict`` and every
estimator take as they take a collected one.

What the dataset needs and the file may not have is derived, and the metadata say so:

- the protocol (loads, positions, commands, repetitions) from the distinct values of the readings;
- ``position_index``: the rank of the reading's position from the tip (1 = nearest the tip, as table 6.1), 0 for no
  load;
- ``test`` (the readings one tare serves, :func:`flexdigit.tactile.localisation.tare`): a mapped column, else a new test
  at every change of command and wherever no-load readings follow loaded ones (the thesis measured "a no load
  condition ... at the start of every test", 6.5);
- ``repetition``: a mapped column, else the count of earlier readings of the same setting in that test;
- ``command``: :data:`~flexdigit.tactile.protocols.RELAXED` without a command column (actuation disabled);
- ``time_s``: a mapped time column, else NaN (unknown: the bounds then add no drift);
- ``pot_v``: a mapped potentiometer column (same unit as the gauges), else NaN.

Every bad cell is refused with one line naming the file, the line and the column: a mapped column that is missing,
a cell that is not a number, NaN or infinity, a negative mass, a position beyond the digit (or a loaded reading
with no position), a command that is not an integer 0..254.

Examples
--------
>>> import tempfile, pathlib
>>> path = pathlib.Path(tempfile.mkdtemp()) / "readings.csv"
>>> _ = path.write_text("sg_a;sg_b;sg_c;mass_g;x_mm\\n12.1;30.2;5.5;25;90\\n11.9;29.8;5.4;0;\\n")
>>> cmap = ColumnMap(gauges=("sg_a", "sg_b", "sg_c"), gauge_unit="mV", load="mass_g", load_unit="g",
...                  position="x_mm", position_unit="mm", position_from="clamp")
>>> ds = import_readings(path, cmap)
>>> ds["load_kg"].tolist(), ds["position_from_tip_m"][:1].tolist(), ds.gauges_v[0].tolist()
([0.025, 0.0], [0.18], [0.0121, 0.0302, 0.0055])
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from flexdigit._io import read_bytes, refuse_special
from flexdigit._table import Table, read_table
from flexdigit._validation import check_choice, check_real
from flexdigit.errors import DataFileError, ParameterError
from flexdigit.params import GAUGE_V, RigParams
from flexdigit.tactile.dataset import MAX_GAUGES, Dataset, dataset_columns, make_meta
from flexdigit.tactile.protocols import RELAXED, Protocol

__all__ = [
    "GAUGE_UNITS",
    "LOAD_UNITS",
    "POSITION_UNITS",
    "TIME_UNITS",
    "POSITION_FROM",
    "MAX_LOAD_KG",
    "ColumnMap",
    "ROLES",
    "import_readings",
]

#: Units each quantity may be given in, and their factor to SI.
GAUGE_UNITS = {"V": 1.0, "mV": 1e-3}
LOAD_UNITS = {"kg": 1.0, "g": 1e-3}
POSITION_UNITS = {"m": 1.0, "cm": 1e-2, "mm": 1e-3}
TIME_UNITS = {"s": 1.0, "ms": 1e-3}
POSITION_FROM = ("tip", "clamp")
#: The heaviest load a dataset holds (kg), as :class:`~flexdigit.tactile.protocols.Protocol` allows.
MAX_LOAD_KG = 10.0


@dataclass(frozen=True)
class ColumnMap:
    """Which column of a foreign file is what, and in which unit.

    Parameters
    ----------
    gauges : tuple of str
        The gauge columns, gauge 1 (nearest the clamp) first: one per gauge of the digit, 1 to 8 (the thesis rig's
        three).
    gauge_unit : {"V", "mV"}
    load, load_unit : str, {"kg", "g"}
        The hung mass column (0 for no load) and its unit.
    position, position_unit : str, {"m", "cm", "mm"}
        Where the load hangs, and the unit (empty cells allowed on no-load rows).
    position_from : {"tip", "clamp"}
        What the position is measured from.
    digit_length_m : float, optional
        Clamp to tip (m); default: the rig parameters' (0.27 m, the thesis digit).
    command, repetition, test, time, pot : str, optional
        Further columns: the servo command (integers 0..254), the repetition and test numbers (integers >= 0),
        the time (``time_unit``), the potentiometer (``gauge_unit``).
    time_unit : {"s", "ms"}
    delimiter : str, optional
        Default: detected (or named by a spreadsheet's ``sep=`` first line). ``","``, ``";"``, ``"tab"``, ``"|"``,
        ``"whitespace"``.
    decimal : {".", ","}, optional
        Default: detected (``,`` where the delimiter is not ``,`` and the numbers have decimal commas).
    name : str, optional
        The dataset's protocol name (default: ``imported:<file stem>``).
    orientation : {"horizontal", "vertical"}
        How the digit lay (the thesis's tactile experiments: horizontal).
    """

    gauges: tuple[str, ...]
    load: str
    position: str
    gauge_unit: str = "V"
    load_unit: str = "kg"
    position_unit: str = "m"
    position_from: str = "tip"
    digit_length_m: float | None = None
    command: str | None = None
    repetition: str | None = None
    test: str | None = None
    time: str | None = None
    time_unit: str = "s"
    pot: str | None = None
    delimiter: str | None = None
    decimal: str | None = None
    name: str | None = None
    orientation: str = "horizontal"

    def __post_init__(self) -> None:
        owner = "ColumnMap"
        if (
            not isinstance(self.gauges, tuple | list)
            or not 1 <= len(self.gauges) <= MAX_GAUGES
            or not all(isinstance(g, str) and g.strip() for g in self.gauges)
        ):
            raise ParameterError(
                f"The 'gauges' parameter of {owner} must be 1 to {MAX_GAUGES} column names, one per gauge, gauge 1 "
                f"first. Got {self.gauges!r}."
            )
        object.__setattr__(self, "gauges", tuple(self.gauges))
        for key in ("load", "position"):
            if not isinstance(getattr(self, key), str) or not getattr(self, key).strip():
                raise ParameterError(
                    f"The '{key}' parameter of {owner} must be a column name. Got {getattr(self, key)!r}."
                )
        for key in ("command", "repetition", "test", "time", "pot", "name"):
            value = getattr(self, key)
            if value is not None and (not isinstance(value, str) or not value.strip()):
                what = "a name" if key == "name" else "a column name"
                raise ParameterError(f"The '{key}' parameter of {owner} must be {what}. Got {value!r}.")
        check_choice(self.gauge_unit, "gauge_unit", tuple(GAUGE_UNITS), owner)
        check_choice(self.load_unit, "load_unit", tuple(LOAD_UNITS), owner)
        check_choice(self.position_unit, "position_unit", tuple(POSITION_UNITS), owner)
        check_choice(self.position_from, "position_from", POSITION_FROM, owner)
        check_choice(self.time_unit, "time_unit", tuple(TIME_UNITS), owner)
        if self.decimal is not None:
            check_choice(self.decimal, "decimal", (".", ","), owner)
        check_choice(self.orientation, "orientation", ("horizontal", "vertical"), owner)
        if self.delimiter is not None:
            check_choice(self.delimiter, "delimiter", (",", ";", "tab", "\t", "|", "whitespace"), owner)
        if self.digit_length_m is not None:
            object.__setattr__(
                self,
                "digit_length_m",
                check_real(self.digit_length_m, "digit_length_m", owner, low=0, low_open=True, high=10),
            )

    def to_dict(self) -> dict[str, Any]:
        """Plain values (the dataset records the map it was imported with)."""
        return {k: list(v) if isinstance(v, tuple) else v for k, v in dataclasses.asdict(self).items()}

    @classmethod
    def from_toml(cls, path: str | Path, **overrides: Any) -> ColumnMap:
        """A map from a TOML file (the keys of :class:`ColumnMap`); ``overrides`` (flags given) win.

        Raises
        ------
        DataFileError
            Naming the file and the key: not TOML, an unknown key, a missing key, a bad value.
        """
        path = Path(path)
        if not path.exists():
            raise FileNotFoundError(2, "No such file", str(path))
        refuse_special(path, "a column map TOML")
        if not path.is_file():
            raise DataFileError(f"{path}: not a file (a directory?); expected a column map TOML")
        try:
            data = tomllib.loads(read_bytes(path, "a column map TOML").decode("utf-8-sig"))
        except (tomllib.TOMLDecodeError, RecursionError) as exc:  # RecursionError: nested past the parser
            raise DataFileError(f"{path}: not valid TOML ({exc})") from None
        except UnicodeDecodeError as exc:
            raise DataFileError(f"{path}: not a text TOML file (byte {exc.start} is not UTF-8)") from None
        return cls.build(data, overrides, source=str(path))

    @classmethod
    def from_flags(cls, flags: dict[str, Any], map_path: str | Path | None = None) -> ColumnMap:
        """``flexdigit collect dataset``'s map: the ``map_path`` TOML with ``flags`` (those not None) winning, or
        the flags alone, which must then name the gauge, load and position columns. ``flags["gauges"]`` may be one
        comma-separated string.

        Raises
        ------
        ParameterError
            Without a map, naming the first of ``--gauges``, ``--load``, ``--position`` missing.
        """
        flags = dict(flags)
        if isinstance(flags.get("gauges"), str):
            flags["gauges"] = tuple(g.strip() for g in flags["gauges"].split(","))
        if map_path:
            return cls.from_toml(map_path, **flags)
        missing = [key for key in ("gauges", "load", "position") if flags.get(key) is None]
        if missing:
            raise ParameterError(
                f"dataset import needs --{missing[0]} (the {ROLES[missing[0]]}): give the flags or a --map TOML"
            )
        return cls.build({}, flags, source="the column flags")

    @classmethod
    def build(cls, data: dict, overrides: dict | None = None, *, source: str = "column map") -> ColumnMap:
        """A map from a dict of keys (a TOML table) and ``overrides``, validated, errors naming ``source``."""
        allowed = [f.name for f in dataclasses.fields(cls)]
        unknown = [k for k in data if k not in allowed]
        if unknown:
            raise DataFileError(f"{source}: unknown key {unknown[0]!r}; expected some of " + ", ".join(allowed))
        merged = {**data, **{k: v for k, v in (overrides or {}).items() if v is not None}}
        for key in ("gauges", "load", "position"):
            if key not in merged:
                raise DataFileError(f"{source}: missing key '{key}' (the {ROLES[key]})")
        if isinstance(merged.get("gauges"), list):
            merged["gauges"] = tuple(merged["gauges"])
        elif isinstance(merged.get("gauges"), str):  # "A,B,C", as --gauges takes it
            merged["gauges"] = tuple(g.strip() for g in merged["gauges"].split(","))
        try:
            return cls(**merged)
        except (ParameterError, TypeError) as exc:
            raise DataFileError(f"{source}: {_as_key(str(exc), from_flags=source == 'the column flags')}") from None


def _as_key(message: str, *, from_flags: bool) -> str:
    """A :class:`ColumnMap` message as the user wrote the map: "key 'gauges' ..." in a TOML file, "--gauges ..."
    on the command line (never the class's name), with what a file should hold."""
    match = re.match(r"The '(\w+)' parameter of ColumnMap must be (.*)", message, re.S)
    if not match:
        return message
    key, rest = match.groups()
    if key == "gauges" and not from_flags:
        rest = rest.replace("column names,", 'column names (a TOML list, gauges = ["A", "B", "C"], or "A,B,C"),', 1)
    name = "--" + key.replace("_", "-") if from_flags else f"key '{key}'"
    return f"{name} must be {rest}"


#: What each mapped column is, for messages.
ROLES = {
    "gauges": "gauge columns (one per gauge)",
    "load": "load column",
    "position": "position column",
    "command": "command column",
    "repetition": "repetition column",
    "test": "test column",
    "time": "time column",
    "pot": "potentiometer column",
}


def import_readings(path: str | Path, column_map: ColumnMap, *, params=None) -> Dataset:
    """Read a foreign tactile readings file into a :class:`~flexdigit.tactile.dataset.Dataset` (see the module
    docstring).

    Parameters
    ----------
    path : path
        CSV-like text (delimiter detected) or Parquet.
    column_map : ColumnMap
    params : RigParams, optional
        The digit: its length when the map gives none, and its gauge count, which the map's gauge columns must
        match.

    Raises
    ------
    DataFileError
        One line naming the file, the line and the column of the first bad cell, or the missing column.
    """
    cmap = column_map
    path = Path(path)
    if params is not None and len(cmap.gauges) != len(params.geometry.gauge_positions_m):
        raise ParameterError(
            f"the column map names {len(cmap.gauges)} gauge columns but the digit has "
            f"{len(params.geometry.gauge_positions_m)} gauges: one column per gauge, gauge 1 first"
        )
    length_m = cmap.digit_length_m or (params or RigParams()).geometry.digit_length_m
    table = read_table(path, delimiter=cmap.delimiter, decimal=cmap.decimal)
    if len(table) == 0:
        raise DataFileError(f"{path}: no readings after the header")
    columns, gauges = _mapped_columns(table, cmap)
    load = _load_kg(table, cmap, columns["load"])
    loaded = load > 0
    from_tip = _positions_from_tip_m(table, cmap, columns["position"], loaded, length_m)
    if not loaded.any():
        raise DataFileError(f"{path}: no loaded reading (every mass in column {columns['load']!r} is 0)")
    if "command" in columns:
        command = _integers(table, columns["command"], 0, 254, "a servo command (an integer 0..254)")
    else:
        command = np.full(len(table), RELAXED, dtype=np.int64)
    test = (
        _factorised(_integers(table, columns["test"], 0, None, "a test number (an integer >= 0)"))
        if "test" in columns
        else _derived_tests(command, loaded)
    )
    if "repetition" in columns:
        repetition = _integers(table, columns["repetition"], 0, None, "a repetition number (an integer >= 0)")
    else:
        repetition = _derived_repetitions(test, load, from_tip, command)
    time_s = (
        table.numbers(columns["time"]) * TIME_UNITS[cmap.time_unit]
        if "time" in columns
        else np.full(len(table), np.nan)
    )
    pot = (
        table.numbers(columns["pot"]) * GAUGE_UNITS[cmap.gauge_unit]
        if "pot" in columns
        else np.full(len(table), np.nan)
    )
    protocol = _protocol(cmap, path, load, from_tip, command, test, loaded)
    positions = np.array(protocol.positions_from_tip_m)
    index = np.zeros(len(table), dtype=np.int64)
    index[loaded] = np.searchsorted(positions, from_tip[loaded]) + 1
    data = {
        "sample": np.arange(len(table), dtype=np.int64),
        "test": test,
        **{f"gauge{k}_v": gauges[:, k - 1] for k in range(1, gauges.shape[1] + 1)},
        "pot_v": pot,
        "load_kg": load,
        "position_index": index,
        "position_from_tip_m": from_tip,
        "position_from_base_m": length_m - from_tip,
        "command": command,
        "repetition": repetition,
        "time_s": time_s,
    }
    count = gauges.shape[1]
    data = {name: np.asarray(data[name], dtype=dtype) for name, dtype in dataset_columns(count).items()}
    return Dataset(data, make_meta(protocol, _rig_meta(path, table, cmap, columns), length_m, gauge_count=count))


def _mapped_columns(table, cmap: ColumnMap) -> tuple[dict[str, str], np.ndarray]:
    """The file's column of each mapped role (all distinct), and the gauges read in volts (range-checked)."""
    columns = {
        role: table.find(getattr(cmap, role), f"the {ROLES[role]}")
        for role in ROLES
        if role != "gauges" and getattr(cmap, role) is not None
    }
    gauge_columns = [table.find(g, f"gauge {k}") for k, g in enumerate(cmap.gauges, start=1)]
    _check_distinct(table, {**{f"gauge {k}": c for k, c in enumerate(gauge_columns, start=1)}, **columns})
    unit = GAUGE_UNITS[cmap.gauge_unit]  # a gauge in mV mapped as V is 1000 times off: named by the range check
    gauges = np.column_stack([table.plausible(c, table.numbers(c) * unit, GAUGE_V) for c in gauge_columns])
    return columns, gauges


def _load_kg(table, cmap: ColumnMap, column: str) -> np.ndarray:
    """The load column in kg, each mass 0 or more and at most :data:`MAX_LOAD_KG`."""
    load = table.numbers(column) * LOAD_UNITS[cmap.load_unit]
    _check_rows(table, column, load, (load < 0), "a negative mass; expected 0 (no load) or more")
    _check_rows(
        table,
        column,
        load,
        load > MAX_LOAD_KG,
        f"more than {MAX_LOAD_KG:g} kg (a unit slip? the map says {cmap.load_unit})",
    )
    return load


def _positions_from_tip_m(table, cmap: ColumnMap, column: str, loaded: np.ndarray, length_m: float) -> np.ndarray:
    """Each loaded reading's position from the tip (m, to the nanometre; NaN unloaded), on the digit."""
    raw_position = table.numbers(column, allow_empty=True)
    position = raw_position * POSITION_UNITS[cmap.position_unit]
    _check_rows(table, column, raw_position, loaded & np.isnan(position), "a loaded reading needs a position")
    length_text = f"{length_m / POSITION_UNITS[cmap.position_unit]:g} {cmap.position_unit}"
    beyond = loaded & ((position < 0) | (position > length_m))
    _check_rows(
        table,
        column,
        raw_position,
        beyond,
        f"beyond the digit (0 to {length_text} from the {cmap.position_from})",
    )
    # to the nanometre: the same position read from the clamp must be the same from the tip on every row
    return np.round(np.where(loaded, position if cmap.position_from == "tip" else length_m - position, np.nan), 9)


def _rig_meta(path: Path, table, cmap: ColumnMap, columns: dict[str, str]) -> dict:
    """The dataset's rig metadata: the file (and its hash), how it was read, and the columns derived."""
    return {
        "url": "import",
        "source": str(path),
        "sha256": hashlib.sha256(path.read_bytes()).hexdigest(),
        "delimiter": table.delimiter,
        "decimal": table.decimal,
        "column_map": cmap.to_dict(),
        "derived": [
            name
            for name, role in (("test", "test"), ("repetition", "repetition"), ("time_s", "time"), ("pot_v", "pot"))
            if role not in columns
        ],
    }


def _check_distinct(table: Table, columns: dict[str, str]) -> None:
    """One column, one role: a column mapped twice (gauge 1 and gauge 2, a gauge and the position) is a slip in the
    map that would give a plausible, wrong dataset."""
    seen: dict[str, str] = {}
    for role, column in columns.items():
        if column in seen:
            first = seen[column] if seen[column].startswith("gauge") else f"the {ROLES[seen[column]]}"
            this = role if role.startswith("gauge") else f"the {ROLES[role]}"
            raise DataFileError(
                f"{table.source}: column {column!r} is mapped twice, as {first} and as {this}; each role needs its "
                "own column"
            )
        seen[column] = role


def _check_rows(table: Table, column: str, values: np.ndarray, bad: np.ndarray, problem: str) -> None:
    rows = np.flatnonzero(bad)
    if rows.size:
        i = int(rows[0])
        more = f" ({rows.size} such rows)" if rows.size > 1 else ""
        cell = table.rows[i][table.columns.index(column)].strip()
        raise DataFileError(f"{table.source}: {table.where(i)}, column {column!r}: {cell or 'empty'}: {problem}{more}")


def _integers(table: Table, column: str, low: int, high: int | None, what: str) -> np.ndarray:
    values = table.numbers(column)
    bad = (values != np.round(values)) | (values < low)
    if high is not None:
        bad |= values > high
    _check_rows(table, column, values, bad, f"expected {what}")
    return values.astype(np.int64)


def _factorised(values: np.ndarray) -> np.ndarray:
    """0, 1, 2... in order of first appearance."""
    _, first, inverse = np.unique(values, return_index=True, return_inverse=True)
    order = np.argsort(np.argsort(first))
    return order[inverse.ravel()].astype(np.int64)


def _derived_tests(command: np.ndarray, loaded: np.ndarray) -> np.ndarray:
    """A new test at every change of command and where no-load readings follow loaded ones."""
    test = np.zeros(command.size, dtype=np.int64)
    for i in range(1, command.size):
        new = command[i] != command[i - 1] or (not loaded[i] and loaded[i - 1])
        test[i] = test[i - 1] + int(new)
    return test


def _derived_repetitions(test, load, from_tip, command) -> np.ndarray:
    """How many readings of the same setting (test, load, position, command) came before each one."""
    seen: dict[tuple, int] = {}
    out = np.empty(test.size, dtype=np.int64)
    for i in range(test.size):
        key = (
            int(test[i]),
            float(load[i]),
            None if math.isnan(from_tip[i]) else float(from_tip[i]),
            int(command[i]),
        )
        out[i] = seen.get(key, 0)
        seen[key] = out[i] + 1
    return out


def _protocol(cmap: ColumnMap, path: Path, load, from_tip, command, test, loaded) -> Protocol:
    """The protocol the readings follow, from their distinct settings (large enough to number every reading)."""
    loads = tuple(float(v) for v in np.unique(load[loaded]))
    positions = tuple(float(v) for v in np.unique(from_tip[loaded]))
    commands = tuple(int(c) for c in np.unique(command)) if (command != RELAXED).any() else ()
    keys = np.column_stack([load, np.nan_to_num(from_tip, nan=-1.0), command])
    _, counts = np.unique(keys[loaded], axis=0, return_counts=True)
    repetitions = int(counts.max())
    tests = len(loads) * max(1, len(commands))
    no_load = int(np.sum(~loaded))
    per_test = int(np.bincount(test[~loaded]).max()) if no_load else 0
    no_load_repetitions = max(per_test, -(-no_load // tests))
    return Protocol(
        name=cmap.name or f"imported:{path.stem}",
        loads_kg=loads,
        positions_from_tip_m=positions,
        actuation_commands=commands,
        repetitions=repetitions,
        no_load_repetitions=no_load_repetitions,
        orientation=cmap.orientation,
        description=f"readings imported from {path.name}",
    )
