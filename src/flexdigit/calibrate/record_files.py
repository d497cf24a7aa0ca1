"""A rig's record files, read for ``flexdigit calibrate`` (CSV-like text or Parquet, one row per sample).

Columns are named as ``flexdigit identify`` reads them, the unit after the last underscore:

- gauges ``gauge1_v`` .. ``gauge3_v`` or ``sg1_v`` .. (``_mv`` for millivolts), as the twin and a DAQ write them;
  the unit may also stand in parentheses or brackets, and case, blanks and ``_`` in the name do not matter
  (``SG 1 (mV)``, ``Gauge_2 [V]``);
- ``command`` (or ``cmd``): the servo command, an integer 0..254;
- ``time_s`` (or ``time_ms``, ``t_us``, ``Time (ms)``, or ``time`` with ``time_unit``);
- any common delimiter and decimal mark (detected, :func:`flexdigit._table.read_table`; ``decimal`` for a file
  whose decimal commas the detection cannot see, such as a ``,``-separated file with quoted cells);
- deflections ``y1_mm`` .. ``y3_mm`` (or ``sg1_mm``, ``gauge1_mm``, ``y_sg1_mm``; ``_cm``, ``_m``): the
  deflection at each gauge position, as thesis table 3.6 gives it (an empty cell, or NaN: not read).

What each record is (thesis sections in brackets):

- **release test** (3.1.2): time and the gauge channels of the digit released from a deflection, cable removed,
  bare or housed; every gauge channel found is identified (:func:`~flexdigit.calibrate.targets.release_figures`);
- **actuation sweep** (3.4.3, E 3.20-3.22): ``command`` and the three gauges, settled readings at each command
  (several a command allowed);
- **deflection table** (3.4.1, table 3.6): ``command`` and the three deflections;
- **rest record**: time and the three gauges of the resting rig (white noise and drift);
- **actuated rest** (repeatability): ``command`` (one value) and the three gauges, repeated readings of the
  unloaded digit lying horizontal, tapped before each reading.

Every problem names the file, and the line and column where there is one.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from flexdigit._table import Table, read_table
from flexdigit._validation import Plausible
from flexdigit.errors import DataFileError
from flexdigit.identify.timeseries import TimeSeries
from flexdigit.params import GAUGE_V

#: A deflection read at a gauge: a digit at most 2 m long (Geometry) deflects less than its length.
DEFLECTION_MM = Plausible("mm", -2000.0, 2000.0, "a deflection of a digit at most 2 m long")

__all__ = [
    "VOLT_UNITS",
    "LENGTH_UNITS",
    "TIME_UNITS",
    "GAUGES",
    "read_release",
    "read_sweep",
    "read_deflections",
    "read_rest",
    "read_actuated_rest",
]

#: Gauge-voltage units and their factor to V.
VOLT_UNITS = {"v": 1.0, "mv": 1e-3}
#: Deflection units and their factor to mm.
LENGTH_UNITS = {"mm": 1.0, "cm": 10.0, "m": 1000.0}
#: Time units and their factor to s.
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6}
GAUGES = (1, 2, 3)

#: A column name's unit: after the last ``_`` (``sg1_mv``), or in parentheses or brackets (``SG 1 (mV)``,
#: ``time [ms]``); the name before it is compared without case, blanks or ``_`` (``Gauge_1``, ``sg 1``).
_NAME_UNIT = re.compile(r"^(?P<stem>.+?)(?:_(?P<suffix>[a-z]+)|\s*[\(\[]\s*(?P<bracket>[a-z]+)\s*[\)\]])$")
_GAUGE_STEM = re.compile(r"^(?:sg|gauge)(\d+)$")
_DEFLECTION_STEM = re.compile(r"^(?:y(?:sg|gauge)?|sg|gauge)(\d+)$")


def _stem_unit(column: str) -> tuple[str, str | None]:
    """``"SG 1 (mV)" -> ("sg1", "mv")``, ``"time_ms" -> ("time", "ms")``, ``"time" -> ("time", None)``."""
    name = column.strip().lower()
    m = _NAME_UNIT.match(name)
    stem, unit = (m.group("stem"), m.group("suffix") or m.group("bracket")) if m else (name, None)
    return re.sub(r"[\s_]+", "", stem), unit


def _gauge_columns(table: Table, pattern: re.Pattern, units: dict[str, float], what: str) -> dict[int, tuple]:
    """``{gauge: (column, factor)}`` for the columns whose name ``pattern`` matches, with a unit of ``units``."""
    found: dict[int, list[tuple[str, float]]] = {}
    for column in table.columns:
        stem, unit = _stem_unit(column)
        m = pattern.match(stem)
        if m and unit in units:
            found.setdefault(int(m.group(1)), []).append((column, units[unit]))
    out = {}
    for gauge, columns in found.items():
        if len(columns) > 1:
            names = ", ".join(repr(c) for c, _ in columns)
            raise DataFileError(f"{table.source}: gauge {gauge} has several {what} columns ({names}); keep one")
        out[gauge] = columns[0]
    return out


def _the_gauges(table: Table, pattern: re.Pattern, units: dict[str, float], what: str, example: str, count: int):
    """The columns of gauges 1..``count`` (the digit's gauges), each required."""
    columns = _gauge_columns(table, pattern, units, what)
    gauges = range(1, count + 1)
    missing = [g for g in gauges if g not in columns]
    if missing:
        raise DataFileError(
            f"{table.source}: no {what} column for gauge {missing[0]} of the digit's {count} (expected e.g. "
            f"{example.format(g=missing[0])}; columns: {', '.join(table.columns)})"
        )
    return [columns[g] for g in gauges]


def _volts(table: Table, *, allow_empty: bool = False, gauges: int = len(GAUGES)) -> np.ndarray:
    cols = _the_gauges(table, _GAUGE_STEM, VOLT_UNITS, "gauge-voltage", "gauge{g}_v or sg{g}_mv", gauges)
    return np.column_stack(
        [table.plausible(c, table.numbers(c, allow_empty=allow_empty) * f, GAUGE_V) for c, f in cols]
    )


def _commands(table: Table) -> np.ndarray:
    name = next((c for c in table.columns if c.strip().lower() in ("command", "cmd")), None)
    if name is None:
        raise DataFileError(f"{table.source}: no 'command' column (columns: {', '.join(table.columns)})")
    values = table.numbers(name)
    for i, v in enumerate(values):
        if v != round(v) or not 0 <= v <= 254:
            raise DataFileError(
                f"{table.source}: {table.where(i)}, column {name!r}: {v:g} is not a servo command (an integer 0..254)"
            )
    return values.astype(int)


def _time_s(table: Table, time_unit: str | None) -> np.ndarray:
    for column in table.columns:
        stem, unit = _stem_unit(column)
        if stem in ("time", "t") and (unit is None or unit in TIME_UNITS):
            if time_unit is not None and unit is not None and unit != time_unit:
                raise DataFileError(
                    f"{table.source}: column {column!r} says its time is in {unit} but the time unit {time_unit} was "
                    "given: drop --time-unit, or rename the column"
                )
            unit = unit or time_unit
            if unit not in TIME_UNITS:
                raise DataFileError(
                    f"{table.source}: column {column!r} has no time unit: name it time_s or time_ms, or give the "
                    "time unit (s, ms, us)"
                )
            t = table.numbers(column) * TIME_UNITS[unit]
            back = np.nonzero(np.diff(t) <= 0)[0]
            if back.size:
                i = int(back[0]) + 1
                raise DataFileError(
                    f"{table.source}: {table.where(i)}, column {column!r}: time must increase, got {t[i]:g} s after "
                    f"{t[i - 1]:g} s"
                )
            return t
    raise DataFileError(
        f"{table.source}: no time column (time_s, time_ms, time (ms), or time with the time unit given); columns: "
        f"{', '.join(table.columns)}"
    )


def read_release(path: str | Path, *, time_unit: str | None = None, decimal: str | None = None) -> list:
    """Every gauge channel of a release-test file as a :class:`~flexdigit.identify.timeseries.TimeSeries` (volts),
    checked as ``identify`` checks a recording (increasing, uniform time; enough samples)."""
    table = read_table(path, decimal=decimal)
    columns = _gauge_columns(table, _GAUGE_STEM, VOLT_UNITS, "gauge-voltage")
    if not columns:
        raise DataFileError(
            f"{path}: no gauge channel (gauge1_v .. gauge3_v, or sg1_v ..; _mv or (mV) for millivolts); columns: "
            + ", ".join(table.columns)
        )
    t = _time_s(table, time_unit)
    return [
        TimeSeries.from_arrays(t, table.numbers(column) * factor, channel=column, unit="V", source=str(path))
        for column, factor in (columns[g] for g in sorted(columns))
    ]


def read_sweep(
    path: str | Path, *, decimal: str | None = None, gauges: int = len(GAUGES)
) -> tuple[np.ndarray, np.ndarray]:
    """``(commands, volts (N, G))`` of an actuation-sweep file, the digit's ``gauges`` channels (3 on the thesis
    rig)."""
    table = read_table(path, decimal=decimal)
    _at_least(table, 2, "an actuation sweep")
    commands = _commands(table)
    _distinct_commands(table, commands, "an actuation sweep", "a slope (E 3.20-3.22)")
    return commands, _volts(table, gauges=gauges)


def read_deflections(
    path: str | Path, *, decimal: str | None = None, gauges: int = len(GAUGES)
) -> tuple[np.ndarray, np.ndarray]:
    """``(commands, mm (G, N))`` of a deflection table; NaN where a cell is empty (not read)."""
    table = read_table(path, decimal=decimal)
    _at_least(table, 2, "a deflection table")  # one row fixes no slope: the fit would be the prior's alone
    commands = _commands(table)
    cols = _the_gauges(table, _DEFLECTION_STEM, LENGTH_UNITS, "deflection", "y{g}_mm", gauges)
    mm = np.vstack([table.plausible(c, table.numbers(c, allow_empty=True) * f, DEFLECTION_MM) for c, f in cols])
    repeated = [c for c in set(commands.tolist()) if np.sum(commands == c) > 1]
    if repeated:
        raise DataFileError(f"{path}: command {repeated[0]} appears twice in the deflection table; give one row each")
    return commands, mm


def read_rest(
    path: str | Path, *, time_unit: str | None = None, decimal: str | None = None, gauges: int = len(GAUGES)
) -> tuple[np.ndarray, np.ndarray]:
    """``(time_s, volts (N, G))`` of a record of the resting rig."""
    table = read_table(path, decimal=decimal)
    _at_least(table, 16, "a rest record")
    t, volts = _time_s(table, time_unit), _volts(table, gauges=gauges)
    _not_constant(table, volts, "a rest record", "its noise")
    return t, volts


def read_actuated_rest(
    path: str | Path, *, decimal: str | None = None, gauges: int = len(GAUGES)
) -> tuple[int, np.ndarray]:
    """``(command, volts (N, G))`` of repeated readings of the unloaded, actuated digit at one command."""
    table = read_table(path, decimal=decimal)
    _at_least(table, 3, "an actuated-rest record")
    commands = _commands(table)
    if np.unique(commands).size != 1:
        raise DataFileError(
            f"{path}: an actuated-rest record holds one command; this one has {sorted(set(commands.tolist()))}"
        )
    volts = _volts(table, gauges=gauges)
    _not_constant(table, volts, "an actuated-rest record", "a repeatability (cable_friction_ratio)")
    return int(commands[0]), volts


def _not_constant(table: Table, volts: np.ndarray, what: str, fits: str) -> None:
    """Refuse a channel that holds one value in every row: a record too constant to fit (a cached DAQ value, a
    disconnected gauge, readings never tapped), which would fit a friction or noise level of exactly 0."""
    for g, column in enumerate(volts.T, start=1):
        finite = column[np.isfinite(column)]
        if finite.size and float(np.ptp(finite)) == 0.0:
            raise DataFileError(
                f"{table.source}: {what} whose gauge {g} holds one value ({finite[0]:g} V) in all {finite.size} rows "
                f"is too constant to give {fits}: a disconnected channel, or readings repeated from a cache?"
            )


def _distinct_commands(table: Table, commands: np.ndarray, what: str, fits: str) -> None:
    if np.unique(commands).size < 2:
        raise DataFileError(
            f"{table.source}: {what} at one command ({int(commands[0])}) gives no {fits}; it needs two commands or more"
        )


def _at_least(table: Table, n: int, what: str) -> None:
    if len(table) < n:
        raise DataFileError(f"{table.source}: {what} needs at least {n} rows; this file has {len(table)}")
