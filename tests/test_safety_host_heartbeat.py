"""Default heartbeat consumer time drive_link arms on the drive (issue 10, busy-host false stops).

Truth: CiA 301 0x1016 sub-entry layout (node-ID bits 23..16, time in ms bits 15..0) read back from
the drive with canopen's SdoClient-backed RemoteNode, and the rule documented in
``Drive.configure_heartbeat_consumer``: max(1000 ms, 3 × the host producer period).
"""

from __future__ import annotations

import uuid

import can
import pytest

from drive_link import Drive
from drive_link.link.drive import CONSUMER_MIN_MS

pytestmark = [pytest.mark.timeout(60), pytest.mark.unit]


@pytest.mark.parametrize(("producer_ms", "expected_ms"), [(100, 1000), (50, 1000), (500, 1500)])
def test_default_consumer_time_has_jitter_margin(producer_ms, expected_ms):
    from virtual_drive.node import VirtualDrive

    ch = f"hb-{uuid.uuid4().hex}"
    b_drive = can.Bus(interface="virtual", channel=ch)
    b_host = can.Bus(interface="virtual", channel=ch)
    vd = VirtualDrive(b_drive, node_id=4).start()
    d = Drive.connect(bus=b_host, node_id=4, heartbeat_ms=producer_ms, host_id=0x7E)
    try:
        d.configure_heartbeat_consumer()
        entry = int(d.read("consumer_heartbeat_time.consumer_1"))
        assert entry >> 16 == 0x7E
        assert entry & 0xFFFF == expected_ms
        assert expected_ms >= CONSUMER_MIN_MS
        d.configure_heartbeat_consumer(250)  # an explicit time is kept as given
        assert int(d.read("consumer_heartbeat_time.consumer_1")) & 0xFFFF == 250
    finally:
        d.close()
        vd.stop()
        b_drive.shutdown()
        b_host.shutdown()
