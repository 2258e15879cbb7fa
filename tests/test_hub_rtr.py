"""Remote frames through the hub and the drive's answers (issue 29, item 5).

Truths: socketcand's protocol (linux-can/socketcand doc/protocol.md): a client sends a remote
frame as ``< sendrtr <id> <dlc> >`` and a rawmode client receives one as
``< rtr <id> <secs>.<usecs> <dlc> >``. CiA 301 §7.5.2.35: a TPDO whose COB-ID has bit 30 = 0
may be requested by a remote frame; §7.2.8.3: error control by heartbeat or node guarding; this
drive declares node guarding absent (no 0x100C/0x100D in the EDS), so an RTR on 0x700+N gets no
answer and SDO access to 0x100C aborts 0x06020000 (object does not exist). The hub is read with
raw sockets speaking the protocol text, the drive through canopen's SDO client.
"""

from __future__ import annotations

import re
import socket
import time

import can
import canopen
import pytest
from canopen.sdo import SdoAbortedError

from firmware_protocol import load_od
from virtual_drive.hub import Hub

pytestmark = pytest.mark.timeout(90)


class RawClient:
    """A socketcand rawmode client written from the protocol document (no project code)."""

    def __init__(self, port: int) -> None:
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=5.0)
        self.buf = b""
        self.expect(b"< hi >")
        self.sock.sendall(b"< open vcan0 >")
        self.expect(b"< ok >")
        self.sock.sendall(b"< rawmode >")
        self.expect(b"< ok >")

    def expect(self, element: bytes) -> None:
        assert self.element() == element

    def element(self, timeout: float = 5.0) -> bytes | None:
        self.sock.settimeout(timeout)
        while b">" not in self.buf:
            try:
                chunk = self.sock.recv(4096)
            except TimeoutError:
                return None
            if not chunk:
                return None
            self.buf += chunk
        head, _, self.buf = self.buf.partition(b">")
        return b" ".join(head.split()) + b" >"

    def close(self) -> None:
        self.sock.close()


def test_hub_carries_remote_frames_as_socketcand_does():
    with Hub(port=0) as hub:
        a, b = RawClient(hub.port), RawClient(hub.port)
        stock = can.Bus(**hub.join_kwargs())  # python-can's own client: no RTR support
        try:
            time.sleep(0.1)
            a.sock.sendall(b"< sendrtr 123 4 >< sendrtr 1ABCDEF0 0 >< send 124 1 55 >")
            got = [b.element() for _ in range(3)]
            assert re.fullmatch(rb"< rtr 123 \d+\.\d{6} 4 >", got[0]), got
            assert re.fullmatch(rb"< rtr 1ABCDEF0 \d+\.\d{6} 0 >", got[1]), got
            assert re.fullmatch(rb"< frame 124 \d+\.\d{6} 55 >", got[2]), got
            # python-can's client skips the rtr lines and still gets the data frame
            msgs = []
            end = time.monotonic() + 3.0
            while time.monotonic() < end and not msgs:
                m = stock.recv(0.5)
                if m is not None:
                    msgs.append(m)
            assert [(m.arbitration_id, bytes(m.data)) for m in msgs] == [(0x124, b"\x55")]
            # a malformed request is refused with an error element, nothing is forwarded
            a.sock.sendall(b"< sendrtr 123 9 >")
            assert a.element().startswith(b"< error")
            assert b.element(0.3) is None
        finally:
            stock.shutdown()
            a.close()
            b.close()


@pytest.fixture(scope="module")
def drive_on_hub():
    from virtual_drive.launch import virtual_bench

    with virtual_bench(nodes=(1,)) as settings:
        hub = settings.hub
        master = can.Bus(interface="vdhub", channel="vcan0", host="127.0.0.1", port=hub.port)
        net = canopen.Network(master)
        net.connect()
        node = canopen.RemoteNode(1, load_od(node_id=1).canopen_od(1))
        net.add_node(node)
        node.sdo.RESPONSE_TIMEOUT = 5.0
        raw = RawClient(hub.port)
        try:
            yield net, node, raw
        finally:
            raw.close()
            net.disconnect()


def frames_of(raw: RawClient, ident: bytes, seconds: float) -> list[bytes]:
    out = []
    end = time.monotonic() + seconds
    while (left := end - time.monotonic()) > 0:
        e = raw.element(left)
        if e is None:
            break
        if e.startswith(b"< frame " + ident + b" "):
            out.append(e)
    return out


def test_tpdo_answers_a_remote_request_node_guarding_is_absent(drive_on_hub):
    net, node, raw = drive_on_hub
    comm = node.sdo[0x1800]
    comm[1].raw = 0x80000181
    comm[5].raw = 0  # no event timer: TPDO1 goes out only when requested
    comm[1].raw = 0x181  # bit 30 = 0: RTR allowed
    node.sdo["producer_heartbeat_time"].raw = 0  # no heartbeat on 0x701 to confuse
    net.send_message(0, bytes([0x01, 1]))
    time.sleep(0.3)
    assert frames_of(raw, b"181", 0.3) == []
    net.bus.send(
        can.Message(arbitration_id=0x181, is_remote_frame=True, dlc=6, is_extended_id=False)
    )
    got = frames_of(raw, b"181", 1.0)
    assert len(got) == 1 and len(got[0].split()[4]) == 12, got  # the drive's 6-byte TPDO1
    # node guarding: no answer on 0x701, and its objects do not exist
    net.bus.send(
        can.Message(arbitration_id=0x701, is_remote_frame=True, dlc=1, is_extended_id=False)
    )
    assert frames_of(raw, b"701", 0.5) == []
    for index in (0x100C, 0x100D):
        with pytest.raises(SdoAbortedError) as exc:
            node.sdo.upload(index, 0)
        assert exc.value.code == 0x06020000
