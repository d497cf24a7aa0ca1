"""The Rig interface: read the gauges (and potentiometer), write a servo command, hang a load (thesis 2.5, 5.2).

Every backend (the twin, the serial servo board, the DAQ card, a recorded run) implements :class:`Rig`, so the
real-time loop (:mod:`flexdigit.rig.loop`) and the tactile experiments drive the twin and the hardware with the same
code. Backends are chosen by name or URL through :func:`open_rig`, the way pyserial's ``serial_for_url`` chooses a
protocol handler::

    sim                                     the twin, virtual time (as fast as it computes)
    sim+paced                               the twin, paced to the wall clock
    serial:///dev/ttyUSB0?baud=9600&channel=0[&daq=0[&pot=3]]   the MILINST servo board, gauges (and pot) from daq
        framing: &sync=0xFF&max_channel=7&max_position=254 (Mini SSC, the defaults)
    daq://0[?pot=3]                         a Measurement Computing card through uldaq (gauges, pot if wired)
    stream:///dev/ttyACM0?baud=115200       gauges (and pot) from a microcontroller ADC, read-only
    serial:///dev/ttyUSB0?daq=stream:///dev/ttyACM0&daq.baud=115200   the servo board with the stream's gauges
    replay://run.jsonl                      a recorded run played back
    hil://firmware/build/flexdigit_board.elf?mode=host   the reference firmware on simavr, joined to the twin
    board:///dev/ttyACM0?mode=host           the reference firmware on a real Uno (docs/board.md)

The servo command (0..254, integer) is a unit of its own: :func:`clamp_command` is the one place it is rounded
and clamped, and 255 (the Mini SSC sync byte) can never come out of it (a board whose framing allows fewer
positions clamps further, :class:`~flexdigit.rig.backends.serial_backend.SerialRig`).
"""

from __future__ import annotations

import abc
import math
import sys
import time
import urllib.parse
from collections.abc import Callable
from dataclasses import dataclass, field
from importlib import import_module
from numbers import Real
from typing import Any

import numpy as np

from flexdigit._validation import _interval_text, check_real
from flexdigit.errors import ParameterError, RigError
from flexdigit.params import RigParams

__all__ = [
    "Reading",
    "Rig",
    "clamp_command",
    "open_rig",
    "parse_rig_url",
    "rig_url_options",
    "seed_option",
    "UrlOption",
    "console_operator",
    "BACKENDS",
]


@dataclass(frozen=True)
class Reading:
    """One sample of the rig.

    Parameters
    ----------
    time_s : float
        Rig time of the sample, s (virtual time on the twin, monotonic time since opening on hardware).
    gauges_v : ndarray, shape (3,)
        Amplified half-bridge voltages of gauges 1..3 (base to tip), V, as the ADC sees them (table 2.2).
    pot_v : float
        Servo potentiometer voltage, V; NaN when the backend has no potentiometer channel.
    command : int
        The servo command in force when the sample was taken (0..254).
    """

    time_s: float
    gauges_v: np.ndarray
    pot_v: float = math.nan
    command: int = 8

    def __post_init__(self) -> None:
        gauges = np.array(self.gauges_v, dtype=float).reshape(-1)
        gauges.setflags(write=False)
        object.__setattr__(self, "gauges_v", gauges)

    @property
    def finite(self) -> bool:
        """True when every gauge voltage is a finite number."""
        return bool(np.all(np.isfinite(self.gauges_v)))


def clamp_command(command: object, params: RigParams | None = None) -> int:
    """Round a command to the nearest integer and clamp it to the actuator range (0..254 on the thesis rig).

    Parameters
    ----------
    command : real
        Requested servo command (any real number; NaN is refused).
    params : RigParams, optional
        Gives ``actuator.command_min``/``command_max``; the thesis rig by default.

    Returns
    -------
    int
        The command actually sendable; never 255 (the Mini SSC sync byte).

    Examples
    --------
    >>> clamp_command(300.7), clamp_command(-3), clamp_command(42.5), clamp_command(43.5)
    (254, 0, 42, 44)
    """
    if isinstance(command, bool) or not isinstance(command, Real | np.integer | np.floating):
        raise ParameterError(f"The 'command' parameter must be a real number. Got {command!r} instead.")
    value = float(command)
    if math.isnan(value):
        raise ParameterError("The 'command' parameter must be a real number, not NaN. Got nan instead.")
    actuator = (params or RigParams()).actuator
    low, high = int(actuator.command_min), min(int(actuator.command_max), 254)
    if value >= high:
        return high
    if value <= low:
        return low
    return int(round(value))  # banker's rounding is fine: a half-quantum tie either way


def console_operator(message: str) -> None:
    """Ask the person at the rig to do something (hang a weight) and wait for Enter.

    With no one to ask (stdin closed or not a terminal at its end) it raises :class:`RigError` naming the step,
    rather than dying in an ``EOFError``: whoever called it then leaves the rig in its safe state. The request goes
    to stderr (``input`` writes it to stdout, which carries a command's result: ``--json`` then did not parse).
    """
    print(f"{message} Press Enter when done. ", end="", file=sys.stderr, flush=True)
    if not sys.stdin or not sys.stdin.readline():
        raise RigError(f"no operator to ask ({message}): stdin is closed; run it from a terminal")


class Rig(abc.ABC):
    """A flexible digit you can read and command: the twin or the hardware.

    Subclasses implement :meth:`_read`, :meth:`_send` and, where it exists, :meth:`_apply_load`; this base class
    owns clamping, the command in force, the clock, the safe state and closing.

    Parameters
    ----------
    params : RigParams, optional
        The rig parameters (thesis rig by default).
    clock : callable, optional
        Monotonic clock in seconds (``time.monotonic`` on hardware; the twin passes its virtual clock). Tests
        inject a fake one.
    sleep : callable, optional
        ``sleep(seconds)`` used by :meth:`wait` on hardware backends (``time.sleep`` by default).
    operator : callable, optional
        ``operator(message)`` asked to hang or remove weights on hardware backends (:func:`console_operator`).
    """

    #: Name used in reprs and messages.
    name = "rig"
    #: False for a backend that cannot hang weights (a replay): tactile collection refuses it up front.
    accepts_loads = True
    #: True when the same actions give the same readings (the twin in virtual time): a resumed collection can
    #: then replay the readings already journalled to bring the rig to the state it was in, and check them.
    deterministic = False

    def __init__(
        self,
        params: RigParams | None = None,
        *,
        clock: Callable[[], float] | None = None,
        sleep: Callable[[float], None] | None = None,
        operator: Callable[[str], None] | None = None,
    ) -> None:
        self.params = params if params is not None else RigParams()
        if not isinstance(self.params, RigParams):
            raise ParameterError(f"The 'params' parameter of {type(self).__name__} must be a RigParams. Got {params!r}")
        self._clock = clock or time.monotonic
        self._sleep = sleep or time.sleep
        self.operator = operator or console_operator
        self._t0 = self._clock()
        self._command = int(self.params.actuator.equilibrium_command)
        self._closed = False
        self.loads: list[tuple[float, float]] = []

    # -- what backends implement -------------------------------------------------------------------------------
    @abc.abstractmethod
    def _read(self) -> tuple[np.ndarray, float]:
        """Return ``(gauges_v (3,), pot_v)`` now."""

    @abc.abstractmethod
    def _send(self, command: int) -> None:
        """Send an already clamped integer command to the actuator."""

    def _apply_load(self, mass_kg: float, position_from_base_m: float) -> None:
        self.operator(f"Hang {mass_kg * 1000:.0f} g at {position_from_base_m * 1000:.0f} mm from the base.")

    def _remove_loads(self) -> None:
        self.operator("Remove every weight from the digit.")

    def _rehang(self, settle_s: float) -> None:
        self.operator("Lift every weight and hang it again at the same place.")
        self.wait(settle_s)

    def _apply_tissue(self, tissue) -> None:
        if tissue is None:
            self.operator("Take the tissue away from the digit.")
        else:
            self.operator(
                f"Place the tissue beside the digit from {tissue.start_m * 1000:.0f} to {tissue.end_m * 1000:.0f} mm "
                f"from the base, {tissue.gap_m * 1000:.1f} mm from its axis on the {tissue.side} side."
            )

    def _close(self) -> None:
        """Release the port/device (after the safe command has been sent); nothing to release by default."""
        return None

    # -- the interface -----------------------------------------------------------------------------------------
    def settings(self) -> dict[str, Any]:
        """The effective settings of this rig (JSON-able): recorded with every dataset and log, compared on resume.

        Backends add what decides their readings (the twin's seed and calibration, the port and framing).
        """
        return {"backend": type(self).name}

    @property
    def closed(self) -> bool:
        return self._closed

    @property
    def command(self) -> int:
        """The last command sent (the equilibrium command before any)."""
        return self._command

    def clock(self) -> float:
        """Rig time in seconds since opening: virtual on the twin, monotonic on hardware."""
        return self._clock() - self._t0

    def command_pulses(self) -> int | None:
        """How many of the servo's pulses will carry a command sent now, or None where the rig cannot tell.

        The thesis's serial board pulses the servo at 52 Hz with the last of the frames sent every 20 ms (3.4.1,
        5.2), so it reads one frame in 25 twice; the twin knows which
        (:meth:`flexdigit.twin.actuator.Servo.pulses_carrying`). The loop's dither counts them
        (:meth:`flexdigit.control.runtime.RuntimeController.update`'s ``pulses``); None counts one.
        """
        return None

    def read(self) -> Reading:
        """Read the three gauges and the potentiometer now."""
        self._check_open()
        gauges, pot = self._read()
        return Reading(self.clock(), gauges, float(pot), self._command)

    def write_command(self, command: object) -> int:
        """Send a servo command, rounded and clamped to the actuator range; return what was sent."""
        self._check_open()
        sent = clamp_command(command, self.params)
        self._send(sent)
        self._command = sent
        return sent

    def wait(self, seconds: float) -> None:
        """Let ``seconds`` pass (advances virtual time on the twin; sleeps on hardware)."""
        self._check_open()
        if seconds > 0:
            self._sleep(seconds)

    def place_load(self, mass_kg: float, position_from_base_m: float) -> None:
        """Hang a point mass at a distance from the base (the twin applies it; on hardware the operator does)."""
        mass = check_real(mass_kg, "mass_kg", type(self).__name__, low=0.0)
        length = self.params.geometry.digit_length_m
        pos = check_real(position_from_base_m, "position_from_base_m", type(self).__name__, low=0.0, high=length)
        self._check_open()
        self._apply_load(mass, pos)
        self.loads.append((mass, pos))

    def rehang(self, settle_s: float) -> None:
        """Lift the hung weights and hang them again at the same places, then let the digit settle ``settle_s``.

        The thesis repeats "the procedure" for every reading (6.4, 7.1); on hardware the operator does it. The twin
        re-hangs exactly, without a swing, so it only lets the cable settle afresh in its guides and does not wait.
        """
        settle = check_real(settle_s, "settle_s", type(self).__name__, low=0.0)
        self._check_open()
        self._rehang(settle)

    def place_tissue(self, tissue) -> None:
        """Put a compliant body beside the digit (:class:`flexdigit.twin.contact.Tissue`) or take it away (None):
        the twin places it, on hardware the operator does (palpation, :mod:`flexdigit.palpation.palpation`)."""
        self._check_open()
        self._apply_tissue(tissue)

    def clear_loads(self) -> None:
        """Remove every load."""
        self._check_open()
        self._remove_loads()
        self.loads.clear()

    def relax(self) -> int:
        """Send the equilibrium command (8 on the thesis rig: no deflection)."""
        return self.write_command(self.params.actuator.equilibrium_command)

    def close(self) -> None:
        """Relax the digit (best effort) and release the port. Safe to call twice."""
        if self._closed:
            return
        try:
            self.relax()
        except OSError:
            pass  # the port may be the thing that failed; closing must still release it
        finally:
            self._closed = True
            self._close()

    def __enter__(self) -> Rig:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        state = "closed" if self._closed else "open"
        return f"{type(self).__name__}<{self.name}>(command={self._command}, loads={self.loads}, {state})"

    def _check_open(self) -> None:
        if self._closed:
            raise RigError(f"{self.name}: the rig is closed")


# -- choosing a backend ----------------------------------------------------------------------------------------

#: scheme -> "module:factory"; each factory takes ``(location, params, options)`` and returns a :class:`Rig`. The
#: module declares what its URL may carry: ``URL_OPTIONS`` (a tuple of :class:`UrlOption`), ``PYTHON_OPTIONS``
#: (keyword arguments only Python passes: callables, open ports, fakes) and ``URL_PREFIXES`` (option prefixes
#: passed on, as text, to a nested source that checks them: ``daq.`` on serial).
BACKENDS: dict[str, str] = {
    "sim": "flexdigit.rig.backends.sim_backend:from_url",
    "sim+paced": "flexdigit.rig.backends.sim_backend:from_url_paced",
    "serial": "flexdigit.rig.backends.serial_backend:from_url",
    "daq": "flexdigit.rig.backends.daq_backend:from_url",
    "replay": "flexdigit.rig.backends.replay_backend:from_url",
    "stream": "flexdigit.rig.backends.stream_backend:from_url",
    "hil": "flexdigit.rig.backends.hil_backend:from_url",
    "board": "flexdigit.rig.backends.board_backend:from_url",
}

_TRUE = ("1", "true", "yes", "on")
_FALSE = ("0", "false", "no", "off")


@dataclass(frozen=True)
class UrlOption:
    """One option a backend's URL may carry, declared once: name, kind and allowed values.

    The one parser (:func:`rig_url_options`) refuses options a backend does not declare, converts the text of
    those it does and checks their range; 0 is a value like any other (``seed=0``, ``pot=0``). Python callers
    passing the same option as a keyword to :func:`open_rig` are checked by the same declaration.

    Parameters
    ----------
    name : str
        The query key (``seed`` in ``sim?seed=3``).
    kind : {"int", "float", "bool", "choice", "str"}
        ``int`` accepts decimal and ``0x``-prefixed hexadecimal (a sync byte); ``bool`` accepts
        1/0, true/false, yes/no, on/off.
    low, high : float, optional
        Closed interval for ``int``/``float`` (``low_open``/``high_open`` make an end open).
    choices : tuple of str
        The allowed values of a ``choice``.
    none : bool
        The value may be ``none`` (or empty), meaning "not wired" (``pot=none``): converted to None.
    help : str
        What it means (in messages and docs).
    """

    name: str
    kind: str
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False
    choices: tuple[str, ...] = ()
    none: bool = False
    help: str = ""

    def expected(self) -> str:
        """What a valid value looks like, for messages."""
        if self.kind == "choice":
            text = "one of " + ", ".join(self.choices)
        elif self.kind == "bool":
            text = "a boolean (1/0, true/false, yes/no, on/off)"
        elif self.kind == "int":
            text = "an integer" + _interval_text(self.low, self.high, False, False)
        elif self.kind == "float":
            text = "a finite number" + _interval_text(self.low, self.high, self.low_open, self.high_open)
        else:
            text = "non-empty text"
        return text + (" or 'none'" if self.none else "")

    def convert(self, value: object, where: str) -> Any:
        """``value`` (URL text, or a Python value) as this option's type, or a :class:`ParameterError` naming
        ``where``, the option and what was expected."""
        about = f" ({self.help})" if self.help else ""
        bad = ParameterError(f"{where}: option {self.name}={value!r} must be {self.expected()}{about}")
        text = value.strip() if isinstance(value, str) else None
        if self.none and (value is None or (text is not None and text.lower() in ("", "none"))):
            return None
        if self.kind == "str":
            if not text:  # not text, or empty: an empty value is not "not given"
                raise bad
            return text
        if self.kind == "choice":
            if text not in self.choices:
                raise bad
            return text
        if self.kind == "bool":
            if isinstance(value, bool | np.bool_):
                return bool(value)
            if text is not None and text.lower() in _TRUE + _FALSE:
                return text.lower() in _TRUE
            raise bad
        if isinstance(value, bool | np.bool_):
            raise bad
        if text is not None:
            try:
                number: float = int(text, 0) if self.kind == "int" else float(text)
            except ValueError:
                raise bad from None
        elif isinstance(value, Real | np.integer | np.floating):
            number = value
        else:
            raise bad
        if self.kind == "int":
            if not float(number).is_integer():
                raise bad
            number = int(number)
        else:
            number = float(number)
        if not math.isfinite(number):
            raise bad
        low_bad = self.low is not None and (number < self.low or (self.low_open and number == self.low))
        high_bad = self.high is not None and (number > self.high or (self.high_open and number == self.high))
        if low_bad or high_bad:
            raise bad
        return number


@dataclass(frozen=True)
class RigURL:
    """A parsed rig URL: ``scheme``, ``location`` (port, board number or path) and query ``options`` (text)."""

    scheme: str
    location: str = ""
    options: dict[str, str] = field(default_factory=dict)

    @property
    def where(self) -> str:
        """The URL as messages name it (``serial:///dev/ttyUSB0``, ``sim``)."""
        return f"{self.scheme}://{self.location}" if self.location else self.scheme


def parse_rig_url(url: str) -> RigURL:
    """Split ``serial:///dev/ttyUSB0?baud=9600`` into scheme, location and options (text, not yet checked).

    A scheme flexdigit does not know and an option given twice are refused here; :func:`rig_url_options`
    checks the options against the backend's declarations.

    Examples
    --------
    >>> parse_rig_url("serial:///dev/ttyUSB0?baud=9600&channel=1")
    RigURL(scheme='serial', location='/dev/ttyUSB0', options={'baud': '9600', 'channel': '1'})
    >>> parse_rig_url("sim").scheme
    'sim'
    """
    if not isinstance(url, str) or not url.strip():
        raise ParameterError(f"The 'url' parameter of open_rig must be a rig name or URL. Got {url!r} instead.")
    text = url.strip()
    if "://" not in text:
        scheme, _, query = text.partition("?")
        rest = ""
    else:
        scheme, _, rest = text.partition("://")
        rest, _, query = rest.partition("?")
    if not (text.isprintable() and urllib.parse.unquote(rest).isprintable()):  # messages quote the URL as given
        raise ParameterError(
            f"The 'url' parameter of open_rig must be printable text (no newline or control character, also not "
            f"%-encoded). Got {url!r} instead."
        )
    scheme = scheme.lower()
    if scheme not in BACKENDS:
        raise ParameterError(
            f"The 'url' parameter of open_rig must start with one of {sorted(BACKENDS)}. Got {url!r} instead."
        )
    options: dict[str, str] = {}
    for key, value in urllib.parse.parse_qsl(query, keep_blank_values=True):
        if key in options:
            raise ParameterError(f"{url}: option {key!r} is given twice ({options[key]!r} and {value!r})")
        options[key] = value
    return RigURL(scheme, urllib.parse.unquote(rest), options)


def _backend_module(scheme: str):
    module_name, _, factory = BACKENDS[scheme].partition(":")
    module = import_module(module_name)
    return module, getattr(module, factory)


def rig_url_options(url: str | RigURL, **given: Any) -> tuple[RigURL, dict[str, Any]]:
    """Check a rig URL's options (and keyword ``given`` by Python) against its backend's declarations.

    Returns the parsed URL and the options as typed values: the URL's, merged with ``given``. An option the
    backend does not declare is refused by name (listing those it takes), a value of the wrong type or out of
    range is refused naming the option and what was expected, and an option given both in the URL and as a
    keyword with different values is refused (neither silently wins). Nothing is opened.

    Examples
    --------
    >>> rig_url_options("sim?seed=0&orientation=horizontal")[1]
    {'seed': 0, 'orientation': 'horizontal'}
    >>> rig_url_options("sim?bogus=1")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    flexdigit.errors.ParameterError: sim: unknown option 'bogus'; a sim URL takes seed, ...
    """
    parsed = url if isinstance(url, RigURL) else parse_rig_url(url)
    module, _ = _backend_module(parsed.scheme)
    declared = {opt.name: opt for opt in getattr(module, "URL_OPTIONS", ())}
    python_only = set(getattr(module, "PYTHON_OPTIONS", ()))
    prefixes = tuple(getattr(module, "URL_PREFIXES", ()))
    where = parsed.where
    takes = ", ".join(declared) if declared else "no options"
    out: dict[str, Any] = {}
    for key, text in parsed.options.items():
        if prefixes and key.startswith(prefixes):
            out[key] = text  # a nested source's option, checked by its own backend
            continue
        if key not in declared:
            raise ParameterError(f"{where}: unknown option {key!r}; a {parsed.scheme} URL takes {takes}")
        out[key] = declared[key].convert(text, where)
    for key, value in given.items():
        if key in declared:
            value = declared[key].convert(value, where)
            if key in out and out[key] != value:
                raise ParameterError(
                    f"{where}: option {key} is {out[key]!r} in the URL but {value!r} was also asked for; give it once"
                )
        elif key not in python_only:
            raise ParameterError(f"{where}: unknown option {key!r}; a {parsed.scheme} URL takes {takes}")
        out[key] = value
    return parsed, out


def seed_option(url: str, seed: int | None) -> dict[str, int]:
    """The options that pass a command line's ``--seed`` to a rig: ``{}`` when it was not given (None).

    The seed drives the twin's noise; a hardware backend has none, so ``--seed`` with one is refused rather than
    ignored. A seed also in the URL must agree (:func:`rig_url_options` refuses ``sim?seed=5 --seed 0``).
    """
    if seed is None:
        return {}
    parsed = parse_rig_url(url)
    module, _ = _backend_module(parsed.scheme)
    if "seed" not in {opt.name for opt in getattr(module, "URL_OPTIONS", ())}:
        raise ParameterError(f"--seed {seed}: the {parsed.scheme} backend has no random noise to seed (the twin does)")
    return {"seed": seed}


def open_rig(url: str = "sim", params: RigParams | None = None, **options: Any) -> Rig:
    """Open a rig backend by name or URL (see the module docstring).

    Keyword ``options`` are the URL's options given from Python (``seed=3``) or Python-only ones (``clock``,
    ``sleep``, ``operator``, ``serial`` ...); every one is checked by :func:`rig_url_options`, and one given both
    ways must agree. The ``sim`` twin of ``params`` runs on the ``calibration`` option if given, else on the one
    default the CLI uses too (:func:`~flexdigit.twin.digit_calibration.twin_calibration`: the packaged thesis fit
    for the thesis rig, the thesis's scaled to any other digit).

    Examples
    --------
    >>> with open_rig("sim", seed=0) as rig:  # the twin, in virtual time
    ...     sent = rig.write_command(300)  # clamped to the board's range
    ...     rig.wait(0.5)
    ...     reading = rig.read()
    >>> sent, reading.time_s, reading.command, reading.gauges_v.shape
    (254, 0.5, 254, (3,))
    """
    parsed, merged = rig_url_options(url, **options)
    _, factory = _backend_module(parsed.scheme)
    return factory(parsed.location, params, merged)
