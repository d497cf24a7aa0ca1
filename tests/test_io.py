"""flexdigit._io: outputs are atomic and never clobber an existing file unless forced."""

from __future__ import annotations

import pytest

from flexdigit._io import atomic_path, atomic_write, check_output
from flexdigit.errors import OutputExistsError


def test_write_then_refuse_existing_keeps_old_content(tmp_path):
    out = tmp_path / "x.txt"
    with atomic_write(out, "w") as fh:
        fh.write("first")
    with pytest.raises(OutputExistsError, match="x.txt: the file exists; pass --force"), atomic_write(out, "w") as fh:
        fh.write("second")
    assert out.read_text() == "first"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.txt"]  # no temporary file left behind


def test_force_replaces(tmp_path):
    out = tmp_path / "x.bin"
    out.write_bytes(b"old")
    with atomic_write(out, force=True) as fh:
        fh.write(b"new")
    assert out.read_bytes() == b"new"


def test_failure_inside_block_leaves_destination_untouched(tmp_path):
    out = tmp_path / "x.txt"
    out.write_text("precious")
    with pytest.raises(RuntimeError), atomic_write(out, "w", force=True) as fh:
        fh.write("half")
        raise RuntimeError("disk full")
    assert out.read_text() == "precious"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.txt"]


def test_failure_with_no_destination_creates_nothing(tmp_path):
    out = tmp_path / "y.parquet"
    with pytest.raises(RuntimeError), atomic_path(out) as tmp:
        tmp.write_bytes(b"partial")
        raise RuntimeError("killed")
    assert list(tmp_path.iterdir()) == []


def test_file_appearing_meanwhile_is_not_clobbered(tmp_path):
    out = tmp_path / "z.txt"
    with pytest.raises(OutputExistsError), atomic_write(out, "w") as fh:
        fh.write("ours")
        out.write_text("someone else's")
    assert out.read_text() == "someone else's"


def test_check_output_names_the_problem_before_work(tmp_path):
    with pytest.raises(FileNotFoundError, match="the directory .*missing does not exist"):
        check_output(tmp_path / "missing" / "out.json")
    with pytest.raises(IsADirectoryError, match="is a directory"):
        check_output(tmp_path, force=True)
    (tmp_path / "a").write_text("")
    with pytest.raises(OutputExistsError, match="pass --force"):
        check_output(tmp_path / "a")
    assert check_output(tmp_path / "a", force=True) == tmp_path / "a"
