"""Hub transport between separate processes, with stock python-can socketcand clients.

* 10,000 frames from one process to another through the hub: all arrive, in order, none echoed.
* Bit-rate pacing: a burst of N identical frames whose length is hand-counted (121 bits, see
  test_hub_frame_bits) takes N × 121 / bitrate seconds at the receiver, within 10 %.
Throughput at a saturated 1 Mbit/s bus is measured by benchmarks/bench_hub.py, not timed here.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from virtual_drive.hub import Hub

pytestmark = pytest.mark.timeout(60)

# A python-can client run as its own process. argv: role port count pattern
CLIENT = r"""
import json, sys, time
import can

role, port, count, pattern = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4]
DONE = 0x7E1

def frame(i):
    if pattern == "car":
        return can.Message(arbitration_id=0x0C1, data=bytes.fromhex("4001087500000000"),
                           is_extended_id=False)
    n = 8 if i % 3 else i % 9
    data = (i.to_bytes(4, "big") + ((i * 2654435761) % 2**32).to_bytes(4, "big"))[:n]
    if i % 7 == 0:
        return can.Message(arbitration_id=0x1000000 + i, data=data, is_extended_id=True)
    return can.Message(arbitration_id=0x100 + i % 0x500, data=data, is_extended_id=False)

bus = can.Bus(interface="socketcand", host="127.0.0.1", port=port, channel="vcan0",
              tcp_tune=True)
out = {}
if role == "receiver":
    time.sleep(0.1)  # past the hub's handshake hold
    print("joined", flush=True)
    got, walls, stamps = [], [], []
    deadline = time.time() + 30
    while len(got) < count and time.time() < deadline:
        m = bus.recv(1.0)
        if m is None:
            continue
        walls.append(time.time())
        stamps.append(m.timestamp)
        got.append([m.arbitration_id, m.is_extended_id, m.data.hex(), m.is_error_frame])
    bus.send(can.Message(arbitration_id=DONE, data=b"", is_extended_id=False))
    out = {"frames": got, "first_wall": walls[0] if walls else None,
           "last_wall": walls[-1] if walls else None,
           "first_stamp": stamps[0] if stamps else None,
           "last_stamp": stamps[-1] if stamps else None}
else:
    t_start = time.time()
    for i in range(count):
        bus.send(frame(i))
    t_sent = time.time()
    others = []
    while True:
        m = bus.recv(30.0)
        if m is None or m.arbitration_id == DONE:
            break
        others.append(m.arbitration_id)
    out = {"t_start": t_start, "t_sent": t_sent, "others": others}
bus.shutdown()
print(json.dumps(out))
"""


def _expected(i: int) -> list:
    n = 8 if i % 3 else i % 9
    data = (i.to_bytes(4, "big") + ((i * 2654435761) % 2**32).to_bytes(4, "big"))[:n]
    if i % 7 == 0:
        return [0x1000000 + i, True, data.hex(), False]
    return [0x100 + i % 0x500, False, data.hex(), False]


def _spawn(role: str, port: int, count: int, pattern: str) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-c", CLIENT, role, str(port), str(count), pattern],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def _run_pair(port: int, count: int, pattern: str) -> tuple[dict, dict]:
    """Receiver first; once it has joined the bus, the sender."""
    procs = {"receiver": _spawn("receiver", port, count, pattern)}
    try:
        joined = procs["receiver"].stdout.readline().strip()
        assert joined == "joined", procs["receiver"].stderr.read()[-2000:]
        procs["sender"] = _spawn("sender", port, count, pattern)
        results = {}
        for role in ("receiver", "sender"):
            p = procs[role]
            out, err = p.communicate(timeout=50)
            assert p.returncode == 0, f"{role} failed: {err[-2000:]}"
            results[role] = json.loads(out.strip().splitlines()[-1])
    finally:
        for p in procs.values():
            if p.poll() is None:
                p.kill()
                p.wait()
    return results["sender"], results["receiver"]


def test_ten_thousand_frames_between_processes_in_order_none_lost():
    count = 10_000
    with Hub(port=0) as hub:
        sender, receiver = _run_pair(hub.port, count, "seq")
        stats = hub.stats
    got = receiver["frames"]
    assert len(got) == count
    assert got == [_expected(i) for i in range(count)]
    assert sender["others"] == []  # the sender never hears its own frames
    assert stats.frames_dropped == 0 and stats.frames_overrun == 0
    assert stats.frames_forwarded == count + 1  # + DONE
    assert stats.protocol_errors == 0


def test_pacing_matches_emulated_bit_rate_within_ten_percent():
    # 50 kbit/s (a CiA 301 bit rate): the bus needs 4.8 s for the burst, so a sender process
    # that a busy host slows (1.1 s for 2000 frames at load 17) still outpaces it
    count, bitrate, bits = 2000, 50_000, 121  # 121 bits: hand count in test_hub_frame_bits
    frame_time = bits / bitrate
    with Hub(port=0, bitrate=bitrate) as hub:
        sender, receiver = _run_pair(hub.port, count, "car")
    assert len(receiver["frames"]) == count
    # the sender pushed the burst much faster than the bus can carry it ...
    assert sender["t_sent"] - sender["t_start"] < 0.5 * count * frame_time
    # ... so frames queued behind each other: first-to-last spacing is (N-1) frame times
    wall_span = receiver["last_wall"] - receiver["first_wall"]
    assert wall_span == pytest.approx((count - 1) * frame_time, rel=0.10)
    # hub timestamps: never closer than one frame time (more only if the sender stalled and the
    # emulated bus went idle for a moment, as a real bus would)
    stamp_span = receiver["last_stamp"] - receiver["first_stamp"]
    assert (count - 1) * frame_time - 20e-6 <= stamp_span <= 1.10 * (count - 1) * frame_time
    # and no frame arrived before the bus could have finished it
    assert receiver["last_wall"] - sender["t_start"] >= count * frame_time - 1e-3
