"""Run a load protocol on a rig (the twin by default): settle, read, journal every reading, resume after a stop.

The runner only uses the :class:`flexdigit.rig.base.Rig` interface (``read``, ``write_command``, ``wait``,
``place_load``, ``clear_loads``, ``relax``), so the same protocol runs on the twin and on hardware, where
``place_load`` asks the operator to hang the weight. Every reading is appended to ``<out>.journal.jsonl`` and
flushed before the next one is taken; running the same command again after Ctrl-C or a crash resumes at the
first missing sample, so no reading is lost or taken twice. At the end the journal is compacted to ``out``
(Parquet) and removed.
"""

from __future__ import annotations

from contextlib import nullcontext
from pathlib import Path

import numpy as np

from flexdigit.errors import ParameterError, RigError
from flexdigit.params import RigParams
from flexdigit.tactile.dataset import Dataset, Journal, load_dataset, make_meta, save_dataset
from flexdigit.tactile.protocols import RELAXED, Protocol


def journal_path(out: str | Path) -> Path:
    """Where the journal of a collection into ``out`` lives: ``<out>.journal.jsonl``."""
    out = Path(out)
    return out.with_name(out.name + ".journal.jsonl")


def describe_rig(rig, url: str | None = None) -> dict:
    """The rig metadata stored with a dataset: its URL (backend), ``repr`` and effective settings (the seed the
    twin actually used, whichever way it was given)."""
    settings = rig.settings() if hasattr(rig, "settings") else {}
    return {"url": url or getattr(rig, "url", type(rig).__name__), "repr": repr(rig), "settings": settings}


def collect(
    protocol: Protocol,
    rig,
    out: str | Path,
    *,
    params: RigParams | None = None,
    rig_url: str | None = None,
    settle_s: float | None = None,
    progress: bool = False,
    fsync: bool = False,
    stop_after: int | None = None,
) -> Dataset:
    """Take every sample of ``protocol`` on ``rig`` and write the dataset to ``out`` (Parquet).

    Parameters
    ----------
    protocol : Protocol
        What to do.
    rig : Rig
        Any backend of :mod:`flexdigit.rig` (the twin, a serial board, a replay).
    out : path
        The dataset to write. Its journal ``<out>.journal.jsonl`` is resumed if present.
    params : RigParams, optional
        For the digit length (positions from the tip -> from the base). Default: the thesis rig.
    rig_url : str, optional
        How the rig was opened, recorded in the metadata.
    settle_s : float, optional
        Override the protocol's settle time (s) after every change of load, position or command.
    progress : bool
        Show a rich progress bar.
    fsync : bool
        Force every reading to disk (power-loss safe; slower).
    stop_after : int, optional
        Stop (as if interrupted) after taking this many new readings; for tests and partial runs.

    Returns
    -------
    Dataset
        The complete dataset (or, with ``stop_after``, what the journal holds so far).

    Raises
    ------
    ParameterError
        If ``out`` already holds a dataset.
    DataFileError
        If the journal belongs to another protocol or is corrupt.
    RigError
        If the rig fails; the journal keeps every reading taken before.
    """
    params = params or RigParams()
    out = Path(out)
    if not getattr(rig, "accepts_loads", True):
        raise ParameterError(
            f"{getattr(rig, 'name', rig)}: cannot collect a load protocol on it (it cannot hang weights); "
            "collect on the twin (--backend sim) or a rig"
        )
    if out.exists():
        raise ParameterError(f"{out} already exists; remove it or choose another output file")
    settle = protocol.settle_s if settle_s is None else float(settle_s)
    plan = protocol.plan(params.geometry.digit_length_m)
    meta = make_meta(protocol, describe_rig(rig, rig_url), params.geometry.digit_length_m)
    journal, done = Journal.open(journal_path(out), meta, fsync=fsync)
    start = len(done)
    total = protocol.sample_count
    taken = 0
    setting = None
    bar = _progress_bar(progress)
    try:
        with bar if bar is not None else nullcontext():
            task = bar.add_task(protocol.name, total=total, completed=start) if bar is not None else None
            for i in range(start, total):
                if stop_after is not None and taken >= stop_after:
                    break
                wanted = (int(plan["test"][i]), float(plan["load_kg"][i]), int(plan["position_index"][i]))
                command = int(plan["command"][i])
                if wanted != setting:
                    _apply_setting(rig, command, float(plan["load_kg"][i]), float(plan["position_from_base_m"][i]))
                    rig.wait(settle)
                    setting = wanted
                else:
                    if protocol.rehang and plan["load_kg"][i] > 0:
                        rig.rehang(settle)
                    if protocol.sample_interval_s > 0:
                        rig.wait(protocol.sample_interval_s)
                reading = rig.read()
                gauges = np.asarray(reading.gauges_v, dtype=float)
                if gauges.shape != (3,) or not np.all(np.isfinite(gauges)):
                    raise RigError(f"rig returned gauge voltages {gauges.tolist()!r} at sample {i}; expected 3 finite")
                journal.append(
                    {
                        "sample": i,
                        "test": int(plan["test"][i]),
                        "gauge1_v": float(gauges[0]),
                        "gauge2_v": float(gauges[1]),
                        "gauge3_v": float(gauges[2]),
                        "pot_v": float(reading.pot_v),
                        "load_kg": float(plan["load_kg"][i]),
                        "position_index": int(plan["position_index"][i]),
                        "position_from_tip_m": _none_if_nan(plan["position_from_tip_m"][i]),
                        "position_from_base_m": _none_if_nan(plan["position_from_base_m"][i]),
                        "command": command,
                        "repetition": int(plan["repetition"][i]),
                        "time_s": float(reading.time_s),
                    }
                )
                taken += 1
                if task is not None:
                    bar.advance(task)
    finally:
        journal.close()
        try:  # leave the rig safe: nothing hanging, servo relaxed
            rig.clear_loads()
            rig.relax()
        except Exception:  # noqa: BLE001 - the original error (if any) matters more than a failed tidy-up
            pass
    dataset = load_dataset(journal_path(out), protocol)
    if len(dataset) == total:
        save_dataset(dataset, out)
        journal_path(out).unlink()
    return dataset


def _apply_setting(rig, command: int, load_kg: float, position_from_base_m: float) -> None:
    rig.clear_loads()
    if command == RELAXED:
        rig.relax()
    else:
        rig.write_command(command)
    if load_kg > 0:
        rig.place_load(load_kg, position_from_base_m)


def _none_if_nan(value: float) -> float | None:
    return None if not np.isfinite(value) else float(value)


def _progress_bar(enabled: bool):
    if not enabled:
        return None
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

    return Progress(  # on stderr: stdout carries the command's result (its --json) and nothing else
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeRemainingColumn(),
        transient=False,
        console=Console(stderr=True),
    )


def load_or_collect(path: str | Path, protocol: Protocol, rig_factory, **kwargs) -> Dataset:
    """Load ``path`` if it holds ``protocol``'s dataset, else collect it on ``rig_factory()`` (closed after)."""
    path = Path(path)
    if path.exists():
        return load_dataset(path, protocol)
    rig = rig_factory()
    try:
        return collect(protocol, rig, path, **kwargs)
    finally:
        rig.close()
