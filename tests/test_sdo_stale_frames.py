"""An SDO answer cannot precede its request (CiA 301 §7.2.4: a confirmed service, the server
answers what it received): a frame the kernel received before a transfer began is not that
transfer's answer, however late the host's bus thread hands it over.

The situation of the SocketCAN lane (a starved host): a second client on the same SDO channel
(a ``drive-link`` command run beside a session) read L_c before a gain set; its answer sat in
the session's socket while the command applied the set; the session's next read of L_c took
that old answer for its own. Here a bus thread that hands over such a frame right after the
request went out is simulated; a server answers the request itself 50 ms later.
"""

from __future__ import annotations

import struct
import threading
import time
import uuid

import can
import canopen
import pytest

from drive_link.link._sdo import SdoChannel, stamps_host_time

pytestmark = pytest.mark.unit

NODE = 5
INDEX, SUB = 0x2010, 1


def _upload_answer(value: int) -> bytes:
    """Expedited upload response, 4 bytes (CiA 301: scs 2, e = s = 1, n = 0)."""
    return struct.pack("<BHBI", 0x43, INDEX, SUB, value)


class Server(can.Listener):
    """Answers every upload request for INDEX:SUB with ``value`` after ``delay_s``."""

    def __init__(self, channel: str, value: int, delay_s: float) -> None:
        self.bus = can.Bus(interface="virtual", channel=channel)
        self.value, self.delay_s = value, delay_s
        self.notifier = can.Notifier(self.bus, [self], 0.05)

    def on_message_received(self, msg: can.Message) -> None:
        if msg.arbitration_id == 0x600 + NODE and msg.data[0] >> 5 == 2:
            threading.Timer(self.delay_s, self._answer).start()

    def _answer(self) -> None:
        data = _upload_answer(self.value)
        self.bus.send(can.Message(arbitration_id=0x580 + NODE, data=data, is_extended_id=False))

    def close(self) -> None:
        self.notifier.stop(1.0)
        self.bus.shutdown()


@pytest.fixture
def rig():
    channel = f"stale-{uuid.uuid4().hex}"
    server = Server(channel, value=222, delay_s=0.05)
    net = canopen.Network()
    net.connect(interface="virtual", channel=channel)
    sdo = SdoChannel(net, NODE, 0x600 + NODE, 0x580 + NODE, timeout=0.5, retries=2)
    yield net, sdo
    sdo.close()
    net.disconnect()
    server.close()


def test_a_frame_received_before_the_request_is_not_its_answer(rig):
    net, sdo = rig
    t_old = time.time() - 1.0  # the kernel received it a second ago
    send = net.send_message

    def send_then_deliver_backlog(cob_id: int, data: bytes, remote: bool = False) -> None:
        send(cob_id, data, remote)
        # the bus thread catches up: hands over the old answer (value 111) only now
        net.notify(0x580 + NODE, bytearray(_upload_answer(111)), t_old)

    net.send_message = send_then_deliver_backlog  # type: ignore[method-assign]
    raw = sdo.upload(INDEX, SUB, "gain")
    assert int.from_bytes(raw, "little") == 222, "a frame older than the request was taken"
    assert sdo.client.stale_dropped == 1


def test_a_frame_stamped_after_the_request_is_taken(rig):
    net, sdo = rig
    send = net.send_message

    def send_then_answer(cob_id: int, data: bytes, remote: bool = False) -> None:
        send(cob_id, data, remote)
        net.notify(0x580 + NODE, bytearray(_upload_answer(333)), time.time())

    net.send_message = send_then_answer  # type: ignore[method-assign]
    raw = sdo.upload(INDEX, SUB, "gain")
    assert int.from_bytes(raw, "little") == 333
    assert sdo.client.stale_dropped == 0


def test_only_host_clock_buses_are_filtered():
    virtual = can.Bus(interface="virtual", channel=f"clk-{uuid.uuid4().hex}")
    kept = can.Bus(
        interface="virtual", channel=f"clk-{uuid.uuid4().hex}", preserve_timestamps=True
    )
    try:
        assert stamps_host_time(virtual)
        assert not stamps_host_time(kept)  # the senders' own stamps: another clock
    finally:
        virtual.shutdown()
        kept.shutdown()

    class Remote:
        channel_info = "socketcand on can0@192.0.2.7:29536"

    class Local:
        channel_info = "socketcand on can0@127.0.0.1:29536"

    assert not stamps_host_time(Remote())  # another machine's clock
    assert stamps_host_time(Local())
    assert not stamps_host_time(object())  # an adapter's own timer
