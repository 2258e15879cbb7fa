"""SDO frames byte for byte, both directions (issue 29, item 3), seen by a sniffer on the bus.

Truths, CiA 301 §7.2.4.3: every SDO frame carries 8 data bytes; in a block-upload
acknowledgement (ccs 5, cs 2) byte 1 is ``ackseq``, byte 2 ``blksize`` and bytes 3..7 are
reserved (0); in the server's block-upload end (scs 6, cs 1) bytes 3..7 are reserved; an abort
(0x80) carries the multiplexer (index, sub-index) of the request it answers and the code, and
0x05040001 is "client/server command specifier not valid or unknown". A frame with fewer than 8
bytes is no SDO request: the drive ignores it (no multiplexer to name in an abort; CANopenNode
drops such frames too) and goes on serving.
"""

from __future__ import annotations

import struct
import time

import can
import pytest
from test_node_support import Bench

from drive_link.link._sdo import SdoChannel

pytestmark = pytest.mark.timeout(60)

ABORT_COMMAND = 0x05040001


@pytest.fixture
def bench():
    b = Bench(speed=1.0)
    b.sniff = can.Bus(interface="virtual", channel=b.channel)
    yield b
    b.sniff.shutdown()
    b.close()


def sniffed(b: Bench, settle: float = 0.2) -> list[tuple[int, bytes]]:
    """Every frame the sniffer got up to ``settle`` s from now (heartbeats never stop)."""
    time.sleep(settle)
    out = []
    while (m := b.sniff.recv(0)) is not None:
        out.append((m.arbitration_id, bytes(m.data)))
    return out


def raw_answer(b: Bench, frame: bytes, timeout: float = 1.0) -> bytes | None:
    """Send ``frame`` on 0x601 as it is (its own length); the first 0x581 frame after it."""
    t0 = time.monotonic()
    b.net.send_message(0x601, frame)
    got = b.log.wait_for(0x581, timeout, since=t0)
    return None if got is None else got[1]


def test_block_upload_acknowledgements_and_end_keep_reserved_bytes_zero(bench):
    sniffed(bench, 0.05)
    ch = SdoChannel(bench.net, 1, 0x601, 0x581)
    try:
        name = ch.upload_block(0x1008, 0)  # device name by block upload (drive_link's client)
    finally:
        ch.close()
    assert name.decode().strip()
    frames = sniffed(bench)
    acks = [d for c, d in frames if c == 0x601 and d[0] & 0xE3 == 0xA2]
    ends = [d for c, d in frames if c == 0x581 and d[0] & 0xE3 == 0xC1]
    assert acks and ends, frames
    for d in acks:
        assert len(d) == 8 and d[3:] == bytes(5), f"client ack {d.hex()}: reserved bytes 3..7"
    for d in ends:
        assert len(d) == 8 and d[3:] == bytes(5), f"server end {d.hex()}: reserved bytes 3..7"


def test_invalid_command_specifier_abort_names_the_requests_own_object(bench):
    # an earlier transfer on another object (0x6041:00 statusword)
    first = raw_answer(bench, struct.pack("<BHB4x", 0x40, 0x6041, 0))
    assert first is not None and first[0] & 0xE0 == 0x40
    # ccs 7 does not exist; the request names 0x1018:01
    got = raw_answer(bench, struct.pack("<BHB4x", 0xE0, 0x1018, 1))
    assert got is not None, "no abort to an invalid command specifier"
    cmd, index, sub, code = struct.unpack("<BHBI", got)
    assert (cmd, code) == (0x80, ABORT_COMMAND), got.hex()
    assert (index, sub) == (0x1018, 1), f"abort names 0x{index:04X}:{sub:02X}"


@pytest.mark.parametrize("length", [1, 4, 7])
def test_short_sdo_frame_is_ignored_and_service_goes_on(bench, length):
    frame = struct.pack("<BHB4x", 0x40, 0x1000, 0)[:length]
    assert raw_answer(bench, frame, 0.3) is None, f"a {length}-byte frame was answered"
    assert bench.drive.sdo.short_frames == 1
    # the next proper request is served as usual
    assert bench.read("device_type") == 0x00020192
