"""Where the time of a shooting tdcr dynamics step goes (method="shooting"; the default is the discrete rod).

Run: ``PYTHONPATH=src python benchmarks/profile_tdcr_dynamics.py`` (under the CPU lock on a shared machine).

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


if __name__ == "__main__":
    import warnings

    warnings.simplefilter("ignore")
    main()
