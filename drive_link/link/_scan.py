"""Finding nodes on a bus: heartbeats / boot-ups, and an SDO probe of 0x1000 on 1..127."""

from __future__ import annotations

import struct
import threading
import time
from dataclasses import dataclass
from typing import Any

import can

from firmware_protocol import load_od

from ..errors import BusError
from . import _connection
from ._nmt import NMT_STATES

__all__ = [
    "HEARTBEAT_WAIT",
    "RE_PROBES",
    "NodeInfo",
    "scan",
]


@dataclass
class NodeInfo:
    """A node found on the bus: ``node_id``, ``device_type`` (0x1000, None if it did not
    answer SDO), ``nmt_state`` (from its heartbeat, None if none seen), ``abort_code`` (if
    the probe was aborted)."""

    node_id: int
    device_type: int | None = None
    nmt_state: str | None = None
    abort_code: int | None = None

    @property
    def profile(self) -> str:
        """Device profile from device_type bits 15..0 (e.g. "CiA 402")."""
        if self.device_type is None:
            return ""
        return f"CiA {self.device_type & 0xFFFF}"


#: Probes sent again to nodes seen by heartbeat that did not answer the first one.
RE_PROBES = 3

#: Extra wait (s) after ``timeout`` for the heartbeat of nodes that answered SDO.
HEARTBEAT_WAIT = 1.5

_DEVICE_TYPE = load_od().entry("device_type")
#: SDO initiate-upload request (command 0x40) for device_type (0x1000:00).
_PROBE = struct.pack("<BHB4x", 0x40, _DEVICE_TYPE.index, _DEVICE_TYPE.subindex)


def scan(
    bus: can.BusABC | None = None,
    timeout: float = 0.3,
    node_ids: range | list[int] = range(1, 128),
    skip: tuple[int, ...] = (),
    **settings: Any,
) -> list[NodeInfo]:
    """Find nodes: probe device_type (0x1000) by SDO on every ID in ``node_ids`` (sent back to
    back; a full SocketCAN transmit queue is waited out, see
    :class:`~drive_link.link._connection.PacedNetwork`), and listen ``timeout`` s for SDO answers
    and heartbeats, then up to :data:`HEARTBEAT_WAIT` s more for the heartbeat of nodes that
    answered. Nodes with an open :class:`Drive` on the same bus can be passed in ``skip`` (their
    SDO channel is not probed, so an ongoing transfer is not disturbed) — they are still found
    by heartbeat.

    ``bus`` or python-can settings (``interface``, ``channel``, ``bitrate``, ``host``, ``port``).
    """
    conn = _connection.acquire(bus=bus, **settings)
    found: dict[int, NodeInfo] = {}
    lock = threading.Lock()

    def on_sdo(can_id: int, data: bytearray, ts: float) -> None:
        nid = can_id - 0x580
        if len(data) < 8:
            return
        cs, index, sub = struct.unpack_from("<BHB", data)
        if (index, sub) != (_DEVICE_TYPE.index, _DEVICE_TYPE.subindex):
            return
        with lock:
            info = found.setdefault(nid, NodeInfo(nid))
            if cs == 0x80:
                info.abort_code = struct.unpack_from("<I", data, 4)[0]
            elif cs & 0xE0 == 0x40:
                info.device_type = struct.unpack_from("<I", data, 4)[0]

    def on_hb(can_id: int, data: bytearray, ts: float) -> None:
        nid = can_id - 0x700
        if not data:
            return
        with lock:
            info = found.setdefault(nid, NodeInfo(nid))
            info.nmt_state = NMT_STATES.get(data[0] & 0x7F, f"0x{data[0]:02X}")

    net = conn.network
    subs = [(0x580 + n, on_sdo) for n in range(1, 128)] + [
        (0x700 + n, on_hb) for n in range(1, 128)
    ]
    try:
        for cob, cb in subs:
            net.subscribe(cob, cb)
        try:
            busy = set(skip) | set(conn.active_nodes)
            for nid in node_ids:
                if nid not in busy:
                    net.send_message(0x600 + nid, _PROBE)
        except (can.CanError, RuntimeError, OSError) as exc:
            raise BusError(f"CAN send failed while scanning: {exc}") from None
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            time.sleep(0.01)
        # Heartbeats are slower than SDO answers (0x1017 is often 100 ms to 1 s): wait up to
        # HEARTBEAT_WAIT s more for nodes that answered SDO to report their NMT state.
        deadline = time.monotonic() + HEARTBEAT_WAIT
        while time.monotonic() < deadline:
            with lock:
                if all(i.nmt_state is not None for i in found.values()):
                    break
            time.sleep(0.01)
        # One probe per node is not enough on a lossy bus: a node seen by its heartbeat whose
        # probe (or answer) was lost is asked again, a few times.
        for _ in range(RE_PROBES):
            with lock:
                again = [
                    n for n, i in found.items()
                    if i.device_type is None and i.abort_code is None and n in node_ids
                    and n not in busy
                ]
            if not again:
                break
            try:
                for nid in again:
                    net.send_message(0x600 + nid, _PROBE)
            except (can.CanError, RuntimeError, OSError) as exc:
                raise BusError(f"CAN send failed while scanning: {exc}") from None
            deadline = time.monotonic() + max(timeout, 0.3)
            while time.monotonic() < deadline:
                with lock:
                    if all(found[n].device_type is not None or found[n].abort_code is not None
                           for n in again):
                        break
                time.sleep(0.01)
    finally:
        for cob, cb in subs:
            try:
                net.unsubscribe(cob, cb)
            except (KeyError, ValueError):
                pass
        _connection.release(conn)
    with lock:
        for nid, device_type in conn.active_nodes.items():  # known from the open Drive
            if nid in node_ids and nid not in skip:
                found.setdefault(nid, NodeInfo(nid)).device_type = device_type
        return [found[k] for k in sorted(found)]
