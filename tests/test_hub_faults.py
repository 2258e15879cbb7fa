"""Hub fault injection (seeded drops, fixed delay), argument checks, loopback-only binding."""

from __future__ import annotations

import math
import socket
import time

import can
import pytest

from virtual_drive.hub import Hub

pytestmark = pytest.mark.timeout(30)


def _pair(hub: Hub) -> tuple[can.BusABC, can.BusABC]:
    a = can.Bus(**hub.join_kwargs())
    b = can.Bus(**hub.join_kwargs())
    time.sleep(Hub.handshake_hold_s + 0.05)
    return a, b


def _burst(a: can.BusABC, b: can.BusABC, count: int) -> list[int]:
    """a sends count numbered frames; returns the numbers b received (in arrival order)."""
    for i in range(count):
        a.send(can.Message(arbitration_id=0x200, data=i.to_bytes(2, "big"), is_extended_id=False))
    a.send(can.Message(arbitration_id=0x7FF, data=b"end", is_extended_id=False))
    got = []
    while True:
        m = b.recv(5.0)
        assert m is not None, "end marker lost"
        if m.arbitration_id == 0x7FF:
            return got
        got.append(int.from_bytes(m.data, "big"))


def _collect(a: can.BusABC, b: can.BusABC, count: int) -> list[int]:
    """a sends count numbered frames; returns the numbers b received until the bus is quiet."""
    for i in range(count):
        a.send(can.Message(arbitration_id=0x200, data=i.to_bytes(2, "big"), is_extended_id=False))
    got = []
    while (m := b.recv(0.5)) is not None:
        got.append(int.from_bytes(m.data, "big"))
    return got


def test_drop_rate_loses_a_binomial_share_in_order_and_is_reproducible():
    count, p = 600, 0.3
    runs = []
    for _ in range(2):
        with Hub(port=0, seed=1234) as hub:
            a, b = _pair(hub)
            hub.set_faults(drop_rate=p)
            got = _collect(a, b, count)
            st = hub.stats
            a.shutdown()
            b.shutdown()
        runs.append(got)
        assert got == sorted(got)  # order kept
        lost = count - len(got)
        assert abs(lost - count * p) < 5 * math.sqrt(count * p * (1 - p))
        assert st.frames_dropped == lost and st.frames_forwarded == len(got)
    assert runs[0] == runs[1]  # same seed, same traffic -> the same frames lost


def test_drop_all_then_none_at_run_time():
    with Hub(port=0) as hub:
        a, b = _pair(hub)
        hub.set_faults(drop_rate=1.0)
        for i in range(20):
            a.send(can.Message(arbitration_id=0x300, data=[i], is_extended_id=False))
        assert b.recv(0.3) is None
        assert hub.stats.frames_dropped == hub.stats.dropped == 20
        hub.set_faults(drop_rate=0.0)
        assert _burst(a, b, 50) == list(range(50))
        a.shutdown()
        b.shutdown()


def test_delay_adds_latency_set_at_run_time():
    with Hub(port=0) as hub:
        a, b = _pair(hub)

        def one_way() -> float:
            t0 = time.time()
            a.send(can.Message(arbitration_id=0x181, data=[1], is_extended_id=False))
            m = b.recv(3.0)
            assert m is not None
            assert m.timestamp >= t0  # stamped when the (delayed) delivery happened
            return time.time() - t0

        base = min(one_way() for _ in range(3))
        assert base < 0.1
        hub.set_faults(delay_s=0.25)
        delayed = [one_way() for _ in range(3)]
        assert all(0.25 <= d < 0.25 + 0.2 for d in delayed), delayed
        hub.set_faults(delay_s=0.0)
        assert one_way() < 0.1
        a.shutdown()
        b.shutdown()


@pytest.mark.parametrize(
    "kwargs",
    [
        {"drop_rate": -0.1},
        {"drop_rate": 1.5},
        {"drop_rate": float("nan")},
        {"delay_s": -1.0},
        {"delay_s": float("inf")},
    ],
)
def test_bad_faults_are_refused_and_nothing_changes(kwargs):
    hub = Hub(port=0, drop_rate=0.1, delay_s=0.01)
    with pytest.raises(ValueError):
        hub.set_faults(**kwargs)
    assert (hub.drop_rate, hub.delay_s) == (0.1, 0.01)
    with pytest.raises(ValueError):
        Hub(port=0, **kwargs)


@pytest.mark.parametrize("bitrate", [0, -1, 1.5, True, 2_000_000_000])
def test_bad_bitrate_is_refused(bitrate):
    with pytest.raises(ValueError):
        Hub(port=0, bitrate=bitrate)


@pytest.mark.parametrize("host", ["0.0.0.0", "", "192.168.1.10", "::", "::1", "example.com"])
def test_non_loopback_host_is_refused(host):
    with pytest.raises(ValueError, match=r"127\.0\.0\.1"):
        Hub(host=host, port=0)


def _listening_addresses(port: int) -> list[str]:
    """Local addresses of TCP sockets listening on port, read from the kernel (/proc/net/tcp*)."""
    found = []
    for path in ("/proc/net/tcp", "/proc/net/tcp6"):
        try:
            lines = open(path).read().splitlines()[1:]
        except OSError:
            continue
        for line in lines:
            fields = line.split()
            addr, port_hex = fields[1].split(":")
            if int(port_hex, 16) == port and fields[3] == "0A":  # 0A = LISTEN
                found.append(addr)
    return found


def test_binds_loopback_only():
    with Hub(host="localhost", port=0) as hub:
        # 0100007F is 127.0.0.1 in /proc's little-endian hex
        assert _listening_addresses(hub.port) == ["0100007F"]
        with socket.create_connection(("127.0.0.1", hub.port), timeout=2) as s:
            assert s.recv(16) == b"< hi >"


def test_busy_port_raises_and_stop_releases_it():
    with Hub(port=0) as first:
        port = first.port
        with pytest.raises(OSError):
            Hub(port=port).start()
    again = Hub(port=port).start()  # freed by stop()
    again.stop()
