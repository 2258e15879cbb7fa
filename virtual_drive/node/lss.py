"""LSS slave (CiA 305 Layer Setting Services) of the virtual drive.

A drive out of the box has no valid node-ID (0xFF: "unconfigured") and keeps quiet on the bus
except for LSS (master → slave 0x7E5, slave → master 0x7E4). An LSS master finds it by its LSS
address (the identity object 0x1018: vendor-ID, product code, revision, serial number), gives it
a node-ID and a bit timing, and may make the drive store them; when the master switches the
slave back to LSS waiting state, an unconfigured drive boots with its new node-ID (NMT boot-up,
then the ordinary CiA 301/402 node). A configured drive takes a new node-ID at its next NMT
reset communication / reset node, as CiA 305 asks.

Services (command specifier in byte 0; the DSP firmware implements the same set, see
``virtual_drive/node/README.md``, "LSS"):

====================  =====================================================================
0x04                  switch state global (byte 1: 0 waiting, 1 configuration), no answer
0x40-0x43 → 0x44      switch state selective: vendor, product, revision, serial in turn
0x11                  configure node-ID (1..127, 0xFF = unconfigured); answer error 0/1
0x13                  configure bit timing (table 0: 0 = 1000, 2 = 500, 3 = 250, 4 = 125 kbit/s)
0x15                  activate bit timing (delay in ms), no answer
0x17                  store configuration (node-ID and bit timing to the LSS file): 0 ok,
                      1 not supported (no file), 2 storage access error
0x46-0x4B → 0x4F      identify remote slave (LSS address ranges)
0x4C → 0x50           identify non-configured remote slave
0x51 → 0x4F           fast scan (only unconfigured slaves in waiting state take part)
0x5A-0x5E             inquire vendor, product, revision, serial, node-ID (configuration state)
====================  =====================================================================
"""

from __future__ import annotations

import json
import logging
import struct
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import can

from firmware_protocol.od import load_od

_OD = load_od()  # where the objects are: the EDS, through firmware_protocol's view
IDENTITY_INDEX = _OD.index_of("identity")


__all__ = ["BIT_TIMING_TABLE", "LSS_RX", "LSS_TX", "UNCONFIGURED", "LssSlave"]

logger = logging.getLogger(__name__)

LSS_RX = 0x7E5  #: master → slave
LSS_TX = 0x7E4  #: slave → master
UNCONFIGURED = 0xFF
#: CiA 305 bit timing table 0: index → bit/s (only the rates the EDS's [DeviceInfo] supports)
BIT_TIMING_TABLE = {0: 1_000_000, 2: 500_000, 3: 250_000, 4: 125_000}

WAITING, CONFIGURATION = 0, 1

#: On a CAN bus, identical frames that several slaves send at once are one frame (they win the
#: arbitration together). Slaves in one process share this: (request, answer) → when sent.
_MERGE_S = 0.005
_answered: dict[tuple[bytes, bytes], float] = {}
_answered_lock = threading.Lock()


class LssSlave:
    """The LSS slave of one virtual drive on ``bus``.

    :param identity: (vendor-ID, product code, revision, serial number), the 0x1018 values.
    :param make_drive: builds (not starts) the drive for a node-ID on ``bus``.
    :param node_id: the node-ID at power-on (None or 0xFF: unconfigured; a stored one wins).
    :param store: the LSS file (JSON with the stored node-ID and bit rate; None: 0x17 refused).
    """

    def __init__(
        self,
        bus: can.BusABC,
        identity: tuple[int, int, int, int],
        make_drive: Callable[[int], Any],
        node_id: int | None = None,
        store: str | Path | None = None,
        bitrate: int = 1_000_000,
    ) -> None:
        self.bus = bus
        self.identity = tuple(int(x) & 0xFFFFFFFF for x in identity)
        self.make_drive = make_drive
        self.store = Path(store) if store is not None else None
        self.bitrate = bitrate
        stored = self._stored()
        self.node_id = stored.get("node_id", node_id if node_id is not None else UNCONFIGURED)
        self.pending_id = self.node_id
        self.pending_bitrate: int | None = None
        self.state = WAITING
        self.drive: Any = None
        self._lock = threading.RLock()
        self._notifier: can.Notifier | None = None
        self._selective: list[int] = []  # switch state selective: parts matched so far
        self._remote: list[int] = []  # identify remote slave: ranges received so far
        self._scan_pos: int | None = None  # fast scan: the LSS sub being checked (LSSPos)
        self._request = b""  # the request being answered

    # -- lifecycle ----------------------------------------------------------------------
    def start(self) -> LssSlave:
        """Unconfigured: listen for LSS alone; configured: boot the drive (it listens too)."""
        with self._lock:
            if 1 <= self.node_id <= 127:
                self._boot(self.node_id)
            else:
                self._notifier = can.Notifier(self.bus, [self._listener()], 0.2)
        return self

    def stop(self) -> None:
        with self._lock:
            if self._notifier is not None:
                self._notifier.stop(2.0)
                self._notifier = None
            if self.drive is not None:
                self.drive.stop()
                self.drive = None

    def _listener(self) -> can.Listener:
        slave = self

        class _L(can.Listener):
            def on_message_received(self, msg: can.Message) -> None:
                if msg.arbitration_id == LSS_RX and not msg.is_remote_frame:
                    slave.on_request(LSS_RX, bytes(msg.data), msg.timestamp)

            def stop(self) -> None:
                pass

        return _L()

    def _boot(self, node_id: int) -> None:
        """Start the drive with ``node_id`` (the bus's reader becomes the drive's notifier)."""
        if self._notifier is not None:
            self._notifier.stop(2.0)
            self._notifier = None
        drive = self.make_drive(node_id)
        for sub, value in enumerate(self.identity, start=1):
            drive.od[IDENTITY_INDEX][sub].default = value
        drive.network.subscribe(LSS_RX, self.on_request)
        drive.network.subscribe(0x000, self._on_nmt)
        drive.start()
        self.drive = drive
        self.node_id = self.pending_id = node_id
        logger.info("LSS: node %d booted (serial %d)", node_id, self.identity[3])

    def _rebooted(self, node_id: int) -> None:
        """A configured drive's new node-ID: stop it, boot the new one (another thread)."""

        def run() -> None:
            with self._lock:
                old, self.drive = self.drive, None
                if old is not None:
                    old.network.unsubscribe(LSS_RX, self.on_request)
                    old.stop()
                if 1 <= node_id <= 127:
                    self._boot(node_id)
                else:
                    self.node_id = UNCONFIGURED
                    self._notifier = can.Notifier(self.bus, [self._listener()], 0.2)

        threading.Thread(target=run, name="lss-reboot", daemon=True).start()

    def _on_nmt(self, can_id: int, data: bytearray, timestamp: float) -> None:
        """NMT reset node (0x81) / reset communication (0x82) takes a pending node-ID."""
        if len(data) >= 2 and data[0] in (0x81, 0x82) and data[1] in (0, self.node_id):
            if self.pending_id != self.node_id:
                self._rebooted(self.pending_id)

    # -- the protocol -------------------------------------------------------------------
    def _send(self, *payload: int, u32: int | None = None) -> None:
        data = bytearray(8)
        data[0 : len(payload)] = bytes(payload)
        if u32 is not None:
            data[1:5] = struct.pack("<I", u32)
        key = (self._request, bytes(data))
        now = time.monotonic()
        with _answered_lock:  # the same answer to the same request from a slave here: merged
            if now - _answered.get(key, -1.0) < _MERGE_S:
                return
            _answered[key] = now
            if len(_answered) > 256:
                for k in [k for k, v in _answered.items() if now - v > _MERGE_S]:
                    del _answered[k]
        msg = can.Message(arbitration_id=LSS_TX, data=data, is_extended_id=False)
        try:
            self.bus.send(msg)
        except can.CanError as exc:
            logger.warning("LSS answer not sent: %s", exc)

    def on_request(self, can_id: int, data: bytes, timestamp: float) -> None:
        """One frame on 0x7E5 (canopen Network subscriber signature)."""
        if len(data) < 1:
            return
        with self._lock:
            self._request = bytes(data).ljust(8, b"\0")
            self._handle(self._request)

    def _handle(self, d: bytes) -> None:
        cs = d[0]
        u32 = struct.unpack_from("<I", d, 1)[0]
        if cs == 0x04:
            self._switch_global(d[1])
        elif 0x40 <= cs <= 0x43 and self.state == WAITING:
            self._switch_selective(cs - 0x40, u32)
        elif 0x46 <= cs <= 0x4B:
            self._identify_remote(cs - 0x46, u32)
        elif cs == 0x4C and self.node_id == UNCONFIGURED and self.pending_id == UNCONFIGURED:
            self._send(0x50)
        elif cs == 0x51:
            self._fast_scan(u32, d[5], d[6], d[7])
        elif self.state != CONFIGURATION:
            return  # everything below is for a slave in configuration state only
        elif cs == 0x11:
            ok = 1 <= d[1] <= 127 or d[1] == UNCONFIGURED
            if ok:
                self.pending_id = d[1]
            self._send(0x11, 0 if ok else 1)
        elif cs == 0x13:
            rate = BIT_TIMING_TABLE.get(d[2]) if d[1] == 0 else None
            if rate is not None:
                self.pending_bitrate = rate
            self._send(0x13, 0 if rate is not None else 1)
        elif cs == 0x15:
            if self.pending_bitrate is not None:  # one rate on the hub: remembered only
                self.bitrate = self.pending_bitrate
        elif cs == 0x17:
            self._send(0x17, self._store())
        elif 0x5A <= cs <= 0x5D:
            self._send(cs, u32=self.identity[cs - 0x5A])
        elif cs == 0x5E:
            self._send(0x5E, self.node_id)

    def _switch_global(self, mode: int) -> None:
        if mode == CONFIGURATION:
            self.state = CONFIGURATION
            return
        if mode != WAITING:
            return
        self.state = WAITING
        self._selective = []
        self._scan_pos = None
        if self.node_id == UNCONFIGURED and 1 <= self.pending_id <= 127:
            self._rebooted(self.pending_id)  # CiA 305: a new node-ID boots the node now

    def _switch_selective(self, part: int, value: int) -> None:
        if part != len(self._selective) or value != self.identity[part]:
            self._selective = []
            return
        self._selective.append(value)
        if len(self._selective) == 4:
            self._selective = []
            self.state = CONFIGURATION
            self._send(0x44)

    def _identify_remote(self, step: int, value: int) -> None:
        if step == 0:
            self._remote = []
        if step != len(self._remote):
            self._remote = []
            return
        self._remote.append(value)
        if step < 5:
            return
        vendor, product, rev_lo, rev_hi, ser_lo, ser_hi = self._remote
        self._remote = []
        _, _, rev, ser = self.identity
        if (
            (vendor, product) == self.identity[:2]
            and rev_lo <= rev <= rev_hi
            and (ser_lo <= ser <= ser_hi)
        ):
            self._send(0x4F)

    def _fast_scan(self, id_number: int, bit_checked: int, sub: int, nxt: int) -> None:
        """CiA 305 fast scan: only an unconfigured slave in waiting state takes part."""
        if self.state != WAITING or self.node_id != UNCONFIGURED:
            return
        if self.pending_id != UNCONFIGURED:
            return
        if bit_checked == 0x80:  # reset: every candidate answers
            self._scan_pos = 0
            self._send(0x4F)
            return
        if self._scan_pos is None or self._scan_pos != sub or not 0 <= sub <= 3:
            return
        if bit_checked > 31:
            return
        mask = (0xFFFFFFFF << bit_checked) & 0xFFFFFFFF
        if (self.identity[sub] ^ id_number) & mask:
            return
        self._send(0x4F)
        if bit_checked == 0:
            if nxt < sub:  # LSSNext wrapped: the whole address matched, this slave is the one
                self._scan_pos = None
                self.state = CONFIGURATION
            else:
                self._scan_pos = nxt

    # -- storage ------------------------------------------------------------------------
    def _stored(self) -> dict[str, int]:
        if self.store is None or not self.store.exists():
            return {}
        try:
            data = json.loads(self.store.read_text())
            node = int(data.get("node_id", UNCONFIGURED))
            return {"node_id": node} if 1 <= node <= 127 else {}
        except (OSError, ValueError, TypeError):
            logger.warning("LSS file %s unreadable: unconfigured", self.store)
            return {}

    def _store(self) -> int:
        """0 stored, 1 storing not supported (no LSS file), 2 the file could not be written."""
        if self.store is None:
            return 1
        tmp = self.store.with_suffix(self.store.suffix + ".tmp")
        try:
            rate = self.pending_bitrate or self.bitrate
            tmp.write_text(json.dumps({"node_id": self.pending_id, "bitrate": rate}))
            tmp.replace(self.store)
        except OSError:
            return 2
        return 0
