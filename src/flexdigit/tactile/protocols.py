"""Load experiments as data: the thesis's tables 6.1 and 7.1 and user-defined protocols in TOML.

A protocol says which loads are hung where on the digit, at which actuation commands, how many times each is
read and how long to let the digit settle. :meth:`Protocol.plan` turns it into the ordered list of samples the
runner takes: for every test (one load, or one (load, command) pair when actuated) the no-load readings first
("a no load condition was measured at the start of every test", 6.5, 7.2), then each position from the tip,
read ``repetitions`` times; with ``tare_each_position`` (a protocol TOML's default) the no-load readings come
before every position instead, a tare per position.

Built-in protocols live in ``tactile/protocols/*.toml``: ``thesis-6.1`` (1275 samples), ``thesis-7.1``
(1500 samples, as printed) and ``thesis-7.1-no-load`` (1650: the no-load readings the text mentions but the
printed count leaves out).

Examples
--------
>>> p = load_protocol("thesis-6.1")
>>> p.sample_count, len(p.positions_from_tip_m), p.loads_kg
(1275, 16, (0.0125, 0.025, 0.0075))
>>> load_protocol("thesis-7.1").sample_count
1500
"""

from __future__ import annotations

import hashlib
import json
import tomllib
from dataclasses import asdict, dataclass, replace
from importlib import resources
from pathlib import Path

import numpy as np

from flexdigit._io import read_text, refuse_special
from flexdigit._validation import (
    Plausible,
    check_array,
    check_choice,
    check_int,
    check_param,
    check_plausible,
    check_real,
)
from flexdigit.errors import ParameterError
from flexdigit.params import LOAD_KG, POSITION_FROM_TIP_M, RigParams

__all__ = [
    "builtin_protocols",
    "RELAXED",
    "MAX_SETTLE_S",
    "REFINE",
    "REFINE_MAX",
    "HELD_OUT_MIN_POSITIONS",
    "BUILTIN",
    "Protocol",
    "protocol_from_toml",
    "load_protocol",
]

#: The ``command`` recorded when actuation is disabled (the servo relaxed, chapter 6).
RELAXED = -1

#: Most steps :meth:`Protocol.refined` cuts one protocol step into (``collect --refine``): at 25, one of
#: thesis-6.1's 25 readings a position is left
REFINE_MAX = 25
REFINE = Plausible("", 1, REFINE_MAX, "steps per protocol step: 25 leaves one of thesis-6.1's 25 readings a position",
                   integer=True)  # fmt: skip

#: :func:`~flexdigit.tactile.pipeline.held_out_positions_split`: the fewest distinct positions it splits (two ends
#: kept, two held out between); here, beside the protocols, as :func:`~flexdigit.tactile.refinement.refinement_for`
#: refines only a protocol a network is scored on held-out positions of (its import stays light)
HELD_OUT_MIN_POSITIONS = 5

#: Longest settle time (and reading interval) a protocol or ``collect --settle`` takes, s: an hour.
MAX_SETTLE_S = 3600.0
#: Time between the repeated readings of one setting: the rig's loop is 20 ms; 10 s is generous, and a 20 "s"
#: interval is 20 ms written in the wrong unit.
SAMPLE_INTERVAL_S = Plausible("s", 0.0, 10.0, "between repeated readings: the rig's loop period is 0.02 s")

#: Names of the protocols packaged in ``tactile/protocols``.
BUILTIN = ("thesis-6.1", "thesis-7.1", "thesis-7.1-no-load")

_KEYS = {
    "name",
    "description",
    "thesis_ref",
    "orientation",
    "loads_g",
    "positions_from_tip_cm",
    "actuation_commands",
    "repetitions",
    "no_load_repetitions",
    "settle_s",
    "sample_interval_s",
    "rehang",
    "wait_until_steady",
    "tare_each_position",
    "expected_samples",
}


@dataclass(frozen=True)
class Protocol:
    """One load experiment.

    Parameters
    ----------
    name : str
        Short identifier, recorded in every dataset.
    loads_kg : tuple of float
        Point loads hung on the digit, one test each, in order (kg).
    positions_from_tip_m : tuple of float
        Load positions measured from the tip, in order (m); position index 1 is the first (table 6.1).
    actuation_commands : tuple of int
        Servo commands (0..254) held during the readings; empty means actuation disabled (servo relaxed).
    repetitions : int
        Readings per (load, position, command).
    no_load_repetitions : int
        No-load readings at the start of every test.
    settle_s : float
        Time allowed after every change of load, position or command before reading (s).
    sample_interval_s : float
        Time between the repeated readings of one setting (s).
    rehang : bool
        Lift and re-hang the weight before every repetition of a loaded setting, as the thesis repeats "the
        procedure" 25 times at each position and weight (6.4, 7.1); each reading then sees the cable settle in
        its guides afresh (:meth:`flexdigit.rig.base.Rig.rehang`). False: read repeatedly after one hang.
    orientation : {"horizontal", "vertical"}
        How the digit lies; the thesis's tactile experiments are horizontal (7, intro).
    wait_until_steady : bool
        After ``settle_s`` (and after every re-hang), keep reading until the gauges are steady before the readings
        are taken, as an experimenter waits for a still reading (a balance's stability indicator): a lightly
        damped digit still swinging after ``settle_s`` would put its swing into the readings, which no Bayes limit
        on the gauges' noise counts (:func:`flexdigit.tactile.runner.wait_until_steady`). A protocol TOML turns it
        on unless it says ``wait_until_steady = false``, as the thesis's built-in protocols do (their fixed settle
        time: their datasets are unchanged); here, and for a stored protocol written before the option, it is off
        (a fixed settle time, the readings as they always were).
    tare_each_position : bool
        Take the ``no_load_repetitions`` no-load readings before every position (the load lifted, the digit
        settled), not only at the start of every test: each loaded reading is then tared on the unloaded one just
        before it (:func:`flexdigit.tactile.localisation.tare`), as a lab zeroes a balance before each weighing,
        so the gauges' drift over a long run (a random walk: 1.4 times the white noise over 200 s on the thesis's
        chain) leaves the readings (a one-gauge digit's network was 1.44 x its Bayes limit with the drift in its
        readings, 0.99 without). ``flexdigit train`` and ``predict`` tare such a dataset's readings. A protocol
        TOML with no-load readings turns it on unless it says ``tare_each_position = false``, as the thesis's
        built-in protocols do ("a no load condition was measured at the start of every test", 6.5, 7.2); here,
        and for a stored protocol written before the option, it is off.
    description, thesis_ref : str
        Free text.
    """

    name: str
    loads_kg: tuple[float, ...]
    positions_from_tip_m: tuple[float, ...]
    actuation_commands: tuple[int, ...] = ()
    repetitions: int = 25
    no_load_repetitions: int = 25
    settle_s: float = 1.0
    sample_interval_s: float = 0.02
    rehang: bool = False
    orientation: str = "horizontal"
    wait_until_steady: bool = False
    tare_each_position: bool = False
    description: str = ""
    thesis_ref: str = ""

    def __post_init__(self) -> None:
        owner = f"Protocol {self.name!r}"
        if not isinstance(self.name, str) or not self.name.strip():
            raise ParameterError(f"The 'name' parameter of Protocol must be a non-empty string. Got {self.name!r}.")
        loads = check_array(self.loads_kg, "loads_kg", owner, ndim=1, min_length=1, low=0, low_open=True, high=10)
        check_plausible(loads, LOAD_KG, "loads_kg", owner)
        positions = check_array(
            self.positions_from_tip_m, "positions_from_tip_m", owner, ndim=1, min_length=1, low=0, high=10
        )
        check_plausible(positions, POSITION_FROM_TIP_M, "positions_from_tip_m", owner)
        if len(set(positions.tolist())) != positions.size:
            raise ParameterError(
                f"The 'positions_from_tip_m' parameter of {owner} must not repeat a position. "
                f"Got {positions.tolist()!r} instead."
            )
        commands = tuple(check_int(c, "actuation_commands", owner, low=0, high=254) for c in self.actuation_commands)
        object.__setattr__(self, "loads_kg", tuple(float(v) for v in loads))
        object.__setattr__(self, "positions_from_tip_m", tuple(float(v) for v in positions))
        object.__setattr__(self, "actuation_commands", commands)
        object.__setattr__(self, "repetitions", check_int(self.repetitions, "repetitions", owner, low=1, high=100_000))
        object.__setattr__(
            self,
            "no_load_repetitions",
            check_int(self.no_load_repetitions, "no_load_repetitions", owner, low=0, high=100_000),
        )
        object.__setattr__(self, "settle_s", check_real(self.settle_s, "settle_s", owner, low=0, high=MAX_SETTLE_S))
        object.__setattr__(
            self,
            "sample_interval_s",
            check_param(self.sample_interval_s, SAMPLE_INTERVAL_S, "sample_interval_s", owner),
        )
        check_choice(self.orientation, "orientation", ("horizontal", "vertical"), owner)
        if self.tare_each_position is True and self.no_load_repetitions == 0:
            raise ParameterError(
                f"The 'tare_each_position' parameter of {owner} needs no-load readings to tare on: "
                "'no_load_repetitions' is 0 (give it > 0, or tare_each_position = false)."
            )
        for key in ("rehang", "wait_until_steady", "tare_each_position"):
            if not isinstance(getattr(self, key), bool):
                raise ParameterError(
                    f"The '{key}' parameter of {owner} must be true or false. Got {getattr(self, key)!r}."
                )

    @property
    def actuated(self) -> bool:
        """Whether the servo holds a command during the readings (chapter 7) or is relaxed (chapter 6)."""
        return bool(self.actuation_commands)

    @property
    def tests(self) -> list[tuple[float, int]]:
        """The tests in order: ``(load_kg, command)``, command :data:`RELAXED` when not actuated.

        Commands outer, loads inner: each command is set once and held while the weights change (three servo
        moves for table 7.1 instead of six, always upwards). The thesis does not give the order.
        """
        commands = self.actuation_commands or (RELAXED,)
        return [(load, command) for command in commands for load in self.loads_kg]

    @property
    def sample_count(self) -> int:
        """Number of samples the protocol takes (1275 for table 6.1, 1500 for table 7.1)."""
        positions = len(self.positions_from_tip_m)
        tares = positions if self.tare_each_position else 1
        return len(self.tests) * (tares * self.no_load_repetitions + positions * self.repetitions)

    def plan(self, digit_length_m: float) -> dict[str, np.ndarray]:
        """The ordered samples: one array per column, ``sample_count`` long.

        Parameters
        ----------
        digit_length_m : float
            Clamp to tip (m), to turn positions from the tip into positions from the base.

        Returns
        -------
        dict of ndarray
            ``sample``, ``test``, ``load_kg``, ``position_index`` (0 for no load, 1.. as table 6.1),
            ``position_from_tip_m`` and ``position_from_base_m`` (NaN for no load), ``command``
            (:data:`RELAXED` when not actuated) and ``repetition``.
        """
        length = check_real(digit_length_m, "digit_length_m", "Protocol.plan", low=0, low_open=True)
        too_far = [p for p in self.positions_from_tip_m if p > length]
        if too_far:
            # Beyond the tip is certainly wrong; if a tenth of every position lies on the digit, the likely slip is
            # positions in mm written where cm are read (positions_from_tip_cm = [0, 20, .., 180]: 1.8 m). The
            # converse, positions in cm read as mm (all within a tenth of the digit), has no sound rule: a protocol
            # that loads only the tip's first 2.7 cm (0, 1, 2 cm) is a legitimate experiment (notes in #22).
            tenth = max(self.positions_from_tip_m) / 10
            slip = (
                f": did you mean mm written as cm (a tenth of each: 0 to {tenth:g} m)?"
                if tenth <= length and self.positions_from_tip_m
                else "."
            )
            raise ParameterError(
                f"The 'positions_from_tip_m' parameter of Protocol {self.name!r} must lie on the digit "
                f"(0 to {length:g} m from the tip). Got {too_far!r} instead{slip}"
            )
        rows: list[tuple] = []
        for test, (load, command) in enumerate(self.tests):
            for index, pos in enumerate(self.positions_from_tip_m, start=1):
                if index == 1 or self.tare_each_position:
                    for rep in range(self.no_load_repetitions):
                        rows.append((test, 0.0, 0, np.nan, command, rep))
                for rep in range(self.repetitions):
                    rows.append((test, load, index, pos, command, rep))
        cols = list(zip(*rows, strict=True))
        tip = np.array(cols[3], dtype=float)
        return {
            "sample": np.arange(len(rows), dtype=np.int64),
            "test": np.array(cols[0], dtype=np.int64),
            "load_kg": np.array(cols[1], dtype=float),
            "position_index": np.array(cols[2], dtype=np.int64),
            "position_from_tip_m": tip,
            "position_from_base_m": length - tip,
            "command": np.array(cols[4], dtype=np.int64),
            "repetition": np.array(cols[5], dtype=np.int64),
        }

    def scaled_to(self, digit_length_m: float, reference_length_m: float = 0.270) -> Protocol:
        """This protocol on a digit ``digit_length_m`` long: every position from the tip times
        ``digit_length_m / reference_length_m`` (the thesis digit's 0.27 m by default), the same fractions of the
        digit (as the design study probes its digits); itself when the lengths agree.

        Examples
        --------
        >>> p = load_protocol("thesis-6.1").scaled_to(0.135)
        >>> p.name, p.positions_from_tip_m[1] == load_protocol("thesis-6.1").positions_from_tip_m[1] / 2
        ('thesis-6.1 on 0.135 m', True)
        """
        length = check_real(digit_length_m, "digit_length_m", "Protocol.scaled_to", low=0, low_open=True)
        ref = check_real(reference_length_m, "reference_length_m", "Protocol.scaled_to", low=0, low_open=True)
        if length == ref:
            return self
        positions = tuple(round(p * length / ref, 9) for p in self.positions_from_tip_m)
        return replace(self, name=f"{self.name} on {length:g} m", positions_from_tip_m=positions)

    def refined(self, factor: int) -> Protocol:
        """This protocol with ``factor`` positions where it has one step: every gap between two neighbouring
        positions of its evenly spaced run (a gap within 1.5 median gaps, as
        :func:`~flexdigit.tactile.pipeline.held_out_positions_split` reads them) cut into ``factor`` equal steps,
        an isolated position (thesis-6.1's 24 cm) kept as it is, and the repetitions divided by ``factor``
        (rounded up) so the run takes about as many readings; itself for ``factor`` 1.

        A network is scored on held-out positions between its training ones (``train --split positions``): two
        protocol steps apart on thesis-6.1, 7-13 mm on the hand-made digits, where a digit that resolves a tenth of
        a millimetre (its Bayes limit) cannot be interpolated to its limit (a gauge's kink where the load passes it
        falls between two training positions). ``flexdigit collect --refine K``.

        Examples
        --------
        >>> p = load_protocol("thesis-6.1").refined(4)
        >>> len(p.positions_from_tip_m), p.repetitions, round(p.positions_from_tip_m[1], 6), p.sample_count
        (58, 7, 0.0025, 1293)
        """
        factor = check_int(factor, "factor", f"Protocol {self.name!r}.refined", low=1, high=REFINE_MAX)
        if factor == 1:
            return self
        tips = np.sort(np.asarray(self.positions_from_tip_m))
        gaps = np.diff(tips)
        near = gaps <= 1.5 * float(np.median(gaps)) if gaps.size else gaps.astype(bool)
        inserted = [a + (b - a) * k / factor for a, b, n in zip(tips[:-1], tips[1:], near, strict=True) if n
                    for k in range(1, factor)]  # fmt: skip
        positions = tuple(round(float(p), 9) for p in sorted({*self.positions_from_tip_m, *inserted}))
        return replace(
            self,
            name=f"{self.name} refined x{factor}",
            positions_from_tip_m=positions,
            repetitions=-(-self.repetitions // factor),
        )

    def commands_on(self, params: RigParams) -> Protocol:
        """This protocol at the digit ``params``'s own commands: each of the thesis's actuation commands
        (:func:`digit_commands`), the same fraction of the digit's operating range from its straight command as of
        the thesis rig's 8..43 (so a cable pair bends both ways); itself when they are the thesis's.

        Examples
        --------
        >>> from flexdigit.params import RigParams
        >>> load_protocol("thesis-7.1").commands_on(RigParams()).actuation_commands  # the thesis rig: as printed
        (0, 20, 40)
        """
        commands = digit_commands(self.actuation_commands, params)
        if commands == self.actuation_commands:
            return self
        listed = "/".join(str(c) for c in commands)
        return replace(self, name=f"{self.name} at commands {listed}", actuation_commands=commands)

    def to_dict(self) -> dict:
        """Plain dict (lists for tuples), as stored in datasets and journals."""
        return {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(self).items()}

    @property
    def fingerprint(self) -> str:
        """A short hash of everything that decides which samples are taken (not the free text)."""
        d = self.to_dict()
        key = {k: d[k] for k in ("loads_kg", "positions_from_tip_m", "actuation_commands", "repetitions")}
        key["no_load_repetitions"] = d["no_load_repetitions"]
        for option in ("wait_until_steady", "tare_each_position"):
            if getattr(self, option):  # only when on: the thesis protocols' fingerprints are the ones they had
                key[option] = True
        return hashlib.sha256(json.dumps(key, sort_keys=True).encode()).hexdigest()[:16]

    @classmethod
    def from_dict(cls, data: dict) -> Protocol:
        """Inverse of :meth:`to_dict`; an unknown key is named (as its repr: a stored key may hold a newline)."""
        unknown = sorted(set(data) - set(cls.__dataclass_fields__))
        if unknown:
            raise ParameterError(f"unknown protocol key {unknown[0]!r}")
        fields = {k: tuple(v) if isinstance(v, list) else v for k, v in data.items()}
        return cls(**fields)


def protocol_from_toml(text: str, source: str = "protocol") -> Protocol:
    """Build a protocol from TOML text (units as in the thesis tables: grams and centimetres).

    Keys: ``name``, ``loads_g``, ``positions_from_tip_cm`` (required); ``actuation_commands`` (default ``[]``,
    actuation disabled), ``repetitions`` (25), ``no_load_repetitions`` (25), ``settle_s`` (1.0),
    ``sample_interval_s`` (0.02), ``rehang`` (false), ``wait_until_steady`` (true), ``tare_each_position`` (true
    when ``no_load_repetitions`` > 0),
    ``orientation`` ("horizontal"), ``description``, ``thesis_ref``,
    ``expected_samples`` (checked if given).

    Raises
    ------
    ParameterError
        Naming ``source``, the key and what was expected.
    """
    try:
        data = tomllib.loads(text)
    except (tomllib.TOMLDecodeError, RecursionError) as exc:  # RecursionError: nested past the parser
        raise ParameterError(f"{source}: not valid TOML ({exc})") from None
    unknown = sorted(set(data) - _KEYS)
    if unknown:
        raise ParameterError(f"{source}: unknown key {unknown[0]!r}; expected some of " + ", ".join(sorted(_KEYS)))
    for key in ("name", "loads_g", "positions_from_tip_cm"):
        if key not in data:
            raise ParameterError(f"{source}: missing key '{key}'")
    for key in ("loads_g", "positions_from_tip_cm", "actuation_commands"):
        if key in data and not isinstance(data[key], list):
            raise ParameterError(f"{source}: '{key}' must be a list. Got {data[key]!r} instead.")
    try:
        loads = check_array(data["loads_g"], "loads_g", source, ndim=1, min_length=1, low=0, low_open=True)
        check_plausible(loads, LOAD_KG.to("g", 1e3), "loads_g", "the protocol")  # a load in kg written as g: named
        tips = check_array(data["positions_from_tip_cm"], "positions_from_tip_cm", source, ndim=1, min_length=1, low=0)
        check_plausible(tips, POSITION_FROM_TIP_M.to("cm", 1e2), "positions_from_tip_cm", "the protocol")
        protocol = Protocol(
            name=data["name"],
            loads_kg=tuple(float(v) / 1000.0 for v in loads),
            positions_from_tip_m=tuple(float(v) / 100.0 for v in tips),
            actuation_commands=tuple(data.get("actuation_commands", ())),
            repetitions=data.get("repetitions", 25),
            no_load_repetitions=data.get("no_load_repetitions", 25),
            settle_s=data.get("settle_s", 1.0),
            sample_interval_s=data.get("sample_interval_s", 0.02),
            rehang=data.get("rehang", False),
            wait_until_steady=data.get("wait_until_steady", True),
            # on wherever there are no-load readings to tare on
            tare_each_position=data.get("tare_each_position", data.get("no_load_repetitions", 25) != 0),
            orientation=data.get("orientation", "horizontal"),
            description=str(data.get("description", "")),
            thesis_ref=str(data.get("thesis_ref", "")),
        )
    except ParameterError as exc:
        raise ParameterError(f"{source}: {exc}") from None
    expected = data.get("expected_samples")
    if expected is not None and expected != protocol.sample_count:
        raise ParameterError(
            f"{source}: 'expected_samples' is {expected!r} but the protocol takes {protocol.sample_count} samples"
        )
    return protocol


#: The thesis rig's straight command and operating range, the frame the built-in protocols' commands are written
#: in (8 and 8..43: 0 to 30 deg of beam rotation, 3.4.1).
THESIS_STRAIGHT_COMMAND, THESIS_OPERATING_COMMANDS = 8, (8, 43)


def digit_commands(commands, params: RigParams) -> tuple[int, ...]:
    """The thesis rig's actuation ``commands`` (table 7.1's 0, 20, 40) laid out on the digit ``params``: each the
    same fraction of the operating range from the straight command as on the thesis rig (``f = (c - 8) / 35``),
    to its top for ``f >= 0`` and, below straight, to its bottom on a cable pair (bending the other way) or, on a
    single cable, as far again as the thesis's command 0 (the cable slack), rounded and kept within the servo's
    range. The thesis rig's, and any digit with its straight command and operating range, get them back.

    Examples
    --------
    >>> from dataclasses import replace
    >>> from flexdigit.params import RigParams
    >>> pair = RigParams().replace(actuator=replace(RigParams().actuator, equilibrium_command=127,
    ...                                              operating_commands=(92, 162)))
    >>> digit_commands((0, 20, 40), pair)   # 127 - 8, 127 + 12, 127 + 32: both ways
    (119, 139, 159)
    """
    a = params.actuator
    straight = int(a.equilibrium_command)
    low, high = (int(c) for c in a.operating_commands)
    t_low, t_high = THESIS_OPERATING_COMMANDS
    up = high - straight
    down = straight - low if low < straight else up  # a single cable: slack below straight, as far as above
    out = []
    for c in commands:
        frac = (int(c) - THESIS_STRAIGHT_COMMAND) / (t_high - THESIS_STRAIGHT_COMMAND)
        moved = straight + frac * (up if frac >= 0 else down)
        out.append(int(min(max(np.floor(moved + 0.5), a.command_min), a.command_max)))
    return tuple(out)


def load_protocol(name_or_path: str | Path, params: RigParams | None = None) -> Protocol:
    """A built-in protocol by name (see :data:`BUILTIN`) or a user protocol from a TOML file.

    Parameters
    ----------
    name_or_path : str or path
    params : RigParams, optional
        The digit it will run on. A built-in protocol's positions are then scaled to the digit's length (the same
        fractions of it, :meth:`Protocol.scaled_to`) and its commands laid out on the digit's operating range
        (:meth:`Protocol.commands_on`), and any protocol is checked against the digit (its positions
        on it, :meth:`Protocol.plan`) before a rig opens: the protocol ``flexdigit collect PROTOCOL --params FILE``
        runs. None: the protocol as written.

    Raises
    ------
    ParameterError
        If the name is unknown and no such file exists, the file is invalid, or a position lies off the digit.

    Examples
    --------
    >>> from flexdigit.params import RigParams
    >>> load_protocol("thesis-6.1", RigParams()) == load_protocol("thesis-6.1")  # the thesis digit: as written
    True
    """
    protocol = _read_protocol(name_or_path)
    if params is None:
        return protocol
    length_m = params.geometry.digit_length_m
    if str(name_or_path) in BUILTIN:
        protocol = protocol.scaled_to(length_m).commands_on(params)
    protocol.plan(length_m)
    return protocol


def _read_protocol(name_or_path: str | Path) -> Protocol:
    text_name = str(name_or_path)
    if text_name in BUILTIN:
        resource = resources.files(__package__).joinpath("protocols", f"{text_name}.toml")
        return protocol_from_toml(resource.read_text(), source=f"protocol {text_name}")
    path = Path(name_or_path)
    refuse_special(path, "a protocol TOML")
    if not path.is_file():
        raise ParameterError(
            f"no protocol {text_name!r}: expected one of {', '.join(BUILTIN)} or a TOML file that exists"
        )
    return protocol_from_toml(read_text(path, "a protocol TOML"), source=str(path))


def builtin_protocols() -> dict[str, str]:
    """The built-in load protocols (:data:`BUILTIN`), each with its one-line description.

    Examples
    --------
    >>> builtin_protocols()["thesis-6.1"][:21]
    'Non-actuated digit: l'
    """
    return {name: load_protocol(name).description for name in BUILTIN}
