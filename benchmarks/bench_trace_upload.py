"""Trace upload speed: 64 KiB of 0x2102 trace_data over the loopback hub at an emulated
1 Mbit/s, SDO block upload (canopen's own block client) vs segmented upload.

Three processes, as on a bench: the hub (``virtual-drive hub``), the drive
(``virtual-drive run``) and this script as the CANopen master.

    python benchmarks/bench_trace_upload.py [--repeat 3] [--no-segmented]

Physical limit of CAN 2.0A at 1 Mbit/s for block transfer: 51–63 kB/s (111–135 bits per
8-byte frame, 7 data bytes each). Goal: block upload >= 45 kB/s. kB = 1000 bytes.

Reliability mode (``--tries N``): N uploads through a hub with frame loss and latency jitter,
printing successes / tries, kB/s (median, p10, p90), restarts, and the load average before and
after, e.g.

    python benchmarks/bench_trace_upload.py --drop 0.01 --delay-ms 2 --jitter-ms 1 --tries 100
    python benchmarks/bench_trace_upload.py --client canopen --tries 20

``--client drive_link`` (default) uploads with ``Drive.sdo_trace.upload_block`` (resends,
restarts); ``--client canopen`` with canopen 2.4.1's stock block client
(``node.sdo.open(..., block_transfer=True)``, RESPONSE_TIMEOUT 2 s). Every upload is compared
byte for byte with a reference read first (its CRC-16 computed by the drive, checked by the
client).
"""

from __future__ import annotations

import argparse
import binascii
import queue
import re
import signal
import struct
import subprocess
import sys
import time
from collections.abc import Sequence

import can
import canopen
from canopen.sdo.exceptions import SdoError

from firmware_protocol import load_od
from virtual_drive.node import spawn_virtual_drive

SIZE = 65536


def start_hub(bitrate: int, faults: Sequence[str] = ()) -> tuple[subprocess.Popen, int]:
    proc = subprocess.Popen(
        [sys.executable, "-m", "virtual_drive.cli", "hub", "--port", "0",
         "--bitrate", str(bitrate), *faults],
        stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
    )  # fmt: skip
    line = proc.stdout.readline()
    m = re.search(r"port=(\d+)", line)
    if not m:
        proc.kill()
        raise SystemExit(f"hub did not start: {line!r}")
    return proc, int(m.group(1))


def capture_64k(node: canopen.RemoteNode) -> None:
    """4 channels x 4096 samples x 4 bytes = 64 KiB, immediate trigger."""
    tc = node.sdo[0x2100]
    tc[4].raw = 0
    tc[3].raw = 1
    tc[1].raw = 4
    for k, sub in enumerate((1, 10, 5, 6), 1):  # i_p, i_p_ref, speed, v_L
        node.sdo[0x2101][k].raw = (0x2040 << 16) | (sub << 8) | 32
    tc[3].raw = 4096
    tc[8].raw = 0
    tc[9].raw = 1
    deadline = time.monotonic() + 5
    while tc[10].raw != 3:
        if time.monotonic() > deadline:
            raise SystemExit("trace did not complete")
        time.sleep(0.01)


def lean_block_upload(net: canopen.Network, node_id: int = 1) -> tuple[bytes, float, float]:
    """Block upload with a minimal client written here from CiA 301 (CRC checked).

    canopen's client spends Python time per segment; this one shows what the drive and the
    bus allow. Returns (data, seconds, median ack->next-segment reaction in s).
    """
    q: queue.Queue = queue.Queue()
    rx, tx = 0x600 + node_id, 0x580 + node_id
    net.subscribe(tx, lambda c, d, ts: q.put((time.perf_counter(), bytes(d))))

    def send(*b: int) -> None:
        net.send_message(rx, bytes(b).ljust(8, b"\0"))

    try:
        t0 = time.perf_counter()
        net.send_message(rx, bytes([0xA4]) + struct.pack("<HB", 0x2102, 0) + bytes([127, 0, 0, 0]))
        _, resp = q.get(timeout=2)
        size = struct.unpack_from("<I", resp, 4)[0]
        send(0xA3)
        chunks: list[bytes] = []
        reactions = []
        t_ack = None
        while True:
            first = True
            while True:
                t, d = q.get(timeout=2)
                if first and t_ack is not None:
                    reactions.append(t - t_ack)
                first = False
                chunks.append(d[1:])
                if d[0] & 0x80 or d[0] & 0x7F == 127:
                    break
            t_ack = time.perf_counter()
            send(0xA2, d[0] & 0x7F, 127)
            if d[0] & 0x80:
                break
        _, end = q.get(timeout=2)
        send(0xA1)
        dt = time.perf_counter() - t0
        unused = (end[0] >> 2) & 7
        data = b"".join(chunks)
        data = data[: len(data) - unused]
        if len(data) != size or struct.unpack_from("<H", end, 1)[0] != binascii.crc_hqx(data, 0):
            raise SystemExit("lean block upload: size or CRC mismatch")
        return data, dt, sorted(reactions)[len(reactions) // 2]
    finally:
        net.unsubscribe(tx)
        node_sdo = net.get(node_id)
        if node_sdo is not None:  # give the canopen client its responses back
            net.subscribe(tx, node_sdo.sdo.on_response)


def loadavg() -> str:
    """The 1-minute load average of this machine (text)."""
    try:
        return open("/proc/loadavg").read().split()[0]
    except OSError:
        return "?"


def _pct(values: list[float], q: float) -> float:
    v = sorted(values)
    return v[min(len(v) - 1, int(q * len(v)))]


def reliability(args: argparse.Namespace) -> int:
    """``--tries`` uploads through a lossy, jittery hub; prints one line per try and a summary."""
    from drive_link import Drive, DriveError
    from drive_link.link._sdo_block import last_stats

    faults = ["--drop", str(args.drop), "--delay-ms", str(args.delay_ms),
              "--jitter-ms", str(args.jitter_ms), "--seed", str(args.seed)]  # fmt: skip
    load0 = loadavg()
    hub, port = start_hub(args.bitrate, faults)
    drive = None
    d = None
    node = None
    try:
        drive = spawn_virtual_drive(port=port, timeout=60.0)
        d = Drive.connect(host="127.0.0.1", port=port, node_id=1, heartbeat_ms=None)
        # V_dc: non-zero data (CRC-16 of zero bytes is 0 at any length)
        d.trace.configure(["V_dc", "i_p", "speed", "theta_e"], length=4096, trigger="immediate")
        d.trace.arm()
        d.trace.wait(60.0)
        # the reference: one block upload whose CRC-16 the drive computed and the client
        # checked (a segmented reference would take minutes on a lossy link)
        ref = d.sdo_trace.upload_block(0x2102, 0, name="trace_data")
        assert len(ref) == SIZE, len(ref)
        node = None
        restarts0 = d.sdo_trace.restarted
        if args.client == "canopen":
            # the stock client alone on its own connection: drive_link's session (its
            # supervisor reads the drive over SDO now and then) would share the SDO channel
            d.close()
            d = None
            net = canopen.Network(
                can.Bus(interface="socketcand", host="127.0.0.1", port=port, channel="vcan0",
                        tcp_tune=True)
            )  # fmt: skip
            net.connect()
            node = canopen.RemoteNode(1, load_od().canopen_od(1))
            node.sdo.RESPONSE_TIMEOUT = 2.0
            net.add_node(node)
        print(
            f"{args.client}: {SIZE} bytes of trace_data, hub {args.bitrate / 1e6:g} Mbit/s, "
            f"drop {args.drop:g}, delay {args.delay_ms:g} ± {args.jitter_ms:g} ms, "
            f"load {load0}",
            flush=True,
        )
        ok, rates, failures = 0, [], {}
        for k in range(args.tries):
            r0 = d.sdo_trace.restarted if d is not None else 0

            def restarted(r0: int = r0) -> str:
                n = d.sdo_trace.restarted - r0 if d is not None else 0
                return f" restarted {n}x: {d.sdo_trace.restart_reasons[-n:]}" if n else ""

            t0 = time.perf_counter()
            try:
                if node is not None:
                    with node.sdo.open(0x2102, 0, "rb", block_transfer=True) as f:
                        data = f.read()
                else:
                    data = d.sdo_trace.upload_block(0x2102, 0, name="trace_data")
                dt = time.perf_counter() - t0
                if data != ref:  # must never happen: counted and shown
                    raise ValueError(f"WRONG DATA accepted ({len(data)} bytes)")
                ok += 1
                rates.append(SIZE / dt / 1000)
                note = "" if node is not None else f" {dict(last_stats)}{restarted()}"
                print(f"try {k + 1}: ok {dt:.2f} s {SIZE / dt / 1000:.1f} kB/s{note}", flush=True)
            except (DriveError, SdoError, AttributeError, ValueError) as exc:
                dt = time.perf_counter() - t0
                reason = str(exc).splitlines()[0][:120]
                failures[reason] = failures.get(reason, 0) + 1
                print(f"try {k + 1}: FAILED after {dt:.2f} s: {reason}{restarted()}", flush=True)
        restarts = d.sdo_trace.restarted - restarts0 if d is not None else 0
        rate = (
            f"median {_pct(rates, 0.5):.1f} kB/s, p10 {_pct(rates, 0.1):.1f}, "
            f"p90 {_pct(rates, 0.9):.1f}"
            if rates
            else "no upload completed"
        )
        print(
            f"RESULT {args.client} drop={args.drop:g} jitter={args.delay_ms:g}±"
            f"{args.jitter_ms:g}ms: {ok}/{args.tries} complete, {rate}, "
            f"{restarts} restarts, load {load0} -> {loadavg()}"
        )
        for reason, n in failures.items():
            print(f"  {n} x {reason}")
        return 0 if ok == args.tries else 1
    finally:
        if d is not None:
            d.close()
        if node is not None:
            node.network.disconnect()
        if drive is not None:
            drive.stop()
        hub.send_signal(signal.SIGTERM)
        hub.wait(10)


def main() -> int:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3, help="block uploads to time")
    ap.add_argument("--bitrate", type=int, default=1_000_000, help="emulated bit rate (bit/s)")
    ap.add_argument("--no-segmented", action="store_true", help="skip the slow segmented run")
    ap.add_argument("--tries", type=int, default=0, help="reliability mode: uploads to try")
    ap.add_argument("--drop", type=float, default=0.0, help="hub frame-loss probability 0..1")
    ap.add_argument("--delay-ms", type=float, default=0.0, help="hub delivery delay, ms")
    ap.add_argument("--jitter-ms", type=float, default=0.0, help="± jitter of that delay, ms")
    ap.add_argument("--seed", type=int, default=1, help="seed of the hub's loss and jitter")
    ap.add_argument(
        "--client", choices=("drive_link", "canopen"), default="drive_link",
        help="block upload client for --tries",
    )  # fmt: skip
    args = ap.parse_args()
    if args.tries:
        return reliability(args)

    hub, port = start_hub(args.bitrate)
    drive = None
    net = None
    try:
        drive = spawn_virtual_drive(port=port)
        bus = can.Bus(
            interface="socketcand", host="127.0.0.1", port=port, channel="vcan0", tcp_tune=True
        )
        net = canopen.Network(bus)
        net.connect()
        node = canopen.RemoteNode(1, load_od().canopen_od(1))
        net.add_node(node)
        node.sdo.RESPONSE_TIMEOUT = 2.0
        capture_64k(node)
        print(f"hub at {args.bitrate / 1e6:g} Mbit/s, {SIZE} bytes of trace_data (0x2102)")
        rates = []
        for k in range(args.repeat):
            t0 = time.perf_counter()
            with node.sdo.open(0x2102, 0, "rb", block_transfer=True) as f:
                data = f.read()
            dt = time.perf_counter() - t0
            assert len(data) == SIZE, len(data)
            rates.append(SIZE / dt / 1000)
            print(f"block upload {k + 1}: {dt:.3f} s, {SIZE / dt / 1000:.1f} kB/s")
        print(
            f"block upload (canopen client): best {max(rates):.1f} kB/s, median "
            f"{sorted(rates)[len(rates) // 2]:.1f} kB/s (goal >= 45, limit 51-63)"
        )
        lean = []
        for _ in range(args.repeat):
            data_l, dt, react = lean_block_upload(net)
            assert data_l == data
            lean.append(SIZE / dt / 1000)
            print(
                f"block upload (lean client): {dt:.3f} s, {SIZE / dt / 1000:.1f} kB/s, "
                f"median ack->next sub-block {react * 1e3:.2f} ms"
            )
        print(
            f"block upload (lean client): best {max(lean):.1f} kB/s, median "
            f"{sorted(lean)[len(lean) // 2]:.1f} kB/s"
        )
        if not args.no_segmented:
            t0 = time.perf_counter()
            data2 = node.sdo.upload(0x2102, 0)
            dt = time.perf_counter() - t0
            assert data2 == data
            print(f"segmented upload: {dt:.3f} s, {SIZE / dt / 1000:.1f} kB/s")
        return 0
    finally:
        if net is not None:
            net.disconnect()
        if drive is not None:
            drive.stop()
        hub.send_signal(signal.SIGTERM)
        hub.wait(10)


if __name__ == "__main__":
    sys.exit(main())
