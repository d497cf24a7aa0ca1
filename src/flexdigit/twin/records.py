"""Records of simulated experiments on the twin, as the thesis ran them on the rig, each a tidy table.

- :func:`release_test`: the digit (cable removed) deflected and released, gauges sampled (3.1.2, figure 3.6);
- :func:`servo_step_test`: a command step, potentiometer and gauges sampled (3.2.4, figure 3.11);
- :func:`actuation_sweep`: commands 8..43, each settled then sampled (3.4.3, figure 3.17, E 3.20-3.22);
- :func:`static_load_test`: weights hung at positions, at actuation commands, repeated (6.4-6.5, 7.1-7.2).

Every result is a :class:`TwinRecord`: a ``pyarrow.Table`` whose column names carry their unit
(``time_s``, ``gauge1_v``) plus metadata (experiment, its arguments, the rig parameters, the calibration, the seed,
the flexdigit version), saved as Parquet with the metadata in the schema, or exported as CSV with the metadata as
``#`` comment lines.

Examples
--------
>>> res = static_load_test([0.025], [0.0], commands=[8], repetitions=2, seed=3)
>>> res.table.num_rows, res.table.column_names[:4]
(4, ['mass_kg', 'position_from_base_m', 'position_from_tip_m', 'command'])
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa

from flexdigit import __version__, _io
from flexdigit._io import RECORDS_LIMIT, atomic_path, atomic_write, check_input, count_lines, read_text
from flexdigit._json import to_jsonable
from flexdigit._repr import summary
from flexdigit._validation import check_choice, check_int, check_positive, check_real, check_values
from flexdigit.errors import DataFileError, ParameterError
from flexdigit.params import RigParams
from flexdigit.twin.calibration import Calibration
from flexdigit.twin.digit import ORIENTATIONS
from flexdigit.twin.digit_calibration import twin_calibration
from flexdigit.twin.twin import DEFAULT_CELLS_PER_SECTION, Twin, cached_digit, static_gauges_v

__all__ = [
    "METADATA_KEY",
    "RELEASE_DT_S",
    "RELEASE_WN_STEP_RAD",
    "release_step_s",
    "TwinRecord",
    "release_test",
    "release_orientation",
    "servo_step_test",
    "actuation_sweep",
    "static_load_test",
]

METADATA_KEY = b"flexdigit"
#: Integration step of a release test (s). A free decay (1.6-2.1 Hz, lightly damped) is a record whose wn and zeta
#: are identified to ~0.1 %: at the twin's 20 ms serial-frame step the L-stable Rosenbrock step shortens the period,
#: and the identified wn comes out 0.23 % (housed) / 0.15 % (bare) below the twin's own linear modes, the bare zeta
#: 1.1 % above (numerical damping); a calibration fitted to such records carries that into the housing stiffness
#: (~1.5 % per 0.2 % of wn). At 10 ms both wn are within 0.03 % and the bare zeta within 0.2 %, for no more time.
RELEASE_DT_S = 0.01
#: The most a release step may advance the digit's first mode (``wn h``, rad). The step's period error grows as
#: ``(wn h)^2``, ~4 % x (wn h)^2 in the identified wn: the thesis rig's 13-17 rad/s at 10 ms is 0.13-0.17 (above:
#: 0.03 %), but a short stiff digit's mode is faster (0.15 m, three 45 mm sections, hung: 51 rad/s, 0.51 a step)
#: and its identified wn came out 1.0 % below its linear mode at 10 ms, 0.04 % at 2 ms
#: (tests/twin/test_digit_calibration.py's release test). A release step is ``min(RELEASE_DT_S,
#: RELEASE_WN_STEP_RAD / wn)`` (:func:`release_step_s`): 10 ms on the thesis rig and on any digit up to 40 rad/s,
#: as before (a finer step on a 29 rad/s digit, the campaign's seed 1, made chapter 3's gauge-1 fit find its flat
#: first peak "saturated"), 6.7 ms on that 0.15 m digit.
RELEASE_WN_STEP_RAD = 0.4


@dataclass
class TwinRecord:
    """A simulated experiment: a tidy table (units in the column names) and what made it.

    Attributes
    ----------
    table : pyarrow.Table
    metadata : dict
        ``experiment``, ``arguments``, ``seed``, ``params``, ``calibration``, ``flexdigit_version``, ``units``.
    """

    table: pa.Table
    metadata: dict[str, Any]

    def __repr__(self) -> str:
        # what made it and the table's shape, not pyarrow's dump of every column (issue 23: 3,300 characters)
        return summary(
            self,
            experiment=self.metadata.get("experiment"),
            seed=self.metadata.get("seed"),
            rows=self.table.num_rows,
            columns=self.table.column_names,
        )

    def column(self, name: str) -> np.ndarray:
        """One column as a numpy array."""
        if name not in self.table.column_names:
            raise KeyError(f"no column {name!r}; columns are {self.table.column_names}")
        return self.table.column(name).to_numpy()

    def save(self, path: str | Path, *, force: bool = False) -> Path:
        """Write Parquet (``.parquet``) or CSV (``.csv``), choosing by suffix; returns the path.

        Atomic (:mod:`flexdigit._io`): a failed write leaves whatever was at ``path``; an existing file is
        refused unless ``force``.
        """
        path = Path(path)
        if path.suffix.lower() == ".csv":
            return self.to_csv(path, force=force)
        import pyarrow.parquet as pq

        meta = dict(self.table.schema.metadata or {})
        meta[METADATA_KEY] = json.dumps(to_jsonable(self.metadata)).encode()
        with atomic_path(path, force=force) as tmp:
            pq.write_table(self.table.replace_schema_metadata(meta), tmp)
        return path

    def to_csv(self, path: str | Path, *, force: bool = False) -> Path:
        """CSV with the metadata as leading ``# key: json`` lines (atomic, no clobber unless ``force``)."""
        import pyarrow.csv as pcsv

        path = Path(path)
        sink = pa.BufferOutputStream()
        pcsv.write_csv(self.table, sink)
        lines = [f"# {k}: {json.dumps(to_jsonable(v))}" for k, v in self.metadata.items()]
        with atomic_write(path, "w", force=force) as fh:
            fh.write("\n".join(lines) + "\n" + sink.getvalue().to_pybytes().decode())
        return path

    @classmethod
    def load(cls, path: str | Path) -> TwinRecord:
        """Read a result saved by :meth:`save` (Parquet or CSV)."""
        path = Path(path)
        if not path.exists():
            raise FileNotFoundError(2, "No such file", str(path))
        check_input(path, "a twin record", RECORDS_LIMIT)
        if path.suffix.lower() == ".csv":
            import io

            import pyarrow.csv as pcsv

            count_lines(path, "a twin record CSV")
            text = read_text(path, "a twin record CSV", RECORDS_LIMIT)
            meta, body = {}, []
            for line in text.splitlines(keepends=True):
                if line.startswith("# ") and not body:
                    key, _, value = line[2:].partition(": ")
                    try:
                        meta[key] = json.loads(value)
                    except (json.JSONDecodeError, RecursionError):
                        raise DataFileError(f"{path}: metadata line for {key!r} is not JSON") from None
                else:
                    body.append(line)
            try:
                table = pcsv.read_csv(io.BytesIO("".join(body).encode()))
            except pa.ArrowInvalid as exc:
                raise DataFileError(f"{path}: not a CSV table ({exc})") from None
            return cls(table, meta)
        import pyarrow.parquet as pq

        try:
            with _io.open_input(path, "a Parquet file", _io.RECORDS_LIMIT) as fh:  # any name, even not UTF-8
                table = pq.read_table(fh)
        except (pa.ArrowInvalid, OSError) as exc:
            raise DataFileError(f"{path}: not a Parquet file ({exc})") from None
        raw = (table.schema.metadata or {}).get(METADATA_KEY)
        if raw is None:
            raise DataFileError(f"{path}: no flexdigit metadata (not written by TwinRecord.save)")
        return cls(table.replace_schema_metadata(None), json.loads(raw))

    def summary(self) -> str:
        """One line per column: name, min, max."""
        lines = [
            f"{self.metadata.get('experiment', '?')}: {self.table.num_rows} rows, seed {self.metadata.get('seed')}"
        ]
        for name in self.table.column_names:
            col = self.column(name).astype(float)
            lines.append(f"  {name:<24} {np.nanmin(col):>12.6g} .. {np.nanmax(col):<12.6g}")
        return "\n".join(lines)


def _units(columns) -> dict[str, str]:
    out = {}
    for c in columns:
        suffix = c.rsplit("_", 1)[-1] if "_" in c else ""
        out[c] = {"s": "s", "v": "V", "m": "m", "kg": "kg", "rad": "rad", "mm": "mm"}.get(suffix, "1")
    out.update({k: "command (0..254)" for k in columns if k == "command"})
    return out


def _result(name: str, columns: dict[str, np.ndarray], arguments: dict, seed, params, calibration) -> TwinRecord:
    table = pa.table({k: pa.array(np.asarray(v)) for k, v in columns.items()})
    meta = {
        "experiment": name,
        "arguments": arguments,
        "seed": seed,
        "units": _units(columns),
        "params": params.to_dict(),
        "calibration": calibration.to_dict(),
        "flexdigit_version": __version__,
    }
    return TwinRecord(table, meta)


def _gauge_columns(params: RigParams) -> list[str]:
    """``gauge1_v .. gaugeG_v``: one column per gauge of the digit (the thesis rig's three)."""
    return [f"gauge{i + 1}_v" for i in range(len(params.geometry.gauge_positions_m))]


def _check_upright(chain, orientation: str, owner: str) -> None:
    """Refuse a digit that cannot stand straight in ``orientation``: a long or soft digit mounted tip up buckles
    under its own weight and its supports' (the straight chain's tangent stiffness, springs plus gravity, has a
    negative eigenvalue), and a release from there falls over instead of ringing."""
    stiffness = chain.tangent_stiffness(np.zeros(chain.n), chain.g_gravity, False)
    lowest = float(np.linalg.eigvalsh(0.5 * (stiffness + stiffness.T))[0])
    if lowest < 0:
        raise ParameterError(
            f"The 'orientation' parameter of {owner} is {orientation!r}, but this digit buckles so under its own "
            f"weight (straight, its lowest tangent stiffness is {lowest:.3g} N m/rad < 0): mount it 'hanging' (tip "
            "down) or 'horizontal'."
        )


def release_orientation(params: RigParams | None = None, calibration: Calibration | None = None) -> str:
    """The mount the digit's release tests (cable removed) can use: ``"vertical"`` (tip up, as the thesis mounted
    it, 2.2.4) when the straight digit stands so, housed and bare, else ``"hanging"`` (tip down: gravity then
    stiffens it). A long digit tip up buckles under its supports' weight (tests/digits.py's 0.5 m, 5 sections);
    ``run --params`` hangs such a digit too. The calibration is the twin's default when not given (the default
    calibration, or for a digit it cannot describe, that fit scaled to the digit)."""
    params = params or RigParams()
    calibration = calibration or twin_calibration(params)
    for housed in (True, False):
        chain = cached_digit(params, calibration, housed, "vertical", DEFAULT_CELLS_PER_SECTION)
        stiffness = chain.tangent_stiffness(np.zeros(chain.n), chain.g_gravity, False)
        if np.linalg.eigvalsh(0.5 * (stiffness + stiffness.T))[0] < 0:  # _check_upright's test
            return "hanging"
    return "vertical"


def _check_rate(duration_s, sample_rate_hz, owner):
    duration = check_real(duration_s, "duration_s", owner, low=0, low_open=True, high=3600)
    rate = check_real(sample_rate_hz, "sample_rate_hz", owner, low=1, high=100_000)
    return duration, rate, np.arange(int(math.floor(duration * rate)) + 1) / rate


def release_step_s(chain, period_s: float) -> float:
    """The integration step (s) of a release of ``chain`` (cable removed, as mounted): :data:`RELEASE_DT_S`, or
    shorter so that its first mode turns at most :data:`RELEASE_WN_STEP_RAD` a step; a divisor of the serial
    period ``period_s`` (what :class:`Twin` rounds its step to), never rounded up past the bound.

    Examples
    --------
    >>> from flexdigit.params import RigParams
    >>> from flexdigit.twin.calibration import default_calibration
    >>> release_step_s(cached_digit(RigParams(), default_calibration(), True, "vertical", 3), 0.02)
    0.01
    """
    wn = float(chain.linear_modes()[0][0])
    bound = min(RELEASE_DT_S, RELEASE_WN_STEP_RAD / wn)
    return period_s / math.ceil(period_s / bound - 1e-9)


def release_test(
    *,
    housing: bool = True,
    tip_deflection_m: float = 0.02,
    duration_s: float = 8.0,
    sample_rate_hz: float = 1000.0,
    seed: int = 0,
    params: RigParams | None = None,
    calibration: Calibration | None = None,
    orientation: str = "vertical",
    compiled: bool = True,
) -> TwinRecord:
    """Deflect the digit (cable removed) by ``tip_deflection_m`` at the tip, release it, sample the gauges (3.1.2).

    ``compiled`` steps the digit with the compiled kernel (:class:`~flexdigit.twin.twin.Twin`'s ``compiled``):
    the gauge readings are the numpy twin's, quantised, and the tip column within 1e-15 m of it
    (tests/twin/test_records.py), for a third of the CPU.

    Returns
    -------
    TwinRecord
        Columns ``time_s, gauge1_v, gauge2_v, gauge3_v, tip_deflection_m``.
    """
    params = params or RigParams()
    calibration = calibration or twin_calibration(params)
    deflection = check_real(tip_deflection_m, "tip_deflection_m", "release_test", low=-0.1, high=0.1)
    _, _, times = _check_rate(duration_s, sample_rate_hz, "release_test")
    check_choice(orientation, "orientation", tuple(ORIENTATIONS), "release_test")
    chain = cached_digit(params, calibration, bool(housing), orientation, DEFAULT_CELLS_PER_SECTION)
    _check_upright(chain, orientation, "release_test")
    twin = Twin(
        params,
        calibration,
        seed=seed,
        orientation=orientation,
        housing=housing,
        cable=False,
        dt_s=release_step_s(chain, params.actuator.serial_period_s),
        compiled=compiled,
    )
    unit = twin.chain.solve_static(tip_force_n=[[0.0, 1e-3]]).tip_m[0, 1] - twin.chain.solve_static().tip_m[0, 1]
    force = 1e-3 * deflection / unit
    for _ in range(3):  # the tip load-deflection curve bends a little: a few secant corrections
        got = twin.chain.solve_static(tip_force_n=[[0.0, force]]).tip_m[0, 1]
        force *= deflection / got if got != 0 else 1.0
    twin.deflect(force)
    series = twin.read_at(times)
    gauges = series.gauges_v
    cols = {"time_s": times, **{f"gauge{i + 1}_v": gauges[:, i] for i in range(gauges.shape[1])}}
    cols["tip_deflection_m"] = series.tip_m[:, 1]
    args = dict(housing=housing, tip_deflection_m=deflection, duration_s=duration_s, sample_rate_hz=sample_rate_hz)
    args["orientation"] = orientation
    return _result("release_test", cols, args, seed, params, calibration)


def servo_step_test(
    *,
    command_from: int = 0,
    command_to: int = 51,
    step_at_s: float = 0.1,
    duration_s: float = 1.5,
    sample_rate_hz: float = 1000.0,
    cable: bool = False,
    seed: int = 0,
    params: RigParams | None = None,
    calibration: Calibration | None = None,
    orientation: str = "vertical",
) -> TwinRecord:
    """A servo command step (3.2.4: to 51), potentiometer and gauges sampled; cable detached by default; the digit
    mounted ``orientation`` (tip up as the thesis; ``"hanging"`` for one that buckles so, :func:`release_orientation`).

    Returns
    -------
    TwinRecord
        Columns ``time_s, command, pot_v, servo_angle_rad, gauge1_v, gauge2_v, gauge3_v``.
    """
    params = params or RigParams()
    calibration = calibration or twin_calibration(params)
    a = params.actuator
    c0 = check_int(command_from, "command_from", "servo_step_test", low=a.command_min, high=a.command_max)
    c1 = check_int(command_to, "command_to", "servo_step_test", low=a.command_min, high=a.command_max)
    step_at = check_real(step_at_s, "step_at_s", "servo_step_test", low=0)
    _, _, times = _check_rate(duration_s, sample_rate_hz, "servo_step_test")
    twin = Twin(params, calibration, seed=seed, cable=cable, command=c0, orientation=orientation)
    before = twin.read_at(times[times < step_at])
    if before.command.size < times.size:  # the step is sent at step_at, before the first read at or after it
        twin.advance(max(step_at - twin.time_s, 0.0))
        twin.command(c1)
    after = twin.read_at(times[times >= step_at])
    gauges, pot, cmd, angles = (np.concatenate(pair) for pair in zip(before[:4], after[:4], strict=True))
    cols = {"time_s": times, "command": cmd, "pot_v": pot, "servo_angle_rad": angles}
    cols.update({f"gauge{i + 1}_v": gauges[:, i] for i in range(gauges.shape[1])})
    args = dict(command_from=c0, command_to=c1, step_at_s=step_at, duration_s=duration_s, cable=cable)
    args["sample_rate_hz"] = sample_rate_hz
    args["orientation"] = orientation
    return _result("servo_step_test", cols, args, seed, params, calibration)


def actuation_sweep(
    commands=None,
    *,
    settle_s: float = 3.0,
    samples: int = 20,
    sample_rate_hz: float = 100.0,
    seed: int = 0,
    params: RigParams | None = None,
    calibration: Calibration | None = None,
    orientation: str = "vertical",
    compiled: bool = True,
) -> TwinRecord:
    """Step through ``commands`` (default 8..43), let each settle, then sample the gauges (3.4.3, E 3.20-3.22).

    ``compiled`` steps the digit with the compiled kernel (:class:`~flexdigit.twin.twin.Twin`'s ``compiled``):
    it follows the numpy twin to ~1e-15 rad, far inside the ADC's quantum, so the readings, the only columns the
    digit's motion reaches, are the numpy twin's (tests/twin/test_records.py) for a fifth of the CPU.

    Returns
    -------
    TwinRecord
        Columns ``command, sample, time_s, gauge1_v, gauge2_v, gauge3_v, pot_v``.
    """
    params = params or RigParams()
    calibration = calibration or twin_calibration(params)
    a = params.actuator
    if commands is None:
        commands = range(a.operating_commands[0], a.operating_commands[1] + 1)
    cmds = [check_int(c, "commands", "actuation_sweep", low=a.command_min, high=a.command_max) for c in commands]
    if not cmds:
        raise ParameterError("The 'commands' parameter of actuation_sweep must not be empty.")
    settle = check_real(settle_s, "settle_s", "actuation_sweep", low=0)
    n = check_int(samples, "samples", "actuation_sweep", low=1, high=100_000)
    rate = check_positive(sample_rate_hz, "sample_rate_hz", "actuation_sweep")
    twin = Twin(params, calibration, seed=seed, orientation=orientation, command=cmds[0], compiled=bool(compiled))
    _check_upright(twin.chain, orientation, "actuation_sweep")  # tip up, a long digit falls over: no sweep
    rows: dict[str, list] = {k: [] for k in ("command", "sample", "time_s", *_gauge_columns(params), "pot_v")}
    for c in cmds:
        twin.command(c)
        twin.advance(settle)
        for k in range(n):
            if k:
                twin.advance(1.0 / rate)
            g, p = twin.read()
            for key, val in zip(("command", "sample", "time_s", "pot_v"), (c, k, twin.time_s, p), strict=True):
                rows[key].append(val)
            for i, name in enumerate(_gauge_columns(params)):
                rows[name].append(g[i])
    cols = {k: np.asarray(v) for k, v in rows.items()}
    args = dict(commands=cmds, settle_s=settle, samples=n, sample_rate_hz=rate, orientation=orientation)
    return _result("actuation_sweep", cols, args, seed, params, calibration)


def _list(value, name: str, owner: str) -> list:
    """A non-empty 1-D sequence of the caller's values (a scalar is one value)."""
    arr = np.atleast_1d(np.asarray(value, dtype=object))
    if arr.ndim != 1 or arr.size == 0:
        raise ParameterError(
            f"The '{name}' parameter of {owner} must be a non-empty list of numbers. Got shape {arr.shape} instead."
        )
    return arr.tolist()


def static_load_test(
    loads_kg,
    positions_from_tip_m,
    *,
    commands=None,
    repetitions: int = 25,
    include_no_load: bool = True,
    seed: int = 0,
    params: RigParams | None = None,
    calibration: Calibration | None = None,
    orientation: str = "horizontal",
) -> TwinRecord:
    """Hang each weight at each position (measured from the tip, as the thesis does) at each command, repeated.

    Mirrors 6.4-6.5 (loads 12.5, 25, 7.5 g; 16 positions; 25 repetitions; cable detached: ``commands=None``)
    and 7.1-7.2 (25, 37.5 g; 10 positions; commands 0, 20, 40). Each repetition is a fresh sample of the
    steady gauges with the calibration's white noise. A no-load case per command is added first when
    ``include_no_load``.

    Returns
    -------
    TwinRecord
        Columns ``mass_kg, position_from_base_m, position_from_tip_m, command, repetition, gauge1_v, gauge2_v,
        gauge3_v`` (``command`` is -1 when the cable is detached).
    """
    params = params or RigParams()
    calibration = calibration or twin_calibration(params)
    length = params.geometry.digit_length_m
    masses, from_tip, reps, commands = _checked_static_plan(
        loads_kg, positions_from_tip_m, repetitions, commands, params
    )
    cmd_list = [None] if commands is None else list(commands)
    rows_m, rows_p, rows_c = _static_cases(masses, from_tip, cmd_list, length, include_no_load)
    m_arr = np.repeat(np.array(rows_m), reps)
    p_arr = np.repeat(np.array(rows_p), reps)
    rep = np.tile(np.arange(reps), len(rows_m))
    if commands is None:
        cmd_arr = None
        cmd_col = np.full(m_arr.size, -1, dtype=np.int64)
    else:
        cmd_arr = np.repeat(np.array(rows_c, dtype=float), reps)
        cmd_col = cmd_arr.astype(np.int64)
    volts = static_gauges_v(
        m_arr, p_arr, cmd_arr, params=params, calibration=calibration, orientation=orientation, seed=seed
    )
    cols = {
        "mass_kg": m_arr,
        "position_from_base_m": p_arr,
        "position_from_tip_m": length - p_arr,
        "command": cmd_col,
        "repetition": rep,
    }
    cols.update({f"gauge{i + 1}_v": volts[:, i] for i in range(volts.shape[1])})
    args = dict(
        loads_kg=masses.tolist(),
        positions_from_tip_m=from_tip.tolist(),
        commands=None if commands is None else [int(c) for c in cmd_list],
        repetitions=reps,
        include_no_load=include_no_load,
        orientation=orientation,
    )
    return _result("static_load_test", cols, args, seed, params, calibration)


def _checked_static_plan(loads_kg, positions_from_tip_m, repetitions, commands, params: RigParams):
    """:func:`static_load_test`'s checked ``(masses, positions from the tip, repetitions, commands or None)``.

    Checked before the cases are repeated over positions, commands and repetitions, so a message quotes what
    the caller passed (once), not the broadcast batch.
    """
    owner = "static_load_test"
    length = params.geometry.digit_length_m
    masses = check_values(_list(loads_kg, "loads_kg", owner), "loads_kg", owner, low=0, low_open=True, unit="kg")
    from_tip = check_values(
        _list(positions_from_tip_m, "positions_from_tip_m", owner),
        "positions_from_tip_m",
        owner,
        low=0,
        high=length,
        high_open=True,
        unit="m from the tip",
        note=f"0 is the tip, {length:g} the clamp: nothing hangs beyond the tip, or at or behind the clamp",
    )
    reps = check_int(repetitions, "repetitions", owner, low=1, high=100_000)
    if commands is not None:
        a = params.actuator
        cmds = check_values(
            _list(commands, "commands", owner),
            "commands",
            owner,
            low=a.command_min,
            high=a.command_max,
            integer=True,
            note="servo commands; None detaches the cable",
        )
        commands = [int(c) for c in cmds]
    return masses, from_tip, reps, commands


def _static_cases(masses, from_tip, cmd_list, length: float, include_no_load: bool):
    """One ``(mass, position from the base, command)`` row per case: per command a no-load case, then each
    weight at each position."""
    rows_m, rows_p, rows_c = [], [], []
    for c in cmd_list:
        if include_no_load:
            rows_m.append(0.0)
            rows_p.append(length)
            rows_c.append(c)
        for m in masses:
            for p in from_tip:
                rows_m.append(float(m))
                rows_p.append(length - float(p))
                rows_c.append(c)
    return rows_m, rows_p, rows_c
