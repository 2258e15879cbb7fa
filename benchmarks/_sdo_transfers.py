"""Count SDO transfers on the bus, from the frames alone (a python-can listener on the hub).

A transfer is what a client starts with an initiate request on COB-ID 0x600 + node:
expedited or segmented download (ccs 1), expedited or segmented upload (ccs 2), block download
(ccs 6, cs 0), block upload (ccs 5, cs 0). Segments, block sub-frames, acknowledgements and
aborts belong to the transfer they are part of and are not counted (CiA 301 §7.2.4.3).
"""

from __future__ import annotations

import threading
from collections import Counter

import can

__all__ = ["SdoTransfers"]


class SdoTransfers(can.Listener):
    """Counts the SDO transfers a client starts with ``node`` (by object, ``(index, sub)``)."""

    def __init__(self, node: int) -> None:
        self.request_id = 0x600 + node
        self.response_id = 0x580 + node
        self.by_object: Counter[tuple[str, int, int]] = Counter()
        self.rpdo_ids = {0x200 + 0x100 * k + node for k in range(4)}  #: RPDO1..4 (default IDs)
        self.rpdos = 0  #: RPDO frames seen (not SDO transfers; counted beside them)
        self._in_block_download = False  # its sub-block frames carry sequence numbers, not ccs
        self._lock = threading.Lock()

    @property
    def total(self) -> int:
        with self._lock:
            return sum(self.by_object.values())

    def snapshot(self) -> Counter[tuple[str, int, int]]:
        with self._lock:
            return Counter(self.by_object)

    def on_message_received(self, msg: can.Message) -> None:
        if msg.is_error_frame or msg.is_remote_frame or not msg.data:
            return
        b0 = msg.data[0]
        with self._lock:
            if msg.arbitration_id in self.rpdo_ids:
                self.rpdos += 1
                return
            if msg.arbitration_id == self.response_id:
                if self._in_block_download and b0 & 0xE3 == 0xA1:  # block download end response
                    self._in_block_download = False
                return
            if msg.arbitration_id != self.request_id or self._in_block_download:
                return
            if b0 & 0xE0 == 0x20:
                kind = "download"
            elif b0 & 0xE0 == 0x40:
                kind = "upload"
            elif b0 & 0xE1 == 0xC0:
                kind = "block download"
                self._in_block_download = True
            elif b0 & 0xE3 == 0xA0:
                kind = "block upload"
            else:
                return  # a segment, an acknowledgement or an abort
            index = int.from_bytes(bytes(msg.data[1:3]), "little")
            self.by_object[(kind, index, msg.data[3] if len(msg.data) > 3 else 0)] += 1
