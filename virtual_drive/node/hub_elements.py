"""The socketcand elements a node writes to the loopback hub: ``send`` and ``sendat`` (a frame
with the time it was ready for the bus, :mod:`virtual_drive.hub_protocol`), formatted for the
drive's pacing loop (a few thousand frames a second). Used by :mod:`virtual_drive.node.hub_bus`.
"""

from __future__ import annotations

import operator
from collections.abc import Sequence

from virtual_drive.hub_protocol import wall_offset

__all__ = [
    "WALL_OFFSET",
    "format_held",
    "format_send",
    "format_sendat",
    "format_sendat_batch",
    "sendat_head",
    "sendat_tail",
]


def format_send(cob_id: int, data: bytes, is_extended: bool = False) -> bytes:
    """``< send <id> <len> <b0> ... >`` as bytes (ids: 3 hex digits standard, 8 extended)."""
    if data:
        if is_extended:
            return b"< send %08X %X %s >" % (cob_id, len(data), data.hex(" ").encode())
        return b"< send %03X %X %s >" % (cob_id, len(data), data.hex(" ").encode())
    return b"< send %08X 0 >" % cob_id if is_extended else b"< send %03X 0 >" % cob_id


#: time.time() − time.monotonic() when this module was loaded (sendat times are Unix times; not
#: two plain readings: see wall_offset)
WALL_OFFSET = wall_offset()


def sendat_head(at: float) -> bytes:
    """``b"< sendat <secs>.<usecs> "`` for frames ready at ``at`` (``time.monotonic()`` s)."""
    usecs = round((at + WALL_OFFSET) * 1e6)
    return b"< sendat %d.%06d " % (usecs // 1_000_000, usecs % 1_000_000)


def sendat_tail(cob_id: int, data: bytes, is_extended: bool = False) -> bytes:
    """``b"<id> <len> <b0> ... >"``: the rest of a ``sendat`` element (no data: ``"<id> 0  >"``,
    as python-can writes an empty ``send``)."""
    ident = b"%08X" % cob_id if is_extended else b"%03X" % cob_id
    return b"%s %X %s >" % (ident, len(data), data.hex(" ").encode())


def format_sendat_batch(at: float, frames: Sequence[tuple[int, bytes]]) -> bytes:
    """The ``< sendat >`` elements of standard frames ``(cob_id, data)`` ready at ``at``
    (``time.monotonic()`` s), one time stamp for all, as one bytes."""
    head = sendat_head(at)
    return b"".join([head + sendat_tail(cob_id, data) for cob_id, data in frames])


_first = operator.itemgetter(0)


def format_held(
    held: list[tuple[float, Sequence[tuple[int, bytes]]]], prefixes: dict[tuple[int, int], bytes]
) -> bytes:
    """:func:`format_sendat_batch` of every batch in ``held`` as one bytes (the flush of a
    tick), in the order of their times (the hub keeps a sender's order, so a batch stated
    earlier but held later, e.g. a heartbeat and the next tick's TPDOs, must not come after),
    with ``b"<id> <len> "`` kept per (id, len) in ``prefixes``: a drive sends the same few
    TPDOs every tick, so this is the time stamp, the data's hex and four joins a frame."""
    out: list[bytes] = []
    add = out.append
    if len(held) > 1:
        held = sorted(held, key=_first)
    for at, frames in held:
        head = sendat_head(at)
        for cob_id, data in frames:
            key = (cob_id, len(data))
            prefix = prefixes.get(key)
            if prefix is None:
                prefix = prefixes[key] = b"%03X %X " % key
            add(head)
            add(prefix)
            add(data.hex(" ").encode() if data else b"")
            add(b" >")
    return b"".join(out)


def format_sendat(at: float, cob_id: int, data: bytes, is_extended: bool = False) -> bytes:
    """``< sendat <secs>.<usecs> <id> <len> <b0> ... >`` for a frame ready at ``at``
    (``time.monotonic()`` seconds) — the loopback hub's element (:mod:`hub_protocol`)."""
    return sendat_head(at) + sendat_tail(cob_id, data, is_extended)
