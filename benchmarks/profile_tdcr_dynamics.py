"""Where the time of a tdcr dynamics step goes: the discrete rod's (the default) and shooting's.

Run: ``PYTHONPATH=src python benchmarks/profile_tdcr_dynamics.py`` (under the CPU lock on a shared machine).

The discrete rod (:func:`discrete`): a step is about one Newton iteration (the Jacobian kept), i.e. one residual
(the frames' exponentials and the forces), one banded solve and the frames' bookkeeping; each part is timed in a
compiled loop (no Python call overhead), CPU time.

Shooting (:func:`main`):

A step is a shooting problem: Newton (Broyden) on the six clamp-wrench unknowns, every iterate one RK4 integration
of the rod from base to tip (4 right-hand sides per interval). The script prints the real-time factor, the Newton
iterations a step, the cost of one integration (dynamic and static) and how it scales with the RK4 steps, so the
step's cost splits as ``integrations per step x intervals x 4 x cost of a right-hand side``.
"""

from __future__ import annotations

import math
import time

import numpy as np


def _timed(func, repeats: int = 2000) -> float:
    func()
    start = time.perf_counter()
    for _ in range(repeats):
        func()
    return (time.perf_counter() - start) / repeats


def main() -> None:
    from flexdigit.tdcr import Robot, Segment, _rod_kernel, simulate, solve_statics
    from flexdigit.tdcr.statics import _nodes

    rod = Robot(name="rod", segments=(Segment(0.4, 39),))  # 40 nodes with the clamp, as bench_tdcr.py
    b = rod.backbone
    plane = np.array([1.0, 1.0, 0.0]) / math.sqrt(2)
    bent = solve_statics(rod, [], tip_force_n=0.002 * plane)
    simulate(rod, bent, 0.01, dt_s=1e-3, method="shooting")  # compile
    duration, dt = 0.5, 1e-3
    start = time.perf_counter()
    motion = simulate(rod, bent, duration, dt_s=dt, method="shooting")
    per_step = (time.perf_counter() - start) / round(duration / dt)
    print(f"real-time factor {dt / per_step:.2f}: {per_step * 1e6:.0f} us a step of {dt * 1e3:g} ms")
    print(f"Newton iterations a step: {motion.iterations.mean():.2f} (converged {motion.converged})")

    nodes, _ = _nodes(rod, 1)
    dyn = np.zeros(6)
    dyn[0] = 1.5 / dt
    dyn[1:5] = [b.mass_per_length_kg_m, *(b.density_kg_m3 * b.second_moment_m4 * np.array([1.0, 1.0, 2.0]))]
    hist = np.zeros((nodes.size, 2 * _rod_kernel.HIST))
    buf, res, x = np.zeros((nodes.size, _rod_kernel.RECORD)), np.zeros(6), np.zeros(6)
    no_tendons = (np.zeros((0, 3)), np.zeros(0), np.zeros(0, dtype=np.int64))
    stiff = (b.shear_extension_stiffness, b.bending_torsion_stiffness, np.zeros(3), np.zeros(3))

    def one(substeps, d):
        return lambda: _rod_kernel._evaluate(x, nodes, substeps, *no_tendons, *stiff, d, hist, *stiff[2:], buf, res)

    integration = _timed(one(1, dyn))
    rhs = 4 * (nodes.size - 1)
    print(
        f"one integration ({nodes.size - 1} intervals, {rhs} right-hand sides): {integration * 1e6:.1f} us dynamic, "
        f"{_timed(one(1, np.zeros(6))) * 1e6:.1f} us static; {integration / rhs * 1e9:.0f} ns a right-hand side"
    )
    for substeps in (2, 4):
        print(f"  with {substeps} RK4 steps an interval: {_timed(one(substeps, dyn), 500) * 1e6:.1f} us")
    print(
        f"integrations a step: {per_step / integration:.1f}; one integration alone caps the real-time factor at "
        f"{dt / integration:.0f}"
    )
    for step in (2e-3, 1e-3, 5e-4):
        m = simulate(rod, bent, 0.1, dt_s=step)
        print(f"dt {step * 1e3:g} ms: {m.iterations.mean():.2f} Newton iterations a step, converged {m.converged}")


def discrete(repeats: int = 20000) -> None:
    """The discrete rod's step on the 40-node cantilever of bench_tdcr.py, by part (CPU time, compiled loops)."""
    import numba

    from flexdigit.tdcr import Robot, Segment, _chain_kernel, simulate, solve_statics
    from flexdigit.tdcr.dynamics import _discrete_model, _element_frames
    from flexdigit.tdcr.statics import _nodes

    rod = Robot(name="rod", segments=(Segment(0.4, 39),))
    plane = np.array([1.0, 1.0, 0.0]) / math.sqrt(2)
    bent = solve_statics(rod, [], tip_force_n=0.002 * plane)
    simulate(rod, bent, 0.01)  # compile
    start = time.process_time()
    motion = simulate(rod, bent, 1.0)
    per_step = (time.process_time() - start) / 1000
    print(f"discrete: {per_step * 1e6:.1f} us a step of 1 ms (CPU), {motion.iterations.mean():.2f} Newton iterations")
    nodes, ends = _nodes(rod, 1)
    model, mass, inertia, hb = _discrete_model(rod, nodes, ends, (np.zeros(0), np.zeros(3), np.zeros(3), np.zeros(3)))
    x, q = bent.positions_m, np.ascontiguousarray(_element_frames(bent.rotations))
    n, a = q.shape[0], 2e-3 / 3
    z = np.random.default_rng(0).normal(size=6 * n) * 1e-3
    zero = np.zeros((n, 3))
    step = (x, q, zero, np.zeros((n + 1, 3)), zero, mass, inertia, model, (1.0, 0.0, zero, zero))
    work = (np.empty((n + 1, 3)), np.empty((n, 3, 3)), np.empty((n + 1, 3)), *(np.empty((n, 3)) for _ in range(3)))
    res, jac, frames = np.empty(6 * n), np.empty((6 * n, 2 * hb + 1)), np.empty((n + 1, 3, 3))
    out = np.zeros(6 * n + 2 * hb)  # the solve's update, padded by hb zeros at each end
    _chain_kernel._jacobian(z, np.full(6 * n, 1e-8), hb, a, 1.0, *step, *work, jac)

    @numba.njit
    def residual(count, z, a, step, work, res):
        for _ in range(count):
            _chain_kernel._residual(z, a, 1.0, *step, *work, res)

    @numba.njit
    def band_solve(count, jac, hb, res, out):
        for _ in range(count):
            _chain_kernel._band_solve(jac, hb, res, out)

    @numba.njit
    def configure(count, z, a, x, q, psih, xx, qq):
        for _ in range(count):
            _chain_kernel._configure(z, a, x, q, psih, xx, qq)

    @numba.njit
    def node_frames(count, q, frames):
        for _ in range(count):
            _chain_kernel._node_frames_of(q, frames)

    parts = {
        "residual (configure + forces + inertia)": lambda c: residual(c, z, a, step, work, res),
        "banded solve": lambda c: band_solve(c, jac, hb, res, out),
        "configure alone (the frames' exponentials)": lambda c: configure(c, z, a, x, q, zero, *work[:2]),
        "node frames (the response)": lambda c: node_frames(c, q, frames),
    }
    for name, part in parts.items():
        part(1)  # compile
        start = time.process_time()
        part(repeats)
        print(f"  {name}: {(time.process_time() - start) / repeats * 1e6:.2f} us")


if __name__ == "__main__":
    import warnings

    warnings.simplefilter("ignore")
    discrete()
    main()
