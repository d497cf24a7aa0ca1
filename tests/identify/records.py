"""Release and step records with known answers, written independently of flexdigit (issue 11, item 1).

The oracle of the step-finding tests: nothing here imports ``flexdigit``. The responses are the closed forms of
``wn^2 / (s^2 + 2 zeta wn s + wn^2)`` written from its poles ``s1, s2 = -zeta wn +- wn sqrt(zeta^2 - 1)``:

- the free response from ``x(0) = 1, x'(0) = 0`` (a release test, thesis 3.1.2) is
  ``(s2 exp(s1 t) - s1 exp(s2 t)) / (s2 - s1)`` (complex arithmetic covers every ``zeta != +-1``, also a growing
  ``zeta < 0``);
- the unit step response (a servo step test, 3.2.4) is ``1 -`` that.

On top: a leading baseline (the held level before the instant, or none: the record starts at the instant), a
step up or down (a release from either side), white noise, isolated single-sample spikes, mains hum (50 or
60 Hz), a linear baseline drift, 200 Hz - 2 kHz sampling, and CSV files of several layouts (column names and
units in several styles, delimiters ``,`` ``;`` tab and spaces, a decimal comma, comment lines, a pandas index
column, time in s or ms, with or without a ``command`` column). Records that cannot be identified (no step, two
steps, constant, too short, saturated, overdamped release, growing) come with the problem a correct
identification must report.

``python tests/identify/records.py DIR`` writes the whole set into DIR with an ``answers.json`` beside it.
"""

from __future__ import annotations

import cmath
import json
import math
import sys
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

#: CSV layouts: (name, delimiter, time column by unit, channel column (format: unit), command column, decimal comma,
#: comment lines, pandas index column, --time-unit needed).
LAYOUTS = {
    "comma": dict(delim=",", time={"s": "time_s", "ms": "time_ms"}, chan="pot_{u}", cmd="command"),
    "semicolon": dict(delim=";", time={"s": "time_s", "ms": "time_ms"}, chan="sg1_{u}", cmd="cmd"),
    "decimal-comma": dict(delim=";", time={"s": "t_s", "ms": "t_ms"}, chan="angle_{u}", cmd="command", decimal=","),
    "tab-bare-time": dict(delim="\t", time={"s": "time", "ms": "time"}, chan="y_{u}", cmd="u", bare_time=True),
    "parentheses": dict(delim=",", time={"s": "Time (s)", "ms": "Time (ms)"}, chan="Pot ({U})", cmd="Command"),
    "brackets-spaces": dict(delim=" ", time={"s": "t[s]", "ms": "t[ms]"}, chan="sg2[{U}]", cmd="command", comments=2),
    "pandas-index": dict(delim=",", time={"s": "time_s", "ms": "time_ms"}, chan="position_{u}", cmd="command", index=1),
}
#: Signal units a channel may be written in, with the factor from volts.
UNITS = {"v": ("V", 1.0), "mv": ("mV", 1000.0)}


def free_response(t, wn: float, zeta: float) -> np.ndarray:
    """``x(t)`` of ``x'' + 2 zeta wn x' + wn^2 x = 0``, ``x(0) = 1``, ``x'(0) = 0``, from the poles (0 before t = 0)."""
    root = cmath.sqrt(zeta * zeta - 1.0)
    s1, s2 = wn * (-zeta + root), wn * (-zeta - root)
    tau = np.maximum(np.asarray(t, dtype=float), 0.0)
    x = (s2 * np.exp(s1 * tau) - s1 * np.exp(s2 * tau)) / (s2 - s1)
    return np.where(np.asarray(t) < 0, 1.0, x.real)


def step_shape(t, wn: float, zeta: float) -> np.ndarray:
    """Unit step response (0 before t = 0)."""
    return 1.0 - free_response(t, wn, zeta)


@dataclass
class Record:
    """One generated record: the file, how to call ``flexdigit identify`` on it, and the known answer.

    ``expect`` is ``"ok"`` (the answer is ``wn_rad_s``, ``zeta``, ``t0_s``) or the problem the identification
    must report (a phrase its message contains).
    """

    name: str
    kind: str
    wn_rad_s: float
    zeta: float
    t0_s: float
    expect: str
    layout: str
    rate_hz: float
    time_unit: str
    baseline_s: float
    direction: int
    command: bool = False
    hum_hz: float | None = None
    spikes: int = 0
    drift: float = 0.0
    noise: float = 0.0
    path: str = ""
    args: list[str] = field(default_factory=list)

    def cli(self, *extra: str) -> list[str]:
        return ["identify", self.kind, self.path, *self.args, *extra]


def make_signal(
    rng: np.random.Generator,
    kind: str,
    *,
    wn: float,
    zeta: float,
    rate_hz: float,
    duration_s: float,
    baseline_s: float,
    amplitude: float,
    offset: float,
    noise: float,
    spikes: int = 0,
    hum_hz: float | None = None,
    hum: float = 0.0,
    drift: float = 0.0,
    start_s: float = 0.0,
) -> tuple[np.ndarray, np.ndarray, float]:
    """Time (s), signal (V) and the instant (s) of one record.

    ``amplitude`` is the step (signed) or the released deflection from the rest value ``offset``; ``noise``,
    ``hum`` and the spike sizes are fractions of ``|amplitude|``; ``drift`` is the baseline's change over the whole
    record, as a fraction of ``|amplitude|``. The record starts at ``start_s``; the instant is ``baseline_s`` later.
    """
    n = int(round(duration_s * rate_hz))
    t = start_s + np.arange(n) / rate_hz
    t0 = start_s + baseline_s
    a = abs(amplitude)
    shape = step_shape(t - t0, wn, zeta) if kind == "step" else free_response(t - t0, wn, zeta)
    y = offset + amplitude * shape
    y = y + drift * a * (t - start_s) / duration_s
    if hum_hz:
        y = y + hum * a * np.sin(2 * np.pi * hum_hz * t + rng.uniform(0, 2 * np.pi))
    y = y + rng.normal(0.0, noise * a, n)
    if spikes:
        where = rng.choice(np.arange(2, n - 2), size=spikes, replace=False)
        y[where] += rng.choice([-1.0, 1.0], spikes) * rng.uniform(0.15, 0.5, spikes) * a
    return t, y, t0


def write_record(path: Path, t_s, y_v, *, layout: str, time_unit: str, unit: str, command=None) -> list[str]:
    """Write one record as CSV in ``layout``; return the extra ``flexdigit identify`` arguments it needs."""
    spec = LAYOUTS[layout]
    unit_name, factor = UNITS[unit]
    tcol = spec["time"][time_unit]
    ccol = spec["chan"].format(u=unit, U=unit_name)
    t = np.asarray(t_s) * (1000.0 if time_unit == "ms" else 1.0)
    cols = [tcol, ccol] + ([spec["cmd"]] if command is not None else [])
    data = [t, np.asarray(y_v) * factor] + ([np.asarray(command)] if command is not None else [])
    delim = spec["delim"]
    fmt = ["%.10g", "%.8g"] + (["%d"] if command is not None else [])
    lines = [f"# generated record {path.name}" for _ in range(spec.get("comments", 0))]
    if spec.get("index"):
        cols = [""] + cols
        data = [np.arange(len(t))] + data
        fmt = ["%d"] + fmt
    lines.append(delim.join(cols))
    for row in zip(*data, strict=True):
        cells = [f % v for f, v in zip(fmt, row, strict=True)]
        if spec.get("decimal") == ",":
            cells = [c.replace(".", ",") for c in cells]
        lines.append(delim.join(cells))
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return ["--time-unit", time_unit] if spec.get("bare_time") else []


def save(rec: Record, path: Path, t_s, y_v, *, unit: str = "v", command=None) -> Record:
    """Write ``rec``'s record to ``path`` in its layout and time unit; set its path and command-line arguments."""
    rec.args = write_record(path, t_s, y_v, layout=rec.layout, time_unit=rec.time_unit, unit=unit, command=command)
    rec.path = str(path)
    return rec


def good_records(directory: Path, n: int = 24, seed: int = 11) -> list[Record]:
    """``n`` identifiable records covering every case of issue 11 (cycled, so each one appears several times).

    Steps: wn 12-40 rad/s, zeta 0.3-0.8 (the servo of 3.2.4: 20.53, 0.5629). Releases: wn 8-20 rad/s, zeta
    0.02-0.15 (the digit of 3.1.2: 13.10, 0.068). Noise 0.3-1.5 %, spikes 15-50 % of the response: the 95 %
    confidence interval of wn then stays within about +-2 %, so the accuracy asked of the identification is not
    left to the luck of the noise (at 2 % noise, 200 Hz and wn = 35 rad/s it is +-4 %).
    """
    rng = np.random.default_rng(seed)
    rates = (200.0, 500.0, 1000.0, 2000.0, 300.0, 1500.0)
    hums = (None, 50.0, 60.0)
    layouts = list(LAYOUTS)
    out = []
    for i in range(n):
        kind = "step" if i % 3 != 2 else "release"
        layout = layouts[i % len(layouts)]
        rate = rates[i % len(rates)]
        time_unit = "ms" if i % 2 else "s"
        baseline = 0.0 if i % 4 == 3 else float(rng.uniform(0.1, 0.4))
        direction = 1 if (i // 2) % 2 == 0 else -1
        hum_hz = hums[i % 3]
        spikes = int(rng.integers(0, 8)) if i % 5 else 0
        drift = float(rng.uniform(-0.05, 0.05)) if i % 2 == 0 else 0.0
        noise = float(rng.uniform(0.003, 0.015))
        command = kind == "step" and i % 4 == 1
        unit = "mv" if i % 7 in (1, 4) else "v"
        if kind == "step":
            wn, zeta = float(rng.uniform(12, 40)), float(rng.uniform(0.3, 0.8))
            duration = baseline + max(1.5, 12.0 / (zeta * wn))
            amplitude = direction * float(rng.uniform(0.2, 1.0))
            offset = float(rng.uniform(0.3, 1.5))
        else:
            wn, zeta = float(rng.uniform(8, 20)), float(rng.uniform(0.02, 0.15))
            duration = baseline + max(3.0, min(12.0, 6.0 / (zeta * wn)))
            amplitude = direction * float(rng.uniform(0.3, 1.5))
            offset = float(rng.uniform(-0.5, 0.5))
        start = float(rng.uniform(0, 5)) if i % 6 == 5 else 0.0  # some records' clocks do not start at 0
        t, y, t0 = make_signal(
            rng,
            kind,
            wn=wn,
            zeta=zeta,
            rate_hz=rate,
            duration_s=duration,
            baseline_s=baseline,
            amplitude=amplitude,
            offset=offset,
            noise=noise,
            spikes=spikes,
            hum_hz=hum_hz,
            hum=float(rng.uniform(0.02, 0.1)) if hum_hz else 0.0,
            drift=drift,
            start_s=start,
        )
        cmd = None
        if command:  # a servo command jumping by 51 (3.2.4) in the direction of the step, latched at the sample
            c0 = 100
            cmd = np.where(t >= t0, c0 + direction * 51, c0)
        rec = Record(
            name=f"good-{i:02d}-{kind}",
            kind=kind,
            wn_rad_s=wn,
            zeta=zeta,
            t0_s=t0,
            expect="ok",
            layout=layout,
            rate_hz=rate,
            time_unit=time_unit,
            baseline_s=baseline,
            direction=direction,
            command=command,
            hum_hz=hum_hz,
            spikes=spikes,
            drift=drift,
            noise=noise,
        )
        out.append(save(rec, directory / f"{rec.name}.csv", t, y, unit=unit, command=cmd))
    return out


def motivating_records(directory: Path, seed: int = 16) -> list[Record]:
    """Issue 11's reproduction: servo steps with no command column after a 0.1-0.4 s baseline, white noise and
    occasional single-sample spikes; one a step down with time in ms (wn came out 51-79 % low with exit 0)."""
    rng = np.random.default_rng(seed)
    out = []
    for i, (direction, time_unit) in enumerate(((1, "s"), (-1, "ms"), (1, "ms"))):
        wn, zeta = 20.53 * float(rng.uniform(0.9, 1.1)), 0.5629 * float(rng.uniform(0.9, 1.1))
        baseline = float(rng.uniform(0.1, 0.4))
        t, y, t0 = make_signal(
            rng,
            "step",
            wn=wn,
            zeta=zeta,
            rate_hz=500.0,
            duration_s=2.0,
            baseline_s=baseline,
            amplitude=direction * 0.4,
            offset=0.9,
            noise=0.02,
            spikes=4,
        )
        rec = Record(f"issue11-{i}", "step", wn, zeta, t0, "ok", "comma", 500.0, time_unit, baseline, direction)
        rec.spikes, rec.noise = 4, 0.02
        out.append(save(rec, directory / f"{rec.name}.csv", t, y))
    return out


def pushed_release_records(directory: Path, seed: int = 31) -> list[Record]:
    """Release tests recorded from rest: the digit at rest 0.2-0.4 s, pushed over by hand in 0.2-0.3 s (a raised
    cosine), held 0.1-0.3 s, released; up and down, 500 Hz and 1 kHz, with spikes and 50 Hz hum."""
    rng = np.random.default_rng(seed)
    out = []
    for i, (direction, rate) in enumerate(((1, 500.0), (-1, 1000.0))):
        wn, zeta = float(rng.uniform(10, 16)), float(rng.uniform(0.04, 0.1))
        rest, push, hold = float(rng.uniform(0.2, 0.4)), float(rng.uniform(0.2, 0.3)), float(rng.uniform(0.1, 0.3))
        baseline = rest + push + hold
        deflection = direction * 0.8
        t, y, t0 = make_signal(
            rng, "release", wn=wn, zeta=zeta, rate_hz=rate, duration_s=baseline + 6.0, baseline_s=baseline,
            amplitude=deflection, offset=0.1, noise=0.01, spikes=3, hum_hz=50.0, hum=0.03,
        )  # fmt: skip
        ramp = np.clip((t - rest) / push, 0.0, 1.0)
        y = np.where(t < rest + push, y - deflection * (1.0 - 0.5 * (1.0 - np.cos(np.pi * ramp))), y)
        rec = Record(f"pushed-{i}", "release", wn, zeta, t0, "ok", "comma", rate, "s", hold, direction)
        rec.spikes, rec.hum_hz, rec.noise = 3, 50.0, 0.01
        out.append(save(rec, directory / f"{rec.name}.csv", t, y))
    return out


def light_release_records(directory: Path, seed: int = 41) -> list[Record]:
    """Release tests of the bare, lightly damped digit (zeta 0.002-0.005 at about 10 rad/s, as the twin's bare strip:
    30 s at 1 kHz still swinging at half its deflection at the end) as a gauge near the tip reads them: a decaying
    higher mode (150 rad/s, zeta 0.3) adds to the deflection at the release, and the gauge's quadratic
    nonlinearity lifts every swing to one side, so the first undershoot is smaller than the swing after it. The
    known answer is the dominant mode's. Noise-free, and with 1.2 % noise; up and down.
    """
    rng = np.random.default_rng(seed)
    out = []
    for i, (noise, direction) in enumerate(((0.0, 1), (0.012, -1), (0.012, 1))):
        wn, zeta = float(rng.uniform(9.5, 11.0)), float(rng.uniform(0.002, 0.005))
        rate = 1000.0
        t = np.arange(int(30.0 * rate)) / rate
        x = free_response(t, wn, zeta)
        shape = x + 0.12 * x * x + 0.5 * free_response(t, 150.0, 0.3)
        a = 0.0084
        y = 0.034 + direction * a * shape + rng.normal(0.0, noise * a, t.size)
        rec = Record(f"light-{i}", "release", wn, zeta, 0.0, "ok", "comma", rate, "s", 0.0, direction, noise=noise)
        out.append(save(rec, directory / f"{rec.name}.csv", t, y))
    return out


def bad_records(directory: Path, seed: int = 23) -> list[Record]:
    """Records no identification can stand behind, each with the problem its refusal must name."""
    rng = np.random.default_rng(seed)
    out = []

    def add(name, kind, t, y, expect, *, wn=math.nan, zeta=math.nan, t0=math.nan, cmd=None, layout="comma"):
        rec = Record(name, kind, wn, zeta, t0, expect, layout, float(1 / (t[1] - t[0])), "s", 0.0, 1, cmd is not None)
        out.append(save(rec, directory / f"bad-{name}.csv", t, y, command=cmd))

    servo = dict(wn=20.53, zeta=0.5629, rate_hz=500.0, amplitude=0.4, offset=0.9, noise=0.02)
    digit = dict(wn=13.1, zeta=0.068, rate_hz=500.0, amplitude=0.8, offset=0.1, noise=0.02)
    # no step: noise, drift and hum around one level
    t, y, _ = make_signal(rng, "step", duration_s=2.0, baseline_s=2.5, hum_hz=50.0, hum=0.05, drift=0.02, **servo)
    add("no-step", "step", t, y, "no step")
    t, y, _ = make_signal(rng, "release", duration_s=5.0, baseline_s=6.0, **digit)
    add("no-release", "release", t, y, "no release")
    # two steps: up at 0.3 s, up again at 1.2 s; and a pulse (up, then back down)
    t, y1, _ = make_signal(rng, "step", duration_s=2.5, baseline_s=0.3, **servo)
    y2 = 0.4 * step_shape(t - 1.2, servo["wn"], servo["zeta"])
    add("two-steps", "step", t, y1 + y2, "two steps", wn=servo["wn"], zeta=servo["zeta"], t0=0.3)
    add("pulse", "step", t, y1 - y2, "two steps", wn=servo["wn"], zeta=servo["zeta"], t0=0.3)
    cmd = np.where(t >= 0.3, 151, 100) + np.where(t >= 1.2, 51, 0)
    add("two-steps-command", "step", t, y1 + y2, "two steps", cmd=cmd)
    # a command column that never changes (issue 16), on a record whose signal steps
    add("constant-command", "step", t, y1, "command", cmd=np.full(t.size, 100))
    # constant
    t = np.arange(0, 2, 0.002)
    add("constant", "step", t, np.full(t.size, 0.731), "constant")
    add("constant-release", "release", t, np.full(t.size, 0.731), "constant")
    # too short: the record ends 60 ms after the step (the servo's first peak comes 0.18 s after it)
    t, y, _ = make_signal(rng, "step", duration_s=0.36, baseline_s=0.3, **servo)
    add("too-short", "step", t, y, "too short")
    # saturated: the overshoot clipped by the ADC (final value 1.3 V, peak 1.35 V, rail 1.32 V)
    t, y, _ = make_signal(rng, "step", duration_s=2.0, baseline_s=0.3, **{**servo, "noise": 0.005})
    add("saturated", "step", t, np.minimum(y, 1.32), "saturated", wn=servo["wn"], zeta=servo["zeta"], t0=0.3)
    t, y, _ = make_signal(rng, "release", duration_s=5.0, baseline_s=0.3, **digit)
    add("saturated-release", "release", t, np.maximum(y, -0.45), "saturated")
    # an overdamped release (zeta 1.5) without --allow-overdamped
    t, y, _ = make_signal(rng, "release", duration_s=4.0, baseline_s=0.3, **{**digit, "zeta": 1.5})
    add("overdamped-release", "release", t, y, "no undershoot")
    t, y, _ = make_signal(rng, "step", duration_s=3.0, baseline_s=0.3, **{**servo, "zeta": 1.6, "noise": 0.005})
    add("overdamped-step", "step", t, y, "overdamped")
    # growing: negative damping, and an exponential run-away (with and without --allow-overdamped)
    t, y, _ = make_signal(rng, "release", duration_s=5.0, baseline_s=0.3, **{**digit, "zeta": -0.03})
    add("growing-release", "release", t, y, "growing")
    t, y, _ = make_signal(rng, "step", duration_s=2.0, baseline_s=0.3, **{**servo, "zeta": -0.1})
    add("growing-step", "step", t, y, "growing")
    t = np.arange(0, 3, 0.002)
    y = 0.1 + 0.05 * np.exp(np.maximum(t - 0.3, 0) / 0.5) + rng.normal(0, 0.01, t.size)
    add("exponential", "step", t, y, "growing")
    add("exponential-release", "release", t, y, "growing")
    return out


def all_records(directory: Path) -> list[Record]:
    directory.mkdir(parents=True, exist_ok=True)
    good = good_records(directory) + motivating_records(directory) + pushed_release_records(directory)
    good += light_release_records(directory)
    return good + bad_records(directory)


if __name__ == "__main__":  # pragma: no cover - a tool for looking at the records by hand
    target = Path(sys.argv[1] if len(sys.argv) > 1 else "generated-records")
    records = all_records(target)
    (target / "answers.json").write_text(json.dumps([asdict(r) for r in records], indent=1))
    print(f"{len(records)} records in {target}")
