"""SDO block upload, client side (CiA 301 §7.2.4.3.12–7.2.4.3.16), robust to lost frames.

canopen 2.4.1's client acknowledges in the middle of a sub-block when it sees a gap, while the
server is still sending; on a lossy link that desynchronises both sides. Here the client never
acknowledges early: after a gap it ignores the rest of the sub-block, and acknowledges the last
in-order segment (``ackseq``) when the sub-block ends (segment ``blksize`` or the last segment
seen) or when no segment arrives for ``timeout`` s; the server then re-sends from ``ackseq + 1``
as a new sub-block numbered from 1. The CRC-16/CCITT (``binascii.crc_hqx``, init 0) of the
whole data is checked when the server supports it.
"""

from __future__ import annotations

import binascii
import queue
import struct
from collections.abc import Callable

from canopen.sdo.client import SdoClient
from canopen.sdo.exceptions import SdoAbortedError, SdoCommunicationError

CCS_BLOCK_UPLOAD = 0xA0  # client command specifier 5
SCS_BLOCK_UPLOAD = 0xC0  # server command specifier 6
CRC_SUPPORTED = 0x04
SIZE_INDICATED = 0x02
CS_INITIATE, CS_END, CS_ACK, CS_START = 0, 1, 2, 3
ABORT = 0x80

#: Figures of the last block upload in this process (for benchmarks): acks, stalls, gaps.
last_stats: dict[str, int] = {}


def _get(client: SdoClient, timeout: float) -> bytes | None:
    try:
        data = client.responses.get(block=True, timeout=timeout)
    except queue.Empty:
        return None
    if data[0] == ABORT and len(data) >= 8:
        raise SdoAbortedError(struct.unpack_from("<I", data, 4)[0])
    return bytes(data)


def block_upload(
    client: SdoClient,
    index: int,
    subindex: int,
    progress: Callable[[int, int | None], None] | None = None,
    blksize: int = 127,
    timeout: float = 0.3,
    max_stalls: int = 8,
    stall_s: float = 0.06,
) -> bytes:
    """Upload ``index``:``subindex`` by block transfer with ``client``'s COB-IDs.

    ``timeout``: s to wait for the answer to the initiate request; ``stall_s``: s without a
    segment before the client acknowledges what it has (a stall; segments follow each other
    within ~0.13 ms at 1 Mbit/s); ``max_stalls``: stalls in a row before giving up
    (:class:`SdoCommunicationError`).
    Raises :class:`SdoAbortedError` when the server aborts.
    """
    send = client.network.send_message
    rx = client.rx_cobid
    client.responses = queue.Queue()  # drop stale frames of an earlier transfer
    req = struct.pack(
        "<BHBBB", CCS_BLOCK_UPLOAD | CRC_SUPPORTED | CS_INITIATE, index, subindex, blksize, 0
    )
    send(rx, req + b"\0\0")
    resp = None
    for _ in range(max_stalls):
        resp = _get(client, timeout)
        if resp is not None:
            break
        send(rx, req + b"\0\0")  # initiate is idempotent until the server sends data
    if resp is None:
        raise SdoCommunicationError("no answer to the block upload request")
    if resp[0] & 0xE1 != SCS_BLOCK_UPLOAD | CS_INITIATE:
        client.abort(0x05040001)
        raise SdoCommunicationError(f"unexpected block upload response 0x{resp[0]:02X}")
    r_index, r_sub = struct.unpack_from("<HB", resp, 1)
    if (r_index, r_sub) != (index, subindex):
        raise SdoCommunicationError("block upload response for another object")
    size = struct.unpack_from("<I", resp, 4)[0] if resp[0] & SIZE_INDICATED else None
    crc_on = bool(resp[0] & CRC_SUPPORTED)
    send(rx, bytes([CCS_BLOCK_UPLOAD | CS_START, 0, 0, 0, 0, 0, 0, 0]))
    if progress:
        progress(0, size)

    data = bytearray()
    block = bytearray()  # in-order segments of the current sub-block
    ackseq = 0  # last in-order seqno of the current sub-block
    prev_ack: bytes | None = None  # the last acknowledgement sent
    done = False  # the last segment arrived in order and was acknowledged
    stalls = 0

    blk_now = blksize  # size of the sub-block being received
    stats = {"acks": 0, "stalls": 0, "gaps": 0, "frames": 0}
    last_stats.clear()
    last_stats.update(stats)

    def acknowledge() -> None:
        nonlocal ackseq, block, prev_ack, blk_now
        stats["acks"] += 1
        stats["gaps"] += ackseq < blk_now and not done
        # adapt the next sub-block: halve it after a loss, grow it back after a clean one
        clean = ackseq >= blk_now
        blk_now = min(blksize, blk_now * 2) if clean else max(8, blk_now // 2)
        prev_ack = bytes([CCS_BLOCK_UPLOAD | CS_ACK, ackseq, blk_now, 0, 0, 0, 0, 0])
        send(rx, prev_ack)
        data.extend(block)
        block = bytearray()
        ackseq = 0
        if progress:
            progress(min(len(data), size) if size else len(data), size)

    while True:
        frame = _get(client, stall_s)
        if frame is None:
            stats["stalls"] += 1
            last_stats.update(stats)
            stalls += 1
            if stalls > max_stalls:
                raise SdoCommunicationError("block upload stalled (frames lost)")
            if ackseq == 0 and not block:
                # nothing new since the last acknowledgement (or the start): it was lost
                send(rx, prev_ack or bytes([CCS_BLOCK_UPLOAD | CS_START, 0, 0, 0, 0, 0, 0, 0]))
            else:
                acknowledge()  # the end of the sub-block was lost
            continue
        stalls = 0
        stats["frames"] += 1
        if done:
            if frame[0] & 0xE1 == SCS_BLOCK_UPLOAD | CS_END:
                break
            continue  # a late segment of a re-sent sub-block
        seqno, last = frame[0] & 0x7F, bool(frame[0] & 0x80)
        if seqno == ackseq + 1:
            ackseq = seqno
            block += frame[1:8]
            if last:
                done = True
                acknowledge()
            elif seqno >= blk_now:
                acknowledge()
        elif seqno >= blk_now or last:
            acknowledge()  # the sub-block ended with a gap: the server re-sends after ackseq
    n_unused = (frame[0] >> 2) & 0x07
    if n_unused:
        del data[-n_unused:]
    if crc_on:
        crc = struct.unpack_from("<H", frame, 1)[0]
        if binascii.crc_hqx(bytes(data), 0) != crc:
            client.abort(0x05040004)
            raise SdoCommunicationError("block upload CRC mismatch")
    send(rx, bytes([CCS_BLOCK_UPLOAD | CS_END, 0, 0, 0, 0, 0, 0, 0]))
    last_stats.update(stats)
    if size is not None and len(data) != size:
        raise SdoCommunicationError(f"block upload returned {len(data)} of {size} bytes")
    return bytes(data)
