"""A study's journal can be trusted (issue 22, item 7): each row carries a CRC-32 of its canonical JSON and the
study's fingerprint, and its row number is checked against the design, so an edited, renumbered, duplicated or
out-of-design row is refused naming the file and the line; a line cut short by a kill is dropped and its row
computed again. A journal of format 1 (no checksums) is refused with a clear message (``--force`` starts over)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from flexdigit.errors import DataFileError
from flexdigit.studies.execution import JOURNAL_NAME, Journal, RowRecord, _done

#: A design of 6 rows of 2 parameters (the values do not matter to the journal, their number does).
DESIGN = np.arange(12.0).reshape(6, 2)
HEADER = {"fingerprint": "f00d"}


@pytest.fixture
def journal(tmp_path):
    """A journal holding rows 0..3 (row 2 failed with its own error, as a refused parameter set is recorded)."""
    path = tmp_path / JOURNAL_NAME
    j = Journal(path, HEADER, design=DESIGN)
    j.append(
        [
            RowRecord(0, {"m": 1.0}),
            RowRecord(1, {"m": 2.0}),
            RowRecord(2, {}, "ValueError: no"),
            RowRecord(3, {"m": 4.0}),
        ]
    )
    return path


def _lines(path):
    return path.read_text().splitlines()


def _write(path, lines, end="\n"):
    path.write_text("\n".join(lines) + end)


def _edited(line, **changes):
    data = json.loads(line)
    data.update(changes)
    return json.dumps(data, sort_keys=True)


def test_rows_round_trip_with_their_checksums(journal):
    again = Journal(journal, HEADER, design=DESIGN)
    assert sorted(again.records) == [0, 1, 2, 3]
    assert again.records[1].values == {"m": 2.0}
    assert all(len(json.loads(line)["crc"]) == 8 for line in _lines(journal)[1:])


@pytest.mark.parametrize(
    ("tamper", "fragment"),
    [
        (lambda ls: [*ls[:2], _edited(ls[2], values={"m": 2.5}), *ls[3:]], "line 3: row 1's checksum does not match"),
        (lambda ls: [*ls[:2], _edited(ls[2], row=5), *ls[3:]], "line 3: row 5's checksum does not match"),
        (lambda ls: [*ls, ls[2]], "line 6: row 1 again, already recorded on line 3"),
        (lambda ls: [*ls, _edited(ls[2], row=9)], "line 6: row 9 is outside the study's design (rows 0..5)"),
        (lambda ls: [*ls[:2], _edited(ls[2], crc="00000000"), *ls[3:]], "line 3: row 1's checksum"),
    ],
    ids=["edited", "renumbered", "duplicated", "out-of-design", "checksum-edited"],
)
def test_a_tampered_journal_is_refused_naming_file_and_line(journal, tamper, fragment):
    _write(journal, tamper(_lines(journal)))
    with pytest.raises(DataFileError) as err:
        Journal(journal, HEADER, design=DESIGN)
    assert str(err.value).startswith(f"{journal}: "), str(err.value)
    assert fragment in str(err.value), str(err.value)


def test_a_row_from_another_study_is_refused(journal, tmp_path):
    other = tmp_path / "other.jsonl"
    Journal(other, {"fingerprint": "beef"}, design=DESIGN).append([RowRecord(4, {"m": 5.0})])
    _write(journal, [*_lines(journal), _lines(other)[1]])  # its checksum is right, for the other study
    with pytest.raises(DataFileError, match="line 6: row 4's checksum does not match"):
        Journal(journal, HEADER, design=DESIGN)


def test_a_failed_tasks_row_may_be_recorded_again(journal):
    j = Journal(journal, HEADER, design=DESIGN)
    j.append([RowRecord(4, {}, "task failed: KilledWorker: all workers died")])
    j.append([RowRecord(4, {"m": 5.0})])  # the rerun computes it again
    assert Journal(journal, HEADER, design=DESIGN).records[4].values == {"m": 5.0}


def test_a_cut_last_line_is_dropped_and_its_row_computed_again(journal):
    lines = _lines(journal)
    _write(journal, [*lines[:-1], lines[-1][:20]], end="")  # a kill in the middle of row 3's line
    again = Journal(journal, HEADER, design=DESIGN)
    assert sorted(again.records) == [0, 1, 2]
    assert not _done(again, 3)
    assert journal.read_text().endswith("}\n")


def test_a_journal_without_checksums_is_refused_clearly(journal):
    lines = _lines(journal)
    header = json.loads(lines[0])
    header["flexdigit_study_journal"] = 1
    rows = [json.dumps({k: v for k, v in json.loads(line).items() if k != "crc"}) for line in lines[1:]]
    _write(journal, [json.dumps(header), *rows])
    with pytest.raises(DataFileError, match="format 1 .* its rows cannot be checked; --force starts the study over"):
        Journal(journal, HEADER, design=DESIGN)
    assert Journal(journal, HEADER, design=DESIGN, force=True).records == {}


def test_appending_a_row_outside_the_design_is_refused(journal):
    with pytest.raises(ValueError, match="row 6 is outside the study's design"):
        Journal(journal, HEADER, design=DESIGN).append([RowRecord(6, {"m": 0.0})])
