"""socketcand "rawmode" text protocol: parsing what clients send, formatting what the hub sends.

This is the protocol spoken by python-can's built-in ``socketcand`` interface
(``can/interfaces/socketcand/socketcand.py``) and by the socketcand daemon:

* server greets ``< hi >``; client ``< open <bus> >`` -> ``< ok >``;
  client ``< rawmode >`` -> ``< ok >``
* client -> server: ``< send <id> <len> <b0> <b1> ... >``, id in hex (3 digits standard, 8 digits
  extended), len in hex, each byte 1-2 hex digits
* server -> client: ``< frame <id> <secs>.<usecs> <HEXDATA> >`` (id 3 or 8 hex digits, data one
  contiguous hex string) and ``< error <id> <secs>.<usecs> [text] >`` for error frames
* remote frames (socketcand's doc/protocol.md): client ``< sendrtr <id> <dlc> >``, server
  ``< rtr <id> <secs>.<usecs> <dlc> >`` (python-can's client sends none and skips the lines)

Two elements are this hub's own (a socketcand daemon answers them with ``< error ... >``, and
python-can's client never sends them):

* client ``< features >`` -> ``< features sendat >``: what the hub understands beyond socketcand;
* client ``< sendat <secs>.<usecs> <id> <len> <b0> ... >``: a frame that was ready for the bus at
  that Unix time (in the past; a sender that runs its ticks in batches, like a USB adapter that
  hands over frames with their hardware times). The hub arbitrates it from that time (never
  before the sender's previous frame, never before the bus is free, never in the future), so the
  receivers see the bus times of a drive that sent each frame on its own.

Pure functions only (no I/O), so they can be tested and reused on their own.
"""

from __future__ import annotations

import re
import time
from binascii import b2a_hex
from dataclasses import dataclass
from itertools import product

__all__ = [
    "CAN_ERR_FLAG",
    "CAN_ERR_PROT",
    "FEATURES_REPLY",
    "LINE_BYTES",
    "MAX_ELEMENT_BYTES",
    "OFFSET_BRACKET_S",
    "SENDAT_MAX_BACKDATE_S",
    "CommandSplitter",
    "Frame",
    "ProtocolError",
    "format_error",
    "format_frame",
    "frame_line",
    "parse_channel",
    "parse_send",
    "parse_send_fields",
    "parse_sendat_fields",
    "parse_sendrtr_fields",
    "rtr_line",
    "scan_sendats",
    "scan_sends",
    "wall_offset",
]

#: A (monotonic, wall, monotonic) reading closer together than this (s) fixes
#: :func:`wall_offset` (a few µs when the thread is not preempted)
OFFSET_BRACKET_S = 50e-6


def wall_offset(tries: int = 50) -> float:
    """``time.time() − time.monotonic()`` (s) for converting ``sendat`` times, read so that
    a preemption between the two clock readings does not enter it.

    Both ends of the hub's protocol convert with such an offset (the sender from its monotonic
    clock to the Unix time it states, the hub back), so an error in either moves every frame
    by it. Read as two plain calls, a thread preempted between them (the GIL's 5 ms switch
    interval, a busy host's run queue) got an offset off by that long for the life of the
    process: a drive's frames then looked stated up to 5 ms in the future, all went on the bus
    at once, and TPDO2 with a 1.5 ms inhibit time showed gaps of 0.25-0.9 ms (ci30/ci34/ci36,
    load 8-9). Here the wall reading is bracketed by two monotonic ones: the first bracket
    narrower than :data:`OFFSET_BRACKET_S` of up to ``tries`` counts, else the narrowest,
    against its middle."""
    best_width, best = float("inf"), 0.0
    for _ in range(max(1, tries)):
        m0 = time.monotonic()
        w = time.time()
        m1 = time.monotonic()
        if m1 - m0 < best_width:
            best_width, best = m1 - m0, w - 0.5 * (m0 + m1)
            if best_width < OFFSET_BRACKET_S:
                break
    return best


#: Reply of the hub to ``< features >`` (the elements it understands beyond socketcand).
FEATURES_REPLY = b"< features sendat >"

#: The oldest time (s before its arrival) a ``sendat`` frame may state: an older one is put on
#: the bus as if stated this long ago. A sender's batch covers a few ms, but on a busy host the
#: hub itself may not be scheduled for tens of ms (its frames then arrive that much late and
#: still take their stated times, keeping their spacing); an older time is a clock the hub does
#: not share. (50 ms put a stalled hub's backlog back to back, closer than the TPDOs' inhibit
#: times, at load 3-5.)
SENDAT_MAX_BACKDATE_S = 0.5

#: SocketCAN error-frame flag and "protocol violation" error class (linux/can/error.h).
CAN_ERR_FLAG = 0x20000000
CAN_ERR_PROT = 0x00000008

#: Frame and error lines are padded with spaces (inside the element) to a multiple of this many
#: bytes. python-can's client reads 1024 bytes at a time and logs a warning for every element cut
#: in two; with elements of 64 bytes a 1024-byte read ends on an element boundary.
LINE_BYTES = 64

#: Longest ``< ... >`` element the hub accepts (a maximal ``send`` is about 45 characters).
MAX_ELEMENT_BYTES = 256

_HEX = frozenset("0123456789abcdefABCDEF")
_CHANNEL_CHARS = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_.-")


class ProtocolError(ValueError):
    """A client sent something that is not a valid socketcand element or command."""


@dataclass(frozen=True)
class Frame:
    """One classical CAN data frame.

    arbitration_id: 11-bit (standard) or 29-bit (extended) identifier.
    data: 0..8 payload bytes.
    is_extended: True for a 29-bit identifier.
    """

    arbitration_id: int
    data: bytes
    is_extended: bool = False


class CommandSplitter:
    """Cuts a TCP byte stream into ``< ... >`` elements.

    ``feed(chunk)`` returns the complete elements, each as the list of its whitespace-separated
    words without the angle brackets (e.g. ``["send", "123", "2", "1", "ff"]``), or a
    :class:`ProtocolError` instance in place of an element that is not well formed. Bytes of an
    unfinished element are kept for the next call. :attr:`overflow` turns True when an unfinished
    element grows past :data:`MAX_ELEMENT_BYTES` (the caller should drop the client).
    """

    __slots__ = ("_partial", "overflow")

    def __init__(self) -> None:
        self._partial = b""
        self.overflow = False

    def feed(self, chunk: bytes) -> list[list[str] | ProtocolError]:
        buf = self._partial + chunk if self._partial else chunk
        parts = buf.split(b">")
        self._partial = parts.pop()
        if len(self._partial) > MAX_ELEMENT_BYTES:
            self.overflow = True
        out: list[list[str] | ProtocolError] = []
        for raw in parts:
            try:
                text = raw.decode("ascii")
            except UnicodeDecodeError:
                out.append(ProtocolError("non-ASCII bytes in element"))
                continue
            words = text.split()
            if not words or words[0] != "<":
                if words and words[0].startswith("<"):
                    words = ["<", words[0][1:], *words[1:]]
                else:
                    out.append(ProtocolError("garbage outside '< ... >'"))
                    continue
            words = words[1:]
            if not words:
                out.append(ProtocolError("empty element"))
            elif "<" in text[text.index("<") + 1 :]:
                out.append(ProtocolError("'<' inside element"))
            else:
                out.append(words)
        return out

    @property
    def pending_bytes(self) -> int:
        """Number of bytes of an unfinished element held back."""
        return len(self._partial)


def _hex_value(word: str, what: str) -> int:
    if not word or not _HEX.issuperset(word):
        raise ProtocolError(f"{what} {word!r} is not hexadecimal")
    return int(word, 16)


def parse_send(words: list[str]) -> Frame:
    """Parse the words of a ``send`` element (``["send", id, len, b0, ...]``) into a :class:`Frame`.

    Raises ProtocolError for a malformed id, a length above 8, a byte count that differs from
    the length, or a byte value above 0xFF.
    """
    if len(words) < 3:
        raise ProtocolError("send needs an id and a length")
    id_word = words[1]
    can_id = _hex_value(id_word, "id")
    if len(id_word) == 8:
        is_extended = True
        if can_id > 0x1FFFFFFF:
            raise ProtocolError(f"extended id {id_word} above 1FFFFFFF")
    elif len(id_word) <= 3:
        is_extended = False
        if can_id > 0x7FF:
            raise ProtocolError(f"standard id {id_word} above 7FF")
    else:
        raise ProtocolError(f"id {id_word!r} must have 1-3 (standard) or 8 (extended) hex digits")
    length = _hex_value(words[2], "length")
    if length > 8:
        raise ProtocolError(f"length {length} above 8")
    byte_words = words[3:]
    if len(byte_words) != length:
        raise ProtocolError(f"length {length} but {len(byte_words)} data bytes")
    if _HEX.issuperset("".join(byte_words)) and all(0 < len(w) <= 2 for w in byte_words):
        return Frame(can_id, bytes([int(w, 16) for w in byte_words]), is_extended)
    for w in byte_words:  # find the culprit for the message
        if len(w) > 2:
            raise ProtocolError(f"data byte {w!r} above FF")
        _hex_value(w, "data byte")
    raise AssertionError("unreachable")  # pragma: no cover


# Every 1-2 digit hex word a byte can be written as ("f", "F", "0f", "aB", ...) -> its value.
_BYTE_WORDS: dict[str, int] = {
    "".join(chars): v
    for v in range(256)
    for word in ({format(v, "x"), format(v, "02x")})
    for chars in product(*[(c, c.upper()) for c in word])
}
_LENGTHS = {str(n): n for n in range(9)}


def parse_send_fields(words: list[str]) -> tuple[int, bytes, bool]:
    """:func:`parse_send` as a tuple ``(arbitration_id, data, is_extended)``, without building a
    :class:`Frame`: the hub's per-frame path. Same acceptance and the same ProtocolError."""
    try:
        id_word = words[1]
        n = len(id_word)
        if (n <= 3 or n == 8) and _HEX.issuperset(id_word):
            data = bytes(map(_BYTE_WORDS.__getitem__, words[3:]))
            if len(data) == _LENGTHS[words[2]]:
                can_id = int(id_word, 16)
                if n <= 3:
                    if can_id <= 0x7FF:
                        return can_id, data, False
                elif can_id <= 0x1FFFFFFF:
                    return can_id, data, True
    except (IndexError, KeyError, ValueError):
        pass
    frame = parse_send(words)  # anything unusual: the full check and its precise message
    return frame.arbitration_id, frame.data, frame.is_extended


def parse_sendrtr_fields(words: list[str]) -> tuple[int, int, bool]:
    """The words of a ``sendrtr`` element (``["sendrtr", id, dlc]``) as ``(id, dlc,
    is_extended)``; ProtocolError for a malformed id (as :func:`parse_send`) or a DLC that is
    not one hex digit 0..8."""
    if len(words) != 3:
        raise ProtocolError("sendrtr needs an id and a DLC")
    frame = parse_send(["send", words[1], "0"])
    dlc = _hex_value(words[2], "DLC")
    if dlc > 8:
        raise ProtocolError(f"DLC {dlc} above 8")
    return frame.arbitration_id, dlc, frame.is_extended


# One ``send`` element exactly as python-can's client writes it: 3- or 8-digit id, one-digit
# length, 1-2 digit bytes, one or two spaces before ">" (two when there is no data).
_SEND_ELEMENT = re.compile(
    rb"< send ([0-9A-Fa-f]{3}|[0-9A-Fa-f]{8}) ([0-8])((?: [0-9A-Fa-f]{1,2})*)  ?>"
)
_BYTE_VALUES = {w.encode(): v for w, v in _BYTE_WORDS.items()}


def _scan(
    pattern: re.Pattern[bytes], chunk: bytes
) -> tuple[list[tuple[re.Match[bytes], int, bytes, bool]], int]:
    """The leading matches of ``pattern`` in ``chunk`` (its last three groups: id, length,
    bytes) as ``(match, id, data, is_extended)``, and how many bytes they took; stops at the
    first element that does not match, or has an id out of range or a length that differs from
    its bytes."""
    found: list[tuple[re.Match[bytes], int, bytes, bool]] = []
    pos = 0
    match = pattern.match
    get = _BYTE_VALUES.__getitem__
    last = pattern.groups
    while True:
        m = match(chunk, pos)
        if m is None:
            break
        id_word, length, byte_words = m.group(last - 2, last - 1, last)
        can_id = int(id_word, 16)
        data = bytes(map(get, byte_words.split()))
        if len(data) != int(length):
            break
        ext = len(id_word) == 8
        if can_id > (0x1FFFFFFF if ext else 0x7FF):
            break
        found.append((m, can_id, data, ext))
        pos = m.end()
    return found, pos


def scan_sends(chunk: bytes) -> tuple[list[tuple[int, bytes, bool]], int]:
    """The leading well-formed ``send`` elements of ``chunk`` as ``(id, data, is_extended)``,
    and how many bytes they took. Stops at the first element that is anything else (or has an
    id out of range, or a length that differs from its bytes): the caller hands the rest to
    :class:`CommandSplitter` and :func:`parse_send`, which give the precise answer. The hub's
    fast path for the frames python-can sends."""
    found, pos = _scan(_SEND_ELEMENT, chunk)
    return [(can_id, data, ext) for _, can_id, data, ext in found], pos


_SENDAT_ELEMENT = re.compile(
    rb"< sendat ([0-9]{1,12})\.([0-9]{6}) ([0-9A-Fa-f]{3}|[0-9A-Fa-f]{8}) ([0-8])"
    rb"((?: [0-9A-Fa-f]{1,2})*)  ?>"
)


def scan_sendats(chunk: bytes) -> tuple[list[tuple[float, int, bytes, bool]], int]:
    """The leading well-formed ``sendat`` elements of ``chunk`` as ``(unix_time_s, id, data,
    is_extended)``, and how many bytes they took; stops like :func:`scan_sends` at the first
    element that is anything else (the caller's full path gives the precise answer)."""
    found, pos = _scan(_SENDAT_ELEMENT, chunk)
    frames = [(int(m[1]) + int(m[2]) * 1e-6, i, data, ext) for m, i, data, ext in found]
    return frames, pos


def parse_sendat_fields(words: list[str]) -> tuple[float, int, bytes, bool]:
    """The words of a ``sendat`` element (``["sendat", "secs.usecs", id, len, b0, ...]``) as
    ``(unix_time_s, id, data, is_extended)``; ProtocolError as :func:`parse_send`, or for a
    time that is not ``<secs>.<usecs>`` (six digits)."""
    if len(words) < 2:
        raise ProtocolError("sendat needs a time, an id and a length")
    secs, dot, usecs = words[1].partition(".")
    if not (dot and secs.isdigit() and len(secs) <= 12 and usecs.isdigit() and len(usecs) == 6):
        raise ProtocolError(f"sendat time {words[1]!r} is not <secs>.<usecs>")
    can_id, data, ext = parse_send_fields(["send", *words[2:]])
    return int(secs) + int(usecs) * 1e-6, can_id, data, ext


def parse_channel(words: list[str]) -> str:
    """Parse the words of an ``open`` element into the bus name (letters, digits, ``_.-``, ≤ 15)."""
    if len(words) != 2:
        raise ProtocolError("open needs exactly one bus name")
    name = words[1]
    if len(name) > 15 or not _CHANNEL_CHARS.issuperset(name):
        raise ProtocolError(f"bad bus name {name!r}")
    return name


def _stamp(timestamp: float) -> str:
    usecs_total = round(timestamp * 1e6)
    return f"{usecs_total // 1_000_000}.{usecs_total % 1_000_000:06d}"


def _padded(body: str) -> bytes:
    """``body + " >"`` with spaces before the ``>`` up to a multiple of LINE_BYTES bytes."""
    pad = -(len(body) + 2) % LINE_BYTES
    return (body + " " * pad + " >").encode("ascii", "replace")


def format_frame(frame: Frame, timestamp: float) -> bytes:
    """``< frame <id> <secs>.<usecs> <HEXDATA> >`` as bytes; timestamp in seconds (Unix time).

    The id has 3 hex digits (standard) or 8 (extended), as python-can tells them apart by length.
    The line is space-padded inside the element to LINE_BYTES bytes.
    """
    if frame.is_extended:
        id_str = f"{frame.arbitration_id:08X}"
    else:
        id_str = f"{frame.arbitration_id:03X}"
    return _padded(f"< frame {id_str} {_stamp(timestamp)} {frame.data.hex().upper()}")


_ID_PREFIX_STD = tuple(f"< frame {i:03X} ".encode() for i in range(0x800))


def frame_line(arbitration_id: int, data: bytes, is_extended: bool, timestamp: float) -> bytes:
    """:func:`format_frame` from the fields (same bytes): the hub's per-frame path."""
    prefix = (
        f"< frame {arbitration_id:08X} ".encode()
        if is_extended
        else _ID_PREFIX_STD[arbitration_id]
    )
    usecs = round(timestamp * 1e6)
    body = b"%s%d.%06d %s" % (prefix, usecs // 1_000_000, usecs % 1_000_000, b2a_hex(data).upper())
    return body + b" " * (-(len(body) + 2) % LINE_BYTES) + b" >"


def rtr_line(arbitration_id: int, dlc: int, is_extended: bool, timestamp: float) -> bytes:
    """``< rtr <id> <secs>.<usecs> <dlc> >`` (a remote frame, socketcand), padded as
    :func:`frame_line`."""
    ident = f"{arbitration_id:08X}" if is_extended else f"{arbitration_id:03X}"
    usecs = round(timestamp * 1e6)
    body = b"< rtr %s %d.%06d %d" % (ident.encode(), usecs // 1_000_000, usecs % 1_000_000, dlc)
    return body + b" " * (-(len(body) + 2) % LINE_BYTES) + b" >"


def format_error(reason: str, timestamp: float, error_class: int = CAN_ERR_PROT) -> bytes:
    """An error frame ``< error <id> <secs>.<usecs> <reason> >`` that python-can parses.

    The id is CAN_ERR_FLAG | error_class (8 hex digits, as socketcand sends); the reason is a
    human-readable text with any angle brackets removed, space-padded like frames.
    Timestamp in seconds (Unix time).
    """
    text = " ".join(reason.replace("<", "(").replace(">", ")").split())
    return _padded(f"< error {CAN_ERR_FLAG | error_class:08X} {_stamp(timestamp)} {text}")
