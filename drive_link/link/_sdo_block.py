"""SDO block upload, client side (CiA 301 §7.2.4.3.12–7.2.4.3.16), robust to lost, late and
duplicated frames.

Within a sub-block the client takes segments in sequence. At the first gap (a lost segment) it
acknowledges at once the last segment it has in sequence (``ackseq``); the server sends the rest
again as a new sub-block numbered from 1. The segments of the old sub-block still on their way
("leftovers") carry sequence numbers above the highest one seen before the acknowledgement, and
a new sub-block starts at 1, so leftovers are recognised and dropped. A sub-block whose last
segment was lost ends after ``silence_s`` without a segment and is acknowledged the same way.
An acknowledgement (or the start request) that gets no sub-block within ``ack_wait`` s is sent
again, waiting twice as long each time (at most 2 s). The sub-block size is halved after a loss
and doubled after a clean sub-block.

Acknowledgements are CiA 301's own (bytes 3..7 reserved, sent as 0). CiA 301 gives sub-blocks
no number, so a server that gets the same acknowledgement twice (the client resent it because
the answer was late, not lost) takes the second one for the next sub-block and skips data: the
length or CRC check below catches that and the upload restarts. So an acknowledgement is sent
again only after ``ack_wait`` (0.3 s, doubling) without a segment. If a resent acknowledgement
stays unanswered ``escalate_after`` times, the client asks for the whole sub-block again
(``ackseq`` 0): the answer itself was lost. (Until issue 29 drive_link numbered its
acknowledgements in reserved byte 3; CiA 301 marks the byte reserved, so no more.)

Never accepts wrong data: the total length is checked against the size the server announced
and, when the server supports it, the CRC-16/CCITT (``binascii.crc_hqx``, init 0) of the whole
data. A late answer can make the server skip a sub-block: the length or CRC check then fails
with :class:`SdoCommunicationError` and the caller (:class:`drive_link.link._sdo.SdoChannel`)
restarts the upload.

A server without block transfer (abort 0x05040001 to the initiate) or one that switches
protocol (a normal upload response) is read by segmented upload instead.
"""

from __future__ import annotations

import binascii
import struct
import time
from collections.abc import Callable

from canopen.sdo.exceptions import SdoAbortedError, SdoCommunicationError

from firmware_protocol import abort_codes

from ._sdo_client import (
    ABORT,
    BLOCK_ACK,
    BLOCK_END,
    BLOCK_INITIATE,
    BLOCK_SEQNO_MASK,
    BLOCK_SIZE_SPECIFIED,
    BLOCK_START,
    BLOCK_SUBCOMMAND_MASK,
    CRC_SUPPORTED,
    CS_MASK,
    LAST_BLOCK_SEGMENT,
    REQUEST_BLOCK_UPLOAD,
    RESPONSE_BLOCK_UPLOAD,
    RESPONSE_UPLOAD,
    ChannelClient,
)
from ._sdo_segmented import Exchange, NoAnswer, continue_upload, upload

ABORT_COMMAND = abort_codes.COMMAND
ABORT_CRC = abort_codes.CRC
MIN_BLKSIZE = 16

#: Figures of the last block upload in this process (for benchmarks): acks, gaps (sub-blocks
#: with a lost segment), silences (sub-blocks whose end was lost), resends (acknowledgements
#: or start requests sent again), leftovers (late segments of an acknowledged sub-block),
#: duplicates (frames delivered twice).
last_stats: dict[str, int] = {}


def block_upload(
    client: ChannelClient,
    index: int,
    subindex: int,
    progress: Callable[[int, int | None], None] | None = None,
    blksize: int = 127,
    timeout: float = 0.3,
    resends: int = 2,
    ack_resends: int = 8,
    silence_s: float = 0.25,
    deadline: float | None = None,
    ack_wait: float = 0.3,
    escalate_after: int = 4,
) -> bytes:
    """Upload ``index``:``subindex`` by block transfer on ``client``'s COB-IDs.

    ``timeout``: s to wait for the answer to the initiate request before sending it again
    (doubling); ``resends``: resends of the initiate request; ``ack_wait``: s to wait for the
    answer to the start request or an acknowledgement (doubling, at most 2 s);
    ``ack_resends``: resends of one of them; ``silence_s``: s without a segment before a
    sub-block counts as ended (0.25 s: a sub-block takes ~15 ms at 1 Mbit/s, but a busy host
    stalls its receive thread for 50–200 ms, and an early acknowledgement costs a resend);
    ``deadline``: ``time.monotonic()`` value after which the upload gives up.
    Raises :class:`SdoAbortedError` (the server aborted),
    :class:`NoAnswer` (the initiate request got no answer) or :class:`SdoCommunicationError`
    (the upload lost sync, CRC or length mismatch, deadline).
    """
    ex = Exchange(client, index, subindex)
    cmd = REQUEST_BLOCK_UPLOAD | CRC_SUPPORTED | BLOCK_INITIATE
    init = struct.pack("<BHBBB2x", cmd, index, subindex, blksize, 0)

    def initiate_answer(r: bytes) -> bool:
        same = struct.unpack_from("<HB", r, 1) == (index, subindex)
        block = r[0] & (CS_MASK | BLOCK_END) == RESPONSE_BLOCK_UPLOAD | BLOCK_INITIATE
        return same and (block or r[0] & CS_MASK == RESPONSE_UPLOAD)

    try:
        resp = ex.request(init, initiate_answer, timeout, resends, initial=True)
    except SdoAbortedError as exc:
        if exc.code != ABORT_COMMAND:
            raise
        # the server has no block transfer: read the object by segmented upload
        return upload(client, index, subindex, timeout, resends)
    if resp[0] & CS_MASK == RESPONSE_UPLOAD:  # protocol switch: a normal upload follows
        return continue_upload(ex, resp, timeout, resends)
    return _receive(
        ex, resp, progress, blksize, min(ack_wait, timeout), ack_resends, escalate_after,
        silence_s, deadline,
    )  # fmt: skip


def _receive(
    ex: Exchange,
    resp: bytes,
    progress: Callable[[int, int | None], None] | None,
    blksize: int,
    ack_wait: float,
    ack_resends: int,
    escalate_after: int,
    silence_s: float,
    deadline: float | None,
) -> bytes:
    size = struct.unpack_from("<I", resp, 4)[0] if resp[0] & BLOCK_SIZE_SPECIFIED else None
    crc_on = bool(resp[0] & CRC_SUPPORTED)
    stats = dict.fromkeys(("acks", "gaps", "silences", "resends", "leftovers", "duplicates"), 0)
    stats["frames"] = 0
    last_stats.clear()
    last_stats.update(stats)

    data = bytearray()
    block = bytearray()  # in-sequence segments of the current sub-block
    ackseq = 0  # last in-sequence seqno of the current sub-block
    seen_max = 0  # highest seqno seen in the current sub-block
    blk = blksize  # sub-block size asked for (the server sends min(blk, what is left))
    awaiting = True  # no segment of the next sub-block seen yet
    old_max = 127  # while awaiting: seqnos above this are leftovers of the previous sub-block
    finished = False  # the last segment arrived in sequence and was acknowledged
    pending = bytes([REQUEST_BLOCK_UPLOAD | BLOCK_START]) + bytes(7)  # sent again when unanswered
    wait = ack_wait
    quiet = 0
    prev = b""  # the previous frame (a duplicate of it is dropped)

    def send_ack(seq: int) -> None:
        nonlocal pending
        # CiA 301 §7.2.4.3.14: ackseq, blksize, bytes 3..7 reserved (always 0)
        pending = bytes([REQUEST_BLOCK_UPLOAD | BLOCK_ACK, seq, blk, 0, 0, 0, 0, 0])
        ex.send(pending)
    ex.send(pending)
    if progress:
        progress(0, size)

    def acknowledge(clean: bool) -> None:
        nonlocal block, ackseq, seen_max, blk, awaiting, old_max, wait, quiet
        data.extend(block)
        if size is not None and len(data) > size + 6:
            raise SdoCommunicationError("block upload: more data than announced (lost sync)")
        blk = min(blksize, blk * 2) if clean else max(MIN_BLKSIZE, blk // 2)
        old_max = 127 if clean else seen_max
        stats["acks"] += 1
        send_ack(ackseq)
        block = bytearray()
        ackseq = seen_max = 0
        awaiting = True
        wait = ack_wait
        quiet = 0
        if progress:
            progress(min(len(data), size) if size is not None else len(data), size)

    while True:
        if deadline is not None and time.monotonic() > deadline:
            raise SdoCommunicationError("block upload did not finish in time")
        frame = ex.next_or_gone(wait if awaiting else silence_s)  # NodeGone: heartbeat stopped
        if frame is None:
            if awaiting:  # the request or its whole answer was lost, or the server is slow
                quiet += 1
                if quiet > ack_resends:
                    raise SdoCommunicationError(
                        f"block upload stalled: no answer to {quiet} acknowledgements"
                    )
                stats["resends"] += 1
                if quiet == escalate_after and not finished:
                    # the server ignores repeats of an answered start or acknowledgement: if
                    # its answer was lost as a whole, ask for that sub-block again
                    send_ack(0)
                else:
                    ex.send(pending)
                wait = min(2.0, wait * 2)
            else:  # the end of the sub-block was lost
                stats["silences"] += 1
                acknowledge(clean=False)
            continue
        stats["frames"] += 1
        if frame == prev:  # the bus delivered the same frame twice
            stats["duplicates"] += 1
            continue
        prev = frame
        if finished:
            end = frame[0] & (CS_MASK | BLOCK_SUBCOMMAND_MASK) == RESPONSE_BLOCK_UPLOAD | BLOCK_END
            if end and (
                size is None or (frame[0] >> 2) & 0x07 == (7 - size % 7) % 7
            ):
                break
            stats["leftovers"] += 1
            continue
        seqno, last = frame[0] & BLOCK_SEQNO_MASK, bool(frame[0] & LAST_BLOCK_SEGMENT)
        if awaiting:
            if seqno == 0 or seqno > old_max:
                old_max = max(old_max, seqno)
                stats["leftovers"] += 1
                continue
            awaiting = False
        if seqno == ackseq + 1:
            ackseq = seen_max = seqno
            block += frame[1:8]
            if last:
                finished = True
                acknowledge(clean=True)
            elif seqno >= blk:
                acknowledge(clean=True)
        elif seqno > ackseq:  # a gap: acknowledge what arrived in sequence right away
            seen_max = seqno
            stats["gaps"] += 1
            acknowledge(clean=False)
        # seqno <= ackseq: the same segment twice (a duplicate frame): ignored
    last_stats.update(stats)
    n_unused = (frame[0] >> 2) & 0x07  # n: bytes of the last segment without data
    if n_unused:
        del data[-n_unused:]
    if size is not None and len(data) != size:
        ex.send(struct.pack("<BHBI", ABORT, ex.index, ex.subindex, ABORT_COMMAND))
        raise SdoCommunicationError(f"block upload returned {len(data)} of {size} bytes")
    if crc_on:
        crc = struct.unpack_from("<H", frame, 1)[0]
        if binascii.crc_hqx(bytes(data), 0) != crc:
            ex.send(struct.pack("<BHBI", ABORT, ex.index, ex.subindex, ABORT_CRC))
            raise SdoCommunicationError("block upload CRC mismatch")
    ex.send(bytes([REQUEST_BLOCK_UPLOAD | BLOCK_END]) + bytes(7))
    if progress:
        progress(len(data), size)
    return bytes(data)


__all__ = ["NoAnswer", "block_upload", "last_stats"]
