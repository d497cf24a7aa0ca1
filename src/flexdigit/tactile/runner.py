"""Run a load protocol on a rig (the twin by default): settle, read, journal every reading, resume after a stop.

The runner only uses the :class:`flexdigit.rig.base.Rig` interface (``read``, ``write_command``, ``wait``,
``place_load``, ``clear_loads``, ``relax``), so the same protocol runs on the twin and on hardware, where
``place_load`` asks the operator to hang the weight. Every reading is appended to ``<out>.journal.jsonl`` and
flushed before the next one is taken; running the same command again after Ctrl-C, a crash or ``kill -9`` resumes
at the first missing sample, so no reading is lost or taken twice. At the end the journal is compacted to ``out``
(Parquet, atomically) and removed.

Nothing mixes: every option is checked before the first reading; the journal's header holds the effective
settings (:func:`effective_settings`: the protocol, the settle time, the rig's own settings such as the twin's seed
and calibration, and whatever the caller adds) and a resume with different ones is refused naming the first
difference. On a deterministic rig (the twin in virtual time) a resume first replays the readings already
journalled, checking each against the journal, so the rig is in the state an uninterrupted run would have left it
in: the resumed dataset equals the uninterrupted one, reading for reading. (Keying the twin's random streams by
reading would not be enough: the digit's swing and the sensor drift carry the history of every earlier setting.)
"""

from __future__ import annotations

import warnings
from contextlib import ExitStack, nullcontext
from pathlib import Path

import numpy as np

from flexdigit._io import check_output, output_lock
from flexdigit._validation import check_real
from flexdigit.errors import DataFileError, OutputError, ParameterError, RigError
from flexdigit.params import RigParams
from flexdigit.rig.base import open_rig, parse_rig_url, seed_option
from flexdigit.rig.gauge_rails import railed_readings
from flexdigit.rig.recording import Recording, recording_rig, rig_metadata
from flexdigit.tactile.dataset import Dataset, Journal, load_dataset, make_meta, save_dataset
from flexdigit.tactile.protocols import MAX_SETTLE_S, RELAXED, Protocol
from flexdigit.tactile.refinement import refinement_for
from flexdigit.twin.digit_calibration import twin_calibration

__all__ = [
    "PROTOCOL_SETTINGS",
    "TACTILE_TWIN_DT_S",
    "journal_path",
    "describe_rig",
    "effective_settings",
    "sim_options",
    "STEADY_FACTOR",
    "STEADY_WINDOW_S",
    "still_scatter_v",
    "wait_until_steady",
    "collect",
    "collect_on",
    "load_or_collect",
]

#: The protocol fields that decide the readings (the free text and the name do not).
PROTOCOL_SETTINGS = (
    "loads_kg",
    "positions_from_tip_m",
    "actuation_commands",
    "repetitions",
    "no_load_repetitions",
    "sample_interval_s",
    "rehang",
    "orientation",
)

#: A steady reading (:func:`wait_until_steady`): over a window of :data:`STEADY_WINDOW_S`, every gauge's standard
#: deviation within this factor of what a still gauge scatters (:func:`still_scatter_v`). A swing of amplitude
#: ``A`` adds ``A^2 / 2`` to the variance, so a steady window leaves at most ``A = sqrt(2 (1.15^2 - 1)) = 0.80``
#: sigma. With 100 readings the deviation of pure noise scatters by ``1 / sqrt(2 x 99) = 7 %``: a still digit fails
#: the test now and then (2 sigma per gauge) and costs one more window, never a reading.
STEADY_FACTOR = 1.15
#: Length of the window a steadiness check reads (s): two seconds, a few periods of a digit's first mode (the
#: slowest drawn digits ring near 1.5-2 Hz), read at the protocol's ``sample_interval_s`` (20 ms: 100 readings).
STEADY_WINDOW_S = 2.0
#: The longest a check waits for a steady reading (s), as a multiple of the settle time (and at least a minute):
#: a rig noisier than its model is never "steady", and its readings are then taken after this wait.
STEADY_CAP_SETTLES = 30.0


def journal_path(out: str | Path) -> Path:
    """Where the journal of a collection into ``out`` lives: ``<out>.journal.jsonl``."""
    out = Path(out)
    return out.with_name(out.name + ".journal.jsonl")


def describe_rig(rig, url: str | None = None) -> dict:
    """The rig metadata stored with a dataset: its URL (backend), ``repr`` and effective settings (the seed the
    twin actually used, whichever way it was given)."""
    settings = rig.settings() if hasattr(rig, "settings") else {}
    return {"url": url or getattr(rig, "url", type(rig).__name__), "repr": repr(rig), "settings": settings}


def effective_settings(protocol: Protocol, rig, settle_s: float, extra: dict | None = None) -> dict:
    """Everything that decides the readings of a collection, as recorded in its journal and dataset.

    ``protocol`` (:data:`PROTOCOL_SETTINGS`), ``settle_s`` (the one used: the protocol's or the override, 0
    included), ``rig`` (:meth:`~flexdigit.rig.base.Rig.settings`: backend, the twin's seed, calibration and
    parameter fingerprints ...) and ``extra`` (anything else the caller applies, e.g. a calibration file).
    """
    proto = protocol.to_dict()
    # the steadiness check and the tare per position only when on: the thesis protocols' settings (and their
    # journals) are as they were
    keys = PROTOCOL_SETTINGS + tuple(k for k in ("wait_until_steady", "tare_each_position") if getattr(protocol, k))
    return {
        "protocol": {key: proto[key] for key in keys},
        "settle_s": float(settle_s),
        "rig": rig.settings() if hasattr(rig, "settings") else {"backend": type(rig).__name__},
        **(extra or {}),
    }


#: Twin step for tactile runs (s): the twin's own default. The sim backend defaults to 2 ms for the control
#: loop's sake; load experiments only need the settled state, which is the same to 0.1 mV (checked in tests).
TACTILE_TWIN_DT_S = 0.020


def sim_options(protocol: Protocol, url: str = "sim") -> dict:
    """Twin options a protocol implies (orientation; cable only when actuated; 20 ms step) unless the URL sets them."""
    given = parse_rig_url(url).options
    out = {}
    if "dt_s" not in given:
        out["dt_s"] = TACTILE_TWIN_DT_S
    if "orientation" not in given:
        out["orientation"] = protocol.orientation
    if "cable" not in given:
        out["cable"] = protocol.actuated
    return out


def still_scatter_v(rig, params: RigParams) -> np.ndarray:
    """The most each gauge's readings scatter (standard deviation, V) when nothing moves: the white noise of the
    rig's twin calibration (a twin rig's own, else the digit's default one,
    :func:`~flexdigit.twin.digit_calibration.twin_calibration`) and half an ADC step either side,
    ``sqrt(sigma^2 + lsb^2 / 4)``. Not the readings' average rounding noise ``lsb / sqrt(12)``: a gauge whose white
    noise is under an LSB toggles between two codes, a deviation of up to ``lsb / 2`` when its value sits on a code
    boundary (a 12-bit gauge with 0.6 mV of noise and 2.4 mV steps read 1.36 x the average one, still). The ADC
    step is the rig's own where it reads through one of its own (``rig.adc_lsb_v``: a board's 10-bit count, 4.9 mV,
    not the described DAQ's; with the DAQ's, a board's gauge toggling by a count was never steady and ``collect``
    over ``hil://`` waited the 180 s cap for a setting)."""
    twin = getattr(rig, "twin", None)
    calibration = getattr(twin, "calibration", None) or twin_calibration(params)
    white = np.asarray(calibration.noise_white_v, dtype=float)
    lsb = getattr(rig, "adc_lsb_v", params.sensors.adc_lsb_v)
    return np.sqrt(white**2 + lsb**2 / 4.0)


def wait_until_steady(rig, noise_v, interval_s: float, cap_s: float) -> tuple[float, bool]:
    """Read the rig in windows of :data:`STEADY_WINDOW_S` until every gauge's standard deviation over a window is
    within :data:`STEADY_FACTOR` of ``noise_v`` (what a still gauge scatters, :func:`still_scatter_v`), or ``cap_s``
    has passed.

    An experimenter's wait for a still reading: the fixed settle time that suits one digit leaves another one
    ringing (a 0.17 m cable-pair digit of 0.2 mm strip still swung 6 sigma 10 s after its load was hung, and its
    network's RMSE was 1.7 x the Bayes limit, which assumes settled readings; read when steady, 1.0 x). The
    readings of the check are not kept. Returns the seconds it read and whether the rig was found steady.
    """
    interval = interval_s if interval_s > 0 else TACTILE_TWIN_DT_S
    count = max(10, int(round(STEADY_WINDOW_S / interval)))
    limit = STEADY_FACTOR * np.asarray(noise_v, dtype=float)
    waited = 0.0
    while True:
        window = np.empty((count, limit.size))
        for k in range(count):
            rig.wait(interval)
            gauges = np.asarray(rig.read().gauges_v, dtype=float)
            if gauges.shape != limit.shape:  # another digit's rig: the reading that follows is refused, naming it
                return waited, True
            window[k] = gauges
        waited += count * interval
        if np.all(window.std(axis=0, ddof=1) <= limit):
            return waited, True
        if waited >= cap_s:
            return waited, False


def _checked_options(protocol: Protocol, rig, settle_s, stop_after) -> float:
    """The settle time to use (s), once ``settle_s``, ``stop_after`` and the rig are checked."""
    settle = (
        protocol.settle_s if settle_s is None else check_real(settle_s, "settle_s", "collect", low=0, high=MAX_SETTLE_S)
    )
    if stop_after is not None and (isinstance(stop_after, bool) or not isinstance(stop_after, int) or stop_after < 0):
        raise ParameterError(f"The 'stop_after' parameter of collect must be an integer >= 0. Got {stop_after!r}.")
    if not getattr(rig, "accepts_loads", True):
        raise ParameterError(
            f"{getattr(rig, 'name', rig)}: cannot collect a load protocol on it (it cannot hang weights); "
            "collect on the twin (--backend sim) or a rig"
        )
    return settle


def _protocol_twin(protocol: Protocol, seed: int, params: RigParams | None = None):
    """The twin ``flexdigit collect`` opens for ``protocol`` (``--backend sim``, ``--seed seed``, ``--params``)."""
    options = sim_options(protocol)
    if params is not None and params != RigParams():
        options["calibration"] = twin_calibration(params)
    return open_rig("sim", params, seed=seed, **options)


def collect(
    protocol: Protocol,
    rig=None,
    out: str | Path | None = None,
    *,
    seed: int = 0,
    params: RigParams | None = None,
    rig_url: str | None = None,
    settle_s: float | None = None,
    progress: bool = False,
    fsync: bool = False,
    stop_after: int | None = None,
    force: bool = False,
    settings: dict | None = None,
    allow_rail: bool = False,
) -> Dataset:
    """Take every sample of ``protocol`` on ``rig`` and write the dataset to ``out`` (Parquet).

    Parameters
    ----------
    protocol : Protocol
        What to do.
    rig : Rig, optional
        Any backend of :mod:`flexdigit.rig` that can hang weights (the twin, a serial board; not a replay). None:
        the twin set up for ``protocol`` as ``flexdigit collect`` sets it up (:func:`sim_options`: the protocol's
        orientation, the cable only when it actuates, the 20 ms step), seeded with ``seed``; the same dataset as
        the command (``tests/tactile/test_collect_command_equals_library.py``).
    out : path
        The dataset to write (required). Its journal ``<out>.journal.jsonl`` is resumed if present.
    seed : int
        The twin's seed when ``rig`` is None (the command's ``--seed``, default 0); ignored otherwise.
    params : RigParams, optional
        The digit (default the thesis rig): its length, its ``G`` gauges (``gauge1_v`` .. ``gaugeG_v``; a rig
        reading another count is refused), with ``rig`` None its twin; a protocol on it: ``load_protocol(name, params)``
    rig_url : str, optional
        How the rig was opened, recorded in the metadata.
    settle_s : float, optional
        Override the protocol's settle time (s, 0..3600; 0 is a value) after every change of load, position or
        command. None: the protocol's.
    progress : bool
        Show a rich progress bar (on stderr).
    fsync : bool
        Force every reading to disk (power-loss safe; slower).
    stop_after : int, optional
        Stop (as if interrupted) after taking this many new readings; for tests and partial runs.
    force : bool
        Overwrite an existing dataset at ``out`` (a journal is still resumed only with the same settings).
    settings : dict, optional
        Further effective settings to record and check on resume (e.g. ``{"calibration": fingerprint}``).
    allow_rail : bool
        Write the dataset even with readings at the ADC's rail (refused by default; the journal is kept).

    Returns
    -------
    Dataset
        The complete dataset (or, with ``stop_after``, what the journal holds so far).

    Raises
    ------
    OutputExistsError
        If ``out`` already holds a dataset (unless ``force``).
    DataFileError
        If the journal was written with other settings (named), is corrupt, or (on a deterministic rig) its
        readings are not what these settings give; or a gauge reads at the ADC's rail (unless ``allow_rail``).
    ParameterError
        If an option is invalid; raised before anything is read or written.
    RigError
        If the rig fails; the journal keeps every reading taken before.
    """
    if out is None:  # -- every check before the first reading --
        raise ParameterError("collect needs out, the dataset to write (a .parquet path)")
    if rig is None:
        rig, rig_url = _protocol_twin(protocol, seed, params), rig_url or "sim"
    out, params = Path(out), params or RigParams()
    journal_file, settle = journal_path(out), _checked_options(protocol, rig, settle_s, stop_after)
    plan = protocol.plan(params.geometry.digit_length_m)  # every position on the digit
    meta, steady = _meta_and_check(protocol, rig, rig_url, params, settle, settings)
    with output_lock(out):  # one collection writes ``out`` and its journal at a time (a second: OutputBusyError)
        args = (protocol, rig, out, journal_file, meta, plan, settle, progress, fsync, stop_after, force, steady)
        return _collect_locked(*args, allow_rail=allow_rail)


def _meta_and_check(protocol: Protocol, rig, rig_url, params: RigParams, settle: float, settings):
    """The dataset's metadata (its effective settings) and the steadiness check (None when the protocol has none)."""
    g = params.geometry
    meta = make_meta(protocol, describe_rig(rig, rig_url), g.digit_length_m, params.sensors.adc_range_v,
                     len(g.gauge_positions_m))  # fmt: skip
    meta["settings"] = effective_settings(protocol, rig, settle, settings)
    steady = _SteadyCheck(still_scatter_v(rig, params), protocol, settle) if protocol.wait_until_steady else None
    return meta, steady


class _SteadyCheck:
    """The steadiness check of one collection: the gauges' noise, the cap, and how many settings it checked."""

    def __init__(self, noise_v, protocol: Protocol, settle_s: float) -> None:
        self.noise_v = noise_v
        self.interval_s = protocol.sample_interval_s
        self.cap_s = min(MAX_SETTLE_S, STEADY_CAP_SETTLES * max(settle_s, 6.0))
        self.checked = self.unsteady = 0

    def __call__(self, rig) -> None:
        _, steady = wait_until_steady(rig, self.noise_v, self.interval_s, self.cap_s)
        self.checked += 1
        self.unsteady += not steady

    def warn(self, out: Path) -> None:
        """Say (a warning) how many settings were read unsteady, after the cap, if any."""
        if self.unsteady:
            warnings.warn(
                f"{out}: {self.unsteady} of {self.checked} settings were not steady (gauges within "
                f"{STEADY_FACTOR:g} x their noise over {STEADY_WINDOW_S:g} s) after {self.cap_s:g} s; their "
                "readings carry the swing or the rig is noisier than its calibration says",
                stacklevel=4,  # collect's caller
            )


def _collect_locked(
    protocol: Protocol,
    rig,
    out: Path,
    journal_file: Path,
    meta: dict,
    plan: dict,
    settle: float,
    progress: bool,
    fsync: bool,
    stop_after: int | None,
    force: bool,
    steady=None,
    *,
    allow_rail: bool = False,
) -> Dataset:
    """:func:`collect` once its checks passed, holding ``out``'s lock; ``steady`` the steadiness check (or None)."""
    gauge_count = meta["gauge_count"]
    if out.exists() and journal_file.exists() and not force:
        return _finish_compaction(out, journal_file, meta, protocol)
    check_output(out, force=force)
    check_output(journal_file, force=True)  # its directory is out's; an existing journal is resumed

    # -- collect -------------------------------------------------------------------------------------------------
    journal, done = Journal.open(journal_file, meta, fsync=fsync)
    start = len(done)
    total = protocol.sample_count
    replay = start > 0 and bool(getattr(rig, "deterministic", False))
    taken = 0
    setting = None
    bar = _progress_bar(progress)
    try:
        with bar if bar is not None else nullcontext():
            task = bar.add_task(protocol.name, total=total, completed=start) if bar is not None else None
            for i in range(0 if replay else start, total):
                if i >= start and stop_after is not None and taken >= stop_after:
                    break
                setting, reading = _take(rig, protocol, plan, i, setting, settle, gauge_count, steady)
                row = _row(plan, i, reading)
                if i < start:  # replaying what the journal holds: the twin must give it again, bit for bit
                    _check_replayed(journal_file, done[i], row)
                    continue
                try:
                    journal.append(row)
                except OSError as exc:  # a full disk: say which file, and that a rerun resumes
                    raise OutputError(
                        f"{journal_file}: cannot write it: {exc.strerror or exc}; the readings before are kept: "
                        "free some space and rerun to resume"
                    ) from exc
                taken += 1
                if task is not None:
                    bar.advance(task)
    finally:
        unwritten = None
        try:  # its last buffered line may meet a full disk: the rig is still made safe, the file named
            journal.close()
        except OSError as exc:
            unwritten = OutputError(
                f"{journal_file}: cannot write it: {exc.strerror or exc}; the readings before are kept: free some "
                "space and rerun to resume"
            )
        try:  # leave the rig safe: nothing hanging, servo relaxed
            rig.clear_loads()
            rig.relax()
        except Exception:  # noqa: BLE001 - the original error (if any) matters more than a failed tidy-up
            pass
        if unwritten is not None:
            raise unwritten  # noqa: B012 - replaces the unnamed OSError the close raised
    dataset = load_dataset(journal_file, protocol)
    if len(dataset) == total:
        _refuse_railed(dataset, _params_of(rig), journal_file, allow_rail)
        save_dataset(dataset, out, force=force)
        journal_file.unlink()
    if steady is not None:
        steady.warn(out)
    return dataset


def _params_of(rig) -> RigParams:
    """The rig's digit (the thesis rig's if the backend does not say)."""
    return getattr(rig, "params", None) or RigParams()


def _refuse_railed(dataset: Dataset, params: RigParams, journal_file: Path, allow: bool) -> None:
    """Refuse to write a dataset with readings at the ADC's rail (:func:`~flexdigit.rig.gauge_rails.railed_readings`)
    unless ``allow``: a network trained on them learns the rail (trial 2: a 0..3.3 V ADC read every gauge of a
    balanced bridge at 0 V, and ``collect`` wrote 1275 rows of 0.0)."""
    said = None if allow else railed_readings(dataset.gauges_v, params.sensors)
    if said is not None:
        raise DataFileError(
            f"{said}; not written (the readings are kept in {journal_file}: rerun with --allow-rail to write them "
            "anyway, or fix the chain: `flexdigit params FILE` says which gauge rails where)"
        )


def _take(rig, protocol: Protocol, plan: dict, i: int, setting, settle: float, gauge_count: int, steady=None):
    """Bring the rig to sample ``i``'s setting (or re-hang and wait between repetitions), wait until it is steady
    if ``steady`` (:class:`_SteadyCheck`) and read it."""
    wanted = (int(plan["test"][i]), float(plan["load_kg"][i]), int(plan["position_index"][i]))
    command = int(plan["command"][i])
    if wanted != setting:
        _apply_setting(rig, command, float(plan["load_kg"][i]), float(plan["position_from_base_m"][i]))
        rig.wait(settle)
        if steady is not None:
            steady(rig)
        setting = wanted
    else:
        if protocol.rehang and plan["load_kg"][i] > 0:
            rig.rehang(settle)
            if steady is not None:
                steady(rig)
        if protocol.sample_interval_s > 0:
            rig.wait(protocol.sample_interval_s)
    reading = rig.read()
    gauges = np.asarray(reading.gauges_v, dtype=float)
    if gauges.shape != (gauge_count,) or not np.all(np.isfinite(gauges)):
        raise RigError(
            f"rig returned gauge voltages {gauges.tolist()!r} at sample {i}; expected {gauge_count} finite (the "
            "digit's gauges: give the rig's parameter file with --params)"
        )
    return setting, reading


def _row(plan: dict, i: int, reading) -> dict:
    gauges = np.asarray(reading.gauges_v, dtype=float)
    return {
        "sample": i,
        "test": int(plan["test"][i]),
        **{f"gauge{k}_v": float(v) for k, v in enumerate(gauges, start=1)},
        "pot_v": _none_if_nan(reading.pot_v),
        "load_kg": float(plan["load_kg"][i]),
        "position_index": int(plan["position_index"][i]),
        "position_from_tip_m": _none_if_nan(plan["position_from_tip_m"][i]),
        "position_from_base_m": _none_if_nan(plan["position_from_base_m"][i]),
        "command": int(plan["command"][i]),
        "repetition": int(plan["repetition"][i]),
        "time_s": float(reading.time_s),
    }


def _check_replayed(path: Path, journalled: dict, replayed: dict) -> None:
    for key, value in replayed.items():
        if journalled.get(key) != value:
            raise DataFileError(
                f"{path}: sample {replayed['sample']}'s {key} is {journalled.get(key)!r} in the journal but the rig "
                f"gives {value!r} with these settings (the journal was edited, or written by another version of "
                "the twin); remove it or use another --out"
            )


def _finish_compaction(out: Path, journal_file: Path, meta: dict, protocol: Protocol) -> Dataset:
    """``out`` and its journal both exist: a run was stopped between writing the dataset and removing the
    journal. Finish it if ``out`` is that journal's complete dataset (same settings); refuse otherwise."""
    dataset = load_dataset(out, protocol)
    journal = load_dataset(journal_file, protocol)
    complete = len(dataset) == protocol.sample_count == len(journal)
    same = dataset.meta.get("settings") == meta["settings"] == journal.meta.get("settings")
    if not (complete and same and np.array_equal(dataset.gauges_v, journal.gauges_v)):
        raise DataFileError(
            f"{out}: the file exists beside a journal ({journal_file.name}) of another or unfinished run; pass "
            "--force to collect again into it, or use another --out"
        )
    journal_file.unlink()
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


def collect_on(
    backend: str,
    protocol: Protocol,
    out: str | Path,
    *,
    params: RigParams | None = None,
    seed: int = 0,
    calibration: str | Path | None = None,
    record: str | Path | None = None,
    settle_s: float | None = None,
    progress: bool = False,
    force: bool = False,
    allow_rail: bool = False,
    refine: int | None = None,
) -> Dataset:
    """``flexdigit collect``: open the rig at ``backend``, take ``protocol`` on it into ``out`` and close it.

    The protocol's positions are refined first (:meth:`~flexdigit.tactile.protocols.Protocol.refined`) by
    ``refine``, or by the ``K`` the digit's resolution asks for (:func:`~flexdigit.tactile.refinement.refinement_for`:
    1 on the thesis rig): the dataset's ``meta["settings"]["refine"]`` says which and why (absent for the thesis
    rig's protocol as written, whose datasets are as they were).

    On a twin URL (``sim...``) the twin is set up for the protocol (:func:`sim_options`) with ``seed`` (unless the
    URL sets one) and, when ``calibration`` (a TOML) or ``params`` (another digit) is given, the calibration of
    :func:`~flexdigit.twin.digit_calibration.twin_calibration`; a real rig refuses ``calibration``. The emulated
    board (``hil://``) takes the protocol's orientation and cable only (its firmware's twin keeps its own 2 ms
    step). ``record`` also writes every reading and load to an MCAP file
    (:func:`flexdigit.rig.recording.recording_rig`). Every option is checked before the rig is opened; the rig
    (and the recording) are closed on every path. The other arguments are :func:`collect`'s.
    """
    out = Path(out)
    if settle_s is not None:
        check_real(settle_s, "--settle", "flexdigit collect", low=0, high=MAX_SETTLE_S)
    if not (out.exists() and journal_path(out).exists()):  # both: a run stopped while tidying up, collect finishes it
        check_output(out, force=force)
    scheme = parse_rig_url(backend).scheme
    on_twin = scheme.startswith("sim")
    if calibration and not on_twin:
        raise ParameterError(
            f"--calibration calibrates the twin: it needs a sim backend, not {backend!r} (a real rig is itself)"
        )
    refinement = refinement_for(protocol, params, refine, calibration=calibration)
    protocol = protocol.refined(refinement.factor)
    settings = None if refinement.chosen == "thesis rig" else {"refine": refinement.to_dict()}
    options = sim_options(protocol, backend) if on_twin else {}
    if scheme == "hil":
        options = {k: v for k, v in sim_options(protocol, backend).items() if k in ("orientation", "cable")}
    if on_twin and (calibration or params is not None):
        options["calibration"] = twin_calibration(params, calibration)
    with ExitStack() as stack:
        rig = stack.enter_context(open_rig(backend, params, **options, **seed_option(backend, seed)))
        if record is not None:
            header = {"backend": backend, "protocol": protocol.name, "seed": rig.settings().get("seed")}
            recording = Recording(
                record, header={**header, "source": "collect"}, metadata=rig_metadata(rig), force=force
            )
            rig = stack.enter_context(recording_rig(rig, recording))  # closes the rig, then the recording
        return collect(
            protocol,
            rig,
            out,
            params=params,
            rig_url=backend,
            settle_s=settle_s,
            progress=progress,
            force=force,
            allow_rail=allow_rail,
            settings=settings,
        )


def load_or_collect(path: str | Path, protocol: Protocol, rig_factory, **kwargs) -> Dataset:
    """Load ``path`` if it holds ``protocol``'s dataset, else collect it on ``rig_factory()`` (closed after)."""
    path = Path(path)
    if path.exists():
        return load_dataset(path, protocol)
    with rig_factory() as rig:
        return collect(protocol, rig, path, **kwargs)
