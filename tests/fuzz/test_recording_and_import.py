"""Fuzz the loaders other helpers added, with the shared strategies: MCAP recordings replayed (``replay://FILE.mcap``,
the live page's and collect's recordings) and foreign readings imported (``flexdigit dataset import``). Every
generated file loads or gives the project's one-line error naming the file (issue 16)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from flexdigit.rig.backends.replay_backend import ReplayRig
from flexdigit.rig.recording import Recording
from flexdigit.tactile.importer import ColumnMap, import_readings

from .strategies import assert_loader_contract, edited_document, json_values, loop_samples, mutated_bytes

SAMPLES = loop_samples(seed=4)
CMAP = ColumnMap(
    gauges=("sg_a", "sg_b", "sg_c"),
    gauge_unit="mV",
    load="mass_g",
    load_unit="g",
    position="x_mm",
    position_unit="mm",
    position_from="clamp",
)


def _write_recording(path, samples) -> None:
    recording = Recording(path, header={"backend": "fuzz", "period_s": 0.02}, force=True)
    for sample in samples:
        recording.write_sample(sample)
    recording.close({"stop": "completed", "message": "fuzz", "safe_command_sent": True})


def _replay(path):
    rig = ReplayRig(str(path))
    rig.close()
    return rig


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    folder = tmp_path_factory.mktemp("recordings")
    _write_recording(folder / "valid.mcap", SAMPLES)
    rng = np.random.default_rng(5)
    rows = ["sg_a;sg_b;sg_c;mass_g;x_mm"]
    for mass, x in [(0, ""), (25, 90), (25, 180), (12.5, 90), (12.5, 180)] * 3:
        a, b, c = rng.normal(20, 5, 3)
        rows.append(f"{a:.3f};{b:.3f};{c:.3f};{mass};{x}")
    (folder / "lab.csv").write_text("\n".join(rows) + "\n")
    return folder


def test_the_seeds_load(folder):
    assert len(_replay(folder / "valid.mcap").recorded_commands) == len(SAMPLES)
    assert len(import_readings(folder / "lab.csv", CMAP)) == 15


@given(data=st.data())
def test_recording_bytes(folder, data):
    path = folder / "bytes.mcap"
    path.write_bytes(data.draw(mutated_bytes((folder / "valid.mcap").read_bytes())))
    assert_loader_contract(_replay, path)


@given(line=st.integers(0, len(SAMPLES) - 1), data=st.data())
def test_recording_values(folder, line, data):
    samples = list(SAMPLES)
    samples[line] = data.draw(edited_document(SAMPLES[line], json_values))
    path = folder / "values.mcap"
    try:
        _write_recording(path, samples)
    except (TypeError, ValueError, OverflowError, KeyError):  # the writer refuses it (no time, a NaN): no file
        return
    assert_loader_contract(_replay, path)


@given(data=st.data())
def test_import_bytes(folder, data):
    path = folder / "bytes-lab.csv"
    path.write_bytes(data.draw(mutated_bytes((folder / "lab.csv").read_bytes())))
    assert_loader_contract(lambda p: import_readings(p, CMAP), path)
