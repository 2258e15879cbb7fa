"""COB-ID and heartbeat-consumer validation (CiA 301 §7.3.5, §7.5.2.16/17/33/35/37).

Truths: CiA 301's restricted CAN-ID table (0x000, 0x001-0x07F, 0x101-0x180, 0x581-0x5FF,
0x601-0x67F, 0x6E0-0x6FF, 0x701-0x77F, 0x780-0x7FF), the COB-ID bit layout (31 not valid,
29 = 29-bit frame), the rule that a valid object's CAN-ID changes only after it was made invalid,
and for 0x1016 node-IDs 1..127 and one entry per node (abort 0x06040043). Written through the
canopen master's SdoClient; the new identifiers are then used by canopen's own SDO client and
seen on the bus.
"""

from __future__ import annotations

import struct
import time

import pytest
from canopen.sdo import SdoAbortedError
from test_node_support import Bench, emcy_frames

pytestmark = [pytest.mark.timeout(90), pytest.mark.unit]

INVALID, INCOMPATIBLE, STATE = 0x06090030, 0x06040043, 0x08000022
BIT31 = 0x80000000
#: the first and last ID of every restricted range, straight from the CiA 301 table
RESTRICTED = [0x000, 0x001, 0x07F, 0x101, 0x180, 0x581, 0x5FF, 0x601, 0x67F, 0x6E0, 0x6FF]
RESTRICTED += [0x701, 0x77F, 0x780, 0x7FF]
FREE = [0x0A5, 0x100, 0x181, 0x57F, 0x580, 0x600, 0x680, 0x6DF]  # next to the ranges


@pytest.fixture
def bench():
    b = Bench(speed=1.0)
    yield b
    b.close()


def code_of(bench: Bench, name: str, value: int) -> int | None:
    e = bench.view.entry(name)
    try:
        bench.node.sdo.download(e.index, e.subindex, struct.pack("<I", value))
    except SdoAbortedError as exc:
        return exc.code
    return None


def test_emcy_cob_id(bench):
    name = "cob_id_emcy"
    assert bench.read(name) == 0x81
    assert code_of(bench, name, 0x0A5) == INVALID  # valid object: switch it off first
    assert code_of(bench, name, 0x81 | BIT31) is None
    for can_id in RESTRICTED:
        assert code_of(bench, name, can_id) == INVALID, hex(can_id)
    for bad in (0x20000081, 0xA0000081, 0x40000081, 0xFFFFFFFF, 0x00000881):
        assert code_of(bench, name, bad) == INVALID, hex(bad)
    assert bench.read(name) == 0x81 | BIT31  # nothing changed by the refusals
    for can_id in FREE:  # valid, then off again to be allowed to move on
        assert code_of(bench, name, can_id) is None, hex(can_id)
        assert code_of(bench, name, can_id | BIT31) is None
    assert code_of(bench, name, 0x0A5) is None
    # the next EMCY goes out on the new identifier, none on the NMT identifier 0x000
    t0 = time.monotonic()
    bench.enable(-1)
    bench.write("sim_fault.inject", 1)
    got = bench.log.wait_for(0x0A5, 2.0, since=t0)
    assert got is not None and struct.unpack_from("<H", got[1])[0] == 0x2310
    assert emcy_frames(bench.log, since=t0) == []  # nothing on 0x81
    assert bench.log.of(0x000, t0) == []


def test_sdo_server_2_cob_ids(bench):
    rx, tx = "sdo_server_2.cob_id_client_to_server", "sdo_server_2.cob_id_server_to_client"
    assert (bench.read(rx), bench.read(tx)) == (0x681, 0x6B1)
    assert code_of(bench, rx, 0x6C1) == INVALID  # valid: off first
    assert code_of(bench, rx, 0x681 | BIT31) is None
    for can_id in (0x601, 0x67F, 0x6E0, 0x581, 0x000):
        assert code_of(bench, rx, can_id) == INVALID, hex(can_id)
    assert code_of(bench, rx, 0x400006C1) == INVALID  # bit 30 "dynamic": not a static server
    assert code_of(bench, rx, 0x200006C1) == INVALID  # 29-bit
    assert code_of(bench, rx, 0x6C1) is None
    # canopen's SDO client on the new identifiers reaches the second server
    sdo2 = bench.node.add_sdo(0x6C1, 0x6B1)
    sdo2.network = bench.net
    sdo2.RESPONSE_TIMEOUT = 2.0
    assert sdo2.upload(0x1000, 0) == struct.pack("<I", 0x00020192)


def test_pdo_cob_ids(bench):
    name = "tpdo4_communication.cob_id"
    bench.nmt(0x01)  # OPERATIONAL: PDO COB-IDs cannot change at all
    assert bench.wait(lambda: bench.drive.nmt.state == 0x05)
    assert code_of(bench, name, 0x481 | BIT31) == STATE
    bench.nmt(0x80)
    assert bench.wait(lambda: bench.drive.nmt.state == 0x7F)
    assert code_of(bench, name, 0x4A1) == INVALID  # valid: off first
    assert code_of(bench, name, 0x481 | BIT31) is None
    for can_id in RESTRICTED:
        assert code_of(bench, name, can_id) == INVALID, hex(can_id)
    assert code_of(bench, name, 0x200004A1) == INVALID
    assert code_of(bench, name, 0x00000CA1) == INVALID  # bits 28..11
    assert code_of(bench, name, 0x400004A1) is None  # TPDO bit 30: no RTR, allowed
    assert code_of(bench, name, 0x400004A1 | BIT31) is None
    assert code_of(bench, name, 0x4A1) is None
    rpdo = "rpdo2_communication.cob_id"
    assert code_of(bench, rpdo, 0x301 | BIT31) is None
    assert code_of(bench, rpdo, 0x77F) == INVALID
    assert code_of(bench, rpdo, 0x3A1) is None
    # TPDO4 now arrives on 0x4A1 and no longer on 0x481: in the bus's order, no 0x481 after the
    # first 0x4A1 (the log's clock is its own arrival time: on a busy host frames sent before
    # the change may be logged late, just before the first 0x4A1)
    bench.nmt(0x01)
    t0 = time.monotonic()
    assert bench.log.wait_for(0x4A1, 2.0, since=t0) is not None
    time.sleep(0.2)  # TPDO4 (100 Hz) sent about 20 times more
    ids = [c for t, c, _ in list(bench.log.frames) if t >= t0]
    first = ids.index(0x4A1)
    assert ids.count(0x4A1) >= 2 and 0x481 not in ids[first:], ids


def test_heartbeat_consumer_entries(bench):
    first, second = "consumer_heartbeat_time.consumer_1", "consumer_heartbeat_time.consumer_2"
    for bad in (
        (0x00 << 16) | 500,  # a time without a node
        (0x80 << 16) | 500,  # node-ID 128
        (0xFF << 16) | 500,  # node-ID 255
        0x01000000 | (0x7E << 16) | 500,  # reserved bits 31..24
        (0x01 << 16) | 500,  # the drive itself (node 1)
    ):
        assert code_of(bench, first, bad) == INVALID, hex(bad)
    assert bench.read(first) == 0
    assert code_of(bench, first, (0x7E << 16) | 500) is None
    assert code_of(bench, second, (0x7E << 16) | 800) == INCOMPATIBLE  # same node twice
    assert code_of(bench, second, (0x7E << 16) | 0) is None  # an entry that is off may
    assert code_of(bench, second, (0x7D << 16) | 300) is None
    assert bench.read(second) == (0x7D << 16) | 300


def test_second_consumer_entry_supervises(bench):
    """Entry 2 alone watches node 0x7D: its heartbeats, then silence -> EMCY 0x8130."""
    bench.write("consumer_heartbeat_time.consumer_2", (0x7D << 16) | 200)
    for _ in range(5):
        bench.net.send_message(0x77D, b"\x05")
        time.sleep(0.05)
    t0 = time.monotonic()
    got = bench.log.wait_for(0x81, 3.0, since=t0, pred=lambda d: d[:2] == b"\x30\x81")
    assert got is not None, "no heartbeat-loss EMCY from entry 2"
    assert got[1][3] == 0x7D
