"""A simulation kept at the wall clock's time: the paced backends (``sim+paced``, ``hil://...?paced=1``).

A paced backend runs its simulation, before each read and command, up to the wall clock's time. It may start
paced (``sim+paced`` on its own) or run in virtual time first and be paced from :meth:`WallPacer.start` on (the
live page: its start's map and tare run on the twin at rest, taking no wall time, and the seconds the start spends
computing are then not simulated at full speed to catch up; the simulation's time carries on from where it was).

On a machine slower than real time (a loaded one, or a costly simulation such as simavr's board), running up to the
wall clock takes longer than the time it simulates, so the next call finds the simulation further behind: each
catch-up longer than the one before, geometrically (the live page's board test once ran over 6 minutes for 15
frames at a load of 20). ``max_catch_up_s`` bounds what one call runs: the simulation then runs as fast as the
machine lets it, ``lag_s`` behind the wall clock (reported, never hidden), and catches up by that bound a call
once the machine is fast enough again.
"""

from __future__ import annotations

import time
from collections.abc import Callable

from flexdigit._validation import check_real

__all__ = ["WallPacer"]


class WallPacer:
    """The wall clock a paced simulation follows, and how far behind it the simulation is.

    Parameters
    ----------
    clock : callable
        The wall clock, s (:func:`time.monotonic`; tests pass a slow fake one).
    max_catch_up_s : float, optional
        The most simulated time one call (:meth:`due`) asks for, s; None for no bound.

    Examples
    --------
    >>> wall = [10.0]
    >>> pacer = WallPacer(lambda: wall[0], max_catch_up_s=0.1)
    >>> pacer.start(sim_time_s=2.0)  # the simulation ran 2 s in virtual time first: paced from 2 s on
    >>> wall[0] += 0.05
    >>> round(pacer.due(2.0), 6), pacer.lag_s
    (0.05, 0.0)
    >>> wall[0] += 1.0  # the machine stalled a second: one call runs 0.1 s of it, the rest is lag
    >>> round(pacer.due(2.05), 6), round(pacer.lag_s, 6)
    (0.1, 0.9)
    """

    def __init__(self, clock: Callable[[], float] = time.monotonic, max_catch_up_s: float | None = None) -> None:
        self.clock = clock
        self.max_catch_up_s = (
            None if max_catch_up_s is None else check_real(max_catch_up_s, "max_catch_up_s", "WallPacer", low=0.0)
        )
        self._wall0: float | None = None
        #: How far the simulation is behind the wall clock after the last call, s (what that call did not run).
        self.lag_s = 0.0
        #: The largest :attr:`lag_s` since pacing started, s.
        self.max_lag_s = 0.0

    @property
    def started(self) -> bool:
        """Whether the simulation follows the wall clock (:meth:`start` called)."""
        return self._wall0 is not None

    def start(self, sim_time_s: float) -> None:
        """Follow the wall clock from now on, the simulation at ``sim_time_s`` now (idempotent)."""
        if self._wall0 is None:
            self._wall0 = self.clock() - float(sim_time_s)

    def now(self) -> float:
        """The wall clock's time on the simulation's axis, s (pacing must have started)."""
        return self.clock() - self._wall0

    def due(self, sim_time_s: float) -> float:
        """Simulated seconds to run now, from ``sim_time_s``: up to the wall clock's time, at most
        ``max_catch_up_s``; what is left over is :attr:`lag_s`. 0 before :meth:`start`."""
        if self._wall0 is None:
            return 0.0
        behind = max(self.now() - sim_time_s, 0.0)
        run = behind if self.max_catch_up_s is None else min(behind, self.max_catch_up_s)
        self.lag_s = behind - run
        self.max_lag_s = max(self.max_lag_s, self.lag_s)
        return run
