"""Tissue and palpation-protocol files (TOML): read, validate, name the culprit.

A tissue file has one ``[tissue]`` table (``name``, ``description``, ``side``, ``start_mm``, ``end_mm``, and, to
place it on the twin, ``gap_mm``, ``modulus_n_m2``, ``exponent``, ``damping_s_m``; ``[[tissue.inclusions]]``
with ``centre_mm``, ``width_mm``, ``ratio``). A protocol file has any of ``[sweep]`` (``commands`` as a list or
``{from, to, step}``, ``settle_s``, ``readings``, ``tare_command``, ``period_s``, ``model``), ``[scan]``
(``offsets_mm``, ``inclusion_width_mm``) and ``[force]`` (``setpoint_n``, ``duration_s``, ``gain``,
``approach_rate``). Built-in files (``palpation/palpation_data``) are named without ``.toml``: tissues
``soft-block``, ``nodule-phantom``, ``hertzian-block``; protocols ``sweep``, ``scan``, ``hold``. The built-in
protocols' commands (and those a file leaves out) are the thesis rig's, counted from its straight command 8: on
another digit they are laid out from its straight command, as far in tip rotation
(:func:`~flexdigit.palpation.palpation.digit_protocol`).

Every problem is one :class:`~flexdigit.errors.DataFileError` naming the file, the key and what was expected,
e.g. ``tissue.toml: key 'tissue.gap_mm' must be a real number (mm); got 'far'``.

Examples
--------
>>> tissue, _ = load_tissue("soft-block")
>>> tissue.modulus_n_m2, round(tissue.gap_m, 3)
(1000.0, 0.03)
>>> load_palpation_protocol("scan").scan["offsets_m"][:3]
(-0.04, -0.03, -0.02)
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

from flexdigit._io import read_text, refuse_special
from flexdigit._validation import Plausible, _interval_text, unit_slip
from flexdigit.errors import DataFileError, ParameterError
from flexdigit.palpation.palpation import PalpationProtocol
from flexdigit.twin.contact import Inclusion, Tissue

__all__ = [
    "builtin_palpation_files",
    "TISSUES",
    "PROTOCOLS",
    "MAX_SERIES",
    "TissueFile",
    "load_tissue",
    "PalpationFile",
    "load_palpation_protocol",
]

TISSUES = ("soft-block", "nodule-phantom", "hertzian-block")
PROTOCOLS = ("sweep", "scan", "hold")

_TISSUE_KEYS = {
    "name",
    "description",
    "side",
    "start_mm",
    "end_mm",
    "gap_mm",
    "modulus_n_m2",
    "exponent",
    "damping_s_m",
    "inclusions",
}
_INCLUSION_KEYS = {"centre_mm", "width_mm", "ratio"}

# Plausible ranges (flexdigit._validation.Plausible): generous for a user's own phantom or tissue, each with its
# reason, so that a value 1e308 or a thousand times off (mm written as m) is refused naming the likely slip.
#: Along the digit from its base: a digit is at most 2 m long (params.DIGIT_LENGTH_M); a body may reach past it.
ALONG_DIGIT_MM = Plausible("mm", -2000.0, 4000.0, "along a digit at most 2 m long, from its base")
#: A tissue's extent (end - start): shorter than 1 cm it is an inclusion of a body, not the body (and a body in m
#: written as mm, under 1 m long, is then named as the m slip, not the cm one).
TISSUE_LENGTH_MM = Plausible("mm", 10.0, 4000.0, "a body 1 cm to 4 m long beside the digit")
#: An inclusion's width: below 1 mm the digit's own width (a few mm) spans it: palpation cannot tell it.
INCLUSION_WIDTH_MM = Plausible("mm", 1.0, 2000.0, "a nodule 1 mm to 2 m wide")
#: Surface to the straight digit's axis: within reach of a 2 m digit (0 touches it, negative starts pressed in).
GAP_MM = Plausible("mm", -2000.0, 2000.0, "within reach of a digit at most 2 m long")
#: Foundation modulus (N/m^2 for exponent 1): a wisp of foam (1 N/m^2: 0.01 N/m per cm pressed in) to steel
#: under the strip; the thesis phantoms are 1e3 and 2e4.
MODULUS_N_M2 = Plausible("N/m^2", 1.0, 1e10, "1 (a wisp of foam) to 1e10 (steel); the phantoms are 1e3 to 2e4")
INCLUSION_RATIO = Plausible("", 1e-3, 1e3, "an inclusion a thousand times softer to a thousand times stiffer")
DAMPING_S_M = Plausible("s/m", 0.0, 100.0, "Hunt-Crossley alpha: tissues 0.1 to 10 s/m")
SETTLE_S = Plausible("s", 0.0, 3600.0, "settle time per setting: an hour at most")
PERIOD_S = Plausible("s", 1e-4, 1.0, "the loop's period: 0.1 ms to 1 s (the thesis: 20 ms)")
SCAN_OFFSET_MM = Plausible("mm", -2000.0, 2000.0, "moves along a digit at most 2 m long")
#: A scan's offsets span (max - min): below 1 mm they are one position (a scan in m written as mm).
SCAN_SPAN_MM = Plausible("mm", 1.0, 4000.0, "a scan across 1 mm to 4 m of the digit")
SETPOINT_N = Plausible("N", 1e-4, 2.0, "a contact force of 0.1 mN to 2 N: the digit's gauges read ~0.1 N")
DURATION_S = Plausible("s", 1e-3, 86_400.0, "a hold of 1 ms to a day")
FORCE_GAIN = Plausible("commands / s / N", 1e-3, 1e5, "an integral gain (the thesis rig's: 30)")
APPROACH_RATE = Plausible("commands / s", 1e-3, 1e4, "commands per second until contact (the thesis rig's: 4)")
#: Most values a ``{from, to, step}`` series may expand to (a staircase has at most 255 commands).
MAX_SERIES = 10_000
_SECTIONS = {
    "sweep": {"commands", "settle_s", "readings", "tare_command", "period_s", "model"},
    "scan": {"offsets_mm", "inclusion_width_mm"},
    "force": {"setpoint_n", "duration_s", "gain", "approach_rate"},
}


class _Table:
    """Typed access to one TOML table that names the file and the dotted key in every error."""

    def __init__(self, data, source: str, prefix: str, allowed) -> None:
        if not isinstance(data, dict):
            raise DataFileError(f"{source}: '{prefix}' must be a table. Got {data!r}.")
        unknown = sorted(set(data) - set(allowed))
        if unknown:
            raise DataFileError(
                f"{source}: unknown key {f'{prefix}.{unknown[0]}'!r}; expected some of {', '.join(sorted(allowed))}"
            )
        self.data, self.source, self.prefix = data, source, prefix

    def where(self, key: str) -> str:
        return f"{self.source}: key '{self.prefix}.{key}'"

    def real(self, key, *, default=None, low=None, high=None, low_open=False, unit=""):
        if key not in self.data:
            if default is None:
                raise DataFileError(f"{self.where(key)} is missing")
            return default
        value = self.data[key]
        text = f" ({unit})" if unit else ""
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
            raise DataFileError(f"{self.where(key)} must be a real number{text}; got {value!r}")
        if (low is not None and (value < low or (low_open and value == low))) or (high is not None and value > high):
            left = "(" if low_open or low is None else "["
            bounds = f"{left}{'-inf' if low is None else low}, {'inf)' if high is None else f'{high}]'}"
            raise DataFileError(f"{self.where(key)} must be inside {bounds}{text}; got {value!r}")
        return float(value)

    def plausible(self, key, declared: Plausible, *, default=None):
        """A real number (:meth:`real`) inside its declared plausible range, or one line naming the likely slip."""
        value = self.real(key, default=default, unit=declared.unit)
        return value if key not in self.data else self.declared(self.where(key), value, declared)

    def declared(self, where: str, value: float, declared: Plausible) -> float:
        """``value`` (a key's or a quantity derived from keys) if ``declared`` is satisfied; else one line."""
        if declared.satisfied_by(value):
            return float(value)
        interval = _interval_text(declared.low, declared.high, declared.low_open, declared.high_open).strip()
        unit = f" {declared.unit}" if declared.unit else ""
        slip = unit_slip(value, declared.unit, declared.low, declared.high)
        tail = f": did you mean {slip}?" if slip else ""
        raise DataFileError(f"{where} must be {interval}{unit} ({declared.why}); got {value!r}{unit}{tail}")

    def optional_real(self, key, **kw):
        return self.real(key, **kw) if key in self.data else None

    def integer(self, key, *, default=None, low=None, high=None):
        if key not in self.data:
            if default is None:
                raise DataFileError(f"{self.where(key)} is missing")
            return default
        value = self.data[key]
        if (
            isinstance(value, bool)
            or not isinstance(value, int)
            or (low is not None and value < low)
            or (high is not None and value > high)
        ):
            raise DataFileError(f"{self.where(key)} must be an integer inside [{low}, {high}]; got {value!r}")
        return int(value)

    def text(self, key, *, default="", choices=None):
        value = self.data.get(key, default)
        if not isinstance(value, str) or (choices is not None and value not in choices):
            expected = f"one of {', '.join(map(repr, choices))}" if choices else "a string"
            raise DataFileError(f"{self.where(key)} must be {expected}; got {value!r}")
        return value

    def series(self, key, *, integer=False, default=None, unit=""):
        """A list of numbers, or ``{from, to, step}`` (inclusive of ``to``)."""
        if key not in self.data:
            if default is None:
                raise DataFileError(f"{self.where(key)} is missing")
            return default
        value = self.data[key]
        kind = "integers" if integer else "numbers"
        if isinstance(value, dict):
            inner = _Table(value, self.source, f"{self.prefix}.{key}", {"from", "to", "step"})
            start, stop = inner.real("from"), inner.real("to")
            step = inner.real("step", low=0, low_open=True)
            span = (stop - start) / step
            if not span < MAX_SERIES:  # a tiny step (or a huge span) would build a list the size of the memory
                raise DataFileError(
                    f"{self.where(key)} runs from {start:g} to {stop:g} in steps of {step:g}: more than {MAX_SERIES} "
                    "values"
                )
            count = int(math.floor(span + 1e-9)) + 1
            if count < 1:
                raise DataFileError(f"{self.where(key)} runs from {start:g} to {stop:g}: 'to' must not be below 'from'")
            value = [start + i * step for i in range(count)]
        if not isinstance(value, list) or not all(
            isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in value
        ):
            raise DataFileError(
                f"{self.where(key)} must be a list of {kind}{f' ({unit})' if unit else ''} or "
                f"{{from, to, step}}; got {value!r}"
            )
        if integer and not all(float(v).is_integer() for v in value):
            raise DataFileError(f"{self.where(key)} must be integers; got {value!r}")
        return [int(v) for v in value] if integer else [float(v) for v in value]


def _read(name_or_path, builtin, kind: str) -> tuple[dict, str]:
    text_name = str(name_or_path)
    if text_name in builtin:
        resource = resources.files(__package__).joinpath("palpation_data", f"{text_name}.toml")
        text, source = resource.read_text(), f"{kind} {text_name}"
    else:
        path = Path(name_or_path)
        refuse_special(path, f"a {kind} TOML")
        if not path.is_file():
            raise DataFileError(
                f"no {kind} {text_name!r}: expected one of {', '.join(builtin)} or a TOML file that exists"
            )
        text, source = read_text(path, f"a {kind} TOML"), str(path)  # binary garbage: named, not a codec error
    try:
        return tomllib.loads(text), source
    except (tomllib.TOMLDecodeError, RecursionError) as exc:  # RecursionError: nested past the parser
        raise DataFileError(f"{source}: not valid TOML ({exc})") from None


@dataclass(frozen=True)
class TissueFile:
    """What a tissue file says beyond the :class:`~flexdigit.twin.contact.Tissue`: its name, and whether it gave
    the gap and modulus (needed to place it on the twin)."""

    name: str
    description: str
    source: str
    placed_on_twin: bool
    #: a built-in tissue (:data:`TISSUES`), written beside the thesis rig: laid out beside another digit by
    #: :func:`~flexdigit.palpation.palpation.digit_tissue`; a file's tissue lies where the file says
    builtin: bool = False


def builtin_palpation_files() -> dict[str, dict[str, str]]:
    """The built-in tissues (:data:`TISSUES`) and palpation protocols (:data:`PROTOCOLS`), each with its one-line
    description: ``{"tissues": {name: text}, "protocols": {name: text}}``."""
    import tomllib

    def first_comment(text: str) -> str:
        lines = [line.lstrip("# ").strip() for line in text.splitlines() if line.startswith("#")]
        return " ".join(lines).split(". ")[0].rstrip(".")

    out: dict[str, dict[str, str]] = {"tissues": {}, "protocols": {}}
    for kind, names in (("tissues", TISSUES), ("protocols", PROTOCOLS)):
        for name in names:
            text = resources.files(__package__).joinpath("palpation_data", f"{name}.toml").read_text()
            doc = tomllib.loads(text)
            out[kind][name] = doc.get("tissue", {}).get("description") or first_comment(text)
    return out


def load_tissue(name_or_path):
    """A tissue from a built-in name (:data:`TISSUES`) or a TOML file: ``(Tissue, TissueFile)``.

    Without ``gap_mm`` and ``modulus_n_m2`` the tissue is only located (``TissueFile.placed_on_twin`` False): enough
    for hardware, where palpation estimates them; the twin needs them to put the tissue there.
    """
    data, source = _read(name_or_path, TISSUES, "tissue")
    if set(data) != {"tissue"}:
        extra = sorted(set(data) - {"tissue"})
        raise DataFileError(
            f"{source}: expected one [tissue] table" + (f"; unknown table {extra[0]!r}" if extra else "")
        )
    t = _Table(data["tissue"], source, "tissue", _TISSUE_KEYS)
    start = t.plausible("start_mm", ALONG_DIGIT_MM) / 1000
    end = t.plausible("end_mm", ALONG_DIGIT_MM) / 1000
    if not end > start:
        raise DataFileError(f"{t.where('end_mm')} must be beyond 'start_mm' ({start * 1000:g}); got {end * 1000:g}")
    # a tissue in m written as mm (start 0.15, end 0.35) is 0.2 mm long: its extent names the slip
    t.declared(f"{source}: the tissue's length 'end_mm' - 'start_mm'", (end - start) * 1000, TISSUE_LENGTH_MM)
    gap = t.plausible("gap_mm", GAP_MM) if "gap_mm" in t.data else None
    modulus = t.plausible("modulus_n_m2", MODULUS_N_M2) if "modulus_n_m2" in t.data else None
    inclusions = []
    raw = t.data.get("inclusions", [])
    if not isinstance(raw, list):
        raise DataFileError(f"{t.where('inclusions')} must be an array of tables [[tissue.inclusions]]; got {raw!r}")
    for i, item in enumerate(raw):
        inc = _Table(item, source, f"tissue.inclusions[{i}]", _INCLUSION_KEYS)
        centre = inc.plausible("centre_mm", ALONG_DIGIT_MM) / 1000
        if not start <= centre <= end:  # outside the body it would change nothing: a plausible wrong answer
            raise DataFileError(
                f"{inc.where('centre_mm')} must lie in the tissue ({start * 1000:g}..{end * 1000:g} mm); "
                f"got {centre * 1000:g}"
            )
        inclusions.append(
            Inclusion(
                centre,
                inc.plausible("width_mm", INCLUSION_WIDTH_MM) / 1000,
                inc.plausible("ratio", INCLUSION_RATIO),
            )
        )
    try:
        tissue = Tissue(
            start,
            end,
            0.0 if gap is None else gap / 1000,
            1.0 if modulus is None else modulus,
            tuple(inclusions),
            exponent=t.real("exponent", default=1.0, low=1.0, high=3.0),
            damping_s_m=t.plausible("damping_s_m", DAMPING_S_M, default=0.0),
            side=t.text("side", default="cable", choices=("cable", "opposite")),
        )
    except ParameterError as exc:
        raise DataFileError(f"{source}: {exc}") from None
    name = t.text("name", default=Path(str(name_or_path)).stem)
    placed = gap is not None and modulus is not None
    info = TissueFile(name, t.text("description"), source, placed, builtin=str(name_or_path) in TISSUES)
    return tissue, info


@dataclass(frozen=True)
class PalpationFile:
    """A palpation protocol file: the sweep, and the optional scan and force-control settings (SI units)."""

    sweep: object
    scan: dict | None = None
    force: dict | None = None
    source: str = ""
    extra: dict = field(default_factory=dict)
    #: which of the sweep's ``commands``, ``tare_command`` and ``settle_s`` are the thesis rig's (its commands counted
    #: from its straight 8), to be laid out on a digit (:func:`~flexdigit.palpation.palpation.digit_protocol`): all
    #: in a built-in protocol, those a file leaves out; a file's own values are the user's for their digit
    laid_out: tuple = ("commands", "tare_command", "settle_s")
    #: a built-in protocol (:data:`PROTOCOLS`): the scan's offsets and inclusion width are the thesis rig's, laid out
    #: beside another digit with a built-in tissue (:func:`~flexdigit.palpation.palpation.tissue_scale`)
    builtin: bool = False


def load_palpation_protocol(name_or_path=None) -> PalpationFile:
    """A palpation protocol from a built-in name (:data:`PROTOCOLS`) or a TOML file (the default sweep if None)."""
    if name_or_path is None:
        name_or_path = "sweep"
    data, source = _read(name_or_path, PROTOCOLS, "palpation protocol")
    unknown = sorted(set(data) - set(_SECTIONS))
    if unknown:
        raise DataFileError(f"{source}: unknown table {unknown[0]!r}; expected some of {', '.join(sorted(_SECTIONS))}")
    if not data:
        raise DataFileError(f"{source}: empty; expected a [sweep], [scan] or [force] table")
    s = _Table(data.get("sweep", {}), source, "sweep", _SECTIONS["sweep"])
    default = PalpationProtocol()
    try:
        sweep = PalpationProtocol(
            commands=tuple(s.series("commands", integer=True, default=list(default.commands))),
            settle_s=s.plausible("settle_s", SETTLE_S, default=default.settle_s),
            readings=s.integer("readings", default=default.readings, low=1, high=100_000),
            tare_command=s.integer("tare_command", default=default.tare_command, low=0, high=254),
            period_s=s.plausible("period_s", PERIOD_S, default=default.period_s),
            model=s.text("model", default=default.model, choices=("linear", "hunt-crossley")),
        )
    except ParameterError as exc:
        raise DataFileError(f"{source}: [sweep] {exc}") from None
    scan = None
    if "scan" in data:
        c = _Table(data["scan"], source, "scan", _SECTIONS["scan"])
        offsets = c.series("offsets_mm", unit="mm")
        if len(offsets) < 3:
            raise DataFileError(f"{c.where('offsets_mm')} must give at least 3 offsets; got {offsets!r}")
        for i, offset in enumerate(offsets):
            c.declared(f"{c.where('offsets_mm')}[{i}]", offset, SCAN_OFFSET_MM)
        # offsets in m written as mm (-0.04 .. 0.04) span 0.08 mm: one position, not a scan
        c.declared(f"{c.where('offsets_mm')} (their span)", max(offsets) - min(offsets), SCAN_SPAN_MM)
        scan = {
            "offsets_m": tuple(round(v / 1000, 9) for v in offsets),
            "inclusion_width_m": c.plausible("inclusion_width_mm", INCLUSION_WIDTH_MM, default=10.0) / 1000,
        }
    force = None
    if "force" in data:
        f = _Table(data["force"], source, "force", _SECTIONS["force"])
        force = {
            "setpoint_n": f.plausible("setpoint_n", SETPOINT_N),
            "duration_s": f.plausible("duration_s", DURATION_S, default=10.0),
            # not given: the digit's own (palpation.force_gains: the thesis rig's 30 and 4 on the thesis rig)
            "gain": f.plausible("gain", FORCE_GAIN) if "gain" in f.data else None,
            "approach_rate": f.plausible("approach_rate", APPROACH_RATE) if "approach_rate" in f.data else None,
        }
    builtin = str(name_or_path) in PROTOCOLS
    laid_out = tuple(key for key in ("commands", "tare_command", "settle_s") if builtin or key not in s.data)
    return PalpationFile(sweep, scan, force, source, laid_out=laid_out, builtin=builtin)
