"""The ``stream://`` line protocol: gauge readings from a microcontroller ADC as checksummed ASCII lines.

Someone rebuilding the rig today reads the three half-bridges with a microcontroller ADC (an ADS1115 or three
HX711s on an Arduino-class board) instead of the thesis's PCI card (2.5.1, out of production), and sends the
readings over USB serial. This module is the protocol, encoding and decoding bytes only (pyserial's
``threaded.Packetizer`` habit: framing apart from transport, unit-tested on bytes);
:mod:`flexdigit.rig.backends.stream_backend`
is the transport and ``examples/flexdigit_stream/flexdigit_stream.ino`` the reference firmware.

One line per sample, ASCII, sent ended by ``\\r\\n``; the host ends a line at ``\\n`` or ``\\r``, whichever
comes, and skips empty lines, so ``\\r\\n``, ``\\n``, ``\\r`` and ``\\n\\r`` all read. Version 2 carries any
digit's 1 to 8 gauges, version 1 the thesis rig's three; the host reads both, line by line::

    $V2,<seq>,<t_us>,<G>,<g1>,...,<gG>[,<pot>[,<rot>]]*<crc>     version 2: G gauges, 1 <= G <= 8
    $<seq>,<t_us>,<g1>,<g2>,<g3>[,<pot>]*<crc>                   version 1: three gauges

- ``V2``: the literal tag of a version-2 line (upper case; it is no integer, so no version-1 line starts so);
- ``G``: how many gauge fields follow, 1..:data:`MAX_GAUGES`; the line then has ``4 + G`` fields, ``5 + G``
  with the pot, or ``6 + G`` with the pot and the rotation (a count that disagrees with the fields is garbled);

- every field is a decimal integer, an optional ``-`` then digits (no ``+``, no blanks, no decimal point, no
  exponent): ADC counts, not volts (the host multiplies by its ``scale``, volts per count);
- ``seq``: 0..65535, 0 on the board's first line after power-up or reset, one more on each line, 0 after 65535.
  A jump forward is that many dropped lines; the same number again is a *duplicated* line and a number up to
  ``window`` lines behind an *out-of-order* one (both counted, neither used: the newest sample stays); a 0 that
  is not the next number, or a jump back further than ``window``, is a *restart* of the board (counted; reading
  goes on from it);
- ``t_us``: 0..4294967295, the board's microsecond clock when the sample was taken (Arduino ``micros()``, which
  wraps after 71.6 minutes; ``millis()`` x 1000 will do). Kept with each sample, never used for timing: the host
  keeps its own clock, so a wrap or a jump is harmless;
- ``g1 .. gG`` (``g1, g2, g3`` in version 1): the gauges, base to tip, as signed ADC counts;
- ``pot``: optional (a line may have it or not), the servo potentiometer in signed ADC counts (the reference
  board firmware, ``firmware/flexdigit_board.c``, sends the servo command it applied here: it has no pot);
- ``rot``: version 2 only, optional, only after ``pot``: the board's own rotation estimate of these gauges, in
  micro-degrees (the board that closes the loop itself streams what it fed its controller: its map's reading minus
  its tare). Added to version 2 in issue 24 (item 5): a version-2 line without it reads as before, and a host that
  predates it refuses a line with it as garbled (one field too many), so a board that streams it needs this host;
- ``crc``: four hexadecimal digits (the firmware sends upper case; either case reads), CRC-16/XMODEM (polynomial
  0x1021, initial value 0, no reflection, no final XOR: Python's ``binascii.crc_hqx(payload, 0)``, avr-libc's
  ``_crc_xmodem_update``; check value 0x31C3 for ``123456789``) of the bytes strictly between ``$`` and ``*``
  (the ``V2,`` tag included).

A line is at most :data:`MAX_LINE_BYTES` bytes; a longer run without a line end is garbage. Lines starting with
``#`` are information from the firmware (its banner: ``# flexdigit-stream 2 adc=ADS1115 v_per_count=0.000125
rate_hz=100 gauges=5``; a banner naming a protocol version other than 1 or 2 is refused); they are counted and
kept, never taken for data. Any other line, a line whose checksum does not match, or one whose fields are not what
is written above is *garbled*, and counted as such (with the reason). Bytes are 8N1 at the baud rate both ends
agree on (115200 in the reference firmware); the rate of lines is free (the host reads the newest).

Examples
--------
>>> line = encode_line(7, 1_000_000, (120, -45, 3000), pot=812)
>>> line
b'$7,1000000,120,-45,3000,812*4297\\r\\n'
>>> decoder = LineDecoder()
>>> [event.kind for event in decoder.feed(line + b"$8,1020000,1,2,3*0000\\r\\n")]
['sample', 'garbled']
>>> decoder.feed(line)[0].sample.gauges
(120, -45, 3000)
>>> v2 = encode_line(8, 1_020_000, (5, 6, 7, 8, 9))
>>> v2
b'$V2,8,1020000,5,5,6,7,8,9*2358\\r\\n'
>>> decoder.feed(v2)[0].sample.gauges
(5, 6, 7, 8, 9)
>>> board = encode_line(9, 1_040_000, (5, 6, 7, 8, 9), pot=130, rotation_udeg=-29_981_250)
>>> board
b'$V2,9,1040000,5,5,6,7,8,9,130,-29981250*BAE5\\r\\n'
>>> decoder.feed(board)[0].sample.rotation_deg
-29.98125
"""

from __future__ import annotations

import binascii
import re
from dataclasses import dataclass

__all__ = [
    "PROTOCOL_VERSION",
    "PROTOCOL_VERSIONS",
    "MAX_GAUGES",
    "Sample",
    "Event",
    "LineDecoder",
    "encode_line",
    "crc16_xmodem",
]

#: The version the reference firmware's banner announces (``# flexdigit-stream 2 ...``).
PROTOCOL_VERSION = 2
#: The versions the host reads (a banner naming another is refused).
PROTOCOL_VERSIONS = (1, 2)
#: Most gauges a version-2 line carries (a digit has 1 to 8).
MAX_GAUGES = 8
_V2_TAG = b"V2"
#: Sequence numbers run 0..SEQ_MODULUS - 1 and wrap.
SEQ_MODULUS = 65536
#: The board's microsecond clock wraps at 2^32.
TIME_MODULUS_US = 2**32
#: A line longer than this without a newline is garbage (a real line is < 70 bytes; eight 32-bit gauges < 140).
MAX_LINE_BYTES = 200
_LINE_END = re.compile(rb"[\r\n]")
_HEX4 = re.compile(rb"^[0-9A-Fa-f]{4}$")


def crc16_xmodem(payload: bytes) -> int:
    """CRC-16/XMODEM of ``payload`` (polynomial 0x1021, initial value 0): ``crc16_xmodem(b"123456789") == 0x31C3``.

    >>> hex(crc16_xmodem(b"123456789"))
    '0x31c3'
    """
    return binascii.crc_hqx(payload, 0)


@dataclass(frozen=True)
class Sample:
    """One decoded line: sequence number, board time (us), gauge counts (1 to 8, base first), pot counts (None
    if not sent) and the board's rotation estimate in micro-degrees (None if not sent)."""

    seq: int
    t_us: int
    gauges: tuple[int, ...]
    pot: int | None = None
    rotation_udeg: int | None = None

    @property
    def rotation_deg(self) -> float | None:
        """The board's rotation estimate, deg (None if the line did not carry one)."""
        return None if self.rotation_udeg is None else self.rotation_udeg / 1e6


@dataclass(frozen=True)
class Event:
    """What one line was: ``kind`` is ``"sample"`` (``sample`` set), ``"info"`` or ``"garbled"`` (``reason``)."""

    kind: str
    sample: Sample | None = None
    text: str = ""
    reason: str = ""


def encode_line(
    seq: int,
    t_us: int,
    gauges,
    pot: int | None = None,
    version: int | None = None,
    rotation_udeg: int | None = None,
) -> bytes:
    """The bytes the firmware sends for one sample (see the module docstring): version 1 for three gauges and
    version 2 otherwise, unless ``version`` says (version 2 carries three as well); ``rotation_udeg`` (the board's
    estimate, micro-degrees) only in version 2 and after a ``pot``."""
    values = [int(g) for g in gauges]
    version = (1 if len(values) == 3 and rotation_udeg is None else 2) if version is None else version
    if version not in PROTOCOL_VERSIONS:
        raise ValueError(f"encode_line writes protocol version 1 or 2. Got {version!r}")
    if version == 1 and len(values) != 3:
        raise ValueError(f"a version-1 line carries 3 gauge values. Got {len(values)}")
    if not 1 <= len(values) <= MAX_GAUGES:
        raise ValueError(f"a version-2 line carries 1 to {MAX_GAUGES} gauge values. Got {len(values)}")
    if rotation_udeg is not None and (version == 1 or pot is None):
        raise ValueError("a rotation estimate goes in a version-2 line, after the pot field. Got no pot or version 1")
    fields = [int(seq) % SEQ_MODULUS, int(t_us) % TIME_MODULUS_US, *([len(values)] if version == 2 else []), *values]
    if pot is not None:
        fields.append(int(pot))
    if rotation_udeg is not None:
        fields.append(int(rotation_udeg))
    payload = (b"V2," if version == 2 else b"") + ",".join(str(v) for v in fields).encode("ascii")
    return b"$" + payload + b"*" + f"{crc16_xmodem(payload):04X}".encode("ascii") + b"\r\n"


def _integer(text: bytes) -> int:
    body = text[1:] if text[:1] == b"-" else text
    if not body or not body.isdigit():
        raise ValueError
    return int(text)


def _too_long() -> Event:
    return Event("garbled", reason=f"line longer than {MAX_LINE_BYTES} bytes")


def decode_line(line: bytes) -> Event:
    """Decode one line without its line end (``\\r`` and ``\\n`` at either end are stripped)."""
    line = line.strip(b"\r\n")
    if line.startswith(b"#"):
        return Event("info", text=line[1:].decode("ascii", "replace").strip())
    if not line.startswith(b"$"):
        return Event("garbled", reason="no '$' at the start")
    payload, star, crc = line[1:].rpartition(b"*")
    if not star or len(crc) != 4:
        return Event("garbled", reason="no '*' and 4-digit checksum at the end")
    if not _HEX4.match(crc):
        return Event("garbled", reason="checksum is not hexadecimal")
    expected = int(crc, 16)
    if crc16_xmodem(payload) != expected:
        return Event("garbled", reason="checksum mismatch")
    parts = payload.split(b",")
    version2 = parts[0] == _V2_TAG
    if version2:
        parts = parts[1:]
    elif len(parts) not in (5, 6):
        return Event("garbled", reason=f"{len(parts)} fields, expected 5 or 6")
    try:
        values = [_integer(p) for p in parts]
    except ValueError:
        return Event("garbled", reason="a field is not an integer")
    count = 3
    if version2:
        if len(values) < 4 or not 1 <= values[2] <= MAX_GAUGES:
            return Event("garbled", reason=f"version 2: no gauge count 1..{MAX_GAUGES} and its gauges")
        count, values = values[2], values[:2] + values[3:]
        if len(values) not in (2 + count, 3 + count, 4 + count):
            return Event("garbled", reason=f"version 2: {len(values) - 2} values after a gauge count of {count}")
    seq, t_us = values[0], values[1]
    if not (0 <= seq < SEQ_MODULUS and 0 <= t_us < TIME_MODULUS_US):
        return Event("garbled", reason="sequence number or time out of range")
    extra = values[2 + count :]  # [pot[, rotation]]
    pot = extra[0] if extra else None
    rotation = extra[1] if len(extra) == 2 else None
    return Event("sample", Sample(seq, t_us, tuple(values[2 : 2 + count]), pot, rotation))


class LineDecoder:
    """Split a byte stream into lines and decode them; keeps a partial line between calls.

    A line ends at ``\\n`` or ``\\r``. A run of more than :data:`MAX_LINE_BYTES` bytes without a line end (noise,
    the wrong baud rate) is dropped as one garbled event, so the buffer never grows without bound.
    """

    def __init__(self) -> None:
        self._buffer = bytearray()

    def feed(self, data: bytes) -> list[Event]:
        """Decode every complete line in ``data`` (plus what was left over from the last call)."""
        self._buffer += data
        events = []
        start = 0
        buffer = self._buffer
        while True:
            found = _LINE_END.search(buffer, start)
            if found is None:
                del buffer[:start]
                if len(buffer) > MAX_LINE_BYTES:
                    buffer.clear()
                    events.append(Event("garbled", reason=f"no line end in {MAX_LINE_BYTES} bytes"))
                return events
            end = found.start()
            line = bytes(buffer[start:end])
            start = end + 1
            if line.strip():
                events.append(decode_line(line) if len(line) <= MAX_LINE_BYTES else _too_long())
