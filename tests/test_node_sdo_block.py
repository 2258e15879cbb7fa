"""SDO block transfer of the drive's servers at frame level (CiA 301 §7.2.4.3.9–17): CRC flag
only when asked, blksize negotiation, retransmission after a lower ackseq, unused bytes of the
last segment, protocol switch threshold, block download through the write checks.

Truth: the frame layouts of CiA 301 written out here by hand, and CRC-16/CCITT computed with
binascii.crc_hqx."""

from __future__ import annotations

import binascii
import queue
import struct
import time

import numpy as np
import pytest
from canopen.sdo import SdoAbortedError
from test_node_support import Bench

from virtual_drive.node.sdo_block import BlockSdoServer

pytestmark = [pytest.mark.timeout(60), pytest.mark.unit]

L = 14.8e-6


class RawClient:
    """Hand-made SDO client frames on COB-ID 0x601, responses from 0x581."""

    def __init__(self, bench: Bench) -> None:
        self.bench = bench
        self.q: queue.Queue[bytes] = queue.Queue()
        bench.net.subscribe(0x581, lambda cid, data, ts: self.q.put(bytes(data)))

    def send(self, *data: int | bytes) -> None:
        while not self.q.empty():  # responses to other clients' transfers on 0x581
            self.q.get_nowait()
        frame = b"".join(bytes([d]) if isinstance(d, int) else d for d in data)
        self.bench.net.send_message(0x601, frame.ljust(8, b"\x00"))

    def recv(self, timeout: float = 1.0) -> bytes:
        return self.q.get(timeout=timeout)

    def none(self, timeout: float = 0.1) -> bool:
        try:
            self.q.get(timeout=timeout)
        except queue.Empty:
            return True
        return False


@pytest.fixture(scope="module")
def bench():
    b = Bench(speed=1.0)
    # a 4000-byte trace to upload: 500 samples x 2 channels, forced at once
    b.write("trace_config.pre_trigger", 0)
    b.write("trace_config.length", 500)
    b.write("trace_config.trigger_mode", 0)
    b.write("trace_config.command", 1)
    assert b.wait(lambda: b.read("trace_config.state") == 3)
    b.trace = b.node.sdo.upload(0x2102, 0)
    assert len(b.trace) == 4000
    b.raw = RawClient(b)
    yield b
    b.close()


def test_block_upload_frames_crc_and_retransmission(bench):
    raw, data = bench.raw, bench.trace
    raw.send(0xA4, struct.pack("<HB", 0x2102, 0), 10, 0)  # initiate, CRC asked, blksize 10
    resp = raw.recv()
    assert resp[0] & 0xE0 == 0xC0 and resp[0] & 0x01 == 0  # scs 6, ss 0 (initiate)
    assert resp[0] & 0x04  # server CRC flag: client asked for it
    assert resp[0] & 0x02 and struct.unpack_from("<I", resp, 4)[0] == 4000
    raw.send(0xA3)  # start
    segs = [raw.recv() for _ in range(10)]
    assert [s[0] for s in segs] == list(range(1, 11))
    assert b"".join(s[1:] for s in segs) == data[:70]
    # acknowledge only 4 segments, ask for blocks of 20: the server resends from segment 5
    raw.send(0xA2, 4, 20)
    segs = [raw.recv() for _ in range(20)]
    assert [s[0] for s in segs] == list(range(1, 21))
    assert b"".join(s[1:] for s in segs) == data[28 : 28 + 140]
    pos = 28 + 140
    raw.send(0xA2, 20, 127)
    while True:
        seg = raw.recv()
        chunk = seg[1:]
        pos += 7
        if seg[0] & 0x80:
            break
        if seg[0] & 0x7F == 127:
            raw.send(0xA2, 127, 127)
    assert pos >= len(data)
    last_len = len(data) - (pos - 7)
    assert chunk[:last_len] == data[pos - 7 :]
    raw.send(0xA2, seg[0] & 0x7F, 127)
    end = raw.recv()
    assert end[0] & 0xE3 == 0xC1  # scs 6, ss 1 (end)
    assert (end[0] >> 2) & 0x07 == 7 - last_len  # bytes of the last segment without data
    assert struct.unpack_from("<H", end, 1)[0] == binascii.crc_hqx(data, 0)
    raw.send(0xA1)  # client end: no response
    assert raw.none()


def test_block_upload_without_crc_and_protocol_switch(bench):
    raw = bench.raw
    raw.send(0xA0, struct.pack("<HB", 0x1008, 0), 127, 0)  # no CRC asked
    resp = raw.recv()
    assert resp[0] & 0xE0 == 0xC0 and not resp[0] & 0x04
    raw.send(0x80, struct.pack("<HB", 0x1008, 0), struct.pack("<I", 0x05040000))  # abort
    # pst = 100 > 18 bytes of the device name: the server answers as a normal upload
    raw.send(0xA4, struct.pack("<HB", 0x1008, 0), 127, 100)
    resp = raw.recv()
    assert resp[0] & 0xE0 == 0x40  # initiate upload response (segmented, size given)
    assert struct.unpack_from("<I", resp, 4)[0] == len("BLDC 5kW 48V drive")
    raw.send(0x80, struct.pack("<HB", 0x1008, 0), struct.pack("<I", 0x05040000))


def test_canopen_block_client_with_and_without_crc(bench):
    for crc in (True, False):
        sdo = bench.node.sdo
        with sdo.open(0x2102, 0, "rb", block_transfer=True, request_crc_support=crc) as f:
            assert f.read() == bench.trace


def test_block_download_through_the_write_checks(bench):
    sdo = bench.node.sdo
    value = struct.pack("<f", 1.25 * L)
    with sdo.open(0x2010, 2, "wb", block_transfer=True, size=4) as f:
        f.write(value)
    assert bench.read("current_controller.L_c") == pytest.approx(1.25 * L)
    assert bench.drive.sim.current.L_c == pytest.approx(float(np.float32(1.25 * L)))
    with pytest.raises(SdoAbortedError) as exc:
        with sdo.open(0x2010, 2, "wb", block_transfer=True, size=4) as f:
            f.write(struct.pack("<f", 3 * L))  # L_c >= 2L: unstable
    assert exc.value.code == 0x06090031
    assert bench.read("current_controller.L_c") == pytest.approx(1.25 * L)
    with pytest.raises(SdoAbortedError) as exc:
        with sdo.open(0x2040, 1, "wb", block_transfer=True, size=4) as f:
            f.write(struct.pack("<f", 1.0))  # read-only
    assert exc.value.code == 0x06010002
    bench.write("current_controller.L_c", L)


def test_block_download_raw_sub_block_ack_and_crc_error(bench):
    raw = bench.raw
    value = struct.pack("<f", 0.9 * L)
    raw.send(0xC6, struct.pack("<HB", 0x2010, 2), struct.pack("<I", 4))  # CRC, size given
    resp = raw.recv()
    assert resp[0] & 0xE3 == 0xA0 and resp[0] & 0x04  # scs 5, ss 0, server CRC
    blksize = resp[4]
    assert 1 <= blksize <= 127
    raw.send(0x81, value)  # segment 1, last
    ack = raw.recv()
    assert ack[0] & 0xE3 == 0xA2 and ack[1] == 1  # ackseq 1
    raw.send(0xC1 | (3 << 2), struct.pack("<H", binascii.crc_hqx(value, 0) ^ 0xFFFF))
    resp = raw.recv()
    assert resp[0] == 0x80 and struct.unpack_from("<I", resp, 4)[0] == 0x05040004  # CRC error
    assert bench.read("current_controller.L_c") == pytest.approx(L)
    # the same with the right CRC is stored
    raw.send(0xC6, struct.pack("<HB", 0x2010, 2), struct.pack("<I", 4))
    raw.recv()
    raw.send(0x81, value)
    raw.recv()
    raw.send(0xC1 | (3 << 2), struct.pack("<H", binascii.crc_hqx(value, 0)))
    assert raw.recv()[0] == 0xA1
    assert bench.read("current_controller.L_c") == pytest.approx(0.9 * L)
    bench.write("current_controller.L_c", L)


def test_no_sdo_in_stopped(bench):
    raw = bench.raw
    bench.nmt(0x02)
    assert bench.wait(lambda: bench.drive.nmt.state == 0x04)
    raw.send(0x40, struct.pack("<HB", 0x6041, 0))
    assert raw.none(0.2)
    bench.nmt(0x80)
    assert bench.wait(lambda: bench.drive.nmt.state == 0x7F)
    raw.send(0x40, struct.pack("<HB", 0x6041, 0))
    assert raw.recv()[0] & 0xE0 == 0x40


def test_full_tx_queue_is_retried_not_dropped():
    """A 127-frame burst on SocketCAN with txqueuelen 10 meets ENOBUFS (python-can #2004):
    here a bus that refuses every 7th send once, as a full queue does, loses no frame."""
    import can
    from can.interfaces.virtual import VirtualBus

    from virtual_drive.node import VirtualDrive

    class FullQueueBus(VirtualBus):
        n = 0

        def send(self, msg, timeout=None):
            FullQueueBus.n += 1
            if FullQueueBus.n % 7 == 3:
                raise can.CanOperationError("Failed to transmit: [Errno 105] No buffer space")
            super().send(msg, timeout)

    b = Bench(start=False)
    drive_bus = FullQueueBus(channel=b.channel)
    drive = VirtualDrive(drive_bus, node_id=1).start()
    try:
        b.write("trace_config.pre_trigger", 0)
        b.write("trace_config.length", 2000)
        b.write("trace_config.trigger_mode", 0)
        b.write("trace_config.command", 1)
        assert b.wait(lambda: b.read("trace_config.state") == 3)
        with b.node.sdo.open(0x2102, 0, "rb", block_transfer=True) as f:
            data = f.read()
        assert len(data) == 2000 * 2 * 4
        assert data == drive.recorder.data_bytes()  # every segment arrived, in order
        assert drive.tx_errors == 0 and FullQueueBus.n > 1000
    finally:
        drive.stop()
        drive_bus.shutdown()
        b.close()


def test_abandoned_block_download_times_out(bench):
    """A block download the client abandons is aborted with 0x05040000 (SDO protocol timed
    out) after the server's timeout; afterwards the channel serves requests again. (The
    timeout is shortened here; the drive's default is 10 s.)"""
    raw = bench.raw
    bench.drive.sdo.timeout = 0.5
    try:
        raw.send(0xC2, struct.pack("<HB", 0x2010, 2), struct.pack("<I", 4))  # initiate, no CRC
        assert raw.recv()[0] & 0xE3 == 0xA0
        abort = raw.recv(timeout=5.0)  # sent by the server on its own
        assert abort[0] == 0x80 and struct.unpack_from("<HBI", abort, 1) == (0x2010, 2, 0x05040000)
        time.sleep(0.05)
        assert bench.read("current_controller.L_c") == pytest.approx(L)
    finally:
        bench.drive.sdo.timeout = BlockSdoServer.timeout
