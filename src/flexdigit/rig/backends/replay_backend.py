"""The replay backend: a recorded run played back as a rig: a JSON-lines loop log (:mod:`flexdigit.rig.sample_log`) or
an MCAP recording (:mod:`flexdigit.rig.recording`), told apart by the file's first bytes.

:meth:`read` returns the recorded sample in force at the current replay time (sample and hold), time advances only
through :meth:`wait` (virtual), and the commands written are kept in :attr:`commands_sent` beside the recorded
ones, so a new controller can be run open-loop on a recorded run and its commands compared with the original's.
Reading past the end of the recording raises :class:`~flexdigit.errors.RigError`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from flexdigit.errors import DataFileError, ParameterError, RigError
from flexdigit.params import RigParams
from flexdigit.rig.base import Rig, UrlOption
from flexdigit.rig.recording import is_mcap, read_recording_columns
from flexdigit.rig.sample_log import SampleView, read_log_columns

__all__ = ["ReplayRig", "from_url"]


class ReplayRig(Rig):
    """Play back ``path`` (a loop log or an MCAP recording written by :func:`~flexdigit.rig.loop.run_loop`)."""

    name = "replay"
    accepts_loads = False  # a recording cannot hang weights: collecting on it would only wait for an operator

    def __init__(self, path: str, params: RigParams | None = None, *, run: int | None = None, **kwargs: Any) -> None:
        self.path = str(path)
        self.run = run
        mcap = is_mcap(path) or str(path).lower().endswith(".mcap")  # an .mcap that is not one is named as such
        if mcap and run not in (None, 1):
            raise ParameterError(f"replay://{path}?run={run}: an MCAP recording holds one run")
        # streamed into columns (64 bytes a sample; a list of sample dicts takes ten times that)
        read = read_recording_columns if mcap else (lambda p: read_log_columns(p, run))
        self.header, columns, self.footer = read(path)
        if not len(columns["t"]):
            raise DataFileError(f"{path}: the log has no samples to replay")
        #: the recorded samples as read, a sequence of dicts (t, gauges_v, pot_v, command, setpoint, y) made on access
        self.samples = SampleView(columns)
        self._times = columns["t"]
        if np.any(np.diff(self._times) < 0):
            raise DataFileError(f"{path}: sample times are not increasing")
        self._gauges = columns["gauges_v"]
        self._pot = columns["pot_v"]
        self.recorded_commands = columns["command"]
        self.commands_sent: list[tuple[float, int]] = []
        self._now = 0.0
        kwargs.setdefault("clock", lambda: self._now)
        kwargs.setdefault("sleep", self._advance)
        super().__init__(params, **kwargs)
        self.name = f"replay {self.path}"

    def _advance(self, seconds: float) -> None:
        self._now += seconds

    @property
    def times_s(self) -> np.ndarray:
        """The recorded samples' times, s (a read-only array)."""
        return self._times

    @property
    def end_time_s(self) -> float:
        return float(self._times[-1])

    def _read(self) -> tuple[np.ndarray, float]:
        t = self.clock() + self._times[0]
        if t > self._times[-1] + 1e-9:
            raise RigError(f"{self.name}: the recording ends at t = {self._times[-1]:.3f} s")
        i = max(int(np.searchsorted(self._times, t + 1e-9, side="right")) - 1, 0)
        return self._gauges[i].copy(), float(self._pot[i])

    def _send(self, command: int) -> None:
        self.commands_sent.append((self.clock(), command))

    def _apply_load(self, mass_kg: float, position_from_base_m: float) -> None:
        raise RigError(f"{self.name}: a recording cannot hang weights; use the twin (sim) or a rig")

    def _remove_loads(self) -> None:
        return None  # nothing hangs on a recording

    def _rehang(self, settle_s: float) -> None:
        raise RigError(f"{self.name}: a recording cannot re-hang weights; use the twin (sim) or a rig")

    def settings(self) -> dict[str, Any]:
        return {"backend": "replay", "path": self.path, "run": self.run, "samples": len(self._times)}


#: What a ``replay://`` URL may carry: which run of a log holding several (``--append``); a recording plays at the
#: loop's own pace, in virtual time.
URL_OPTIONS = (UrlOption("run", "int", low=1, help="which run of a log that holds several, 1 the first"),)
#: Keyword arguments only Python passes.
PYTHON_OPTIONS = ("clock", "sleep", "operator")


def from_url(location: str, params: RigParams | None, options: dict[str, Any]) -> ReplayRig:
    """``replay://path/to/run.jsonl`` or ``replay://path/to/run.mcap``."""
    if not location:
        raise ParameterError("replay:// needs the recorded log, e.g. replay://run.jsonl or replay://run.mcap")
    return ReplayRig(location, params, **options)
