"""Fuzz the JSON loaders (saved models, collection journals, loop logs): every generated file loads or gives the
project's one-line error naming the file (issue 16). Valid seeds are made here: a network fitted on seeded
numbers, a journal and a log written line by line from a seeded generator."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from flexdigit.rig.sample_log import LOG_FORMAT, read_log_runs
from flexdigit.tactile.dataset import JOURNAL_FORMAT, Journal, load_dataset, make_meta, read_journal, row_checksum
from flexdigit.tactile.model_io import load_model, save_model
from flexdigit.tactile.pipeline import ThesisNetwork
from flexdigit.tactile.protocols import Protocol

from .strategies import assert_loader_contract, edited_document, json_values, loop_samples, mutated_bytes

PROTOCOL = Protocol("fuzz", (0.0125, 0.025), (0.0, 0.05), repetitions=2, no_load_repetitions=1)


def _model_doc() -> dict:
    rng = np.random.default_rng(0)
    x = rng.normal(size=(40, 3))
    net = ThesisNetwork(hidden=3, epochs=1, random_state=0).fit(x, x.sum(axis=1))
    import tempfile
    from pathlib import Path

    path = Path(tempfile.mkdtemp()) / "m.json"
    save_model(path, net, target="position", inputs=["gauge1_v", "gauge2_v", "gauge3_v"])
    return json.loads(path.read_text())


def _journal_lines() -> list[dict]:
    rng = np.random.default_rng(1)
    plan = PROTOCOL.plan(0.270)
    meta = make_meta(PROTOCOL, {"url": "fuzz", "repr": "fuzz"}, 0.270)
    header = {"journal": JOURNAL_FORMAT, **meta, "settings": {"settle_s": 1.0}}
    rows = []
    for i in range(PROTOCOL.sample_count):
        tip = plan["position_from_tip_m"][i]
        rows.append(
            {
                "sample": i,
                "test": int(plan["test"][i]),
                "gauge1_v": float(rng.normal(0, 0.1)),
                "gauge2_v": float(rng.normal(0, 0.1)),
                "gauge3_v": float(rng.normal(0, 0.1)),
                "pot_v": None,
                "load_kg": float(plan["load_kg"][i]),
                "position_index": int(plan["position_index"][i]),
                "position_from_tip_m": None if np.isnan(tip) else float(tip),
                "position_from_base_m": None if np.isnan(tip) else 0.270 - float(tip),
                "command": int(plan["command"][i]),
                "repetition": int(plan["repetition"][i]),
                "time_s": 0.5 * i,
            }
        )
        rows[-1]["crc"] = row_checksum(rows[-1])
    return [header, *rows]


def _log_lines() -> list[dict]:
    samples = loop_samples(seed=2)
    header = {"format": LOG_FORMAT, "controller": "digital20", "period_s": 0.02}
    return [header, *samples, {"stop": "completed", "message": "ran 8 samples", "safe_command_sent": True}]


MODEL = _model_doc()
JOURNAL = _journal_lines()
LOG = _log_lines()


def _jsonl(lines) -> bytes:
    return ("\n".join(json.dumps(line) for line in lines) + "\n").encode()


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("json")


def _open_journal(path):
    journal, rows = Journal.open(path, {k: v for k, v in JOURNAL[0].items() if k != "journal"})
    journal.close()
    return rows


def test_the_seeds_load(folder):
    (folder / "m.json").write_text(json.dumps(MODEL))
    assert load_model(folder / "m.json").target == "position"
    (folder / "j.jsonl").write_bytes(_jsonl(JOURNAL))
    assert len(read_journal(folder / "j.jsonl")) == PROTOCOL.sample_count
    assert len(_open_journal(folder / "j.jsonl")) == PROTOCOL.sample_count
    (folder / "l.jsonl").write_bytes(_jsonl(LOG))
    assert len(read_log_runs(folder / "l.jsonl")[0][2]) == 8


@given(data=mutated_bytes(json.dumps(MODEL, indent=1).encode()))
def test_model_bytes(folder, data):
    path = folder / "model-bytes.json"
    path.write_bytes(data)
    assert_loader_contract(load_model, path)


@given(doc=edited_document(MODEL, json_values))
def test_model_values(folder, doc):
    path = folder / "model-values.json"
    path.write_text(json.dumps(doc))
    assert_loader_contract(load_model, path)


@given(data=mutated_bytes(_jsonl(JOURNAL)))
def test_journal_bytes(folder, data):
    path = folder / "journal-bytes.jsonl"
    path.write_bytes(data)
    assert_loader_contract(load_dataset, path)  # read and checked against its protocol
    path.write_bytes(data)
    assert_loader_contract(_open_journal, path)  # the resume path reads it the same way


@given(data=mutated_bytes(_jsonl(LOG)))
def test_log_bytes(folder, data):
    path = folder / "log-bytes.jsonl"
    path.write_bytes(data)
    assert_loader_contract(read_log_runs, path)


def _line_values(seed_lines: list[dict], name: str, load):
    """A property: one line of a JSON-lines file has one value edited (``edited_document``)."""

    @given(line=st.integers(0, len(seed_lines) - 1), data=st.data())
    def test(folder, line, data):
        lines = list(seed_lines)
        lines[line] = data.draw(edited_document(seed_lines[line], json_values))
        path = folder / f"{name}-values.jsonl"
        path.write_bytes(_jsonl(lines))
        assert_loader_contract(load, path)

    return test


test_journal_values = _line_values(JOURNAL, "journal", load_dataset)
test_log_values = _line_values(LOG, "log", read_log_runs)
