"""Hub fault injection (seeded drops, fixed delay), argument checks, loopback-only binding."""

from __future__ import annotations

import itertools
import math
import socket
import time

import can
import pytest

from virtual_drive.hub import Hub
from virtual_drive.hub_faults import FaultInjection

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


def _collect(hub: Hub, a: can.BusABC, b: can.BusABC, count: int) -> list[int]:
    """a sends count numbered frames; returns the numbers b received, once the hub has passed or
    dropped every one and b has read as many as were passed (a busy host may take seconds: a
    fixed quiet time would end the count early), and then 0.2 s more (nothing else may come)."""
    for i in range(count):
        a.send(can.Message(arbitration_id=0x200, data=i.to_bytes(2, "big"), is_extended_id=False))
    deadline = time.monotonic() + 20.0
    while time.monotonic() < deadline:
        st = hub.stats
        if st.frames_forwarded + st.frames_dropped >= count:
            break
        time.sleep(0.01)
    got = []
    while len(got) < hub.stats.frames_forwarded and time.monotonic() < deadline:
        m = b.recv(0.5)
        if m is not None:
            got.append(int.from_bytes(m.data, "big"))
    while (m := b.recv(0.2)) is not None:
        got.append(int.from_bytes(m.data, "big"))
    return got


def test_drop_rate_loses_a_binomial_share_in_order_and_is_reproducible():
    count, p = 600, 0.3
    runs = []
    for _ in range(2):
        with Hub(port=0, seed=1234) as hub:
            a, b = _pair(hub)
            hub.set_faults(drop_rate=p)
            got = _collect(hub, a, b, count)
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


@pytest.mark.unit
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


@pytest.mark.unit
@pytest.mark.parametrize("bitrate", [0, -1, 1.5, True, 2_000_000_000])
def test_bad_bitrate_is_refused(bitrate):
    with pytest.raises(ValueError):
        Hub(port=0, bitrate=bitrate)


@pytest.mark.unit
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


@pytest.mark.unit
def test_jitter_delay_is_uniform_bounded_and_reproducible():
    """delay 2 ms ± 1 ms: frames far apart get end + U(1, 3) ms; frames back to back keep
    their order (never due before the previous one, nor before they complete)."""
    delay, jitter = 0.002, 0.001

    def dues(seed: int, spacing: float, n: int = 2000) -> list[tuple[float, float]]:
        faults = FaultInjection(delay_s=delay, jitter_s=jitter, seed=seed)  # as Hub(...) makes
        out, last = [], 0.0
        for k in range(n):
            end = 1.0 + k * spacing
            last = faults.delivery_due(end, last)
            out.append((end, last))
        return out

    far = dues(3, 0.01)
    offsets = [due - end for end, due in far]
    assert all(delay - jitter <= x <= delay + jitter for x in offsets)
    mean = sum(offsets) / len(offsets)
    assert abs(mean - delay) < 0.05e-3  # uniform: mean 2 ms, sd 0.58 ms / sqrt(2000)
    assert min(offsets) < delay - 0.9 * jitter and max(offsets) > delay + 0.9 * jitter
    assert dues(3, 0.01) == far  # same seed, same draws
    assert dues(4, 0.01) != far
    close = dues(3, 0.0001)  # 0.1 ms apart: the jitter would reorder them
    assert all(due >= end for end, due in close)
    assert all(b[1] >= a[1] for a, b in itertools.pairwise(close))
    with pytest.raises(ValueError):
        Hub(port=0, jitter_s=-0.001)
    hub = Hub(port=0, jitter_s=0.001)
    with pytest.raises(ValueError):
        hub.set_faults(jitter_s=float("nan"))
    assert hub.jitter_s == 0.001


def test_jitter_keeps_order_and_the_same_frames_are_dropped():
    """Through a running hub: with 2 ± 1 ms jitter every frame arrives in order, its
    timestamp (the hub's delivery time) never goes back, and with the same seed the same
    frames are lost as without jitter (separate RNGs)."""
    runs = []
    for jitter in (0.0, 0.001):
        with Hub(port=0, seed=77) as hub:
            a, b = _pair(hub)
            hub.set_faults(drop_rate=0.2, delay_s=0.002, jitter_s=jitter)
            for i in range(300):
                data = i.to_bytes(2, "big")
                a.send(can.Message(arbitration_id=0x200, data=data, is_extended_id=False))
            got, stamps = [], []
            while (m := b.recv(0.5)) is not None:
                got.append(int.from_bytes(m.data, "big"))
                stamps.append(m.timestamp)
            a.shutdown()
            b.shutdown()
        assert got == sorted(got)
        assert all(t1 >= t0 for t0, t1 in itertools.pairwise(stamps))
        runs.append(got)
    assert runs[0] == runs[1]


def test_cli_takes_delay_jitter_drop_and_seed():
    """`virtual-drive hub --delay-ms 2 --jitter-ms 1 --drop 0.01 --seed 5` serves; a negative
    jitter is refused with one line and exit 2."""
    import re
    import signal
    import subprocess
    import sys

    cmd = [sys.executable, "-m", "virtual_drive.cli", "hub", "--port", "0"]
    proc = subprocess.Popen(
        [*cmd, "--delay-ms", "2", "--jitter-ms", "1", "--drop", "0.01", "--seed", "5"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        line = proc.stdout.readline()
        assert re.search(r"port=\d+", line), line
    finally:
        proc.send_signal(signal.SIGTERM)
        proc.wait(10)
    assert proc.returncode == 0
    bad = subprocess.run(
        [*cmd, "--jitter-ms", "-1"], capture_output=True, text=True, timeout=30
    )
    assert bad.returncode == 2
    assert bad.stderr.strip().count("\n") == 0 and "jitter_s" in bad.stderr
