"""TPDO timing of the virtual drive: rate and spacing of TPDO2 (event timer 1 ms) with an
inhibit time, and the missed-period counter 0x2070, on python-can's in-process virtual bus.

    python benchmarks/bench_tpdo_timing.py --seconds 5 --inhibit 20

Prints the frames/s, the gap percentiles between the bus's own send time stamps, frames +
missed periods against the elapsed periods, and the load average. Expected: 1e4/inhibit Hz
(500 Hz for 2 ms) minus the lateness the host adds; the smallest gap never below the inhibit.
"""

from __future__ import annotations

import argparse
import itertools
import os
import statistics
import struct
import threading
import time

import can
import canopen

from firmware_protocol import load_od
from virtual_drive.node import VirtualDrive


class _Stamps(can.Listener):
    def __init__(self, cob_id: int) -> None:
        self.cob_id = cob_id
        self.t: list[float] = []
        self.lock = threading.Lock()

    def on_message_received(self, msg: can.Message) -> None:
        if msg.arbitration_id == self.cob_id:
            with self.lock:
                self.t.append(msg.timestamp)


def main() -> None:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=5.0)
    ap.add_argument("--inhibit", type=int, default=20, help="TPDO2 inhibit time, 100 us units")
    args = ap.parse_args()
    channel = f"bench-tpdo-{os.getpid()}"
    drive_bus = can.Bus(interface="virtual", channel=channel)
    bus = can.Bus(interface="virtual", channel=channel)
    net = canopen.Network(bus)
    net.connect()
    node = canopen.RemoteNode(1, load_od().canopen_od(1))
    net.add_node(node)
    node.sdo.RESPONSE_TIMEOUT = 2.0
    drive = VirtualDrive(drive_bus, node_id=1).start()
    try:
        sdo = node.sdo
        for k in (1, 3, 4):  # only TPDO2
            sdo.download(0x1800 + k - 1, 1, struct.pack("<I", 0x80000001 + 0x80 + 0x100 * k))
        sdo.download(0x1801, 1, struct.pack("<I", 0x80000281))
        sdo.download(0x1801, 3, struct.pack("<H", args.inhibit))
        sdo.download(0x1801, 1, struct.pack("<I", 0x281))
        stamps = _Stamps(0x281)
        net.notifier.add_listener(stamps)
        missed0 = struct.unpack("<I", sdo.upload(0x2070, 2))[0]
        net.send_message(0, bytes([0x01, 1]))
        time.sleep(0.3)
        t0 = time.time()
        time.sleep(args.seconds)
        t1 = time.time()
        net.send_message(0, bytes([0x80, 1]))
        time.sleep(0.2)
        missed = struct.unpack("<I", sdo.upload(0x2070, 2))[0] - missed0
        with stamps.lock:
            all_t = list(stamps.t)
        t = [x for x in all_t if t0 <= x <= t1]
        gaps = sorted(b - a for a, b in itertools.pairwise(t))
        period = max(1e-3, args.inhibit * 100e-6)
        q = statistics.quantiles(gaps, n=100)
        print(f"TPDO2 event 1 ms, inhibit {args.inhibit * 0.1:.1f} ms: {len(t) / (t1 - t0):.1f} "
              f"frames/s (nominal {1 / period:.0f})")
        print(f"gaps ms: min {gaps[0] * 1e3:.3f}  p50 {q[49] * 1e3:.3f}  p99 {q[98] * 1e3:.3f}  "
              f"max {gaps[-1] * 1e3:.3f}")
        span = (all_t[-1] - all_t[0]) / 1e-3 + 1
        print(f"1 ms event periods first..last frame: {span:.0f}; frames {len(all_t)} + "
              f"missed (0x2070) {missed} = {len(all_t) + missed}")
        print("loadavg " + open("/proc/loadavg").read().strip())
    finally:
        drive.stop()
        net.disconnect()
        drive_bus.shutdown()


if __name__ == "__main__":
    main()
