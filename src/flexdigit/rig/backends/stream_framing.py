"""The ``stream://`` line protocol: gauge readings from a microcontroller ADC as checksummed ASCII lines.

Someone rebuilding the rig today reads the three half-bridges with a microcontroller ADC (an ADS1115 or three
HX711s on an Arduino-class board) instead of the thesis's PCI card (2.5.1, out of production), and sends the
readings over USB serial. This module is the protocol, encoding and decoding bytes only (pyserial's
``threaded.Packetizer`` habit: framing apart from transport, unit-tested on bytes);
:mod:`flexdigit.rig.backends.stream_backend`
is the transport and ``examples/flexdigit_stream/flexdigit_stream.ino`` the reference firmware.

One line per sample, ASCII, sent ended by ``\\r\\n``; the host ends a line at ``\\n`` or ``\\r``, whichever
comes, and skips empty lines, so ``\\r\\n``, ``\\n``, ``\\r`` and ``\\n\\r`` all read::

    $<seq>,<t_us>,<g1>,<g2>,<g3>[,<pot>]*<crc>

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
- ``g1, g2, g3``: the gauges, base to tip, as signed ADC counts;
- ``pot``: optional (a line may have it or not), the servo potentiometer in signed ADC counts;
- ``crc``: four hexadecimal digits (the firmware sends upper case; either case reads), CRC-16/XMODEM (polynomial
  0x1021, initial value 0, no reflection, no final XOR: Python's ``binascii.crc_hqx(payload, 0)``, avr-libc's
  ``_crc_xmodem_update``; check value 0x31C3 for ``123456789``) of the bytes strictly between ``$`` and ``*``.

A line is at most :data:`MAX_LINE_BYTES` bytes; a longer run without a line end is garbage. Lines starting with
``#`` are information from the firmware (its banner: ``# flexdigit-stream 1 adc=ADS1115 v_per_count=0.000125
rate_hz=100``; a banner naming another protocol version is refused); they are counted and kept, never taken for
data. Any other line, a line whose checksum does not match, or one whose fields are not what is written above is
*garbled*, and counted as such (with the reason). Bytes are 8N1 at the baud rate both ends agree on (115200 in
the reference firmware); the rate of lines is free (the host reads the newest).

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
"""

from __future__ import annotations

import binascii
import re
from dataclasses import dataclass

__all__ = ["PROTOCOL_VERSION", "Sample", "Event", "LineDecoder", "encode_line", "crc16_xmodem"]

#: The version the banner line announces (``# flexdigit-stream 1 ...``).
PROTOCOL_VERSION = 1
#: Sequence numbers run 0..SEQ_MODULUS - 1 and wrap.
SEQ_MODULUS = 65536
#: The board's microsecond clock wraps at 2^32.
TIME_MODULUS_US = 2**32
#: A line longer than this without a newline is garbage (a real line is < 70 bytes).
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
    """One decoded line: sequence number, board time (us), gauge counts and pot counts (None if not sent)."""

    seq: int
    t_us: int
    gauges: tuple[int, int, int]
    pot: int | None = None


@dataclass(frozen=True)
class Event:
    """What one line was: ``kind`` is ``"sample"`` (``sample`` set), ``"info"`` or ``"garbled"`` (``reason``)."""

    kind: str
    sample: Sample | None = None
    text: str = ""
    reason: str = ""


def encode_line(seq: int, t_us: int, gauges, pot: int | None = None) -> bytes:
    """The bytes the firmware sends for one sample (see the module docstring)."""
    fields = [int(seq) % SEQ_MODULUS, int(t_us) % TIME_MODULUS_US, *(int(g) for g in gauges)]
    if len(fields) != 5:
        raise ValueError(f"encode_line needs 3 gauge values. Got {len(fields) - 2}")
    if pot is not None:
        fields.append(int(pot))
    payload = ",".join(str(v) for v in fields).encode("ascii")
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
    if len(parts) not in (5, 6):
        return Event("garbled", reason=f"{len(parts)} fields, expected 5 or 6")
    try:
        values = [_integer(p) for p in parts]
    except ValueError:
        return Event("garbled", reason="a field is not an integer")
    seq, t_us = values[0], values[1]
    if not (0 <= seq < SEQ_MODULUS and 0 <= t_us < TIME_MODULUS_US):
        return Event("garbled", reason="sequence number or time out of range")
    pot = values[5] if len(values) == 6 else None
    return Event("sample", Sample(seq, t_us, (values[2], values[3], values[4]), pot))


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
