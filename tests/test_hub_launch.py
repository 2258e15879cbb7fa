"""virtual_drive.launch.virtual_bench: one way to start a hub with virtual drives.

Truths: CiA 301 (SDO server of node N on 0x600 + N, replies on 0x580 + N; device type 0x1000 of
this drive 0x00020192 as in its EDS), python-can's own ``can.Bus(**settings)``, and /proc for
whether the child processes are gone.
"""

from __future__ import annotations

import os
import socket
import time

import can
import pytest

from virtual_drive.launch import parse_nodes, virtual_bench

pytestmark = pytest.mark.timeout(180)


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def _port_open(port: int) -> bool:
    try:
        socket.create_connection(("127.0.0.1", port), timeout=1.0).close()
    except OSError:
        return False
    return True


def _sdo_device_type(bus: can.BusABC, node: int, timeout: float = 10.0) -> bytes | None:
    bus.send(
        can.Message(
            arbitration_id=0x600 + node, data=[0x40, 0, 0x10, 0, 0, 0, 0, 0], is_extended_id=False
        )
    )
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        m = bus.recv(0.5)
        if m is not None and m.arbitration_id == 0x580 + node:
            return bytes(m.data)
    return None


def test_two_nodes_answer_on_their_ids_restart_and_everything_stops():
    with virtual_bench(nodes=(1, 2), drop_rate=0.0, seed=3) as bus:
        assert bus["interface"] == "socketcand" and bus["host"] == "127.0.0.1"
        assert set(bus.drives) == {1, 2} and bus.hub is not None
        port, pids = bus.port, [d.pid for d in bus.drives.values()]
        raw = can.Bus(**bus)  # the settings are python-can's own keywords
        try:
            time.sleep(0.1)
            for node in (1, 2):
                assert _sdo_device_type(raw, node) == bytes([0x43, 0, 0x10, 0, 0x92, 1, 2, 0])
            new = bus.restart_drive(2)
            assert new.pid != pids[1] and not _alive(pids[1])
            assert _sdo_device_type(raw, 2) is not None
            pids.append(new.pid)
        finally:
            raw.shutdown()
        bus.hub.set_faults(drop_rate=0.5)  # the in-process hub is reachable for fault injection
        assert bus.hub.drop_rate == 0.5
    deadline = time.monotonic() + 20
    while any(_alive(p) for p in pids) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not any(_alive(p) for p in pids)
    assert not _port_open(port)


def test_hub_in_its_own_process_ends_with_the_block():
    with virtual_bench(nodes=(), hub_process=True, delay_s=0.001) as bus:
        assert bus.hub is None and bus.drives == {}
        pid = bus.hub_process.pid
        assert pid != os.getpid() and _alive(pid)
        assert _port_open(bus.port)
    deadline = time.monotonic() + 10
    while _alive(pid) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not _alive(pid)


@pytest.mark.unit
@pytest.mark.parametrize(
    "kwargs",
    [{"nodes": (0,)}, {"nodes": (1, 1)}, {"nodes": (128,)}, {"drop_rate": 2.0}, {"bitrate": 0}],
)
def test_bad_settings_raise_before_anything_starts(kwargs):
    with pytest.raises(ValueError), virtual_bench(**kwargs):
        pass


@pytest.mark.unit
def test_parse_nodes():
    assert parse_nodes("1-4") == (1, 2, 3, 4)
    assert parse_nodes("2") == (2,)
    assert parse_nodes("1-2,5") == (1, 2, 5)
    for bad in ("", "0", "4-1", "1,1", "a", "1-200"):
        with pytest.raises(ValueError):
            parse_nodes(bad)
