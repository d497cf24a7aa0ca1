"""Servo-board frames, encoded apart from the transport (thesis 2.5.3, 5.2: the MILINST 1-904 board).

The board follows the Mini SSC convention: a sync byte 0xFF, the servo number, and a position 0..254. Because
0xFF is the sync byte a position of 255 would be read as the start of the next frame, so :func:`encode_frame`
refuses it and :class:`FrameDecoder` (the board's side, used by tests and by anyone checking a capture) never
produces it. Framing is a small frozen dataclass so that a board with another sync byte or channel range can be
described without code changes (pyserial's ``threaded.Packetizer`` keeps framing apart from the port the same way).
"""

from __future__ import annotations

from dataclasses import dataclass

from flexdigit._validation import check_int
from flexdigit.errors import ParameterError

__all__ = ["Framing", "MINI_SSC", "encode_frame", "FrameDecoder"]


@dataclass(frozen=True)
class Framing:
    """How a servo frame is laid out.

    Parameters
    ----------
    sync : int
        Start byte (0xFF for Mini SSC); no other byte of a frame may equal it.
    max_channel : int
        Highest servo number (7 on a Mini SSC II; the 1-904 board drives 8 servos).
    max_position : int
        Highest position byte (254: 255 is the sync byte).
    """

    sync: int = 0xFF
    max_channel: int = 7
    max_position: int = 254

    def __post_init__(self) -> None:
        check_int(self.sync, "sync", "Framing", low=0, high=255)
        check_int(self.max_channel, "max_channel", "Framing", low=0, high=254)
        check_int(self.max_position, "max_position", "Framing", low=1, high=254)
        if self.sync <= max(self.max_channel, self.max_position):
            raise ParameterError(
                f"The 'sync' parameter of Framing must be above every channel and position byte "
                f"(max {max(self.max_channel, self.max_position)}). Got {self.sync} instead."
            )


#: The thesis board's framing.
MINI_SSC = Framing()


def encode_frame(channel: int, position: int, framing: Framing = MINI_SSC) -> bytes:
    """Encode one servo command as ``sync, channel, position``.

    Parameters
    ----------
    channel : int
        Servo number, 0..``framing.max_channel``.
    position : int
        Servo position 0..254 (the command of the thesis); 255 is refused, never sent.

    Examples
    --------
    >>> encode_frame(0, 8).hex()
    'ff0008'
    >>> encode_frame(0, 255)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    flexdigit.errors.ParameterError: The 'position' parameter of encode_frame must be ...Got 255 instead.
    """
    ch = check_int(channel, "channel", "encode_frame", low=0, high=framing.max_channel)
    pos = check_int(position, "position", "encode_frame", low=0, high=framing.max_position)
    return bytes((framing.sync, ch, pos))


class FrameDecoder:
    """Decode a byte stream into ``(channel, position)`` frames, resynchronising on the sync byte.

    Bytes before the first sync, and frames cut short by a new sync byte, are dropped and counted in
    :attr:`dropped_bytes`.

    Examples
    --------
    >>> dec = FrameDecoder()
    >>> dec.feed(bytes([0x12, 0xFF, 0, 8, 0xFF, 1]) )
    [(0, 8)]
    >>> dec.feed(bytes([43])), dec.dropped_bytes
    ([(1, 43)], 1)
    """

    def __init__(self, framing: Framing = MINI_SSC) -> None:
        self.framing = framing
        self._buffer: list[int] = []
        self._in_frame = False
        self.dropped_bytes = 0

    def feed(self, data: bytes) -> list[tuple[int, int]]:
        frames = []
        for byte in data:
            if byte == self.framing.sync:
                self.dropped_bytes += len(self._buffer)
                self._buffer = []
                self._in_frame = True
                continue
            if not self._in_frame:
                self.dropped_bytes += 1
                continue
            self._buffer.append(byte)
            if len(self._buffer) == 2:
                channel, position = self._buffer
                self._buffer = []
                self._in_frame = False
                if channel > self.framing.max_channel:
                    self.dropped_bytes += 2
                else:
                    frames.append((channel, position))
        return frames
