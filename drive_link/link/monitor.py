"""``drive-link monitor``: the raw bus as a live table, one row per CAN-ID, with its CANopen
meaning (:mod:`drive_link.link._monitor_decode`): count, rate, age of the last frame, its data and
what it says (NMT, heartbeat state, SDO object and value, PDO signals, EMCY text).

The monitor opens its own bus (it sees every node, beside a running shell or dashboard). Per
frame it only counts and keeps the data (and follows SDO traffic, to know the PDO mappings);
the text is made when a row is shown, so its cost stays bounded at the bus's full rate.

>>> from drive_link.link.monitor import BusTable
>>> table = BusTable()            # feed it frames: table.on_frame(can_id, data, t)
>>> table.rows()                  # one dict per CAN-ID: id, kind, node, count, rate_hz, …
[]
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import Any

import can

from ..errors import InvalidValue
from ._monitor_decode import FrameDecoder, kind_of

__all__ = ["BusTable", "IdFilter", "TableFeed", "parse_ids", "render"]


@dataclass
class _Row:
    count: int = 0
    first: float = 0.0
    last: float = 0.0
    data: bytes = b""
    rtr: bool = False
    shown_count: int = 0  # count at the previous rate sample
    shown_t: float = 0.0
    rate: float = 0.0


def parse_ids(text: str) -> set[int]:
    """``0x181,0x281`` or ``0x700-0x77F`` (ranges inclusive) → the set of CAN-IDs."""
    out: set[int] = set()
    for part in filter(None, (p.strip() for p in text.split(","))):
        lo, _, hi = part.partition("-")
        try:
            a, b = int(lo, 0), int(hi or lo, 0)
        except ValueError:
            raise InvalidValue(
                f"--ids {part!r}: not a CAN-ID or range (0x181, 0x700-0x77F)"
            ) from None
        if not 0 <= a <= b <= 0x1FFFFFFF:
            raise InvalidValue(f"--ids {part!r}: CAN-IDs are 0..0x1FFFFFFF, low to high")
        out.update(range(a, b + 1))
    return out


@dataclass
class IdFilter:
    """Rows shown: of these ``nodes`` (None: all; frames without a node, NMT/SYNC/LSS, always)
    and these ``ids`` (None: all)."""

    nodes: set[int] | None = None
    ids: set[int] | None = None

    def __call__(self, can_id: int) -> bool:
        if self.ids is not None and can_id not in self.ids:
            return False
        if self.nodes is not None:
            node = kind_of(can_id)[1]
            if node is not None and node not in self.nodes:
                return False
        return True


class BusTable:
    """Per CAN-ID counters of the frames fed to :meth:`on_frame` (any thread), and the rows
    with their CANopen text (:meth:`rows`). ``paused``: :meth:`rows` returns the table as it
    was when paused (frames are still counted)."""

    def __init__(self, decoder: FrameDecoder | None = None, keep: IdFilter | None = None):
        self.decoder = decoder or FrameDecoder()
        self.keep = keep or IdFilter()
        self._rows: dict[int, _Row] = {}
        self._lock = threading.Lock()
        self.frames = 0
        self.paused = False
        self._frozen: list[dict[str, Any]] = []

    def on_frame(self, can_id: int, data: bytes, t: float, rtr: bool = False) -> None:
        """Count one frame (``t``: its time stamp, s)."""
        with self._lock:
            row = self._rows.get(can_id)
            if row is None:
                row = self._rows[can_id] = _Row(first=t, shown_t=t)
            row.count += 1
            row.last = t
            row.data = data
            row.rtr = rtr
            self.frames += 1
        if 0x580 <= can_id < 0x680:
            self.decoder.observe(can_id, data, t)

    def pause(self, on: bool | None = None) -> bool:
        """Freeze (or thaw; None toggles) what :meth:`rows` shows; returns the new state."""
        rows = self.rows() if not self.paused else None
        self.paused = (not self.paused) if on is None else on
        if self.paused and rows is not None:
            self._frozen = rows
        return self.paused

    def rows(self, now: float | None = None) -> list[dict[str, Any]]:
        """One dict per CAN-ID passing the filter, by ID: ``id`` ("0x181"), ``kind``, ``node``,
        ``count``, ``rate_hz`` (since the previous call, or over the frames seen at the first),
        ``age_s`` (since its last frame; ``now`` in the frames' clock, default the latest
        frame's time), ``data`` (hex), ``text`` (its CANopen meaning)."""
        if self.paused:
            return self._frozen
        with self._lock:
            items = [(cid, r, r.count, r.last, r.data, r.rtr) for cid, r in self._rows.items()]
        if now is None:
            now = max((x[3] for x in items), default=0.0)
        out = []
        for cid, row, count, last, data, rtr in sorted(items, key=lambda x: x[0]):
            if not self.keep(cid):
                continue
            span = now - row.shown_t
            if span >= 0.25:
                row.rate = (count - row.shown_count) / span
                row.shown_count, row.shown_t = count, now
            elif row.shown_count == 0 and count > 1 and last > row.first:
                row.rate = (count - 1) / (last - row.first)
            kind, node = kind_of(cid)
            out.append(
                {
                    "id": f"0x{cid:03X}",
                    "kind": kind,
                    "node": node,
                    "count": count,
                    "rate_hz": round(row.rate, 1),
                    "age_s": round(max(0.0, now - last), 3),
                    "data": "RTR" if rtr else data.hex(" ").upper(),
                    "text": "" if rtr else self.decoder.text(cid, data),
                }
            )
        return out


def render(rows: list[dict[str, Any]], width: int = 120, paused: bool = False) -> list[str]:
    """The table as text lines (header first)."""
    head = f"{'ID':>6} {'kind':<11} {'count':>8} {'Hz':>7} {'age s':>7}  {'data':<23}  meaning"
    lines = [head + ("   [paused]" if paused else "")]
    for r in rows:
        line = (
            f"{r['id']:>6} {r['kind']:<11} {r['count']:>8} {r['rate_hz']:>7.1f} "
            f"{r['age_s']:>7.2f}  {r['data']:<23}  {r['text']}"
        )
        lines.append(line[:width])
    return lines


class TableFeed(can.Listener):
    """A python-can listener that counts every frame but error frames into ``table`` (the
    ``monitor`` command and the dashboard's Bus tab put it on their notifier)."""

    def __init__(self, table: BusTable):
        self.table = table

    def on_message_received(self, msg: can.Message) -> None:
        if not msg.is_error_frame:
            self.table.on_frame(msg.arbitration_id, bytes(msg.data), msg.timestamp,
                                msg.is_remote_frame)  # fmt: skip
