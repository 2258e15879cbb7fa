"""SDO server: expedited, segmented and block transfer (CiA 301 §7.2.4.3), NMT gating, and
tolerance of slow, repeating or duplicating clients.

canopen 2.4.1's :class:`canopen.sdo.SdoServer` serves expedited and segmented transfers only,
aborts a repeated segment request (toggle error) and never times a transfer out.
:class:`BlockSdoServer` serves every transfer itself:

- expedited and segmented upload/download; a repeated segment request (the same toggle bit as
  the one just answered: the client did not get the answer) is answered again with the same
  segment, and a repeated download segment is not stored twice;
- block upload: initiate (blksize, pst, CRC flag), sub-blocks of up to 127 segments of 7 bytes,
  acknowledgement with ``ackseq`` (segments after ``ackseq`` are sent again as the next
  sub-block, numbered from 1), end with the number of unused bytes in the last segment and the
  CRC-16/CCITT (``binascii.crc_hqx``, initial value 0) when the client asked for it; a
  protocol-switch threshold ``pst`` larger than the size falls back to a normal upload;
- block download: the server proposes ``blksize``, acknowledges each sub-block with the last
  segment received in sequence, checks the CRC when both sides support it, and stores the
  data through the node's checked :meth:`set_data` (write callbacks may abort);
- NMT gating: no SDO service in STOPPED (or while initialising); requests are ignored as
  CiA 301 prescribes.

Repeats and duplicates (a client that resends a request it got no answer to, or a frame the bus
delivered twice): any initiate request starts its transfer afresh and replaces whatever was open
on the channel; a repeated block-upload "start" is ignored once the first sub-block is out; an
acknowledgement while the upload-end response is out makes the server send that response again;
a repeated client "end" is ignored. A repeated block-upload *acknowledgement* of a sub-block the
server already answered cannot be told from the acknowledgement of the next sub-block (CiA 301
gives sub-blocks no number): a standard client's repeat is taken as the next acknowledgement and
the CRC of the end response exposes the damage to the client. Reserved bytes of requests are
not interpreted (CiA 301); the server's own reserved bytes are 0.

Frames that are not SDO requests: a frame on the request COB-ID with fewer than 8 data bytes is
ignored and counted in :attr:`BlockSdoServer.short_frames` (CiA 301 §7.2.4.3: every SDO frame
carries 8 bytes; CANopenNode's server drops other lengths the same way). An abort is not sent:
a 1-byte frame carries no multiplexer the abort could name, and it is a damaged or foreign
frame, not a request. A request with an invalid command specifier is aborted with 0x05040001
naming its own index/sub-index (bytes 1..3), not an earlier transfer's.

Timeout (:attr:`BlockSdoServer.timeout`, 10 s): an open transfer (segmented or block) that gets
no client frame for that long is aborted with 0x05040000 (SDO protocol timed out) and forgotten.
A client that pauses for seconds is served normally when it goes on.

The same class serves the second server channel (0x1201) with other COB-IDs.
"""

from __future__ import annotations

import binascii
import logging
import struct
import threading
import time
from collections.abc import Callable

from canopen.sdo import SdoAbortedError, SdoServer
from canopen.sdo.constants import (
    ABORT_CRC_ERROR,
    ABORT_INVALID_BLOCK_SIZE,
    ABORT_INVALID_COMMAND_SPECIFIER,
    ABORT_INVALID_SEQUENCE_NUMBER,
    ABORT_NO_DATA_AVAILABLE,
    ABORT_NOT_IN_OD,
    ABORT_TIMED_OUT,
    ABORT_TOGGLE_NOT_ALTERNATED,
    BLOCK_SIZE_SPECIFIED,
    CRC_SUPPORTED,
    REQUEST_ABORTED,
    RESPONSE_BLOCK_DOWNLOAD,
    RESPONSE_BLOCK_UPLOAD,
    SDO_STRUCT,
)

from firmware_protocol import abort_codes

from .local_node import DriveLocalNode

__all__ = ["MAX_BLKSIZE", "BlockSdoServer", "crc16_ccitt"]

logger = logging.getLogger(__name__)

#: Largest sub-block the protocol allows (seqno is 7 bits, 0 invalid).
MAX_BLKSIZE = 127

ABORT_READ_ONLY = abort_codes.WRITE_READ_ONLY
ABORT_LENGTH = abort_codes.LENGTH

# client command specifiers (bits 7..5 of byte 0)
_CCS_SEG_DOWN, _CCS_INIT_DOWN, _CCS_INIT_UP, _CCS_SEG_UP = 0, 1, 2, 3
_CCS_ABORT, _CCS_BLOCK_UP, _CCS_BLOCK_DOWN = 4, 5, 6
_TOGGLE = 0x10

# block transfer sub-commands
_CS_INITIATE = 0
_CS_END = 1
_CS_ACK = 2
_CS_START = 3


def crc16_ccitt(data: bytes, crc: int = 0) -> int:
    """CRC-16/CCITT (XMODEM: poly 0x1021, init 0) as CiA 301 specifies for block transfer."""
    return binascii.crc_hqx(data, crc)


class BlockSdoServer(SdoServer):
    """SDO server for expedited, segmented and block transfers (see the module doc).

    :param rx_cobid: COB-ID of client→server requests (0x600+N for 0x1200).
    :param tx_cobid: COB-ID of server→client responses (0x580+N for 0x1200).
    :param node: the local node (``get_data`` / ``set_data``).
    :param allowed: returns False while the NMT state forbids SDO (STOPPED).
    :param download_blksize: sub-block size this server proposes for block downloads.
    :param send: ``send(cob_id, data)``; default: the network's ``send_message``.
    :param timeout: s without a client frame before an open transfer is aborted (0x05040000).
    """

    #: Default s without a client frame before an open transfer is aborted with 0x05040000.
    timeout = 10.0

    def __init__(
        self,
        rx_cobid: int,
        tx_cobid: int,
        node: DriveLocalNode,
        allowed: Callable[[], bool] = lambda: True,
        download_blksize: int = MAX_BLKSIZE,
        send: Callable[[int, bytes], None] | None = None,
        timeout: float | None = None,
    ) -> None:
        super().__init__(rx_cobid, tx_cobid, node)
        if timeout is not None:
            self.timeout = float(timeout)
        self._allowed = allowed
        self._send = send
        self._lock = threading.RLock()
        self._timer: threading.Timer | None = None
        self._last_rx = 0.0
        self._timed_out = False  # the last transfer was dropped by the timeout
        self.download_blksize = download_blksize
        self._index = 0
        self._subindex = 0
        #: transfers the server aborted because the client went silent (for tests/benchmarks)
        self.timeouts = 0
        #: frames on the request COB-ID with other than 8 data bytes (ignored)
        self.short_frames = 0
        self._reset()

    # -- state -------------------------------------------------------------------------------
    def _reset(self) -> None:
        """Forget any open transfer (the repeat cache of the last segment too)."""
        #: None, "seg_up", "seg_down", "up_init", "up", "up_end", "down", "down_end"
        self._mode: str | None = None
        self._data = b""
        self._pos = 0  # upload: offset of the next segment / of the current sub-block
        self._toggle = 0  # segmented: toggle bit expected next
        self._last_seg: tuple[str, int, bytes] | None = None  # (kind, toggle, response)
        self._blksize = 0
        self._sent = 0  # block upload: segments sent in the current sub-block
        self._acks = 0  # block upload: acknowledgements received
        self._end_frame = b""  # block upload: the end response (sent again on a repeated ack)
        self._crc_on = False
        self._chunks: list[bytes] = []
        self._expected = 1
        self._last_seen = False
        self._last_frame = b""  # block download: the previous segment (duplicate filter)
        self._last_ack = b""  # block download: the last acknowledgement sent
        self._size: int | None = None

    def _open(self, mode: str) -> None:
        """Enter a transfer state that waits for the client (watched by the timeout)."""
        self._mode = mode
        self._timed_out = False
        if self._timer is not None:
            self._timer.cancel()
        self._start_timer(self.timeout)

    def _start_timer(self, delay: float) -> None:
        timer = threading.Timer(delay, self._watchdog)
        timer.daemon = True
        self._timer = timer
        timer.start()

    def _watchdog(self) -> None:
        with self._lock:
            self._timer = None
            if self._mode is None:
                return
            idle = time.monotonic() - self._last_rx
            if idle < self.timeout:
                self._start_timer(self.timeout - idle)
                return
            self._expire(tell_client=True)

    def _expire(self, tell_client: bool) -> None:
        logger.info(
            "SDO transfer 0x%04X:%02X timed out (%s, no client frame for %.1f s)",
            self._index,
            self._subindex,
            self._mode,
            self.timeout,
        )
        self.timeouts += 1
        self._reset()
        self._timed_out = True
        if tell_client and self._allowed():
            try:
                self.abort(ABORT_TIMED_OUT)
            except Exception:  # a closed bus: nobody to tell
                logger.debug("timeout abort not sent", exc_info=True)

    def _no_transfer(self) -> SdoAbortedError:
        """Abort for a continuation request without an open transfer."""
        if self._timed_out:
            return SdoAbortedError(ABORT_TIMED_OUT)
        return SdoAbortedError(ABORT_INVALID_COMMAND_SPECIFIER)

    # -- dispatch ----------------------------------------------------------------------------
    def on_request(self, can_id: int, data: bytes | bytearray, timestamp: float) -> None:
        if not self._allowed():
            return
        data = bytes(data)
        if len(data) != 8:  # not an SDO frame (CiA 301: 8 bytes): ignored, counted
            self.short_frames += 1
            return
        with self._lock:
            now = time.monotonic()
            if self._mode is not None and now - self._last_rx > self.timeout:
                # the watchdog thread has not run yet (busy host): a continuation request
                # gets the timeout abort below, an initiate request is served
                self._expire(tell_client=False)
            self._last_rx = now
            try:
                self._dispatch(data)
            except SdoAbortedError as exc:
                self._reset()
                self.abort(exc.code)
            except KeyError:
                self._reset()
                self.abort(ABORT_NOT_IN_OD)
            except Exception:  # keep the node alive; report a general error
                logger.exception("SDO transfer failed")
                self._reset()
                self.abort()

    def _dispatch(self, data: bytes) -> None:
        command = data[0]
        if self._mode == "down":
            # During a block download every frame is a segment (no command specifier);
            # seqno 0 is invalid, so 0x80 is the client's abort request.
            if command == REQUEST_ABORTED:
                self._reset()
            else:
                self._download_segment(data)
            return
        ccs = command >> 5
        if ccs == _CCS_ABORT:
            self._reset()
        elif ccs == _CCS_INIT_UP:
            self._init_upload(data)
        elif ccs == _CCS_SEG_UP:
            self._segment_upload(command)
        elif ccs == _CCS_INIT_DOWN:
            self._init_download(data)
        elif ccs == _CCS_SEG_DOWN:
            self._segment_download(data)
        elif ccs == _CCS_BLOCK_UP:
            self._block_upload(data)
        elif ccs == _CCS_BLOCK_DOWN:
            self._block_download(data)
        else:  # the abort names this request's own multiplexer (bytes 1..3)
            self._index, self._subindex = SDO_STRUCT.unpack_from(data)[1:]
            raise SdoAbortedError(ABORT_INVALID_COMMAND_SPECIFIER)

    def send_response(self, response: bytes) -> None:
        if self._send is not None:
            self._send(self.tx_cobid, bytes(response))
        else:
            self.network.send_message(self.tx_cobid, response)

    def _begin(self, req: bytes) -> tuple[int, int]:
        """A new transfer replaces whatever was open on this channel."""
        self._reset()
        _, index, subindex = SDO_STRUCT.unpack_from(req)
        self._index, self._subindex = index, subindex
        return index, subindex

    # -- expedited / segmented upload ------------------------------------------------------
    def _init_upload(self, req: bytes) -> None:
        index, subindex = self._begin(req)
        data = bytes(self._node.get_data(index, subindex, check_readable=True))
        self._respond_upload(index, subindex, data)

    def _respond_upload(self, index: int, subindex: int, data: bytes) -> None:
        size = len(data)
        if size == 0:
            raise SdoAbortedError(ABORT_NO_DATA_AVAILABLE)
        if size <= 4:  # expedited, size indicated
            cmd = 0x43 | ((4 - size) << 2)
            self.send_response(SDO_STRUCT.pack(cmd, index, subindex) + data.ljust(4, b"\0"))
            return
        self._data = data
        self._pos = 0
        self._toggle = 0
        self._open("seg_up")
        self.send_response(struct.pack("<BHBL", 0x41, index, subindex, size))

    def _segment_upload(self, command: int) -> None:
        toggle = command & _TOGGLE
        last = self._last_seg
        if self._mode == "seg_up" and toggle == self._toggle:
            chunk = self._data[self._pos : self._pos + 7]
            self._pos += len(chunk)
            done = self._pos >= len(self._data)
            cmd = toggle | ((7 - len(chunk)) << 1) | (1 if done else 0)
            resp = bytes([cmd]) + chunk.ljust(7, b"\0")
            self._toggle ^= _TOGGLE
            if done:
                self._mode = None  # complete; the segment stays cached for a repeat
                self._data = b""
            self._last_seg = ("up", toggle, resp)
            self.send_response(resp)
        elif last is not None and last[0] == "up" and last[1] == toggle:
            self.send_response(last[2])  # the client did not get it: the same segment again
        elif self._mode == "seg_up":
            raise SdoAbortedError(ABORT_TOGGLE_NOT_ALTERNATED)
        else:
            raise self._no_transfer()

    # -- expedited / segmented download ----------------------------------------------------
    def _init_download(self, req: bytes) -> None:
        index, subindex = self._begin(req)
        command = req[0]
        resp = SDO_STRUCT.pack(0x60, index, subindex) + bytes(4)
        if command & 0x02:  # expedited
            size = 4 - ((command >> 2) & 0x03) if command & 0x01 else 4
            self._node.set_data(index, subindex, req[4 : 4 + size], check_writable=True)
            self.send_response(resp)
            return
        obj = self._node.find_object(index, subindex)
        if not obj.writable:
            raise SdoAbortedError(ABORT_READ_ONLY)
        if command & 0x01:
            (self._size,) = struct.unpack_from("<L", req, 4)
        self._chunks = []
        self._toggle = 0
        self._open("seg_down")
        self.send_response(resp)

    def _segment_download(self, req: bytes) -> None:
        command = req[0]
        toggle = command & _TOGGLE
        last = self._last_seg
        if self._mode == "seg_down" and toggle == self._toggle:
            n = 7 - ((command >> 1) & 0x07)
            self._chunks.append(req[1 : 1 + n])
            resp = bytes([0x20 | toggle]) + bytes(7)
            self._toggle ^= _TOGGLE
            if command & 0x01:  # no more segments
                data = b"".join(self._chunks)
                if self._size is not None and len(data) != self._size:
                    raise SdoAbortedError(ABORT_LENGTH)
                self._node.set_data(self._index, self._subindex, data, check_writable=True)
                self._mode = None
                self._chunks = []
            self._last_seg = ("down", toggle, resp)
            self.send_response(resp)
        elif last is not None and last[0] == "down" and last[1] == toggle:
            self.send_response(last[2])  # already stored: answer again, store nothing
        elif self._mode == "seg_down":
            raise SdoAbortedError(ABORT_TOGGLE_NOT_ALTERNATED)
        else:
            raise self._no_transfer()

    # -- block upload ---------------------------------------------------------------------
    def _block_upload(self, req: bytes) -> None:
        cs = req[0] & 0x03
        if cs == _CS_INITIATE:
            index, subindex = self._begin(req)
            blksize, pst = req[4], req[5]
            if not 0 < blksize <= MAX_BLKSIZE:
                raise SdoAbortedError(ABORT_INVALID_BLOCK_SIZE)
            data = bytes(self._node.get_data(index, subindex, check_readable=True))
            if not data:
                raise SdoAbortedError(ABORT_NO_DATA_AVAILABLE)
            if pst and len(data) <= pst:
                # Protocol switch: answer as a normal (expedited/segmented) upload.
                self._respond_upload(index, subindex, data)
                return
            self._data = data
            self._blksize = blksize
            self._crc_on = bool(req[0] & CRC_SUPPORTED)
            self._open("up_init")
            cmd = RESPONSE_BLOCK_UPLOAD | BLOCK_SIZE_SPECIFIED | _CS_INITIATE
            if self._crc_on:
                cmd |= CRC_SUPPORTED
            self.send_response(struct.pack("<BHBL", cmd, index, subindex, len(data)))
        elif cs == _CS_START:
            if self._mode == "up_init":
                self._mode = "up"
                self._send_sub_block()
            elif self._mode in ("up", "up_end"):
                # a repeated start: the first sub-block is already out (a client that got
                # nothing acknowledges with ackseq 0 and gets it again)
                logger.debug("repeated block upload start ignored")
            else:
                raise self._no_transfer()
        elif cs == _CS_ACK:
            ackseq, blksize = req[1], req[2]  # bytes 3..7 reserved (CiA 301)
            if self._mode == "up_end":
                self.send_response(self._end_frame)  # the client did not get the end
                return
            if self._mode == "up_init":
                self._mode = "up"  # the start request was lost: ackseq 0 acts as start
            elif self._mode != "up":
                raise self._no_transfer()
            if ackseq > self._sent:
                raise SdoAbortedError(ABORT_INVALID_SEQUENCE_NUMBER)
            if not 0 < blksize <= MAX_BLKSIZE:
                raise SdoAbortedError(ABORT_INVALID_BLOCK_SIZE)
            self._acks += 1
            # Segments up to ackseq arrived; the rest of this sub-block is sent again.
            self._pos = min(self._pos + 7 * ackseq, len(self._data))
            self._blksize = blksize
            if self._pos >= len(self._data):
                self._send_upload_end()
            else:
                self._send_sub_block()
        elif cs == _CS_END:
            if self._mode == "up_end":
                self._reset()  # transfer complete, no response
            elif self._mode is not None:
                raise SdoAbortedError(ABORT_INVALID_COMMAND_SPECIFIER)
            # no transfer open: a repeated end of a finished upload, nothing to do

    def _send_sub_block(self) -> None:
        data, pos = self._data, self._pos
        n = len(data)
        seq = 0
        send = self.send_response
        while seq < self._blksize and pos < n:
            seq += 1
            chunk = data[pos : pos + 7]
            pos += 7
            last = pos >= n
            frame = bytes([seq | (0x80 if last else 0)]) + chunk + bytes(7 - len(chunk))
            send(frame)
        self._sent = seq

    def _send_upload_end(self) -> None:
        n = len(self._data)
        unused = (7 - n % 7) % 7
        cmd = RESPONSE_BLOCK_UPLOAD | (unused << 2) | _CS_END
        crc = crc16_ccitt(self._data) if self._crc_on else 0
        self._mode = "up_end"
        self._end_frame = struct.pack("<BH5x", cmd, crc)
        self.send_response(self._end_frame)

    # -- block download -------------------------------------------------------------------
    def _block_download(self, req: bytes) -> None:
        cs = req[0] & 0x01
        if self._mode == "down_end":
            if cs == _CS_END and req[0] & 0x02 == 0:
                self._finish_download(req)
                return
            if cs != _CS_INITIATE:
                self.send_response(self._last_ack)  # a re-sent last sub-block: ack again
                return
        if cs != _CS_INITIATE:
            raise self._no_transfer()
        index, subindex = self._begin(req)
        obj = self._node.find_object(index, subindex)
        if not obj.writable:
            raise SdoAbortedError(ABORT_READ_ONLY)
        if req[0] & BLOCK_SIZE_SPECIFIED:
            (self._size,) = struct.unpack_from("<L", req, 4)
        self._crc_on = bool(req[0] & CRC_SUPPORTED)
        self._open("down")
        self._blksize = self.download_blksize
        self._expected = 1
        cmd = RESPONSE_BLOCK_DOWNLOAD | _CS_INITIATE
        if self._crc_on:
            cmd |= CRC_SUPPORTED
        self.send_response(struct.pack("<BHBB3x", cmd, index, subindex, self._blksize))

    def _download_segment(self, seg: bytes) -> None:
        if seg == self._last_frame:
            return  # the bus delivered the same segment twice
        self._last_frame = seg
        seqno = seg[0] & 0x7F
        last = bool(seg[0] & 0x80)
        if seqno == self._expected:
            self._chunks.append(bytes(seg[1:8]))
            self._expected += 1
            if last:
                self._last_seen = True
        if seqno >= self._blksize or last:
            ackseq = self._expected - 1
            if self._last_seen:
                self._mode = "down_end"
            self._expected = 1
            cmd = RESPONSE_BLOCK_DOWNLOAD | _CS_ACK
            self._last_ack = struct.pack("<BBB5x", cmd, ackseq, self._blksize)
            self.send_response(self._last_ack)

    def _finish_download(self, req: bytes) -> None:
        unused = (req[0] >> 2) & 0x07
        data = b"".join(self._chunks)
        if unused:
            data = data[:-unused]
        if self._size is not None and len(data) != self._size:
            raise SdoAbortedError(ABORT_LENGTH)
        if self._crc_on:
            (crc,) = struct.unpack_from("<H", req, 1)
            if crc != crc16_ccitt(data):
                raise SdoAbortedError(ABORT_CRC_ERROR)
        index, subindex = self._index, self._subindex
        self._reset()
        self._node.set_data(index, subindex, data, check_writable=True)
        self.send_response(bytes([RESPONSE_BLOCK_DOWNLOAD | _CS_END]) + bytes(7))
