"""Benchmark of the loopback CAN hub (virtual_drive.hub) with stock python-can clients.

Prints:
* throughput, frames/s, of a burst of 8-byte frames from one process to another, at the
  emulated 1 Mbit/s (expected: the bus limit, 1e6 / frame_bits) and with pacing made
  negligible (1 Gbit/s: the hub's own capacity), plus the hub's CPU use (one core = 100 %);
* SDO-like round-trip latency: a requester process sends 0x601 (8 bytes) and waits for the 0x581
  reply of a responder process; and a burst of 8 frames answered by one reply (a block-transfer
  sub-block); each with and without python-can's ``tcp_tune``.

* forwarding the default streams: a virtual drive (``virtual-drive run``, OPERATIONAL: TPDO1-4
  at 100/1000/1000/100 Hz, about 2,200 frames/s) and two python-can clients on a hub in its own
  process (``virtual-drive hub``); the hub's CPU from /proc over the window (one core = 100 %;
  goal of issue 11: <= 10 %), with the load average beside it.

Run: python benchmarks/bench_hub.py [--frames 20000] [--round-trips 1000] [--forward-seconds 15]
     python benchmarks/bench_hub.py --forward-only
Clients run as separate processes; the hub of the throughput/round-trip runs in this process.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

from _bench_clients import cpu_seconds, go, loadavg, result, spawn_client, wait_joined

from firmware_protocol.can_bits import frame_bits
from virtual_drive.hub import Hub
from virtual_drive.launch import virtual_bench

CLIENT = r"""
import json, os, sys, time
import can

role, port, count, tune = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), sys.argv[4] == "1"
bus = can.Bus(interface="socketcand", host="127.0.0.1", port=port, channel="vcan0", tcp_tune=tune)
out = {}
if role == "sink":
    time.sleep(0.1)
    print("joined", flush=True)
    n, first, last, stamp0, stamp1 = 0, None, None, None, None
    while n < count:
        m = bus.recv(10.0)
        if m is None:
            break
        last, stamp1 = time.perf_counter(), m.timestamp
        if first is None:
            first, stamp0 = last, stamp1
        n += 1
    out = {"n": n, "span": (last - first) if n > 1 else None,
           "stamp_span": (stamp1 - stamp0) if n > 1 else None}
elif role == "source":
    rng = __import__("random").Random(1)
    for i in range(count):
        bus.send(can.Message(arbitration_id=0x181, data=bytes(rng.randrange(256) for _ in range(8)),
                             is_extended_id=False))
    time.sleep(0.5)
elif role == "responder":
    time.sleep(0.1)
    print("joined", flush=True)
    served = 0
    while served < count:
        m = bus.recv(10.0)
        if m is None:
            break
        if m.arbitration_id == 0x601:
            bus.send(can.Message(arbitration_id=0x581, data=bytes([0x43, 0, 0x10, 0, 1, 2, 3, 4]),
                                 is_extended_id=False))
            served += 1
    out = {"served": served}
elif role == "block_responder":
    time.sleep(0.1)
    print("joined", flush=True)
    served = 0
    while served < count:
        m = bus.recv(10.0)
        if m is None:
            break
        if m.arbitration_id == 0x601 and m.data[0] == 7:  # last frame of a burst of 8
            bus.send(can.Message(arbitration_id=0x581, data=bytes([0xA2, 8, 127, 0, 0, 0, 0, 0]),
                                 is_extended_id=False))
            served += 1
    out = {"served": served}
elif role == "block_requester":
    rtts = []
    for _ in range(count):
        t0 = time.perf_counter()
        for k in range(8):
            bus.send(can.Message(arbitration_id=0x601, data=bytes([k] * 8), is_extended_id=False))
        m = bus.recv(5.0)
        if m is None:
            break
        rtts.append(time.perf_counter() - t0)
    out = {"rtts": rtts}
elif role == "requester":
    rtts = []
    req = can.Message(arbitration_id=0x601, data=bytes([0x40, 0, 0x10, 0, 0, 0, 0, 0]),
                      is_extended_id=False)
    for _ in range(count):
        t0 = time.perf_counter()
        bus.send(req)
        while True:
            m = bus.recv(5.0)
            if m is None or m.arbitration_id == 0x581:
                break
        if m is None:
            break
        rtts.append(time.perf_counter() - t0)
    out = {"rtts": rtts}
bus.shutdown()
print(json.dumps(out))
"""


def _spawn(role: str, port: int, count: int, tune: bool) -> subprocess.Popen:
    args = [sys.executable, "-c", CLIENT, role, str(port), str(count), "1" if tune else "0"]
    return subprocess.Popen(args, stdout=subprocess.PIPE, text=True)


def _pair(port: int, roles: tuple[str, str], count: int, tune: bool) -> dict:
    """Start roles[1] (the listening side); once it has joined the bus, roles[0]."""
    first = _spawn(roles[1], port, count, tune)
    if first.stdout.readline().strip() != "joined":
        raise SystemExit(f"bench_hub: {roles[1]} could not join the hub")
    procs = {roles[1]: first, roles[0]: _spawn(roles[0], port, count, tune)}
    results = {}
    for r, p in procs.items():
        out, _ = p.communicate(timeout=300)
        if p.returncode != 0:
            raise SystemExit(f"bench_hub: {r} process failed (exit {p.returncode})")
        results[r] = json.loads(out.strip().splitlines()[-1])
    return results


def throughput(frames: int, bitrate: int) -> tuple[float, float, float]:
    """(frames/s on the emulated bus by the hub's timestamps, frames/s received by the sink,
    hub CPU time per frame in µs) for a burst of 8-byte frames.

    The CPU time is this process's (the hub thread's; the clients are child processes) over the
    whole run, so it slightly overstates the per-frame cost.
    """
    with Hub(port=0, bitrate=bitrate) as hub:
        cpu0 = os.times()
        res = _pair(hub.port, ("source", "sink"), frames, True)
        cpu1 = os.times()
        sink = res["sink"]
        if sink["n"] != frames:
            raise SystemExit(f"bench_hub: sink got {sink['n']} of {frames} frames")
    bus_rate = (frames - 1) / sink["stamp_span"]
    rate = (frames - 1) / sink["span"]
    cpu = (cpu1.user - cpu0.user) + (cpu1.system - cpu0.system)
    return bus_rate, rate, 1e6 * cpu / frames


def round_trip(count: int, tune: bool, burst: bool = False) -> list[float]:
    """Round-trip times (s) of count exchanges at 1 Mbit/s: one request and its reply, or
    (burst=True) 8 frames back to back and one reply, like a block-transfer sub-block."""
    roles = ("block_requester", "block_responder") if burst else ("requester", "responder")
    with Hub(port=0) as hub:
        res = _pair(hub.port, roles, count, tune)
    return res[roles[0]]["rtts"]


def forwarding(seconds: float) -> dict:
    """Hub CPU (% of one core) forwarding one virtual drive's default TPDO streams to two
    python-can clients; also the drive's CPU and the clients' received frame rates."""
    with virtual_bench(nodes=(1,), hub_process=True) as bus:
        clients = [spawn_client(r, bus.port, seconds + 4) for r in ("start", "sink")]
        for c in clients:
            wait_joined(c)
        go(clients)
        time.sleep(2.0)  # NMT start sent, TPDOs flowing
        hub_pid, drive_pid = bus.hub_process.pid, bus.drives[1].pid
        c_hub, c_drive, t0 = cpu_seconds(hub_pid), cpu_seconds(drive_pid), time.monotonic()
        load0 = loadavg()
        time.sleep(seconds)
        dt = time.monotonic() - t0
        hub_pct = 100 * (cpu_seconds(hub_pid) - c_hub) / dt
        drive_pct = 100 * (cpu_seconds(drive_pid) - c_drive) / dt
        load1 = loadavg()
        rates = [result(c).get("rate", 0.0) for c in clients]
    return {
        "hub_pct": hub_pct,
        "drive_pct": drive_pct,
        "rates": rates,
        "load": f"{load0} -> {load1}",
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=20_000, help="frames per throughput run")
    parser.add_argument("--round-trips", type=int, default=1000, help="exchanges per RTT run")
    parser.add_argument("--forward-seconds", type=float, default=15.0, help="forwarding window")
    parser.add_argument("--forward-only", action="store_true", help="only the forwarding run")
    args = parser.parse_args(argv)
    print(f"hub benchmark  (python {sys.version.split()[0]}, {os.cpu_count()} CPUs)")
    f = forwarding(args.forward_seconds)
    print(
        f"forwarding 1 drive's default streams to 2 clients over {args.forward_seconds:g} s: "
        f"hub CPU {f['hub_pct']:.1f} % of one core (goal <= 10 %); virtual drive "
        f"{f['drive_pct']:.1f} %; clients received "
        + " / ".join(f"{r:,.0f}" for r in f["rates"])
        + f" frames/s; load {f['load']}"
    )
    if args.forward_only:
        return 0

    import random

    rng = random.Random(1)
    sample = [bytes(rng.randrange(256) for _ in range(8)) for _ in range(args.frames)]
    mean_bits = sum(frame_bits(0x181, d) for d in sample) / len(sample)
    print(f"8-byte frames: mean {mean_bits:.1f} bits with exact stuffing")
    for bitrate, label in ((1_000_000, "1 Mbit/s emulated"), (1_000_000_000, "pacing off")):
        bus_rate, rate, us = throughput(args.frames, bitrate)
        limit = f"limit {bitrate / mean_bits:,.0f}" if bitrate <= 1_000_000 else "no limit"
        print(
            f"throughput, {label:18s}: on the bus {bus_rate:9,.0f} frames/s ({limit}), "
            f"at the python-can sink {rate:9,.0f} frames/s; hub CPU {us:.1f} µs/frame"
        )
    floor = frame_bits(0x601, bytes([0x40, 0, 0x10, 0, 0, 0, 0, 0])) + frame_bits(
        0x581, bytes([0x43, 0, 0x10, 0, 1, 2, 3, 4])
    )
    print(f"round trips at 1 Mbit/s include 2 frames on the bus: {floor / 1e3:.3f} ms")
    for burst, label in ((False, "1 request + reply"), (True, "8-frame burst + reply")):
        for tune in (True, False):
            rtts = sorted(round_trip(args.round_trips, tune, burst))
            if not rtts:
                print(f"{label}, tcp_tune={tune!s:5s}: no replies")
                continue
            p95 = rtts[min(len(rtts) - 1, int(0.95 * len(rtts)))]
            print(
                f"{label:22s} tcp_tune={tune!s:5s}: median {statistics.median(rtts) * 1e3:6.3f}"
                f" ms, p95 {p95 * 1e3:6.3f} ms, mean {statistics.fmean(rtts) * 1e3:6.3f} ms"
                f" ({len(rtts)} exchanges)"
            )
    return 0


if __name__ == "__main__":
    t0 = time.time()
    code = main()
    print(f"(bench took {time.time() - t0:.1f} s)")
    sys.exit(code)
