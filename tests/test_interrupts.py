"""SIGTERM, SIGHUP and SIGINT as stops (issue 22): raised as Interrupted in the main thread, deferred out of the
sections that must not be cut, handlers restored after, an ignored signal left ignored.

The signals are sent to this process (``os.kill``); Python runs the handler between two bytecodes, so each test
spins a bounded loop until it does (never a sleep)."""

from __future__ import annotations

import os
import signal

import pytest

from flexdigit.errors import Interrupted
from flexdigit.interrupts import STOP_SIGNALS, signals_deferred, stop_on_signals

#: Bytecodes a test spins waiting for the handler: it runs at the first check (a few), this bounds a failure.
SPIN = 10**6


def _spin() -> None:
    for _ in range(SPIN):
        pass


@pytest.fixture(autouse=True)
def _defaults():
    """Each test starts with the default actions for SIGTERM and SIGHUP and Python's own for SIGINT."""
    saved = {s: signal.getsignal(s) for s in STOP_SIGNALS}
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    signal.signal(signal.SIGHUP, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    for s, handler in saved.items():
        signal.signal(s, handler)


@pytest.mark.parametrize("signum, code", [(signal.SIGTERM, 143), (signal.SIGHUP, 129), (signal.SIGINT, 130)])
def test_a_stop_signal_raises_interrupted_naming_it(signum, code):
    with pytest.raises(Interrupted) as caught, stop_on_signals():
        os.kill(os.getpid(), signum)
        _spin()
    assert caught.value.signum == signum
    assert caught.value.exit_code == code
    assert str(caught.value) == f"interrupted by {signal.Signals(signum).name}"
    assert isinstance(caught.value, KeyboardInterrupt)  # every Ctrl-C path (finally, except KeyboardInterrupt) runs


def test_the_previous_handlers_are_restored():
    def mine(signum, frame):
        pass

    signal.signal(signal.SIGHUP, mine)
    with stop_on_signals():
        assert signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL
    assert signal.getsignal(signal.SIGHUP) is mine
    assert signal.getsignal(signal.SIGTERM) == signal.SIG_DFL
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_a_signal_inside_a_deferred_section_waits_for_its_end():
    finished = []
    with pytest.raises(Interrupted, match="SIGTERM"), stop_on_signals():
        with signals_deferred():
            os.kill(os.getpid(), signal.SIGTERM)
            _spin()
            with signals_deferred():  # nested: only the outermost end raises
                _spin()
            finished.append("the section")
        finished.append("after it")  # never reached: raised as the section ended
    assert finished == ["the section"]


def test_signals_during_the_stop_are_ignored_and_a_third_forces_the_default(tmp_path):
    # in a child: the third signal ends it by SIGTERM's default action (the stop itself hung)
    import subprocess
    import sys

    code = (
        "import os, signal\n"
        "from flexdigit.interrupts import stop_on_signals\n"
        "with stop_on_signals():\n"
        "    try:\n"
        "        os.kill(os.getpid(), signal.SIGTERM)\n"
        "        for _ in range(10**6): pass\n"
        "    except KeyboardInterrupt:\n"
        "        os.kill(os.getpid(), signal.SIGTERM)  # the second: ignored, the stop goes on\n"
        "        for _ in range(10**6): pass\n"
        "        print('stopping', flush=True)\n"
        "        os.kill(os.getpid(), signal.SIGTERM)  # the third: the default action\n"
        "        for _ in range(10**6): pass\n"
        "        print('not reached', flush=True)\n"
    )
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert run.stdout == "stopping\n"
    assert run.returncode == -signal.SIGTERM


def test_an_ignored_signal_stays_ignored():
    # nohup ignores SIGHUP; a background job of a non-interactive shell ignores SIGINT: a stop was not asked for
    signal.signal(signal.SIGHUP, signal.SIG_IGN)
    with stop_on_signals():
        assert signal.getsignal(signal.SIGHUP) == signal.SIG_IGN
        os.kill(os.getpid(), signal.SIGHUP)
        _spin()
    assert signal.getsignal(signal.SIGHUP) == signal.SIG_IGN


def test_interrupted_pickles_with_its_signal():
    import pickle

    again = pickle.loads(pickle.dumps(Interrupted(signal.SIGHUP)))
    assert again.signum == signal.SIGHUP
    assert again.signal_name == "SIGHUP"


def _signal_inside_a_kernel(signum):
    """What a numba kernel does with a signal that arrives while it runs: the handler runs, its exception is lost,
    and another comes back ("SystemError: CPUDispatcher(...) returned a result with an exception set")."""
    import flexdigit.interrupts as interrupts

    interrupts._state.deferred += 1  # the handler's Interrupted held back, then dropped, as the kernel drops it
    try:
        os.kill(os.getpid(), signum)
        _spin()
    finally:
        interrupts._state.deferred -= 1
        interrupts._state.pending = None
    raise SystemError("CPUDispatcher(<function _train>) returned a result with an exception set")


def test_a_stop_that_comes_back_as_another_exception_is_still_a_stop():
    from flexdigit.interrupts import raise_if_stopping, stop_requested

    with stop_on_signals():
        assert stop_requested() is None
        raise_if_stopping()  # nothing asked: nothing raised
        with pytest.raises(SystemError):
            _signal_inside_a_kernel(signal.SIGTERM)
        assert stop_requested().signal_name == "SIGTERM"
        with pytest.raises(Interrupted, match="SIGTERM") as caught:
            raise_if_stopping(SystemError("from a kernel"))
        assert isinstance(caught.value.__cause__, SystemError)


def test_the_loop_takes_a_stop_inside_its_rig_for_a_stop_not_a_bug():
    # the twin's compiled kernels run inside rig.read(): a signal there must stop the run, not fault and re-raise
    from flexdigit.rig.base import open_rig
    from flexdigit.rig.loop import run_loop

    class Kernel:
        measure = None

        def __init__(self):
            self.calls = 0

        def reset(self, command):
            pass

        def step(self, setpoint, reading):
            self.calls += 1
            if self.calls == 5:
                _signal_inside_a_kernel(signal.SIGHUP)
            return 8.0

    rig = open_rig("sim")
    with stop_on_signals():
        result = run_loop(rig, Kernel(), 0.0, 1.0, guard=False)
    assert result.status == "interrupted"
    assert result.extra["signal"] == "SIGHUP"
    assert "interrupted by SIGHUP" in result.message
    assert result.safe_command_sent


def test_the_command_line_takes_it_for_a_stop_too(monkeypatch, capsys):
    import json

    import flexdigit.cli.params_file as params_commands
    from flexdigit.cli import main

    monkeypatch.setattr(params_commands, "_params", lambda args: _signal_inside_a_kernel(signal.SIGTERM))
    assert main(["params", "--json"]) == 143
    out = json.loads(capsys.readouterr().out)
    assert out["signal"] == "SIGTERM"
    assert out["error"] == "interrupted by SIGTERM"
