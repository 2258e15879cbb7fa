"""SDO server with block transfer (CiA 301 §7.2.4.3.9–7.2.4.3.17) and NMT gating.

canopen 2.4.1's :class:`canopen.sdo.SdoServer` serves expedited and segmented transfers only.
:class:`BlockSdoServer` adds:

- block upload: initiate (blksize, pst, CRC flag), sub-blocks of up to 127 segments of 7 bytes,
  acknowledgement with ``ackseq`` (segments after ``ackseq`` are sent again in the next
  sub-block), end with the number of unused bytes in the last segment and the CRC-16/CCITT
  (``binascii.crc_hqx``, initial value 0) when the client asked for it;
  a protocol-switch threshold ``pst`` larger than the size falls back to a normal upload;
- block download: the server proposes ``blksize``, acknowledges each sub-block with the last
  segment received in sequence, checks the CRC when both sides support it, and stores the
  data through the node's checked :meth:`set_data` (write callbacks may abort);
- NMT gating: no SDO service in STOPPED (or while initialising); requests are ignored as
  CiA 301 prescribes.

The same class serves the second server channel (0x1201) with other COB-IDs.
"""

from __future__ import annotations

import binascii
import logging
import struct
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
    BLOCK_SIZE_SPECIFIED,
    CRC_SUPPORTED,
    REQUEST_ABORTED,
    REQUEST_BLOCK_DOWNLOAD,
    REQUEST_BLOCK_UPLOAD,
    RESPONSE_BLOCK_DOWNLOAD,
    RESPONSE_BLOCK_UPLOAD,
    SDO_STRUCT,
)

logger = logging.getLogger(__name__)

#: Largest sub-block the protocol allows (seqno is 7 bits, 0 invalid).
MAX_BLKSIZE = 127

_CS_INITIATE = 0
_CS_END = 1
_CS_ACK = 2
_CS_START = 3


def crc16_ccitt(data: bytes, crc: int = 0) -> int:
    """CRC-16/CCITT (XMODEM: poly 0x1021, init 0) as CiA 301 specifies for block transfer."""
    return binascii.crc_hqx(data, crc)


class BlockSdoServer(SdoServer):
    """SDO server that also speaks block upload/download.

    :param rx_cobid: COB-ID of client→server requests (0x600+N for 0x1200).
    :param tx_cobid: COB-ID of server→client responses (0x580+N for 0x1200).
    :param node: the local node (``get_data`` / ``set_data``).
    :param allowed: returns False while the NMT state forbids SDO (STOPPED).
    :param download_blksize: sub-block size this server proposes for block downloads.
    :param send: ``send(cob_id, data)``; default: the network's ``send_message``.
    """

    #: A block transfer with no frame from the client for this long (s) is dropped.
    timeout = 1.0

    def __init__(
        self,
        rx_cobid: int,
        tx_cobid: int,
        node,
        allowed: Callable[[], bool] = lambda: True,
        download_blksize: int = MAX_BLKSIZE,
        send: Callable[[int, bytes], None] | None = None,
    ) -> None:
        super().__init__(rx_cobid, tx_cobid, node)
        self._allowed = allowed
        self._send = send
        self._last_rx = 0.0
        self.download_blksize = download_blksize
        self._index = 0
        self._subindex = 0
        self._reset_block()

    # -- dispatch --------------------------------------------------------------------------
    def _reset_block(self) -> None:
        self._mode: str | None = None  # "up_init", "up", "up_end", "down", "down_end"
        self._data = b""
        self._pos = 0  # upload: offset of the first segment of the current sub-block
        self._blksize = 0
        self._sent = 0  # segments sent in the current sub-block
        self._crc_on = False
        self._chunks: list[bytes] = []
        self._expected = 1
        self._last_seen = False
        self._size: int | None = None

    def on_request(self, can_id: int, data: bytes, timestamp: float) -> None:
        if not self._allowed():
            return
        if len(data) < 8:
            data = bytes(data) + bytes(8 - len(data))
        command = data[0]
        now = time.monotonic()
        if self._mode is not None and now - self._last_rx > self.timeout:
            # the client went away mid-transfer: forget it (a stale block download would
            # otherwise read the next client's requests as segments)
            logger.info("SDO block transfer 0x%04X:%02X timed out", self._index, self._subindex)
            self._reset_block()
        self._last_rx = now
        if self._mode == "down":
            # During a block download every frame is a segment (no command specifier);
            # seqno 0 is invalid, so 0x80 is the client's abort request.
            if command == REQUEST_ABORTED:
                self._reset_block()
                return
            try:
                self._download_segment(data)
            except SdoAbortedError as exc:
                self._reset_block()
                self.abort(exc.code)
            return
        ccs = command & 0xE0
        try:
            if ccs == REQUEST_BLOCK_UPLOAD:
                self._block_upload(data)
                return
            if ccs == REQUEST_BLOCK_DOWNLOAD:
                self._block_download(data)
                return
            if ccs == REQUEST_ABORTED:
                self._reset_block()
            elif self._mode is not None:
                # A new expedited/segmented request ends any block transfer in progress.
                self._reset_block()
        except SdoAbortedError as exc:
            self._reset_block()
            self.abort(exc.code)
            return
        except KeyError:
            self._reset_block()
            self.abort(ABORT_NOT_IN_OD)
            return
        except Exception:  # keep the node alive; report a general error
            logger.exception("SDO block transfer failed")
            self._reset_block()
            self.abort()
            return
        super().on_request(can_id, data, timestamp)

    def send_response(self, response: bytes) -> None:
        if self._send is not None:
            self._send(self.tx_cobid, bytes(response))
        else:
            self.network.send_message(self.tx_cobid, response)

    # -- block upload ---------------------------------------------------------------------
    def _block_upload(self, req: bytes) -> None:
        cs = req[0] & 0x03
        if cs == _CS_INITIATE:
            self._reset_block()
            _, index, subindex = SDO_STRUCT.unpack_from(req)
            self._index, self._subindex = index, subindex
            blksize, pst = req[4], req[5]
            if not 0 < blksize <= MAX_BLKSIZE:
                raise SdoAbortedError(ABORT_INVALID_BLOCK_SIZE)
            data = bytes(self._node.get_data(index, subindex, check_readable=True))
            if not data:
                raise SdoAbortedError(ABORT_NO_DATA_AVAILABLE)
            if pst and len(data) <= pst:
                # Protocol switch: answer as a normal (expedited/segmented) upload.
                self.init_upload(req)
                return
            self._data = data
            self._blksize = blksize
            self._crc_on = bool(req[0] & CRC_SUPPORTED)
            self._mode = "up_init"
            cmd = RESPONSE_BLOCK_UPLOAD | BLOCK_SIZE_SPECIFIED | _CS_INITIATE
            if self._crc_on:
                cmd |= CRC_SUPPORTED
            self.send_response(struct.pack("<BHBL", cmd, index, subindex, len(data)))
        elif cs == _CS_START:
            if self._mode != "up_init":
                raise SdoAbortedError(ABORT_INVALID_COMMAND_SPECIFIER)
            self._mode = "up"
            self._send_sub_block()
        elif cs == _CS_ACK:
            if self._mode != "up":
                raise SdoAbortedError(ABORT_INVALID_COMMAND_SPECIFIER)
            ackseq, blksize = req[1], req[2]
            if ackseq > self._sent:
                raise SdoAbortedError(ABORT_INVALID_SEQUENCE_NUMBER)
            if not 0 < blksize <= MAX_BLKSIZE:
                raise SdoAbortedError(ABORT_INVALID_BLOCK_SIZE)
            # Segments up to ackseq arrived; the rest of this sub-block is sent again.
            self._pos = min(self._pos + 7 * ackseq, len(self._data))
            self._blksize = blksize
            if self._pos >= len(self._data):
                self._send_upload_end()
            else:
                self._send_sub_block()
        elif cs == _CS_END:
            if self._mode != "up_end":
                raise SdoAbortedError(ABORT_INVALID_COMMAND_SPECIFIER)
            self._reset_block()  # transfer complete, no response
        else:
            raise SdoAbortedError(ABORT_INVALID_COMMAND_SPECIFIER)

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
        self.send_response(struct.pack("<BH5x", cmd, crc))

    # -- block download -------------------------------------------------------------------
    def _block_download(self, req: bytes) -> None:
        cs = req[0] & 0x01
        if self._mode == "down_end" and cs == _CS_END:
            self._finish_download(req)
            return
        if cs != _CS_INITIATE:
            raise SdoAbortedError(ABORT_INVALID_COMMAND_SPECIFIER)
        self._reset_block()
        _, index, subindex = SDO_STRUCT.unpack_from(req)
        self._index, self._subindex = index, subindex
        obj = self._node._find_object(index, subindex)
        if not obj.writable:
            raise SdoAbortedError(0x06010002)
        if req[0] & BLOCK_SIZE_SPECIFIED:
            (self._size,) = struct.unpack_from("<L", req, 4)
        self._crc_on = bool(req[0] & CRC_SUPPORTED)
        self._mode = "down"
        self._blksize = self.download_blksize
        self._expected = 1
        cmd = RESPONSE_BLOCK_DOWNLOAD | _CS_INITIATE
        if self._crc_on:
            cmd |= CRC_SUPPORTED
        self.send_response(struct.pack("<BHBB3x", cmd, index, subindex, self._blksize))

    def _download_segment(self, seg: bytes) -> None:
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
            self.send_response(struct.pack("<BBB5x", cmd, ackseq, self._blksize))

    def _finish_download(self, req: bytes) -> None:
        unused = (req[0] >> 2) & 0x07
        data = b"".join(self._chunks)
        if unused:
            data = data[:-unused]
        if self._size is not None and len(data) != self._size:
            raise SdoAbortedError(0x06070010)
        if self._crc_on:
            (crc,) = struct.unpack_from("<H", req, 1)
            if crc != crc16_ccitt(data):
                raise SdoAbortedError(ABORT_CRC_ERROR)
        index, subindex = self._index, self._subindex
        self._reset_block()
        self._node.set_data(index, subindex, data, check_writable=True)
        self.send_response(bytes([RESPONSE_BLOCK_DOWNLOAD | _CS_END]) + bytes(7))
