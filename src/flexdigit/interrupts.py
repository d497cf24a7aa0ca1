"""Interruptions are stops, not crashes: SIGTERM and SIGHUP take the path Ctrl-C takes.

``kill``, systemd, a batch scheduler and a closed terminal end a process with SIGTERM or SIGHUP, whose default
action kills it where it stands: a servo left at its last command, a log without its footer, a recording cut
mid-record, temporary files behind. :func:`stop_on_signals` turns SIGINT, SIGTERM and SIGHUP into
:class:`~flexdigit.errors.Interrupted` (a :class:`KeyboardInterrupt`) raised in the main thread, so every
``finally`` and context manager that handles Ctrl-C runs: the rig goes to its safe state, logs and recordings get
their closing record, temporary files are removed, journals are left for a rerun to resume. The ``flexdigit``
command runs every sub-command inside it; a library user wraps a run the same way::

    with stop_on_signals():
        result = run_loop(rig, controller, 30.0, 10.0)

A stop is taken once: further signals while it runs are ignored (the safe command and the footers are written
whole), and a third ends the process at once, by the signal's default action (``kill -9`` always does).
:func:`signals_deferred` marks a few lines that must not be cut (a record written to a file, the swap of a
report folder): a signal arriving inside waits for their end. A signal its process was started ignoring (``nohup``
ignores SIGHUP; a background job of a non-interactive shell, SIGINT) stays ignored.

Examples
--------
>>> import os, signal
>>> from flexdigit.errors import Interrupted
>>> try:
...     with stop_on_signals():
...         os.kill(os.getpid(), signal.SIGTERM)
...         for _ in range(10**6):
...             pass  # the handler runs between two bytecodes
... except Interrupted as exc:
...     print(exc, exc.exit_code)
interrupted by SIGTERM 143
>>> signal.getsignal(signal.SIGTERM) == signal.SIG_DFL  # the previous handler is back
True
"""

from __future__ import annotations

import os
import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager

from flexdigit.errors import Interrupted

__all__ = [
    "STOP_SIGNALS",
    "stop_on_signals",
    "signals_deferred",
    "stop_requested",
    "raise_if_stopping",
    "Interrupted",
]

#: The signals that stop a run: Ctrl-C, ``kill`` (and systemd, batch schedulers), a closed terminal. Those this
#: platform lacks (SIGHUP on Windows) are left out.
STOP_SIGNALS: tuple[signal.Signals, ...] = tuple(
    getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name)
)
#: Signals received before the process is ended at once by the default action (the stop itself hung).
_SIGNALS_TO_FORCE = 3


class _State:
    """What the handler needs: whether a stop is under way, how deep in a deferred section, what waits."""

    def __init__(self) -> None:
        self.received = 0
        self.deferred = 0
        self.pending: Interrupted | None = None
        self.first: Interrupted | None = None


_state = _State()


def _handler(signum: int, frame) -> None:
    _state.received += 1
    if _state.received >= _SIGNALS_TO_FORCE:  # the stop hangs: let the signal do what it does by default
        signal.signal(signum, signal.SIG_DFL)
        os.kill(os.getpid(), signum)
        return
    if _state.received > 1:
        return  # the stop is under way: let it finish (the safe command, the footers)
    exc = _state.first = Interrupted(signum)
    if _state.deferred:
        _state.pending = exc
        return
    raise exc


def _in_main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


@contextmanager
def stop_on_signals(signals: tuple[int, ...] = STOP_SIGNALS) -> Iterator[None]:
    """Within the block, ``signals`` raise :class:`~flexdigit.errors.Interrupted` in the main thread.

    The previous handlers are restored when the block ends. Outside the main thread (where Python cannot set a
    handler) the block runs unchanged. Signals the process ignores (``SIG_IGN``) stay ignored.
    """
    if not _in_main_thread():
        yield
        return
    global _state
    outer, _state = _state, _State()
    previous = {}
    try:
        for signum in signals:
            handler = signal.getsignal(signum)
            if handler == signal.SIG_IGN:
                continue
            previous[signum] = handler
            signal.signal(signum, _handler)
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, signal.SIG_DFL if handler is None else handler)
        _state = outer


class signals_deferred:  # noqa: N801 - used like a function: ``with signals_deferred():``
    """A section a signal must not cut (a record being written, a folder swap): a stop signal that arrives inside
    is raised as :class:`~flexdigit.errors.Interrupted` when the outermost section ends.

    Cheap enough for every sample of a 1 kHz loop (two attribute updates); a no-op outside the main thread.
    """

    __slots__ = ("_active",)

    def __enter__(self) -> None:
        self._active = _in_main_thread()
        if self._active:
            _state.deferred += 1

    def __exit__(self, exc_type, exc, tb) -> None:
        if not self._active:
            return
        _state.deferred -= 1
        if _state.deferred == 0 and _state.pending is not None:
            pending, _state.pending = _state.pending, None
            raise pending  # a signal that came inside; an exception of the section becomes its context


def stop_requested() -> Interrupted | None:
    """The stop a signal asked for in the current :func:`stop_on_signals` block (None when none came).

    A signal that arrives while C code runs (a numba-compiled kernel, a BLAS call) may come back from it as another
    exception (numba's ``SystemError: ... returned a result with an exception set``): code that classifies
    exceptions asks this first, so the stop is taken for what it is, not for a bug or a failed row.
    """
    return _state.first


def raise_if_stopping(cause: BaseException | None = None) -> None:
    """Raise the requested stop (:func:`stop_requested`), if any, from ``cause``: for a catch-all (``except
    Exception``) that keeps going after a failure (a chapter, a study row), which must not keep going after a stop."""
    stop = _state.first
    if stop is not None:
        raise Interrupted(stop.signum) from cause
