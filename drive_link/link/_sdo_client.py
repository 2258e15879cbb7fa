"""canopen's SDO client as drive_link's channels use it, and the SDO command specifiers by name.

Frames are built from canopen's own names (:mod:`canopen.sdo.constants`) where it has them;
CiA 301 §7.2.4.3 puts the command specifier in the top three bits of byte 0 (:data:`CS_MASK`),
the flags below it. The few names canopen lacks (the block sub-commands "acknowledge" and the
client's block-upload end, the segment "size in n" field) are defined here from CiA 301.

:class:`ChannelClient` is canopen's :class:`~canopen.sdo.SdoClient` with the state our transfer
code keeps per channel declared on the class (nothing is patched onto canopen's objects).
"""

from __future__ import annotations

import collections
from typing import Protocol

from canopen.sdo import constants as cs
from canopen.sdo.client import SdoClient

__all__ = [
    "ABORT",
    "BLOCK_ACK",
    "BLOCK_END",
    "BLOCK_INITIATE",
    "BLOCK_SEQNO_MASK",
    "BLOCK_SIZE_SPECIFIED",
    "BLOCK_START",
    "BLOCK_SUBCOMMAND_MASK",
    "CRC_SUPPORTED",
    "CS_MASK",
    "EXPEDITED",
    "LAST_BLOCK_SEGMENT",
    "LATENCIES_KEPT",
    "NO_MORE_SEGMENTS",
    "REQUEST_BLOCK_UPLOAD",
    "REQUEST_DOWNLOAD",
    "REQUEST_SEGMENT_DOWNLOAD",
    "REQUEST_SEGMENT_UPLOAD",
    "REQUEST_UPLOAD",
    "RESPONSE_BLOCK_UPLOAD",
    "RESPONSE_DOWNLOAD",
    "RESPONSE_SEGMENT_DOWNLOAD",
    "RESPONSE_SEGMENT_UPLOAD",
    "RESPONSE_UPLOAD",
    "SIZE_SPECIFIED",
    "TOGGLE_BIT",
    "ChannelClient",
    "NodeWatch",
]

CS_MASK = 0xE0
"""Command specifier bits of byte 0 (CiA 301 §7.2.4.3)."""
REQUEST_UPLOAD = cs.REQUEST_UPLOAD  # ccs 2: initiate upload
RESPONSE_UPLOAD = cs.RESPONSE_UPLOAD  # scs 2
REQUEST_SEGMENT_UPLOAD = cs.REQUEST_SEGMENT_UPLOAD  # ccs 3
RESPONSE_SEGMENT_UPLOAD = cs.RESPONSE_SEGMENT_UPLOAD  # scs 0
REQUEST_DOWNLOAD = cs.REQUEST_DOWNLOAD  # ccs 1: initiate download
RESPONSE_DOWNLOAD = cs.RESPONSE_DOWNLOAD  # scs 3
REQUEST_SEGMENT_DOWNLOAD = cs.REQUEST_SEGMENT_DOWNLOAD  # ccs 0
RESPONSE_SEGMENT_DOWNLOAD = cs.RESPONSE_SEGMENT_DOWNLOAD  # scs 1
REQUEST_BLOCK_UPLOAD = cs.REQUEST_BLOCK_UPLOAD  # ccs 5
RESPONSE_BLOCK_UPLOAD = cs.RESPONSE_BLOCK_UPLOAD  # scs 6
ABORT = cs.REQUEST_ABORTED  # cs 4, either direction
EXPEDITED = cs.EXPEDITED  # e
SIZE_SPECIFIED = cs.SIZE_SPECIFIED  # s (initiate); c "no more segments" in a segment
TOGGLE_BIT = cs.TOGGLE_BIT  # t
CRC_SUPPORTED = cs.CRC_SUPPORTED  # cc / sc (block)
BLOCK_SIZE_SPECIFIED = cs.BLOCK_SIZE_SPECIFIED  # s (block upload initiate response)
NO_MORE_SEGMENTS = cs.NO_MORE_DATA  # c: the last segment
LAST_BLOCK_SEGMENT = cs.NO_MORE_BLOCKS  # c of a block segment (byte 0 bit 7)
BLOCK_SEQNO_MASK = 0x7F
"""Sequence number bits of a block segment's byte 0."""
BLOCK_SUBCOMMAND_MASK = 0x03
"""Block transfer sub-command bits (cs/ss) of byte 0."""
BLOCK_INITIATE = cs.INITIATE_BLOCK_TRANSFER  # 0
BLOCK_END = cs.END_BLOCK_TRANSFER  # 1
BLOCK_ACK = 2  # CiA 301 §7.2.4.3.14: "block upload response" sub-command (not in canopen)
BLOCK_START = cs.START_BLOCK_UPLOAD  # 3


#: answers whose time (s from the last send of their request) a channel keeps
LATENCIES_KEPT = 8

class NodeWatch(Protocol):
    """Says when the node counts as gone (its heartbeat stopped): a supervised channel."""

    def gone_at(self) -> float | None:
        """Monotonic time from which the node counts as gone; None: no heartbeat watch."""
        ...

    def gone_reason(self) -> str:
        """One line: why the node counts as gone."""
        ...


class ChannelClient(SdoClient):
    """canopen's client without the abort frame after a response timeout, deaf to frames
    received before the present transfer began, with the per-channel state of our transfers.

    After a lost frame canopen sends an abort (0x05040000) and, on a retry, the new request
    right behind it; nothing requires that abort (the server times the transfer out itself and
    every initiate request starts afresh, CiA 301 §7.2.4.3), and on a lossy or slow link the
    back-to-back pair only adds load. Other aborts (CRC, protocol errors) are still sent.

    An answer cannot precede its request. On a starved host the bus thread may hand over
    frames seconds after the kernel received them: another client's answer on the same
    channel (a ``drive-link`` command run beside a session) or a late duplicate, for the same
    object, can then look like the answer to a request sent after it (seen in the SocketCAN
    lane: a gain read back as it was before a set that had been applied). Where the bus stamps
    frames with this host's clock (``host_clock``), a frame stamped before ``not_before`` (set
    when a transfer starts, :mod:`drive_link.link._sdo_segmented`) is dropped and counted in
    ``stale_dropped``.
    """

    def __init__(self, *args: object, host_clock: bool = False) -> None:
        super().__init__(*args)
        self.host_clock = host_clock
        #: host time (s) before which received frames belong to earlier transfers
        self.not_before = 0.0
        #: frames dropped as older than the transfer they arrived in
        self.stale_dropped = 0
        #: [frame, copies, owed until (monotonic s)]: late duplicates of earlier transfers'
        #: answers that transfers skip (see drive_link.link._sdo_segmented)
        self.stale_answers: list[list] = []
        #: the heartbeat watch of a supervised channel (None: requests wait their resends)
        self.watch: NodeWatch | None = None
        #: s from the last send of a request to its answer, for the last few answers (how long
        #: a frame held back as a late copy waits: drive_link.link._sdo_segmented.settle_s)
        self.latencies: collections.deque[float] = collections.deque(maxlen=LATENCIES_KEPT)

    def gone_at(self) -> float | None:
        """Monotonic time at which the node counts as gone (None: no heartbeat watch)."""
        return None if self.watch is None else self.watch.gone_at()

    def gone_reason(self) -> str:
        """Why the node counts as gone."""
        return "heartbeat stopped" if self.watch is None else self.watch.gone_reason()

    def on_response(self, can_id: int, data: bytearray, timestamp: float) -> None:
        if self.host_clock and timestamp and timestamp < self.not_before:
            self.stale_dropped += 1
            return
        super().on_response(can_id, data, timestamp)

    def abort(self, abort_code: int = cs.ABORT_GENERAL_ERROR) -> None:
        if abort_code == cs.ABORT_TIMED_OUT:  # SDO protocol timed out: see the class doc
            return
        super().abort(abort_code)
