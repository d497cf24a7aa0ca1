"""Rewrite tests/data/chain_kernel_before.npz: the chain kernel before its speed-ups, its answer on the test's case.

tests/tdcr/test_chain_kernel.py compares the faster kernel (``flexdigit.tdcr._chain_kernel``) with the kernel as
it was before its speed-ups (``benchmarks/tdcr_kernel_before.py``, f3eec46). Compiling that kernel took ~60 s of
the test's 66 (numba, every fresh clone): its answer on the test's case is stored here instead, with what made it
(the kernel file's SHA-256, the commit, numba's, numpy's and Python's versions, the case). The case: the 40-node rod
of ``benchmarks/bench_tdcr.py``, released from a 2 mN diagonal tip load, 1 ms steps for 0.3 s, through the same
:func:`flexdigit.tdcr.simulate`, once at its default tolerance and once at ``tol = 1e-10`` (the converged
trajectory, the floor the finite-difference Jacobian sets), of which only the largest distance is kept.

Run it when ``benchmarks/tdcr_kernel_before.py`` changes (the test refuses a file made from another kernel) and
commit the file; ``--check`` regenerates it in memory and prints how far the stored arrays are from the new ones
(the kernel before's arithmetic is deterministic on one machine: 0 there, round-off across CPUs)::

    .venv/bin/python tests/data/update_chain_kernel_before.py [--check]
"""

from __future__ import annotations

import hashlib
import importlib
import math
import subprocess
import sys
from pathlib import Path
from unittest import mock

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
STORED = Path(__file__).with_name("chain_kernel_before.npz")
KERNEL = ROOT / "benchmarks" / "tdcr_kernel_before.py"
#: The case (tests/tdcr/test_chain_kernel.py checks its own against these)
LENGTH_M = 0.4
ELEMENTS = 39
TIP_FORCE_N = 0.002 * np.array([1.0, 1.0, 0.0]) / math.sqrt(2)
DURATION_S = 0.3
CONVERGED_TOL = 1e-10


def kernel_sha256() -> str:
    """The SHA-256 of benchmarks/tdcr_kernel_before.py's bytes: which kernel the stored answer is of."""
    return hashlib.sha256(KERNEL.read_bytes()).hexdigest()


def _commit() -> str:
    try:
        out = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "HEAD"], capture_output=True, text=True, check=True)
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return out.stdout.strip()


def compute() -> dict:
    """The kernel before's answer on the case, and its provenance, as the arrays the .npz holds."""
    import numba
    from scipy.spatial.transform import Rotation

    from flexdigit.tdcr import Robot, Segment, dynamics, simulate, solve_statics

    sys.path.insert(0, str(ROOT))  # by its package, as the benchmark imports it (numba's cache finds it by name)
    before_kernel = importlib.import_module("benchmarks.tdcr_kernel_before")
    rod = Robot(name="rod", segments=(Segment(LENGTH_M, ELEMENTS),))
    bent = solve_statics(rod, [], tip_force_n=TIP_FORCE_N)
    with mock.patch.object(dynamics, "_chain_kernel", before_kernel):
        before = simulate(rod, bent, DURATION_S)
        converged = simulate(rod, bent, DURATION_S, tol=CONVERGED_TOL)
    if not (before.converged and converged.converged):
        raise RuntimeError("the kernel before did not converge on the case: nothing written")
    shape = before.positions_m.shape
    return {
        "initial_positions_m": bent.positions_m,
        "positions_m": before.positions_m,
        # the frames as rotation vectors: a third of the bytes; back to matrices within 1e-14, the test's tolerance
        # on a frame's entries is 3e-7
        "rotation_vectors": Rotation.from_matrix(before.rotations.reshape(-1, 3, 3)).as_rotvec().reshape(shape),
        "tolerance_error_m": np.abs(before.positions_m - converged.positions_m).max(),
        "length_m": LENGTH_M,
        "elements": ELEMENTS,
        "tip_force_n": TIP_FORCE_N,
        "duration_s": DURATION_S,
        "converged_tol": CONVERGED_TOL,
        "kernel_sha256": kernel_sha256(),
        "commit": _commit(),
        "numba": numba.__version__,
        "numpy": np.__version__,
        "python": sys.version.split()[0],
    }


def main(argv: list[str]) -> int:
    new = compute()
    if "--check" in argv:
        with np.load(STORED) as old:
            for key in ("initial_positions_m", "positions_m", "rotation_vectors", "tolerance_error_m"):
                print(f"{key}: largest difference {np.abs(old[key] - new[key]).max():.3g}")
        return 0
    np.savez_compressed(STORED, **new)
    print(f"wrote {STORED} ({STORED.stat().st_size} bytes), kernel {new['kernel_sha256'][:12]}, numba {new['numba']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
