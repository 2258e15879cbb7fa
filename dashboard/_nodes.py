"""The nodes on the bench's bus: which ones the dashboard sees, and one :class:`Bench` per node.

The bench's own node (``--node``) is opened at start-up (:func:`dashboard._virtual.open_bench`);
every other node gets its own :class:`Bench` (its own drive state, plots, captures and control
lease) the first time a browser or a REST call selects it. Its ``drive_link.Drive`` shares the
bench's bus connection (no second connection to the hub or the interface) and sends no host
heartbeat of its own (the first drive already does, on 0x700 + host-ID).

Nodes are seen passively by their heartbeats (0x701–0x77F, the host's own excluded) and, on
request (:meth:`Nodes.scan`), by ``drive_link.scan`` (SDO probe of 0x1000 on 1..127; the nodes
with an open bench are not probed, so their transfers are not disturbed). Units: s.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Callable
from typing import Any

from dashboard._bench import Bench
from drive_link.errors import NodeNotFound
from drive_link.link.bus import NMT_STATES

__all__ = ["OFFLINE_AFTER_S", "Nodes"]

OFFLINE_AFTER_S = 1.0  #: a node whose heartbeat is older than this is listed as OFFLINE (s)
OPERATIONAL_WAIT_S = 2.0  #: a newly opened node must reach OPERATIONAL within this (s)


class Nodes:
    """The benches of the nodes on one bus, keyed by node-ID; ``default`` is the bench's own.

    ``on_new``: called with each :class:`Bench` opened after the first (the GUI attaches its
    listeners). Thread-safe."""

    def __init__(self, default: Bench) -> None:
        self.default = default
        self._benches: dict[int, Bench] = {default.node_id: default}
        self._heard: dict[int, tuple[str, float]] = {}  # node → (NMT state, time.monotonic())
        self._scanned: dict[int, float] = {}  # node → time.monotonic() of the scan that found it
        self._lock = threading.RLock()
        self.on_new: list[Callable[[Bench], None]] = []
        self._network: Any = None
        self._host_id = getattr(default.drive, "host_id", None)
        conn = getattr(default.drive, "_conn", None)
        if conn is not None:
            self._network = conn.network
            for node in range(1, 128):
                if node != self._host_id:
                    self._network.subscribe(0x700 + node, self._on_heartbeat)

    # ---------------------------------------------------------------- what is seen
    def _on_heartbeat(self, can_id: int, data: bytearray, timestamp: float) -> None:
        if len(data) < 1:
            return
        state = NMT_STATES.get(data[0] & 0x7F, f"0x{data[0]:02X}")
        self._heard[can_id - 0x700] = (state, time.monotonic())

    def ids(self) -> list[int]:
        """Node-IDs seen (heartbeat or scan) or open, ascending."""
        with self._lock:
            return sorted(set(self._benches) | set(self._heard) | set(self._scanned))

    def listing(self) -> list[dict[str, Any]]:
        """One row per node: ``node_id``, ``nmt_state`` (of its last heartbeat; ``OFFLINE``
        once older than :data:`OFFLINE_AFTER_S`; None without heartbeats), ``heartbeat_age_s``,
        ``open`` (a bench exists), ``default``, and for an open node its CiA 402 ``state``
        and ``controller`` (who holds its lease)."""
        now = time.monotonic()
        rows = []
        for node in self.ids():
            heard = self._heard.get(node)
            age: float | None = None
            nmt: str | None = None
            if heard is not None:
                age = now - heard[1]
                nmt = "OFFLINE" if age > OFFLINE_AFTER_S else heard[0]
            row: dict[str, Any] = {
                "node_id": node,
                "nmt_state": nmt,
                "heartbeat_age_s": age,
                "open": node in self._benches,
                "default": node == self.default.node_id,
                "state": None,
                "controller": None,
            }
            bench = self._benches.get(node)
            if bench is not None:
                with contextlib.suppress(Exception):
                    row["state"] = bench.state().get("state")
                holder = bench.lease.holder
                row["controller"] = holder.client if holder else None
            rows.append(row)
        return rows

    def scan(self, timeout: float = 0.3) -> list[dict[str, Any]]:
        """Probe every node-ID by SDO (``drive_link.scan`` on the bench's bus); returns
        :meth:`listing`."""
        from drive_link import scan

        with self._lock:
            skip = tuple(self._benches)
        found = scan(bus=self.default.drive.bus, timeout=timeout, skip=skip)
        now = time.monotonic()
        with self._lock:
            for info in found:
                self._scanned[info.node_id] = now
        return self.listing()

    # ---------------------------------------------------------------- benches
    def get(self, node: int | None) -> Bench:
        """The bench of ``node`` (None: the default), opened on first use; raises
        NodeNotFound for a node not seen (heartbeat or :meth:`scan`) or that does not answer,
        ValueError outside 1..127."""
        if node is None or node == self.default.node_id:
            return self.default
        if not 1 <= int(node) <= 127:
            raise ValueError(f"node-ID {node} is outside 1..127")
        if node == self._host_id:
            raise ValueError(f"node-ID {node} is this host's own heartbeat ID")
        with self._lock:
            bench = self._benches.get(node)
            if bench is None and node not in self._heard and node not in self._scanned:
                raise NodeNotFound(
                    f"node {node} not seen on the bus (no heartbeat; a scan probes every ID)"
                )
            if bench is None:
                bench = self._open(node)
                self._benches[node] = bench
        for cb in list(self.on_new):
            with contextlib.suppress(Exception):
                cb(bench)
        return bench

    def benches(self) -> list[Bench]:
        with self._lock:
            return list(self._benches.values())

    def _open(self, node: int) -> Bench:
        from drive_link import Drive

        base = self.default
        drive = Drive.connect(bus=base.drive.bus, node_id=node, heartbeat_ms=None)
        try:
            if drive.nmt_state != "OPERATIONAL":
                drive.nmt("start")  # TPDOs (live values) flow in OPERATIONAL only
                deadline = time.monotonic() + OPERATIONAL_WAIT_S
                while drive.nmt_state != "OPERATIONAL":
                    if time.monotonic() > deadline:
                        raise NodeNotFound(f"node {node} did not enter OPERATIONAL")
                    time.sleep(0.02)
            bench = Bench(drive, description=base.description, node_id=node, virtual=base.virtual)
        except BaseException:
            drive.close()
            raise
        bench.hub_port = base.hub_port
        return bench

    def close(self) -> None:
        """Close every bench but the default one (its opener closes it) and stop listening."""
        if self._network is not None:
            for node in range(1, 128):
                if node != self._host_id:
                    with contextlib.suppress(Exception):
                        self._network.unsubscribe(0x700 + node, self._on_heartbeat)
        with self._lock:
            others = [b for n, b in self._benches.items() if b is not self.default]
            self._benches = {self.default.node_id: self.default}
        for bench in others:
            with contextlib.suppress(Exception):
                bench.close()
            with contextlib.suppress(Exception):
                bench.drive.close()
