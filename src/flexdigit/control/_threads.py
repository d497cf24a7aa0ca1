"""One BLAS thread around small dense solves.

SLICOT's SB10AD and AB13DD work on 5-10 state matrices; with OpenBLAS free to spawn threads on a busy 2-core
machine each call went from 1.5 ms to 40-375 ms (measured), so the control routines pin BLAS to one thread
while they run (threadpoolctl, which scikit-learn already depends on).
"""

from __future__ import annotations

import contextlib
from functools import lru_cache


@lru_cache(maxsize=1)
def _controller():
    try:
        from threadpoolctl import ThreadpoolController
    except ImportError:  # pragma: no cover - scikit-learn brings threadpoolctl
        return None
    return ThreadpoolController()


def single_blas_thread():
    """Context manager limiting BLAS to one thread (a no-op without threadpoolctl)."""
    ctl = _controller()
    if ctl is None:  # pragma: no cover
        return contextlib.nullcontext()
    return ctl.limit(limits=1, user_api="blas")
