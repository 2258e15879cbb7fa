"""0x1005 COB-ID SYNC (issue 29, item 4) through canopen's master.

Truths, CiA 301 §7.5.2.5: 0x1005 (UNSIGNED32, rw) holds the SYNC COB-ID, default 0x80; bit 30
"gen" says the node produces SYNC (this drive does not: refused with 0x06090030), bit 29 a 29-bit
frame (an 11-bit device refuses it), bits 10..0 the CAN-ID; synchronous TPDOs (transmission
type 1..240) count the SYNC frames on that CAN-ID. The EDS is read with canopen's own importer.
"""

from __future__ import annotations

import time
from pathlib import Path

import canopen
import pytest
from canopen.sdo import SdoAbortedError
from test_node_support import Bench

pytestmark = pytest.mark.timeout(60)

EDS = Path(__file__).resolve().parents[1] / "firmware_protocol" / "bldc_drive.eds"
INVALID = 0x06090030


@pytest.fixture
def bench():
    b = Bench(speed=1.0)
    tpdo = b.node.sdo[0x1803]
    tpdo[1].raw = 0x80000481
    tpdo[2].raw = 1  # TPDO4 on every SYNC
    tpdo[1].raw = 0x481
    yield b
    b.close()


def answers(b: Bench, sync_id: int, n: int = 5) -> int:
    """How many TPDO4 frames ``n`` SYNC frames on ``sync_id`` bring."""
    t0 = time.monotonic()
    for _ in range(n):
        b.net.send_message(sync_id, b"")
        time.sleep(0.01)
    time.sleep(0.1)
    return len(b.log.of(0x481, t0))


def test_eds_declares_0x1005_as_cia301_says():
    od = canopen.import_od(str(EDS), node_id=1)
    var = od[0x1005]
    assert var.data_type == canopen.objectdictionary.UNSIGNED32
    assert var.access_type == "rw" and var.default == 0x80


def test_sync_follows_0x1005(bench):
    bench.nmt(0x01)
    time.sleep(0.1)
    assert bench.node.sdo[0x1005].raw == 0x80
    assert answers(bench, 0x080) == 5
    bench.node.sdo[0x1005].raw = 0x0A0
    assert answers(bench, 0x080) == 0
    assert answers(bench, 0x0A0) == 5


@pytest.mark.parametrize(
    "value",
    [0x40000080, 0x20000080, 0x00000601, 0x00000000, 0x00000701, 0x00010080],
    ids=["gen", "29-bit", "sdo-id", "nmt-id", "heartbeat-id", "bits-28..11"],
)
def test_refused_values_change_nothing(bench, value):
    with pytest.raises(SdoAbortedError) as exc:
        bench.node.sdo[0x1005].raw = value
    assert exc.value.code == INVALID
    assert bench.node.sdo[0x1005].raw == 0x80


def test_reset_communication_reloads_the_default(bench):
    bench.node.sdo[0x1005].raw = 0x0A0
    t0 = time.monotonic()
    bench.nmt(0x82)
    assert bench.log.wait_for(0x701, 5.0, since=t0, pred=lambda d: d == b"\x00")
    assert bench.wait(lambda: bench.drive.nmt.state == 0x7F)
    assert bench.node.sdo[0x1005].raw == 0x80
