"""Tables made elsewhere: a CSV-like text file (any common delimiter, detected) or Parquet, read cell by cell.

Files from other rigs and spreadsheets come with a byte-order mark, CRLF line ends, ``;`` or tab delimiters
(``,`` as the decimal mark), quoted headers with spaces and units, comment lines and extra columns. :func:`read_table`
reads any of those into a :class:`Table` of raw cells that remembers the file line of every row, so
:meth:`Table.numbers` can refuse a bad cell naming the file, the line and the column. A leaf module (standard
library, numpy, and pyarrow for Parquet), shared by every reader of foreign files (tactile datasets, calibration
records).

The delimiter is detected by parsing the first lines with each candidate (``,`` ``;`` tab ``|``) and keeping the one
that splits every line into the same number (> 1) of fields, the most fields winning; failing all, runs of
whitespace. ``csv.Sniffer`` was tried first and dropped: it guesses from character frequencies and picks ``,`` in
``;``-separated files with decimal commas.

Examples
--------
>>> import tempfile, pathlib
>>> path = pathlib.Path(tempfile.mkdtemp()) / "r.csv"
>>> _ = path.write_bytes('\\ufeff"SG 1 (mV)";mass [g]\\r\\n12,5;25\\r\\n13,0;0\\r\\n'.encode())
>>> table = read_table(path, decimal=",")
>>> table.columns, table.delimiter
(['SG 1 (mV)', 'mass [g]'], ';')
>>> table.numbers("SG 1 (mV)").tolist()
[12.5, 13.0]
"""

from __future__ import annotations

import csv
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from flexdigit import _io
from flexdigit._io import RECORDS_LIMIT, check_input, count_lines, read_bytes, refuse_special
from flexdigit._validation import check_plausible
from flexdigit.errors import DataFileError

__all__ = ["Table", "read_table", "DELIMITERS"]

#: Delimiters tried, in order of preference on a tie; "whitespace" is the fallback.
DELIMITERS = (",", ";", "\t", "|")
#: A number as a cell may hold it (no NaN, no infinity, no digit separators).
_NUMBER = re.compile(r"^[+-]?(\d+(\.\d*)?|\.\d+)([eE][+-]?\d+)?$")
#: What a cell may hold for "no value" where a value may be missing (as pandas, MATLAB or R write it).
_MISSING = ("nan", "na", "n/a", "null", "none")
#: A character no plain number holds (``float`` would also take ``nan``, ``inf``, ``1_000``, other scripts' digits).
_NOT_NUMERIC = re.compile(r"[^0-9+\-.eE\n]")
#: A number with a decimal comma / a decimal point (for detecting the decimal mark).
_COMMA_NUMBER = re.compile(r"^[+-]?\d*,\d+([eE][+-]?\d+)?$")
_POINT_NUMBER = re.compile(r"^[+-]?\d*\.\d+([eE][+-]?\d+)?$")
#: A spreadsheet's first line naming the delimiter (``sep=;``).
_SEP_LINE = re.compile(r"^sep=[,;|\t]$")
#: What starts a comment line (``#``; ``%`` as MATLAB writes them).
_COMMENT = ("#", "%")
#: Lines used to detect the delimiter.
_SNIFF_LINES = 50


@dataclass
class Table:
    """Raw cells of a table and where each row came from.

    Attributes
    ----------
    source : str
        The file, for messages.
    columns : list of str
        Header names, stripped of surrounding whitespace.
    rows : list of list of str
        Cells as text (Parquet values converted with ``str``; a null is ``""``).
    lines : list of int
        File line of each row (CSV, counting from 1) or row number (Parquet, from 1).
    delimiter : str or None
        The delimiter found (``"whitespace"`` for runs of blanks; None for Parquet).
    decimal : str
        The decimal mark numbers are read with.
    """

    source: str
    columns: list[str]
    rows: list[list[str]]
    lines: list[int]
    delimiter: str | None = None
    decimal: str = "."
    unit: str = field(default="line")

    def __len__(self) -> int:
        return len(self.rows)

    def where(self, i: int) -> str:
        """``"line 12"`` (CSV) or ``"row 12"`` (Parquet) for row ``i``."""
        return f"{self.unit} {self.lines[i]}"

    def find(self, name: str, role: str = "") -> str:
        """The column ``name`` names: exactly, else ignoring case, surrounding quotes and runs of blanks.

        Raises
        ------
        DataFileError
            Naming the file, the column (and its ``role``, e.g. "the load column") and the columns there are.
        """
        if name in self.columns:
            return name
        key = _loose(name)
        matches = [c for c in self.columns if _loose(c) == key]
        if len(matches) == 1:
            return matches[0]
        what = f" ({role})" if role else ""
        if len(matches) > 1:
            raise DataFileError(
                f"{self.source}: column {name!r}{what} is ambiguous: it could be any of {', '.join(map(repr, matches))}"
            )
        raise DataFileError(
            f"{self.source}: no column {name!r}{what}; the header (line {self._header_line()}) has "
            + ", ".join(repr(c) for c in self.columns)
        )

    def _header_line(self) -> int:
        return self.lines[0] - 1 if self.lines and self.unit == "line" else 1

    def numbers(self, name: str, *, allow_empty: bool = False, role: str = "") -> np.ndarray:
        """Column ``name`` as floats; an empty cell (or ``NaN``, ``NA``, ``null``: "no value") is NaN when
        ``allow_empty``.

        Raises
        ------
        DataFileError
            ``FILE: line N, column 'X': 'abc' is not a number`` for the first bad cell: text, NaN or infinity
            written out, a decimal comma when the decimal mark is ``.`` (the message says so), or an empty cell
            unless allowed.
        """
        column = self.find(name, role)
        k = self.columns.index(column)
        cells = [row[k].strip() for row in self.rows]
        if self.decimal == ",":
            cells = [c.replace(",", ".") for c in cells]
        if allow_empty:
            cells = ["" if c.lower() in _MISSING else c for c in cells]
        # the whole column at once when it holds only plain numbers (a 1e5-row file in well under a second); any
        # other cell: cell by cell, for the message naming it
        given = [c for c in cells if c] if allow_empty else cells
        if given and not _NOT_NUMERIC.search("\n".join(given)):
            try:
                out = np.array([c or "nan" for c in cells] if allow_empty else cells, dtype=float)
            except ValueError:
                pass
            else:
                if not np.isinf(out).any():
                    return out
                i = int(np.argmax(np.isinf(out)))  # 1e999 parses, as infinity: no measurement is that
                raise DataFileError(
                    f"{self.source}: {self.where(i)}, column {column!r}: {self.rows[i][k].strip()!r} is beyond a "
                    "float's range (|x| > 1.8e308); every mapped cell needs a finite number"
                )
        out = np.empty(len(cells))
        for i, text in enumerate(cells):
            cell = self.rows[i][k].strip()
            if text == "":
                if allow_empty:
                    out[i] = math.nan
                    continue
                raise DataFileError(f"{self.source}: {self.where(i)}, column {column!r}: empty cell; expected a number")
            if not _NUMBER.match(text):
                hint = ""
                if self.decimal == "." and re.match(r"^[+-]?\d+,\d+$", cell):
                    hint = " (a decimal comma? give the decimal mark ',')"
                elif cell.lower().lstrip("+-") in ("nan", "na", "n/a", "inf", "infinity", "null", "none"):
                    hint = " (a missing or infinite value; every mapped cell needs a finite number)"
                raise DataFileError(
                    f"{self.source}: {self.where(i)}, column {column!r}: {cell!r} is not a number{hint}"
                )
            out[i] = float(text)
            if math.isinf(out[i]):
                raise DataFileError(
                    f"{self.source}: {self.where(i)}, column {column!r}: {cell!r} is beyond a float's range "
                    "(|x| > 1.8e308); every mapped cell needs a finite number"
                )
        return out

    def plausible(self, column: str, values: np.ndarray, declared, name: str | None = None) -> np.ndarray:
        """``values`` (column ``column``, row for row, in the declaration's unit; NaN: not read) if every one is
        inside the :class:`~flexdigit._validation.Plausible` range ``declared``; else a :class:`DataFileError`
        naming the file, the line, the column, the value, the range and its likely unit slip."""
        out = np.asarray(values, dtype=float)
        read = ~np.isnan(out)
        try:
            check_plausible(out[read], declared, name or column, error=DataFileError)  # vectorised: 1e7 rows in ms
        except DataFileError as exc:
            rows = np.flatnonzero(read)
            first = next(int(i) for i in rows if not declared.satisfied_by(float(out[i])))
            raise DataFileError(f"{self.source}: {self.where(first)}, column {column!r}: {exc}") from None
        return out


def _loose(name: str) -> str:
    return " ".join(name.strip().strip("\"'").split()).lower()


def read_table(path: str | Path, *, delimiter: str | None = None, decimal: str | None = None) -> Table:
    """Read a CSV-like text file or a ``.parquet`` file into a :class:`Table` (see the module docstring).

    Parameters
    ----------
    path : path
        The file. Text: UTF-8 (a byte-order mark is skipped), UTF-16 with its byte-order mark (a spreadsheet's
        "Unicode text"), or Latin-1 if it is not UTF-8; lines starting with ``#`` or ``%`` and blank lines are
        skipped; a first line ``sep=;`` (a spreadsheet's export) names the delimiter; the first other line is the
        header.
    delimiter : str, optional
        ``","``, ``";"``, ``"\\t"`` (or ``"tab"``), ``"|"``, ``"whitespace"``; default: ``sep=`` or detected.
    decimal : {".", ","}, optional
        The decimal mark of the numbers. Default: detected, ``,`` only where the delimiter is not ``,`` and the
        first rows hold numbers with a decimal comma and none with a decimal point; with the ``,`` delimiter a
        decimal comma needs quoted cells and ``decimal=","``.

    Raises
    ------
    DataFileError
        Naming the file (and line): not found as a file, binary, empty, no delimiter that splits the header into
        columns, a row with a different number of fields than the header, duplicate column names.
    FileNotFoundError
        If the file does not exist.
    """
    p = Path(path)
    if not p.exists():
        raise FileNotFoundError(2, "No such file", str(p))
    refuse_special(p, "a CSV-like text or .parquet file")
    if not p.is_file():
        raise DataFileError(f"{p}: not a file (a directory?); expected a CSV-like text or .parquet file")
    if decimal not in (None, ".", ","):
        raise DataFileError(f"{p}: the decimal mark must be '.' or ','. Got {decimal!r} instead.")
    if delimiter == "tab":
        delimiter = "\t"
    if delimiter is not None and delimiter not in (*DELIMITERS, "whitespace"):
        raise DataFileError(
            f"{p}: the delimiter must be one of ',', ';', 'tab', '|', 'whitespace'. Got {delimiter!r} instead."
        )
    if p.suffix.lower() == ".parquet":
        check_input(p, "a Parquet table")
        return _read_parquet(p, decimal or ".")
    count_lines(p, "a text table")  # a 10-million-row file is refused in a second, not read into gigabytes
    numbered = _text_lines(p)
    first = numbered[0][1].strip(" \"'")
    if _SEP_LINE.match(first):  # "sep=;": a spreadsheet's export names its delimiter on the first line
        numbered = numbered[1:]
        named = "\t" if first[4:] == "\t" else first[4:]
        delimiter = delimiter or named
        if not numbered:
            raise DataFileError(f"{p}: empty file: expected a header line and rows of numbers")
    if delimiter is None:
        delimiter = _detect_delimiter(p, [line for _, line in numbered[:_SNIFF_LINES]], decimal)
    rows = _split_all(p, numbered, delimiter)
    if decimal is None:
        decimal = _detect_decimal(rows[1 : 1 + _SNIFF_LINES * 4], delimiter)
    header = [c.strip() for c in rows[0]]
    header_line = numbered[0][0]
    # a delimiter closing every line (spreadsheet exports) makes an empty last column: drop it
    if header and header[-1] == "" and all(len(r) == len(header) and r[-1].strip() == "" for r in rows[1:]):
        header, rows = header[:-1], [r[:-1] for r in rows]
    if any(c == "" for c in header):
        raise DataFileError(f"{p}: line {header_line}: the header has an empty column name: {header!r}")
    seen = set()
    for c in header:
        if c in seen:
            raise DataFileError(f"{p}: line {header_line}: column {c!r} appears twice in the header")
        seen.add(c)
    lines = [n for n, _ in numbered[1:]]
    body = rows[1:]
    for n, row in zip(lines, body, strict=True):
        if len(row) != len(header):
            raise DataFileError(
                f"{p}: line {n} has {len(row)} fields, the header (line {header_line}) has {len(header)}"
            )
    return Table(str(p), header, body, lines, delimiter, decimal, "line")


def _text_lines(p: Path) -> list[tuple[int, str]]:
    """``(line number, line)`` of the lines that are neither blank nor comments; refuses binary and empty files."""
    data = read_bytes(p, "a text table", RECORDS_LIMIT)
    if data[:2] in (b"\xff\xfe", b"\xfe\xff"):  # UTF-16 with its byte-order mark
        try:
            text = data.decode("utf-16")
        except UnicodeDecodeError:
            raise DataFileError(f"{p}: not a text table (a broken UTF-16 file)") from None
    elif b"\x00" in data[:4096]:
        raise DataFileError(f"{p}: not a text table (binary content); expected CSV-like text or a .parquet file")
    else:
        try:
            text = data.decode("utf-8-sig")
        except UnicodeDecodeError:
            text = data.decode("latin-1")
    numbered = [
        (n, line)
        for n, line in enumerate(text.splitlines(), start=1)
        if line.strip() and not line.lstrip().startswith(_COMMENT)
    ]
    if not numbered:
        raise DataFileError(f"{p}: empty file: expected a header line and rows of numbers")
    return numbered


def _split(line: str, delimiter: str) -> list[str]:
    if delimiter == "whitespace":
        return next(csv.reader([line.strip()], delimiter=" ", skipinitialspace=True))
    return next(csv.reader([line], delimiter=delimiter))


def _split_all(p: Path, numbered: list[tuple[int, str]], delimiter: str) -> list[list[str]]:
    """Every line split on ``delimiter``: one :mod:`csv` reader for all (fast), line by line where a quote left
    open would let the reader run on into the next line, or to name the line :mod:`csv` cannot split (a field past
    its limit of 131072 characters: a file with a hole of NUL bytes)."""
    lines = [line for _, line in numbered]
    try:
        if delimiter == "whitespace":
            rows = list(csv.reader([line.strip() for line in lines], delimiter=" ", skipinitialspace=True))
        else:
            rows = list(csv.reader(lines, delimiter=delimiter))
    except csv.Error:
        rows = []
    if len(rows) == len(lines):
        return rows
    rows = []
    for number, line in numbered:
        try:
            rows.append(_split(line, delimiter))
        except csv.Error as exc:
            raise DataFileError(
                f"{p}: line {number}: not a row of a table ({exc}; {len(line)} characters on one line): expected "
                "numbers between delimiters"
            ) from None
    return rows


def _count(line: str, delimiter: str) -> int:
    """The fields of ``line``; -1 where :mod:`csv` cannot split it (then no delimiter agrees with it)."""
    try:
        return len(_split(line, delimiter))
    except csv.Error:
        return -1


def _detect_delimiter(p: Path, lines: list[str], decimal: str | None) -> str:
    """The delimiter that splits the header into the most columns (> 1) and every other line into as many; else
    runs of blanks doing so; else the delimiter most lines agree with (the ragged line is then named)."""
    candidates = [d for d in DELIMITERS if d != decimal] + ([","] if decimal == "," else [])
    consistent, partial = [], []
    for d in candidates:
        fields = [_count(line, d) for line in lines]
        if fields[0] < 2:
            continue
        agree = sum(n == fields[0] for n in fields) / len(fields)
        (consistent if agree == 1.0 else partial).append((-fields[0], -agree, d))
    if consistent:
        return min(consistent, key=lambda k: k[:1])[2]  # most columns; on a tie, the first delimiter tried
    counts = {_count(line, "whitespace") for line in lines}
    if len(counts) == 1 and counts.pop() > 1:
        return "whitespace"
    if partial:
        agree, _, d = max((-a, -n, d) for n, a, d in partial)  # most lines agreeing, then most columns
        if agree >= 0.5:
            return d
    raise DataFileError(
        f"{p}: no delimiter splits the header (the first line that is not a comment) into columns and most of the "
        f"{len(lines) - 1} lines after it into as many (tried ',', ';', tab, '|' and blanks); give the delimiter"
    )


def _detect_decimal(rows: list[list[str]], delimiter: str) -> str:
    """``,`` when the delimiter is not ``,`` and the cells hold decimal commas (``12,5``) and no decimal points."""
    if delimiter == ",":
        return "."
    cells = [c.strip() for row in rows for c in row]
    comma = any(_COMMA_NUMBER.match(c) for c in cells)
    point = any(_POINT_NUMBER.match(c) for c in cells)
    return "," if comma and not point else "."


def _read_parquet(p: Path, decimal: str) -> Table:
    import pyarrow.parquet as pq

    try:
        with _io.open_input(p, "a Parquet file", _io.RECORDS_LIMIT) as fh:  # any name, even not UTF-8
            rows = pq.ParquetFile(fh).metadata.num_rows
            too_many = rows > _io.RECORDS_ROW_LIMIT  # a table's cells become Python strings: bounded first
            table = None if too_many else pq.read_table(fh)
    except Exception as exc:  # pyarrow raises several types for a damaged file; all mean "cannot read it"
        raise DataFileError(f"{p}: not a readable Parquet file ({exc})") from None
    if table is None:
        raise DataFileError(
            f"{p}: {rows:,} rows; flexdigit reads a table of at most {_io.RECORDS_ROW_LIMIT:,} rows (17 minutes at "
            "1 kHz): cut the part you want into a file of its own"
        )
    columns = [str(c) for c in table.column_names]
    values = [table.column(c).to_pylist() for c in table.column_names]
    rows = [
        ["" if v is None else repr(float(v)) if isinstance(v, float) else str(v) for v in row]
        for row in zip(*values, strict=True)
    ]
    return Table(str(p), columns, rows, list(range(1, len(rows) + 1)), None, ".", "row")
