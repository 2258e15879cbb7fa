"""The drive's lean hub client and the shared pacing loop (issue 11).

Truths: python-can's own ``socketcand`` interface is the independent peer on the hub (what it
reads is what went on the bus); wall-clock time (``time.monotonic``) for the pacing loop.
"""

from __future__ import annotations

import threading
import time

import can
import pytest
from conftest import recv_frames
from test_node_process import HubProcess

from virtual_drive.node.cli_run import parse_nodes, store_for
from virtual_drive.node.hub_bus import HubBus, HubConnection
from virtual_drive.node.runner import TS, Pacer, Runner

pytestmark = pytest.mark.timeout(60)


@pytest.fixture(scope="module")
def hub():
    h = HubProcess()
    yield h
    h.stop()


def test_send_many_reaches_a_python_can_peer_in_order(hub):
    peer = can.Bus(**hub.join_kwargs())
    bus = HubBus(channel="vcan0", host="127.0.0.1", port=hub.port)
    try:
        time.sleep(0.2)  # both joined before anything is sent
        frames = [(0x181 + k, bytes(range(0xF8, 0xF8 + k))) for k in range(9)]  # 0..8 bytes
        assert bus.send_many(frames) == 9
        bus.send(can.Message(arbitration_id=0x1ABCDEF, data=b"\x01", is_extended_id=True))
        got = recv_frames(peer, 10)
        assert [(m.arbitration_id, bytes(m.data)) for m in got[:9]] == frames
        assert not any(m.is_extended_id for m in got[:9])
        assert got[9].is_extended_id and got[9].arbitration_id == 0x1ABCDEF
    finally:
        bus.shutdown()
        peer.shutdown()


def test_frames_nobody_wants_are_dropped_before_parsing(hub):
    peer = can.Bus(**hub.join_kwargs())
    bus = HubBus(channel="vcan0", host="127.0.0.1", port=hub.port)
    try:
        time.sleep(0.2)
        bus.rx_wanted = {0x601, 0x000}
        for cob_id, data in ((0x182, b"\x01"), (0x601, b"\x40\x41\x60\x00"), (0x000, b"\x01\x00")):
            peer.send(can.Message(arbitration_id=cob_id, data=data, is_extended_id=False))
        got = recv_frames(bus, 2)
        assert [(m.arbitration_id, bytes(m.data)) for m in got] == [
            (0x601, b"\x40\x41\x60\x00"),
            (0x000, b"\x01\x00"),
        ]
        assert bus.rx_dropped == 1
        assert bus.recv(0.2) is None
    finally:
        bus.shutdown()
        peer.shutdown()


def test_registered_as_python_can_interface_and_clear_errors(hub):
    bus = can.Bus(interface="vdhub", channel="vcan0", host="127.0.0.1", port=hub.port)
    try:
        assert isinstance(bus, HubBus) and bus.lost() is None
    finally:
        bus.shutdown()
    with pytest.raises(can.CanInitializationError, match="cannot connect"):
        HubBus(channel="vcan0", host="127.0.0.1", port=1, connect_timeout=2.0)


def test_shared_connection_delivers_like_one_bus(hub):
    """Ports of one HubConnection: a frame a port sends reaches the hub's other clients once
    and the sibling ports that want it; frames from the hub reach the ports that want them;
    frames sent on the batching thread wait for flush()."""
    peer = can.Bus(**hub.join_kwargs())
    conn = HubConnection(channel="vcan0", host="127.0.0.1", port=hub.port)
    a, b = conn.port(), conn.port()
    try:
        time.sleep(0.2)
        a.rx_wanted, b.rx_wanted = {0x601}, {0x701, 0x602}
        a.send(can.Message(arbitration_id=0x701, data=b"\x05", is_extended_id=False))
        assert [(m.arbitration_id, bytes(m.data)) for m in recv_frames(b, 1)] == [(0x701, b"\x05")]
        assert a.recv(0.1) is None  # a port does not hear itself
        assert [m.arbitration_id for m in recv_frames(peer, 1)] == [0x701]  # the hub got it
        peer.send(can.Message(arbitration_id=0x601, data=b"\x40", is_extended_id=False))
        peer.send(can.Message(arbitration_id=0x602, data=b"\x41", is_extended_id=False))
        assert [m.arbitration_id for m in recv_frames(a, 1)] == [0x601]
        assert [m.arbitration_id for m in recv_frames(b, 1)] == [0x602]
        conn.batch_on(threading.get_ident())
        a.send_many([(0x181, b"\x01"), (0x281, b"\x02")])
        assert peer.recv(0.3) is None  # held
        conn.flush()
        assert [m.arbitration_id for m in recv_frames(peer, 2)] == [0x181, 0x281]
        assert peer.recv(0.3) is None  # each frame once
    finally:
        a.shutdown()
        b.shutdown()
        peer.shutdown()


@pytest.mark.unit
def test_parse_nodes_and_store_names():
    assert parse_nodes("1-4") == [1, 2, 3, 4]
    assert parse_nodes("1,3,5") == [1, 3, 5]
    assert parse_nodes("1-3,7") == [1, 2, 3, 7]
    for bad in ("0-3", "4-1", "1,1", "x", "1-200", "1-17"):
        with pytest.raises(ValueError):
            parse_nodes(bad)
    assert str(store_for("p.json", 2, True)) == "p-node2.json"
    assert str(store_for("p.json", 2, False)) == "p.json"
    assert str(store_for("d/{node}.json", 3, True)) == "d/3.json"
    assert store_for(None, 1, True) is None


@pytest.mark.unit
def test_one_pacer_runs_several_runners_at_wall_clock_pace():
    """Two runners on one pacer both follow wall-clock time; a failing one stops alone."""
    samples = {"a": 0, "b": 0}
    lock = threading.Lock()

    def stepper(name):
        def step(n):
            with lock:
                samples[name] += n

        return step

    def failing(n):
        raise RuntimeError("boom")

    pacer = Pacer()
    runners = {
        name: pacer.adopt(Runner(stepper(name), lambda now: None)) for name in ("a", "b")
    }
    bad = pacer.adopt(Runner(failing, lambda now: None))
    try:
        t0 = time.monotonic()
        for r in (*runners.values(), bad):
            r.start()
        time.sleep(0.5)
        wall = time.monotonic() - t0
        with lock:
            got = dict(samples)
        for name, r in runners.items():
            assert r.running and r.error is None
            # simulated time = wall-clock time, give or take the chunks of a busy host
            assert abs(got[name] * TS - wall) < 0.1 + r.stats.max_lag_s, (got, wall)
        assert bad.error is not None and not bad.running
        assert pacer.running
    finally:
        for r in runners.values():
            r.stop()
        pacer.stop()
    assert not pacer.running
