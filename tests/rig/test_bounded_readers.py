"""Replay logs and MCAP recordings are read with bounded memory, and what a reader cannot take is refused in one
line naming the file (issue 22): a log is read a line at a time (a hole of NUL bytes or a line past
MAX_LOG_LINE_BYTES is refused after reading that much), an MCAP chunk over MAX_RECORD_BYTES or claiming 2**62
bytes is refused before anything is allocated, and JSON nested 10**5 deep is bad input, not a RecursionError."""

from __future__ import annotations

import json
import struct
import tracemalloc

import pytest

from flexdigit.cli import main
from flexdigit.errors import DataFileError
from flexdigit.rig import recording
from flexdigit.rig.recording import SAMPLE_TOPIC, read_recording
from flexdigit.rig.sample_log import LOG_FORMAT, MAX_LOG_LINE_BYTES, read_log

NESTED = "[" * 100_000 + "]" * 100_000
#: A hole in a sparse log (a copy cut short, a disk image): reads back as NUL bytes, takes no disk.
HOLE_BYTES = 256 * 2**20
#: What reading past such a hole may allocate at most: a few of its longest lines (MAX_LOG_LINE_BYTES), never the
#: file (reading it whole took over twice the hole).
READ_PEAK_BYTES = 8 * MAX_LOG_LINE_BYTES


def _sample(k: int) -> dict:
    return {"k": k, "t": round(0.02 * k, 4), "gauges_v": [1.0, 1.1, 1.2], "pot_v": None, "command": 8}


def _log(path, lines: list[bytes]):
    header = json.dumps({"format": LOG_FORMAT, "controller": None, "period_s": 0.02}).encode()
    path.write_bytes(b"\n".join([header, *lines]) + b"\n")
    return path


def _cli_error(capsys, *args) -> str:
    assert main([*args, "--json"]) == 2
    out = json.loads(capsys.readouterr().out)
    assert "internal error" not in out["error"], out
    return out["error"]


def test_a_log_line_nested_too_deep_is_named(tmp_path, capsys):
    path = _log(tmp_path / "run.jsonl", [json.dumps(_sample(0)).encode(), NESTED.encode(), b"{}"])
    with pytest.raises(DataFileError, match=r"run\.jsonl: line 3 is not a loop log line \(JSON nested too deep\)"):
        read_log(path)
    assert _cli_error(capsys, "run", "--backend", f"replay://{path}").startswith(f"{path}: line 3")


def test_a_log_with_a_hole_is_refused_after_reading_a_line(tmp_path):
    path = _log(tmp_path / "run.jsonl", [json.dumps(_sample(0)).encode()])
    with open(path, "r+b") as fh:
        fh.seek(0, 2)
        fh.truncate(fh.tell() + HOLE_BYTES)  # sparse: a hole, then one more sample
        fh.seek(0, 2)
        fh.write(b"\n" + json.dumps(_sample(1)).encode() + b"\n")
    tracemalloc.start()
    try:
        with pytest.raises(DataFileError, match=rf"run\.jsonl: line 3 is longer than {MAX_LOG_LINE_BYTES:,} bytes"):
            read_log(path)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < READ_PEAK_BYTES, peak


def test_a_log_is_read_a_line_at_a_time(tmp_path):
    n = 20_000
    path = _log(tmp_path / "run.jsonl", [json.dumps(_sample(k)).encode() for k in range(n)])
    _, samples, _ = read_log(path)
    assert [s["k"] for s in samples] == list(range(n))  # every sample, in order, streamed


def _mcap(path, n=50, compression="zstd"):
    from mcap.writer import CompressionType, Writer

    with open(path, "wb") as fh:
        writer = Writer(fh, compression=CompressionType[compression.upper()])
        writer.start("flexdigit", "test")
        schema = writer.register_schema("flexdigit.Sample", "jsonschema", b"{}")
        channel = writer.register_channel(SAMPLE_TOPIC, "json", schema)
        for k in range(n):
            ns = k * 20_000_000
            writer.add_message(channel, log_time=ns, publish_time=ns, data=json.dumps(_sample(k)).encode())
        writer.finish()
    return path


def _first_chunk(data: bytes) -> tuple[int, int]:
    """Offset and length of the first top-level chunk record (opcode 0x06) of an MCAP file."""
    pos = 8  # the magic
    while True:
        opcode, length = data[pos], struct.unpack_from("<Q", data, pos + 1)[0]
        if opcode == 0x06:
            return pos, length
        pos += 9 + length


def _unsized_zstd_chunk_claiming(path, claimed: int):
    """Rewrite the first chunk as zstd without its size in the frame (a streaming compressor's), claiming
    ``claimed`` bytes of records: the mcap library hands the claim to zstd as the output size."""
    import zstandard

    data = path.read_bytes()
    pos, length = _first_chunk(data)
    body = data[pos + 9 : pos + 9 + length]
    start, end, _, _, name_len = struct.unpack_from("<QQQII", body)
    (data_len,) = struct.unpack_from("<Q", body, 32 + name_len)
    records = body[40 + name_len : 40 + name_len + data_len]
    packed = zstandard.ZstdCompressor(write_content_size=False).compress(records)
    new = struct.pack("<QQQII", start, end, claimed, 0, 4) + b"zstd" + struct.pack("<Q", len(packed)) + packed
    path.write_bytes(data[:pos] + b"\x06" + struct.pack("<Q", len(new)) + new + data[pos + 9 + length :])
    return path


def test_a_chunk_claiming_2_to_the_62_bytes_is_refused_naming_the_file(tmp_path, capsys):
    path = _unsized_zstd_chunk_claiming(_mcap(tmp_path / "run.mcap", compression="none"), 2**62)
    with pytest.raises(DataFileError, match=r"run\.mcap: the chunk ending at byte [\d,]+ claims 4,611,686,018,"):
        read_recording(path)
    assert _cli_error(capsys, "run", "--backend", f"replay://{path}").startswith(f"{path}: the chunk")


def test_a_zstd_chunk_within_the_limit_still_reads(tmp_path):
    path = _mcap(tmp_path / "run.mcap", compression="zstd")
    _, samples, _ = read_recording(path)
    assert [s["k"] for s in samples] == list(range(50))


def test_a_chunk_over_the_limit_is_refused_not_read_whole(tmp_path, monkeypatch):
    path = _mcap(tmp_path / "run.mcap", n=2000, compression="none")  # the writer's default chunk: one of about 200 kB
    _, length = _first_chunk(path.read_bytes())
    monkeypatch.setattr(recording, "MAX_RECORD_BYTES", 64 * 1024)  # stands for 64 MiB against a 1.2 GB chunk
    with pytest.raises(DataFileError, match=r"run\.mcap: a record of [\d,]+ bytes at byte [\d,]+; .* 65,536 bytes"):
        read_recording(path)
    assert length > 64 * 1024


def test_an_mcap_message_nested_too_deep_is_named(tmp_path):
    from mcap.writer import Writer

    path = tmp_path / "run.mcap"
    with open(path, "wb") as fh:
        writer = Writer(fh)
        writer.start("flexdigit", "test")
        schema = writer.register_schema("flexdigit.Sample", "jsonschema", b"{}")
        channel = writer.register_channel(SAMPLE_TOPIC, "json", schema)
        writer.add_message(channel, log_time=0, publish_time=0, data=NESTED.encode(), sequence=7)
        writer.finish()
    with pytest.raises(DataFileError, match=rf"run\.mcap: message 7 on {SAMPLE_TOPIC}: JSON nested too deep"):
        read_recording(path)


#: What a replay may hold per recorded sample while reading and after, bytes: its columns take 64 (t, 3 gauges,
#: pot, setpoint, y as float64, the command as int16); a list of sample dicts took 790 and 910 at its peak, more
#: than the log's own 120 bytes a line.
REPLAY_BYTES_PER_SAMPLE = 200


@pytest.mark.parametrize("kind", ["jsonl", "mcap"])
def test_a_replay_holds_its_samples_in_columns_not_dicts(tmp_path, kind):
    from flexdigit.rig.backends.replay_backend import ReplayRig

    n = 50_000
    if kind == "jsonl":
        path = _log(tmp_path / "run.jsonl", [json.dumps(_sample(k)).encode() for k in range(n)])
    else:
        path = _mcap(tmp_path / "run.mcap", n=n)
    tracemalloc.start()
    try:
        rig = ReplayRig(str(path))
        held, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < REPLAY_BYTES_PER_SAMPLE * n, peak / n
    assert held < REPLAY_BYTES_PER_SAMPLE * n, held / n
    last = rig.samples[-1]  # read back as the log has it
    assert len(rig.samples) == n
    assert last["t"] == _sample(n - 1)["t"]
    assert last["gauges_v"] == [1.0, 1.1, 1.2]
    assert last["pot_v"] is None
    assert last["command"] == 8
