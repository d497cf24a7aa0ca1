"""The exported C against flexdigit's Python controller, compiled on the host with gcc (issue 25, step 1).

Oracle: :class:`flexdigit.control.runtime.RuntimeController` in float64. The C is compiled with
``gcc -std=c99 -Wall -Wextra -Wconversion -Werror`` and run on step and random inputs; after every sample the
Python controller takes the C's state and last command (exactly representable in float64) and computes the next
sample, so each sample is compared on its own, from the same state:

- float32: the unrounded command and each state within Higham's dot-product bound for float32
  (``gamma_k |M| |v|``, u = 2^-24) plus the float32 rounding of each coefficient (computed exactly);
- fixed point: within the same model with the realised integer coefficients and half an LSB per rounding, and
  bit for bit against :class:`FixedPointController` (integer arithmetic is exact in Python too);
- the integer command equal, except in a sample where the exact command lies within that bound of a decision
  threshold (a rounding midpoint, a saturation limit, the hysteresis or deadband edge): there either answer is
  right, and such samples must stay rare (AMBIGUOUS_FRACTION).
"""

from __future__ import annotations

import shutil
import subprocess

import control as ct
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from flexdigit.control.c_export import (
    ControllerSpec,
    FixedPointController,
    RotationMap,
    _Realisation,
    analyse_export,
    export_controller,
    fixed_format,
    render_c,
)
from flexdigit.control.design20ms import design_20ms, thesis_controller
from flexdigit.control.runtime import RuntimeController
from flexdigit.errors import DesignError, OutputExistsError, ParameterError

#: The compiler and the flags the issue names: any warning fails the build.
GCC = shutil.which("gcc")
CFLAGS = ["-std=c99", "-Wall", "-Wextra", "-Wconversion", "-Werror", "-O2"]
#: The AVR compiler and the firmware's flags (firmware/Makefile: AVR_CFLAGS), compile only: any warning fails.
AVR_GCC = shutil.which("avr-gcc")
AVR_CFLAGS = [
    "-mmcu=atmega328p",
    "-DF_CPU=16000000UL",
    "-Os",
    "-std=c99",
    "-Wall",
    "-Wextra",
    "-Wconversion",
    "-Werror",
]
#: Largest share of samples whose integer command may legitimately differ (exact value within the bound of a
#: threshold). With the bounds here (~1e-5 commands) a uniform command hits that window ~1e-5 of the time.
AMBIGUOUS_FRACTION = 0.01


def _need_gcc():
    assert GCC, "the C export tests need gcc on the PATH (Debian: apt-get install gcc)"


HARNESS_FLOAT = r"""
#include <stdio.h>
#include "ctl.h"
int main(void)
{
    ctl_t c;
    double r, y;
    int16_t u = 0;
    int i;
    ctl_reset(&c, (float)CTL_COMMAND_EQ);
    while (scanf("%lf %lf", &r, &y) == 2) {
        int ret = ctl_update(&c, (float)r, (float)y, &u);
        printf("%d %d %.9g", ret, (int)u, (double)c.u_raw);
        for (i = 0; i < CTL_NSTATES; i++) {
            printf(" %.9g", (double)c.x[i]);
        }
#if CTL_DITHER
        printf(" %.9g", (double)c.carry);
#endif
        printf("\n");
    }
    return 0;
}
"""

HARNESS_FIXED = r"""
#include <stdio.h>
#include "ctl.h"
int main(void)
{
    ctl_t c;
    long r, y;
    int16_t u = 0;
    int i;
    ctl_reset(&c, (float)CTL_COMMAND_EQ);
    while (scanf("%ld %ld", &r, &y) == 2) {
        int ret = ctl_update_q(&c, (int32_t)r, (int32_t)y, &u);
        printf("%d %d %ld", ret, (int)u, (long)c.u_raw);
        for (i = 0; i < CTL_NSTATES; i++) {
            printf(" %ld", (long)c.x[i]);
        }
#if CTL_DITHER
        printf(" %ld", (long)c.carry);
#endif
        printf("\n");
    }
    return 0;
}
"""


def _avr_compiles(tmp_path, spec, fmt=None) -> None:
    """The export compiles for the ATmega328P as the firmware compiles it, without a warning."""
    assert AVR_GCC, "the C export tests need avr-gcc: run 'make avr' (apt-get install gcc-avr avr-libc)"
    c_text, h_text = render_c(spec, fmt, prefix="ctl")
    (tmp_path / "ctl.c").write_text(c_text)
    (tmp_path / "ctl.h").write_text(h_text)
    build = subprocess.run(
        [AVR_GCC, *AVR_CFLAGS, "-c", "-o", str(tmp_path / "ctl.o"), str(tmp_path / "ctl.c")],
        capture_output=True,
        text=True,
    )
    assert build.returncode == 0, build.stderr


def _num(v):
    """A Python int or float (repr of a numpy scalar is not a C number)."""
    return int(v) if isinstance(v, int | np.integer) else float(v)


def _build(tmp_path, spec, fmt=None):
    """Compile the export and the harness; return a function running it on (r, y) rows."""
    _need_gcc()
    c_text, h_text = render_c(spec, fmt, prefix="ctl")
    (tmp_path / "ctl.c").write_text(c_text)
    (tmp_path / "ctl.h").write_text(h_text)
    (tmp_path / "main.c").write_text(HARNESS_FIXED if fmt else HARNESS_FLOAT)
    exe = tmp_path / "ctl_test"
    build = subprocess.run(
        [GCC, *CFLAGS, "-o", str(exe), str(tmp_path / "ctl.c"), str(tmp_path / "main.c")],
        capture_output=True,
        text=True,
    )
    assert build.returncode == 0, build.stderr

    def run(rows):
        text = "\n".join(f"{a!r} {b!r}" for a, b in ((_num(a), _num(b)) for a, b in rows)) + "\n"
        out = subprocess.run([str(exe)], input=text, capture_output=True, text=True, check=True).stdout
        data = np.array([[float(v) for v in line.split()] for line in out.splitlines()])
        return data

    return run


def _inputs(rng, k, scale, m, step=None):
    """float32-representable (r, y) rows: a step, or random."""
    if step is not None:
        r = np.full(k, step)
        y = step * (1 - np.exp(-np.arange(k) / 20.0)) + rng.normal(0, 0.3, k)
    else:
        r = rng.uniform(-scale, scale, k)
        y = rng.uniform(-scale, scale, k)
    return np.float32(r).astype(float), np.float32(y).astype(float)


def _compare_float(spec: ControllerSpec, data: np.ndarray, r, y, fmt=None) -> int:
    """The synchronised sample-by-sample comparison described in the module docstring; returns the number of
    ambiguous samples."""
    n, m = spec.nstates, spec.ninputs
    real = _Realisation(spec, fmt)
    rc = spec.runtime()
    scale = np.array([2.0**-b for b in fmt.state_bits]) if fmt else np.ones(n)
    u_scale = 2.0**-fmt.command_bits if fmt else 1.0
    x_prev = np.zeros(n)
    last = int(round(spec.u_eq))
    carry = 0.0  # the dither's carried rounding error (spec.dither), synchronised like the state
    ambiguous = 0
    C, D = spec.C.reshape(-1), spec.D.reshape(-1)
    lo, hi = spec.u_min, spec.u_max
    for k in range(len(r)):
        ret, u_c, u_raw_c = data[k, 0], int(data[k, 1]), data[k, 2] * u_scale
        x_c = data[k, 3 : 3 + n] * scale
        assert ret == 0, f"sample {k}: the C returned fault {ret}"
        rc._v[:n] = x_prev
        rc.last_command = last
        rc._carry = carry
        w = np.array([r[k] - y[k]]) if m == 1 else np.array([r[k], y[k]])
        u_raw = spec.u_eq + C @ x_prev + D @ w
        u_py = rc.update(r[k], y[k])
        u_clip = min(max(u_raw, lo), hi)
        u_applied = u_py if spec.quantise else u_clip
        e_u, e_x = real.one_step_bound(x_prev, w, u_clip - u_raw, u_applied - u_clip)
        assert abs(u_raw_c - u_raw) <= e_u, f"sample {k}: u_raw {u_raw_c} vs {u_raw} (bound {e_u:.3g})"
        near = [abs((u_clip % 1.0) - 0.5), abs(u_raw - hi), abs(u_raw - lo)]
        if spec.hysteresis:
            near.append(abs(abs(u_clip - last) - (0.5 + spec.hysteresis)))
        if spec.dither:  # the rounding of the carried command, and the carry's clip at +-0.5
            wanted = u_clip + carry
            near += [abs((wanted % 1.0) - 0.5), abs(abs(wanted - u_py) - 0.5)]
        if spec.deadband is not None:
            near.append(abs(abs(r[k] - y[k]) - spec.deadband[1]) / max(1.0, abs(r[k] - y[k])) * 1e3)
        if spec.antiwindup == "clamp" and (u_raw > hi or u_raw < lo):
            # the freeze decision: the sign of the drift C (A x + B w - x), which the C has to its rounding
            drift = C @ (spec.A @ x_prev + spec.B @ w - x_prev)
            near.append(abs(drift) - np.abs(C) @ e_x)
        carry_c = data[k, 3 + n] * u_scale if spec.dither else 0.0
        # with dither the C also rounds the sum u_clip + carry: half a float32 ulp of up to 256 (fixed: exact)
        tol = e_u + (2.0**-16 if spec.dither and fmt is None else 0.0)
        if min(near) <= tol:
            ambiguous += 1
        else:
            assert u_c == int(round(u_py)), f"sample {k}: command {u_c} vs {u_py}"
            np.testing.assert_array_less(np.abs(x_c - rc.state), e_x + 1e-300, err_msg=f"sample {k}: state")
            # the carry is the unrounded command less the integer one: it errs as the command does
            assert abs(carry_c - rc._carry) <= tol, f"sample {k}: carry {carry_c} vs {rc._carry}"
        x_prev, last, carry = x_c, u_c, carry_c
    assert ambiguous <= AMBIGUOUS_FRACTION * len(r) + 1, f"{ambiguous} ambiguous samples of {len(r)}"
    return ambiguous


@pytest.fixture(scope="module")
def digital20():
    d = design_20ms(period_s=0.02)
    return d, ControllerSpec.from_runtime(d.runtime(), RotationMap((49.5, 68.2, 50.5), -3.0))


def test_float_export_matches_runtime_on_step_and_random(tmp_path, digital20):
    d, spec = digital20
    run = _build(tmp_path, spec)
    rng = np.random.default_rng(1)
    for step, scale in ((30.0, None), (None, 60.0), (None, 400.0)):  # 400: saturates both ways
        r, y = _inputs(rng, 400, scale, 2, step)
        _compare_float(spec, run(zip(r, y, strict=True)), r, y)


def test_fixed_export_is_the_python_model_bit_for_bit(tmp_path, digital20):
    d, spec = digital20
    fmt = fixed_format(spec, 180.0)
    run = _build(tmp_path, spec, fmt)
    rng = np.random.default_rng(2)
    b = fmt.input_bits
    rq = [int(v) for v in rng.integers(-(180 << b), 180 << b, 1500)]
    yq = [int(v) for v in rng.integers(-(180 << b), 180 << b, 1500)]
    rq[:500] = [30 << b] * 500  # a step first
    data = run(zip(rq, yq, strict=True))
    model = FixedPointController(spec, fmt)
    for k, (a, c) in enumerate(zip(rq, yq, strict=True)):
        u = model.update(a, c)
        assert [u, model.u_raw_q, *model.x] == [int(v) for v in data[k, 1:]], f"sample {k}"


def test_fixed_export_bit_for_bit_error_input_and_hysteresis(tmp_path):
    """The other branches of the fixed-point code: one (error) input, no anti-windup, quantiser hysteresis, and
    the input-range fault (|r - y| beyond the analysed range: the C refuses the sample, the model raises)."""
    import dataclasses

    spec = dataclasses.replace(ControllerSpec.from_runtime(thesis_controller("tustin", 0.005)), hysteresis=0.2)
    fmt = fixed_format(spec, 0.3)
    run = _build(tmp_path, spec, fmt)
    rng = np.random.default_rng(5)
    w = int(0.3 * 2**fmt.input_bits)
    small = w // 3000  # 0.1 mm: commands inside 0..254, where the hysteresis decides
    rq = [int(v) for v in rng.integers(-small, small, 500)] + [int(v) for v in rng.integers(-w // 2, w // 2, 500)]
    yq = [int(v) for v in rng.integers(-small, small, 500)] + [int(v) for v in rng.integers(-w // 2, w // 2, 500)]
    rq, yq = rq + [w, -w], yq + [-w, w]
    data = run(zip(rq, yq, strict=True))
    model = FixedPointController(spec, fmt)
    for k, (a, c) in enumerate(zip(rq, yq, strict=True)):
        if k >= 1000:  # |r - y| = 2 w: out of the analysed range
            assert int(data[k, 0]) == 2
            with pytest.raises(OverflowError):
                model.update(a, c)
            continue
        u = model.update(a, c)
        assert [0, u, model.u_raw_q, *model.x] == [int(v) for v in data[k]], f"sample {k}"
    inside = data[:500, 1]
    assert np.mean((inside > 0) & (inside < 254)) > 0.5  # the small inputs did keep the command in range


def test_fixed_export_within_the_analysed_bound(tmp_path, digital20):
    d, spec = digital20
    fmt = fixed_format(spec, 180.0)
    run = _build(tmp_path, spec, fmt)
    rng = np.random.default_rng(3)
    for step, scale in ((30.0, None), (None, 170.0)):
        r, y = _inputs(rng, 500, scale, 2, step)
        b = fmt.input_bits
        r = np.round(r * 2.0**b) / 2.0**b  # inputs exactly on the Q grid: the one-step bound has no input term
        y = np.round(y * 2.0**b) / 2.0**b
        data = run(zip((int(v) for v in r * 2.0**b), (int(v) for v in y * 2.0**b), strict=True))
        _compare_float(spec, data, r, y, fmt)
    # free run: while the integer commands agree, the unrounded command stays within the analysed bound
    analysis = analyse_export(spec, fmt)
    r, y = _inputs(rng, 800, None, 2, 30.0)
    model, rc = FixedPointController(spec, fmt), spec.runtime()
    worst = 0.0
    for a, c in zip(r, y, strict=True):
        u_q = model.update_float(a, c)
        w = np.array([a, c])
        u_raw = spec.u_eq + spec.C.reshape(-1) @ rc.state + spec.D.reshape(-1) @ w
        u_py = rc.update(a, c)
        if u_q != u_py:
            break
        worst = max(worst, abs(model.u_raw_q * 2.0**-fmt.command_bits - u_raw))
    assert worst <= analysis.command_error_bound
    # inputs here are rounded to the Q grid by the wrapper: at most half an input LSB times |D|, inside the bound
    assert analysis.headroom_bits > 1.0


def test_thesis_tustin_error_input_no_antiwindup(tmp_path):
    rc = thesis_controller("tustin", 0.005)
    spec = ControllerSpec.from_runtime(rc)
    run = _build(tmp_path, spec)
    rng = np.random.default_rng(4)
    r, y = _inputs(rng, 600, 0.02, 1)  # metres of gauge-1 deflection
    _compare_float(spec, run(zip(r, y, strict=True)), r, y)


def _random_stable(seed: int, n: int, m: int) -> ct.StateSpace:
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(n, n))
    A *= rng.uniform(0.2, 0.97) / max(1e-9, np.max(np.abs(np.linalg.eigvals(A))))
    return ct.ss(A, rng.normal(size=(n, m)) * 3, rng.normal(size=(1, n)), rng.normal(size=(1, m)), 0.01)


@settings(max_examples=24, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    seed=st.integers(0, 2**31 - 1),
    n=st.integers(1, 4),
    m=st.sampled_from([1, 2]),
    antiwindup=st.sampled_from(["none", "back_calculation", "clamp"]),
    rounding=st.sampled_from(["round", "hysteresis", "dither"]),
    deadband=st.booleans(),
    scale=st.sampled_from([1.0, 30.0, 300.0]),
    straight=st.sampled_from([8, 127]),
    gauges=st.integers(0, 6),
)
def test_property_float_export_holds_to_the_runtime(
    tmp_path_factory, seed, n, m, antiwindup, rounding, deadband, scale, straight, gauges
):
    """Random stable designs, with what ``export controller --params`` gives a digit's: the command rounded
    plainly, with hysteresis or with the runtime's dither (the carried rounding error), a straight command of 8 or
    a cable pair's 127, a rotation map over G gauges (0: none; at most the Uno's 6). Each is held to the Python
    controller sample for sample in C (and its map to the Python map) and built for the AVR without a warning."""
    import dataclasses

    from flexdigit.params import RigParams

    sys = _random_stable(seed, n, m)
    rng = np.random.default_rng(seed)
    kwargs = {}
    if antiwindup == "back_calculation":
        kwargs = {"aw_gain": _stable_aw_gain(sys, rng), "aw_quantisation": bool(rng.integers(2))}
    hysteresis, dither = (0.25 if rounding == "hysteresis" else 0.0), rounding == "dither"
    base = RigParams()
    operating = (straight, straight + 35) if straight == 8 else (straight - 35, straight + 35)  # 3.4.1's span
    actuator = dataclasses.replace(base.actuator, equilibrium_command=straight, operating_commands=operating)
    params = base.replace(actuator=actuator)
    rc = RuntimeController(
        sys,
        params,
        antiwindup=antiwindup,
        hysteresis=hysteresis,
        deadband=(0, 0.5) if deadband else None,
        dither=dither,
        **kwargs,
    )
    rotation = (
        RotationMap(tuple(float(v) for v in rng.uniform(-80, 80, gauges)), float(rng.normal())) if gauges else None
    )
    spec = ControllerSpec.from_runtime(rc, rotation)
    assert spec.dither == dither
    assert spec.u_eq == straight
    folder = tmp_path_factory.mktemp("prop")
    run = _build(folder, spec)
    r, y = _inputs(rng, 200, scale, m)
    _compare_float(spec, run(zip(r, y, strict=True)), r, y)
    if rotation is not None:
        _check_measure(folder, spec, rng.uniform(-2.4, 2.4, gauges))
    _avr_compiles(folder, spec)  # and the same source builds for the board, warning-free


def _stable_aw_gain(sys: ct.StateSpace, rng) -> np.ndarray:
    """A random back-calculation gain L that keeps the design stable when saturated: there the state runs on
    ``A - L C`` (the command's share of the state fed back), which a random L can make unstable (the state then
    diverges, and the C export rightly reports it non-finite). Halved until that spectral radius is below 1."""
    A, C = np.asarray(sys.A), np.asarray(sys.C)
    L = rng.normal(size=A.shape[0]) * 0.1
    while np.max(np.abs(np.linalg.eigvals(A - np.outer(L, C)))) >= 0.99:
        L = L / 2
    return L


def _check_measure(tmp_path, spec, volts) -> None:
    """The export's map (``ctl_measure``) on gauge volts ``volts`` is the Python map's, to float32 rounding."""
    g = spec.rotation.gauges
    (tmp_path / "m.c").write_text(
        '#include <stdio.h>\n#include "ctl.h"\nint main(void){ const float g[CTL_GAUGES] = {'
        + ", ".join(f"{float(v)!r}f" for v in volts)
        + '};\n printf("%.9g\\n", (double)ctl_measure(g)); return 0; }\n'
    )
    subprocess.run(
        [GCC, *CFLAGS, "-o", str(tmp_path / "m"), str(tmp_path / "ctl.c"), str(tmp_path / "m.c")], check=True
    )
    got = float(subprocess.run([str(tmp_path / "m")], capture_output=True, text=True, check=True).stdout)
    want = spec.rotation([float(np.float32(v)) for v in volts])
    # 2G + 2 float32 operations on terms of at most max|weight| x max|volts| (+ the offset)
    term = max(abs(w) for w in spec.rotation.coef) * max(2.5, *np.abs(volts)) + abs(spec.rotation.offset)
    assert got == pytest.approx(want, abs=(2 * g + 2) * 2.0**-24 * term)


@pytest.mark.parametrize(  # the thesis's forward-Euler controller has no fixed-point export (its state update
    # is unstable at 20 ms, spectral radius 3.9: refused, see test_fixed_point_refuses_an_unbounded_state)
    "design, fixed",
    [("digital20", False), ("digital20", True), ("thesis39-euler", False), ("thesis39-tustin", False),
     ("thesis39-tustin", True)],
)  # fmt: skip
def test_exports_compile_for_the_avr_without_a_warning(tmp_path, design, fixed):
    if design == "digital20":
        rc = design_20ms(period_s=0.02).runtime()
        spec = ControllerSpec.from_runtime(rc, RotationMap((49.5, 68.2, 50.5), -3.0))
        input_max = 180.0
    else:
        spec = ControllerSpec.from_runtime(
            thesis_controller(design.rsplit("-", 1)[1].replace("euler", "forward_euler"), 0.02)
        )
        input_max = 0.3
    _avr_compiles(tmp_path, spec, fixed_format(spec, input_max) if fixed else None)


def test_rotation_map_in_c_is_the_estimators(tmp_path, digital20):
    d, spec = digital20
    _need_gcc()
    c_text, h_text = render_c(spec, prefix="ctl")
    (tmp_path / "ctl.c").write_text(c_text)
    (tmp_path / "ctl.h").write_text(h_text)
    (tmp_path / "m.c").write_text(
        '#include <stdio.h>\n#include "ctl.h"\nint main(void){ const float g[3] = {0.25f, -0.5f, 1.0f};\n'
        ' printf("%.9g\\n", (double)ctl_measure(g)); return 0; }\n'
    )
    subprocess.run(
        [GCC, *CFLAGS, "-o", str(tmp_path / "m"), str(tmp_path / "ctl.c"), str(tmp_path / "m.c")], check=True
    )
    got = float(subprocess.run([str(tmp_path / "m")], capture_output=True, text=True, check=True).stdout)
    want = spec.rotation([0.25, -0.5, 1.0])
    assert got == pytest.approx(want, abs=8 * 2.0**-24 * 70)  # 4 float32 operations on terms of at most ~70 deg


def test_analysis_of_digital20(digital20):
    d, spec = digital20
    fmt = fixed_format(spec, 180.0)
    a = analyse_export(spec, fmt, plant_d=d.plant_d, setpoints=(0.0, 30.0))
    assert a.closed_loop_stable
    assert a.limit_cycle_free
    # the realised loop's poles are the design's within the pole shift
    np.testing.assert_allclose(np.sort(np.abs(a.closed_loop_poles)), np.sort(np.abs(d.closed_loop_poles)), atol=1e-6)
    assert a.gain_margin_db > 6
    assert a.phase_margin_deg > 30
    assert a.headroom_bits > 1
    assert a.command_error_bound < 1e-3
    assert "closed loop: stable" in repr(a)


def test_fixed_point_refuses_an_unbounded_state():
    rc = thesis_controller("forward_euler", 0.020)  # 1 - 245 x 0.02 = -3.9: the state update is unstable
    with pytest.raises(DesignError, match="spectral radius"):
        fixed_format(ControllerSpec.from_runtime(rc), 0.05)


def test_export_writes_both_files_and_never_overwrites(tmp_path, digital20):
    d, spec = digital20
    out = tmp_path / "ctrl.c"
    res = export_controller(spec, out, format="fixed", plant_d=d.plant_d)
    assert out.exists()
    assert (tmp_path / "ctrl.h").exists()
    assert '#include "ctrl.h"' in out.read_text()
    with pytest.raises(OutputExistsError):
        export_controller(spec, out)
    export_controller(spec, out, force=True)
    assert "float32" in (tmp_path / "ctrl.h").read_text()
    assert res.analysis.format == "fixed"


# Hostile review: '--prefix int16' wrote a header whose 'int16_t' struct redeclared <stdint.h>'s type, so the
# export did not compile; a 300-character prefix passed though C99 guarantees 31 significant characters.
@pytest.mark.parametrize("prefix", ["int16", "uint8", "int_fast32", "uintptr", "1abc", "a-b", "", "x" * 23])
def test_prefixes_that_make_bad_c_are_refused_in_one_line(digital20, prefix):
    d, spec = digital20
    with pytest.raises(ParameterError) as info:
        render_c(spec, prefix=prefix)
    message = str(info.value)
    assert "\n" not in message
    assert repr(prefix) in message
    assert "--prefix" in message
    assert "<stdint.h>" in message


@pytest.mark.parametrize("prefix", ["int", "int24", "uint8x", "x" * 22])
def test_prefixes_near_the_refused_ones_compile(tmp_path, digital20, prefix):
    """C keywords are fine (the prefix is never used bare); so are names beside the <stdint.h> ones."""
    _need_gcc()
    d, spec = digital20
    c_text, h_text = render_c(spec, prefix=prefix, header_name="ctl.h")
    (tmp_path / "ctl.c").write_text(c_text)
    (tmp_path / "ctl.h").write_text(h_text)
    build = subprocess.run(
        [GCC, *CFLAGS, "-c", "-o", str(tmp_path / "ctl.o"), str(tmp_path / "ctl.c")], capture_output=True, text=True
    )
    assert build.returncode == 0, build.stderr


# -- a described digit's design (issue 24): its G-gauge map, its straight command, the runtime's dither ----------


@pytest.fixture(scope="module", params=["six-gauges-geared", "four-sections-two-cables"])
def digit_export(request):
    """A test digit's 20 ms design as ``flexdigit run --params`` runs it (dithered), with a made-up map over its
    gauges (6 weights; 4 for the pair, whose commands are signed about its straight command 127)."""
    from digits import DIGITS
    from flexdigit.control.design20ms import digit_design_20ms
    from flexdigit.params import RigParams

    params = RigParams.from_dict(DIGITS[request.param])
    d = digit_design_20ms(params, period_s=0.02)
    gauges = len(params.geometry.gauge_positions_m)
    weights = tuple(float(v) for v in np.linspace(20.0, 60.0, gauges))
    spec = ControllerSpec.from_runtime(d.runtime(params, dither=True), RotationMap(weights, -1.5))
    return request.param, params, d, spec


def test_digit_float_export_with_dither_matches_runtime(tmp_path, digit_export):
    name, params, d, spec = digit_export
    assert spec.dither
    assert spec.u_eq == params.actuator.equilibrium_command
    run = _build(tmp_path, spec)
    rng = np.random.default_rng(11)
    for step, scale in ((30.0, None), (-30.0, None), (None, 60.0), (None, 400.0)):
        r, y = _inputs(rng, 400, scale, 2, step)
        data = run(zip(r, y, strict=True))
        _compare_float(spec, data, r, y)
        carry = data[:, 3 + spec.nstates]  # the rounding error carried: at most half a command, and used
        assert np.all(np.abs(carry) <= 0.5)
        assert np.mean(carry != 0) > 0.5


def test_digit_fixed_export_with_dither_is_the_python_model_bit_for_bit(tmp_path, digit_export):
    name, params, d, spec = digit_export
    fmt = fixed_format(spec, 180.0)
    run = _build(tmp_path, spec, fmt)
    rng = np.random.default_rng(12)
    b = fmt.input_bits
    rq = [int(v) for v in rng.integers(-(60 << b), 60 << b, 800)]
    yq = [int(v) for v in rng.integers(-(60 << b), 60 << b, 800)]
    rq[:400] = [30 << b] * 400
    yq[:400] = [int(v) for v in (30 << b) * (1 - np.exp(-np.arange(400) / 20.0))]
    data = run(zip(rq, yq, strict=True))
    model = FixedPointController(spec, fmt)
    for k, (a, c) in enumerate(zip(rq, yq, strict=True)):
        u = model.update(a, c)
        assert [u, model.u_raw_q, *model.x, model.carry_q] == [int(v) for v in data[k, 1:]], f"sample {k}"
    assert len({int(v) for v in data[300:400, 1]}) == 2  # the step's command dithered between two neighbours


def test_a_digits_map_over_its_gauges_in_c(tmp_path, digit_export):
    name, params, d, spec = digit_export
    _need_gcc()
    c_text, h_text = render_c(spec, prefix="ctl")
    g = spec.rotation.gauges
    assert f"#define CTL_GAUGES {g}" in h_text
    assert "#define CTL_DITHER 1" in h_text
    (tmp_path / "ctl.c").write_text(c_text)
    (tmp_path / "ctl.h").write_text(h_text)
    _check_measure(tmp_path, spec, [0.25 * (-1) ** i * (i + 1) / g for i in range(g)])
    _avr_compiles(tmp_path, spec)
    _avr_compiles(tmp_path, spec, fixed_format(spec, 180.0))


def test_a_map_of_nine_gauges_is_refused():
    with pytest.raises(ParameterError, match="1 to 8"):
        RotationMap(tuple(range(9)), 0.0)
