"""A study's table: named columns of numbers (and labels), frozen, as studies return them and reports show them.

Studies (``control.studies``, ``tactile.studies``, ...) return their tables as :class:`ResultTable`: cells are floats,
ints, strings (labels such as a controller's name) or None (no value), never pre-formatted numbers, so a user
gets the numbers with one call and the report's ``results.json`` holds them as numbers; only the HTML formats
them. A leaf module (standard library only).

Examples
--------
>>> t = ResultTable("demo.gamma", "gamma by two routes", ("filter_hz", "riccati", "lmi"), ((5.0, 0.0182, 0.0182),))
>>> t.column("riccati")
[0.0182]
>>> t.as_dict()["columns"]
['filter_hz', 'riccati', 'lmi']
"""

from __future__ import annotations

from dataclasses import dataclass

Cell = float | int | str | None


@dataclass(frozen=True)
class ResultTable:
    """Rows of cells under named columns (units in the names, as in the rest of flexdigit).

    Parameters
    ----------
    key : str
        A stable dotted name (``"control.gamma_routes"``): how ``results.json`` and tests find the table.
    title : str
        One line saying what the table shows.
    columns : tuple of str
        Column names with their units (``"settling_s"``, ``"rmse_mm"``).
    rows : tuple of tuples
        One tuple of cells per row, as long as ``columns``.
    """

    key: str
    title: str
    columns: tuple[str, ...]
    rows: tuple[tuple[Cell, ...], ...]

    def __post_init__(self) -> None:
        columns = tuple(str(c) for c in self.columns)
        rows = tuple(tuple(_cell(v) for v in row) for row in self.rows)
        for i, row in enumerate(rows):
            if len(row) != len(columns):
                raise ValueError(f"table {self.key!r}: row {i} has {len(row)} cells for {len(columns)} columns")
        object.__setattr__(self, "columns", columns)
        object.__setattr__(self, "rows", rows)

    def column(self, name: str) -> list[Cell]:
        """The cells of one column, top to bottom."""
        if name not in self.columns:
            raise KeyError(f"table {self.key!r} has no column {name!r} (columns: {', '.join(self.columns)})")
        i = self.columns.index(name)
        return [row[i] for row in self.rows]

    def as_dict(self) -> dict:
        """``{key, title, columns, rows}`` with lists (JSON-ready; NaN stays NaN, ``to_jsonable`` makes it null)."""
        return {
            "key": self.key,
            "title": self.title,
            "columns": list(self.columns),
            "rows": [list(r) for r in self.rows],
        }


def _cell(value) -> Cell:
    """numpy scalars become Python numbers; bools stay bools (a yes/no column); strings and None as they are."""
    if value is None or isinstance(value, str | bool | int):
        return value
    kind = getattr(getattr(value, "dtype", None), "kind", "f")
    if kind == "b":
        return bool(value)
    if kind in "iu":
        return int(value)
    try:
        return float(value)
    except (TypeError, ValueError):
        raise ValueError(f"a table cell must be a number, a string or None. Got {value!r}") from None
