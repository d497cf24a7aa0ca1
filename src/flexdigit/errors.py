"""Exceptions raised by flexdigit.

Every exception subclasses a built-in so that callers can catch ``ValueError`` or ``OSError`` without
knowing flexdigit (the python-control ``ControlDimension(ValueError)`` and pyserial
``SerialException(IOError)`` habit). The CLI turns any of them into a one-line message and exit code 2.
"""

from __future__ import annotations

__all__ = [
    "FlexdigitError",
    "ParameterError",
    "DataFileError",
    "DesignError",
    "UnstableError",
    "RigError",
    "OutputExistsError",
    "ConvergenceWarning",
    "DesignWarning",
    "Interrupted",
    "one_line",
]


class FlexdigitError(Exception):
    """Base of every flexdigit-specific error."""


class ParameterError(FlexdigitError, ValueError):
    """A parameter (rig, model, design or experiment) has a bad value; the message names it."""


class DataFileError(FlexdigitError, ValueError):
    """A data file (time series, dataset, parameter TOML, saved model) cannot be used as it is."""


class DesignError(FlexdigitError, ValueError):
    """A control design problem is ill-posed or infeasible (bad weights, infeasible gamma)."""


class UnstableError(FlexdigitError, ArithmeticError):
    """A closed loop or a model that must be stable is not; norms of it are meaningless."""


class RigError(FlexdigitError, OSError):
    """The rig (hardware or twin backend) failed: port vanished, board silent, sensor fault."""


class OutputExistsError(FlexdigitError, FileExistsError):
    """An output file exists and would be overwritten; the message names it and says ``--force``."""


class OutputError(FlexdigitError, OSError):
    """An output cannot be written (full disk, quota, permission) or must not be (a FIFO, a device, a directory at
    its path); the message names the file and says the previous file, if any, is kept."""


class OutputBusyError(OutputError, BlockingIOError):
    """Another process is writing the same output (its advisory lock is held); refused, never mixed."""


class ConvergenceWarning(UserWarning):
    """An iterative solver stopped before meeting its tolerance; the result carries ``converged=False``.

    The same role as scikit-learn's ``ConvergenceWarning`` (flexdigit's own, so the twin does not import
    scikit-learn): the answer is returned with its flag, never silently as if it had converged.
    """


class DesignWarning(UserWarning):
    """A design is returned that its own checks say misses a figure it was asked for; the warning names the figure
    (the result carries it too, e.g. :attr:`~flexdigit.control.design20ms.WeightsChoice.failing`)."""


def one_line(message: object) -> str:
    """``message`` (an exception from a library, say) on one line: its whitespace runs collapsed to one space.

    pyarrow and others put newlines in their messages; flexdigit's errors are one line.

    Examples
    --------
    >>> one_line("Couldn't deserialize thrift\\nDeserializing page header failed.\\n")
    "Couldn't deserialize thrift Deserializing page header failed."
    """
    return " ".join(str(message).split())


class Interrupted(KeyboardInterrupt):
    """The run was stopped by a signal (SIGINT, SIGTERM, SIGHUP): a stop, not a crash.

    A :class:`KeyboardInterrupt`, so every ``finally`` and context manager that handles Ctrl-C (the rig's safe
    state, a log's footer, a temporary file's removal) handles ``kill``, a batch scheduler and a closed terminal the
    same way (:func:`flexdigit.interrupts.stop_on_signals` raises it). ``exit_code`` is the shell's convention for a
    process ended by the signal, 128 + its number (130 for SIGINT, 143 for SIGTERM, 129 for SIGHUP).

    Examples
    --------
    >>> import signal
    >>> exc = Interrupted(signal.SIGTERM)
    >>> exc.signal_name, exc.exit_code, str(exc)
    ('SIGTERM', 143, 'interrupted by SIGTERM')
    """

    def __init__(self, signum: int) -> None:
        import signal

        self.signum = int(signum)
        try:
            self.signal_name = signal.Signals(self.signum).name
        except ValueError:
            self.signal_name = f"signal {self.signum}"
        super().__init__(f"interrupted by {self.signal_name}")

    @property
    def exit_code(self) -> int:
        return 128 + self.signum

    def __reduce__(self):  # picklable with its signal (a worker process reports it to its parent)
        return type(self), (self.signum,)
