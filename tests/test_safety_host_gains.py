"""drive_link refuses, before sending, a current-controller write the drive's rule refuses
(firmware_protocol.current_stability is the one home of the rule; issue 10).

Truth: the drive's own SDO abort for the same write (sent with canopen's SdoClient), and the
drive's object unchanged after drive_link refused it.
"""

from __future__ import annotations

import struct
import uuid

import can
import canopen
import pytest
from canopen.sdo import SdoAbortedError, SdoClient

from drive_link import Drive, InvalidValue, apply_gains

pytestmark = [pytest.mark.timeout(60), pytest.mark.unit]


def test_host_refuses_what_the_drive_refuses():
    from virtual_drive.node import VirtualDrive

    ch = f"hg-{uuid.uuid4().hex}"
    b_drive = can.Bus(interface="virtual", channel=ch)
    b_host = can.Bus(interface="virtual", channel=ch)
    vd = VirtualDrive(b_drive, node_id=5).start()
    d = Drive.connect(bus=b_host, node_id=5, heartbeat_ms=None)
    net = canopen.Network()
    net.connect(interface="virtual", channel=ch)
    # the drive's second SDO server (0x1201: 0x680+N / 0x6B0+N): a second client on the
    # Drive's own channel 0x1200 would collide with its supervision reads (SDO has no lock)
    sdo = SdoClient(0x685, 0x6B5, canopen.ObjectDictionary())
    sdo.network = net
    sdo.RESPONSE_TIMEOUT = 2.0
    net.subscribe(0x6B5, sdo.on_response)
    try:
        # predictive control without the back-EMF feed-forward (issue 10: held 649 of 1000 rpm)
        with pytest.raises(InvalidValue, match="feed-forward"):
            apply_gains(d, {"type": 2})  # a gain changes through the one gain path
        assert d.read("current_controller.type") == 0
        with pytest.raises(SdoAbortedError) as exc:
            sdo.download(0x2010, 1, bytes([2]))
        assert exc.value.code == 0x06090030
        # a PI pair far above the paper's (k_p = 100 V/A): unstable current loop
        apply_gains(d, {"type": 1})
        with pytest.raises(InvalidValue, match="unstable"):
            apply_gains(d, {"k_p": 100.0})
        with pytest.raises(SdoAbortedError) as exc:
            sdo.download(0x2010, 4, struct.pack("<f", 100.0))
        assert exc.value.code == 0x06090031
        assert d.read("current_controller.k_p") == pytest.approx(0.4647)
        # what both accept goes through
        apply_gains(d, {"emf_feedforward": 1})
        apply_gains(d, {"type": 2})
        assert d.read("current_controller.type") == 2
    finally:
        net.disconnect()
        d.close()
        vd.stop()
        b_drive.shutdown()
        b_host.shutdown()
