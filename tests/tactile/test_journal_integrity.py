"""A collection's journal can be trusted (issue 22, item 7): every reading carries a CRC-32 of its canonical JSON
and its sample number is checked against the protocol's plan, so an edited, renumbered, duplicated or out-of-plan
reading is refused naming the file and the line, before the rig moves; a line cut short by a kill is dropped and
taken again. A journal of the previous format (no checksums) is resumed as legacy: its readings are measurements
that cannot be taken again."""

from __future__ import annotations

import json

import pytest

from flexdigit.cli import main
from flexdigit.errors import DataFileError
from flexdigit.tactile.dataset import LEGACY_JOURNAL_FORMATS, load_dataset, row_checksum
from flexdigit.tactile.protocols import Protocol
from flexdigit.tactile.runner import collect, journal_path
from flexdigit.tactile.thesis_experiments import twin_rig

#: 2 loads x (1 no-load + 2 positions x 2 repetitions) = 10 readings, in virtual time.
PROTOCOL = Protocol("integrity", (0.0125, 0.025), (0.0, 0.05), repetitions=2, no_load_repetitions=1, settle_s=0.0)


def _collect(out, stop_after=None):
    rig = twin_rig(PROTOCOL, seed=3)
    try:
        return collect(PROTOCOL, rig, out, rig_url="sim", stop_after=stop_after)
    finally:
        rig.close()


@pytest.fixture
def stopped(tmp_path):
    """A collection stopped after 6 of its 10 readings: the journal and its lines (header first)."""
    out = tmp_path / "d.parquet"
    _collect(out, stop_after=6)
    path = journal_path(out)
    return out, path, path.read_text().splitlines()


def _write(path, lines, end="\n"):
    path.write_text("\n".join(lines) + end)


def test_every_reading_carries_its_checksum(stopped):
    _, _, lines = stopped
    for line in lines[1:]:
        row = json.loads(line)
        assert row["crc"] == row_checksum(row)
        assert len(row["crc"]) == 8


def _edit(lines, i, **changes):
    row = json.loads(lines[i])
    row.update(changes)
    return [*lines[:i], json.dumps(row), *lines[i + 1 :]]


@pytest.mark.parametrize(
    ("tamper", "fragment"),
    [
        # a value edited by hand (the checksum left as it was)
        (lambda ls: _edit(ls, 3, gauge2_v=json.loads(ls[3])["gauge2_v"] + 1e-3), "line 4: the checksum of sample 2"),
        # renumbered: sample 2 -> 3
        (lambda ls: _edit(ls, 3, sample=3), "line 4: the checksum of sample 3"),
        # a line duplicated (checksum intact): sample 2 twice
        (lambda ls: [*ls[:4], ls[3], *ls[4:]], "line 5 holds sample 2, expected 3"),
        # a reading whose settings are not its sample's, checksum recomputed
        (lambda ls: [*ls[:3], _forged(ls[3], load_kg=0.5)], "line 4: sample 2 has load_kg = 0.5, but protocol"),
    ],
    ids=["edited", "renumbered", "duplicated", "out-of-plan-settings"],
)
def test_a_tampered_journal_is_refused_naming_file_and_line(stopped, tamper, fragment):
    out, path, lines = stopped
    _write(path, tamper(lines))
    before = path.read_bytes()
    with pytest.raises(DataFileError) as err:
        _collect(out)
    assert str(err.value).startswith(f"{path}: "), str(err.value)
    assert fragment in str(err.value), str(err.value)
    assert path.read_bytes() == before
    assert not out.exists()  # nothing taken, nothing written


def _forged(line, **changes):
    row = json.loads(line)
    row.update(changes)
    row["crc"] = row_checksum(row)
    return json.dumps(row)


def test_a_reading_beyond_the_plan_is_refused(tmp_path):
    out = tmp_path / "d.parquet"
    _collect(out, stop_after=PROTOCOL.sample_count - 1)
    path = journal_path(out)
    lines = path.read_text().splitlines()
    last = json.loads(lines[-1])
    # the protocol's last reading, then one more it never takes (checksum recomputed, settings copied)
    lines.append(_forged(json.dumps(last), sample=last["sample"] + 1))
    lines.append(_forged(json.dumps(last), sample=last["sample"] + 2))
    _write(path, lines)
    with pytest.raises(DataFileError, match=rf"line {len(lines)} holds sample 10, beyond the 10 readings"):
        _collect(out)


def test_the_cli_refuses_a_tampered_journal_in_one_line(stopped, capsys, tmp_path):
    out, path, lines = stopped
    protocol_file = tmp_path / "p.toml"
    protocol_file.write_text('name = "x"\nloads_g = [12.5]\npositions_from_tip_cm = [0, 5]\n')
    _write(path, _edit(lines, 2, gauge1_v=9.0))
    # a journal of another protocol is refused by its fingerprint; this one's own protocol by its checksum
    assert main(["collect", str(protocol_file), "--out", str(out)]) == 2
    assert capsys.readouterr().err.count("\n") == 1


def test_a_cut_last_line_is_dropped_and_taken_again(stopped, tmp_path):
    out, path, lines = stopped
    _write(path, [*lines[:-1], lines[-1][: len(lines[-1]) // 2]], end="")  # a kill in the middle of the last line
    resumed = _collect(out)
    reference = _collect(tmp_path / "ref.parquet")
    assert len(resumed) == len(reference) == PROTOCOL.sample_count
    assert (resumed["gauge1_v"] == reference["gauge1_v"]).all()  # the twin in virtual time: the same readings
    assert load_dataset(out)["sample"].tolist() == list(range(PROTOCOL.sample_count))


def test_a_legacy_journal_without_checksums_is_resumed(stopped, tmp_path):
    out, path, lines = stopped
    header = json.loads(lines[0])
    header["journal"] = LEGACY_JOURNAL_FORMATS[0]
    rows = [{k: v for k, v in json.loads(line).items() if k != "crc"} for line in lines[1:]]
    _write(path, [json.dumps(header), *map(json.dumps, rows)])
    resumed = _collect(out)
    reference = _collect(tmp_path / "ref.parquet")
    assert (resumed["gauge3_v"] == reference["gauge3_v"]).all()
