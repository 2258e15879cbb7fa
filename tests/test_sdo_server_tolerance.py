"""The drive's SDO server tolerates slow, repeating and duplicating clients (CiA 301 §7.2.4.3).

Frames are written here by hand from CiA 301's layouts; the truth for the data is the
recorder's own buffer (``drive.recorder.data_bytes()``, read in-process, not over CAN) and
CRC-16/CCITT from ``binascii.crc_hqx``. The 3 s pauses are shorter than the server's 10 s
timeout and far longer than anything a busy host adds.
"""

from __future__ import annotations

import binascii
import queue
import struct
import time

import pytest
from test_node_support import Bench

from virtual_drive.node.sdo_block import BlockSdoServer

pytestmark = [pytest.mark.timeout(90), pytest.mark.unit]

L = 14.8e-6
TRACE = struct.pack("<HB", 0x2102, 0)


class Raw:
    """Hand-made client frames on 0x601; every response of 0x581 in a queue."""

    def __init__(self, bench: Bench) -> None:
        self.bench = bench
        self.q: queue.Queue[bytes] = queue.Queue()
        bench.net.subscribe(0x581, lambda cid, data, ts: self.q.put(bytes(data)))

    def send(self, *parts: int | bytes) -> None:
        frame = b"".join(bytes([p]) if isinstance(p, int) else p for p in parts)
        self.bench.net.send_message(0x601, frame.ljust(8, b"\x00"))

    def drain(self) -> None:
        """Forget responses to other clients' requests (the bench's canopen client)."""
        while not self.q.empty():
            self.q.get_nowait()

    def recv(self, timeout: float = 5.0) -> bytes:
        return self.q.get(timeout=timeout)

    def quiet(self, timeout: float = 0.2) -> bool:
        """True if nothing arrives within ``timeout`` s."""
        try:
            self.q.get(timeout=timeout)
        except queue.Empty:
            return True
        return False


@pytest.fixture(scope="module")
def bench():
    b = Bench(speed=1.0)
    # 4000 bytes of trace: 500 samples x 2 channels, immediate trigger
    b.write("trace_config.pre_trigger", 0)
    b.write("trace_config.length", 500)
    b.write("trace_config.trigger_mode", 0)
    b.write("trace_config.command", 1)
    assert b.wait(lambda: b.read("trace_config.state") == 3, timeout=10)
    b.truth = b.drive.recorder.data_bytes()
    assert len(b.truth) == 4000
    b.raw = Raw(b)
    yield b
    b.close()


def _segments(raw: Raw, count: int) -> list[bytes]:
    return [raw.recv() for _ in range(count)]


def test_block_upload_with_pause_repeats_and_lost_segments(bench):
    raw, truth = bench.raw, bench.truth
    raw.drain()
    init = (0xA4, TRACE, 20, 0)  # CRC asked, blksize 20, no protocol switch
    raw.send(*init)
    first = raw.recv()
    raw.send(*init)  # repeated initiate: the transfer starts afresh, same answer
    assert raw.recv() == first
    assert first[0] == 0xC6 and struct.unpack_from("<I", first, 4)[0] == len(truth)
    raw.send(0xA3)  # start
    raw.send(0xA3)  # a duplicate start: the first sub-block goes out once
    segs = _segments(raw, 20)
    assert [s[0] for s in segs] == list(range(1, 21))
    assert raw.quiet()
    time.sleep(3.0)  # the client pauses: no abort, the transfer goes on
    assert raw.quiet(0.05)
    raw.send(0xA2, 20, 30)  # all 20 arrived; next sub-blocks of 30
    segs = _segments(raw, 30)
    assert b"".join(s[1:] for s in segs) == truth[140 : 140 + 210]
    raw.send(0xA2, 12, 30)  # segments 13.. were lost: sent again from there as 1..30
    segs = _segments(raw, 30)
    assert [s[0] for s in segs] == list(range(1, 31))
    pos = 140 + 12 * 7
    assert b"".join(s[1:] for s in segs) == truth[pos : pos + 210]
    pos += 210
    time.sleep(3.0)  # a second pause mid-transfer
    raw.send(0xA2, 30, 127)
    data = bytearray(truth[:pos])
    while True:
        seg = raw.recv()
        data += seg[1:]
        if seg[0] & 0x80:
            break
        if seg[0] & 0x7F == 127:
            raw.send(0xA2, 127, 127)
    raw.send(0xA2, seg[0] & 0x7F, 127)
    end = raw.recv()
    raw.send(0xA2, seg[0] & 0x7F, 127)  # repeated final ack: the end response again
    assert raw.recv() == end
    assert end[0] & 0xE3 == 0xC1
    unused = (end[0] >> 2) & 0x07
    assert bytes(data[: len(data) - unused]) == truth
    assert struct.unpack_from("<H", end, 1)[0] == binascii.crc_hqx(truth, 0)
    raw.send(0xA1)  # client end: no response
    raw.send(0xA1)  # a duplicate end: still nothing
    assert raw.quiet()
    assert bench.drive.sdo.timeouts == 0


def test_block_upload_ack_instead_of_lost_start(bench):
    """The start request was lost; the client acknowledges nothing (ackseq 0): the server
    sends the first sub-block."""
    raw, truth = bench.raw, bench.truth
    raw.drain()
    raw.send(0xA4, TRACE, 10, 0)
    raw.recv()
    raw.send(0xA2, 0, 10)
    segs = _segments(raw, 10)
    assert [s[0] for s in segs] == list(range(1, 11))
    assert b"".join(s[1:] for s in segs) == truth[:70]
    raw.send(0x80, TRACE, struct.pack("<I", 0x08000000))  # client abort: nothing answers
    assert raw.quiet()


def test_new_request_replaces_an_open_block_upload(bench):
    raw = bench.raw
    raw.drain()
    raw.send(0xA4, TRACE, 10, 0)
    raw.recv()
    raw.send(0xA3)
    _segments(raw, 10)
    raw.send(0x40, struct.pack("<HB", 0x1000, 0))  # an expedited read in the middle
    resp = raw.recv()
    assert resp[0] == 0x43 and struct.unpack_from("<I", resp, 4)[0] == 0x00020192
    raw.send(0xA2, 10, 10)  # an ack for the replaced upload: no transfer open
    abort = raw.recv()
    assert abort[0] == 0x80 and struct.unpack_from("<I", abort, 4)[0] == 0x05040001


def test_segmented_upload_with_pause_and_repeated_requests(bench):
    raw, truth = bench.raw, bench.truth
    raw.drain()
    raw.send(0x40, TRACE)
    first = raw.recv()
    raw.send(0x40, TRACE)  # repeated initiate: starts afresh
    assert raw.recv() == first
    assert first[0] == 0x41 and struct.unpack_from("<I", first, 4)[0] == len(truth)
    data = bytearray()
    toggle = 0
    k = 0
    while True:
        raw.send(0x60 | toggle)
        seg = raw.recv()
        if k % 50 == 7:  # the answer "was lost": the same request again
            raw.send(0x60 | toggle)
            assert raw.recv() == seg
        if k == 100:
            time.sleep(3.0)  # a pause mid-transfer
        assert seg[0] & 0xE0 == 0x00 and seg[0] & 0x10 == toggle
        n = 7 - ((seg[0] >> 1) & 0x07)
        data += seg[1 : 1 + n]
        k += 1
        if seg[0] & 0x01:
            break
        toggle ^= 0x10
    assert bytes(data) == truth
    raw.send(0x60 | toggle)  # the last answer repeated after the transfer ended
    assert raw.recv() == seg
    raw.send(0x60 | (toggle ^ 0x10))  # a request beyond the end: no transfer open
    abort = raw.recv()
    assert abort[0] == 0x80 and struct.unpack_from("<I", abort, 4)[0] == 0x05040001


def test_segmented_download_repeated_segment_is_stored_once(bench, monkeypatch):
    raw = bench.raw
    raw.drain()
    node = bench.drive.node
    writes = []
    original = node.set_data

    def counting(index, subindex, data, check_writable=False):
        writes.append((index, subindex, bytes(data)))
        return original(index, subindex, data, check_writable=check_writable)

    monkeypatch.setattr(node, "set_data", counting)
    value = struct.pack("<f", 1.1 * L)
    raw.send(0x21, struct.pack("<HB", 0x2010, 2), struct.pack("<I", 4))  # segmented, size 4
    assert raw.recv()[0] == 0x60
    seg = bytes([0x00 | (3 << 1) | 0x01]) + value  # toggle 0, 3 bytes unused, last
    raw.send(seg)
    resp = raw.recv()
    raw.send(seg)  # the answer "was lost": the client repeats the segment
    assert raw.recv() == resp == bytes([0x20]) + bytes(7)
    assert writes == [(0x2010, 2, value)]
    assert bench.read("current_controller.L_c") == pytest.approx(1.1 * L)
    raw.drain()
    # a wrong length is refused and changes nothing
    raw.send(0x21, struct.pack("<HB", 0x2010, 2), struct.pack("<I", 8))
    raw.recv()
    raw.send(bytes([0x01]) + value + b"\0\0\0")  # 7 bytes, last: 7 != 8 announced
    abort = raw.recv()
    assert abort[0] == 0x80 and struct.unpack_from("<I", abort, 4)[0] == 0x06070010
    monkeypatch.undo()
    assert bench.read("current_controller.L_c") == pytest.approx(1.1 * L)
    bench.write("current_controller.L_c", L)


def test_silent_client_is_aborted_after_the_timeout_not_before(bench):
    """With the timeout shortened to 1.5 s: a 1 s pause is served, 1.5 s of silence brings
    abort 0x05040000 unprompted, and a late continuation gets the same code."""
    raw = bench.raw
    raw.drain()
    bench.drive.sdo.timeout = 1.5
    try:
        raw.send(0x40, TRACE)
        raw.recv()
        raw.send(0x60)
        raw.recv()
        assert raw.quiet(1.0)  # nothing unprompted within 1 s
        raw.send(0x70)
        assert raw.recv()[0] & 0xF0 == 0x10  # served: segment with toggle 1
        t0 = time.monotonic()
        abort = raw.recv(timeout=10.0)
        waited = time.monotonic() - t0
        assert abort[0] == 0x80 and struct.unpack_from("<HBI", abort, 1) == (0x2102, 0, 0x05040000)
        assert waited >= 1.4
        raw.send(0x60)
        late = raw.recv()
        assert late[0] == 0x80 and struct.unpack_from("<I", late, 4)[0] == 0x05040000
    finally:
        bench.drive.sdo.timeout = BlockSdoServer.timeout


def test_default_timeout_is_generous():
    """CANopenNode makes the server timeout a parameter (SDOserverTimeoutTime_ms); the drive
    uses 10 s so a client paused by a busy host for seconds is not cut off."""
    assert BlockSdoServer.timeout >= 10.0
