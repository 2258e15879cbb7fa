"""Helpers of the hub / multi-node benchmarks: CPU time of a process from /proc, the load average,
and python-can client processes (a counting sink, an SDO requester) that join a loopback hub.

Not a benchmark itself; imported by ``bench_hub.py`` and ``bench_nodes.py``.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

__all__ = ["CLIENT", "cpu_seconds", "go", "loadavg", "result", "spawn_client", "wait_joined"]


def cpu_seconds(pid: int) -> float:
    """User + system CPU time of process ``pid`` and its threads so far, s (/proc/PID/stat)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def loadavg() -> str:
    """The 1/5/15-minute load averages as text."""
    return " ".join(Path("/proc/loadavg").read_text().split()[:3])


#: A client process. argv: role port seconds [nodes] [bits]. Roles: ``sink`` counts frames for
#: ``seconds``; ``start`` also sends NMT "start all nodes" (CiA 301: 0x000, [1, 0]) first;
#: ``sdo`` reads 0x6041:00 (statusword, expedited upload) from each node in turn, 50 reads/s
#: per node, and reports the request -> reply times as seen by this client (``latency``) and
#: up to the end of the reply on the bus by the hub's timestamp (``latency_bus``: without this
#: client's own receive backlog). Prints one JSON line at the end.
CLIENT = r"""
import json, sys, time
import can

role, port, seconds = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
nodes = [int(n) for n in sys.argv[4].split(",") if n]
count_bits = sys.argv[5] == "1"
if count_bits:
    from firmware_protocol.can_bits import frame_bits_fast
bus = can.Bus(interface="socketcand", host="127.0.0.1", port=port, channel="vcan0", tcp_tune=True)
time.sleep(0.1)
print("joined", flush=True)
sys.stdin.readline()  # go
out = {"frames": 0}
if role == "start":
    bus.send(can.Message(arbitration_id=0, data=[1, 0], is_extended_id=False))
t_end = time.monotonic() + seconds
if role == "sdo":
    lat = {n: [] for n in nodes}
    lat_bus = {n: [] for n in nodes}
    lost = {n: 0 for n in nodes}
    period = 1.0 / (50 * len(nodes))
    k = 0
    while time.monotonic() < t_end:
        n = nodes[k % len(nodes)]
        k += 1
        t0 = time.perf_counter()
        w0 = time.time()
        bus.send(can.Message(arbitration_id=0x600 + n, data=[0x40, 0x41, 0x60, 0, 0, 0, 0, 0],
                             is_extended_id=False))
        while True:
            m = bus.recv(0.5)
            if m is None:
                lost[n] += 1
                break
            out["frames"] += 1
            if m.arbitration_id == 0x580 + n and m.data[1:3] == b"\x41\x60":
                lat[n].append(time.perf_counter() - t0)
                lat_bus[n].append(m.timestamp - w0)  # hub stamp: reply complete on the bus
                break
        rest = period - (time.perf_counter() - t0)
        t_next = time.monotonic() + max(0.0, rest)
        while time.monotonic() < t_next:
            m = bus.recv(max(0.0, t_next - time.monotonic()))
            if m is not None:
                out["frames"] += 1
    out["latency"] = lat
    out["latency_bus"] = lat_bus
    out["lost"] = lost
else:
    first = last = None
    bits = 0
    while time.monotonic() < t_end:
        m = bus.recv(0.2)
        if m is not None:
            out["frames"] += 1
            last = time.monotonic()
            first = first or last
            if count_bits:
                bits += frame_bits_fast(m.arbitration_id, bytes(m.data), m.is_extended_id)
    if first is not None and last > first:
        out["rate"] = (out["frames"] - 1) / (last - first)
        out["bits_rate"] = bits / (last - first)
bus.shutdown()
print(json.dumps(out), flush=True)
"""


def spawn_client(
    role: str, port: int, seconds: float, nodes: str = "", bits: bool = False
) -> subprocess.Popen:
    """Start a :data:`CLIENT` process; call :func:`wait_joined`, then :func:`go`. ``bits``: the
    sink also sums the frames' exact bit counts (bus load)."""
    args = [sys.executable, "-c", CLIENT, role, str(port), repr(seconds), nodes, "01"[bits]]
    return subprocess.Popen(args, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)


def wait_joined(proc: subprocess.Popen) -> None:
    """Wait for the client's "joined" line; raises SystemExit if it failed."""
    if proc.stdout.readline().strip() != "joined":
        raise SystemExit("benchmark client could not join the hub")


def go(procs: list[subprocess.Popen]) -> None:
    """Let joined clients start."""
    for p in procs:
        p.stdin.write("go\n")
        p.stdin.flush()


def result(proc: subprocess.Popen, timeout: float = 120.0) -> dict:
    """The client's JSON result line (waits for it to finish)."""
    out, _ = proc.communicate(timeout=timeout)
    if proc.returncode != 0:
        raise SystemExit(f"benchmark client failed (exit {proc.returncode})")
    return json.loads(out.strip().splitlines()[-1])
