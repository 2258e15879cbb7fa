"""Benchmark of the host library (drive_link): prints figures, asserts nothing.

    python benchmarks/bench_link.py                  # own loopback hub + `virtual-drive run` child
    python benchmarks/bench_link.py --host 127.0.0.1 --port 29536 --node 1   # any drive on a hub
    python benchmarks/bench_link.py --interface socketcan --channel can0     # a real bus

Figures: expedited SDO read latency (median / p99), trace upload throughput by SDO block
upload vs segmented upload, status-read latency while a block upload runs on the second SDO
channel, scan time, measured TPDO rates and bus load.
"""

from __future__ import annotations

import argparse
import contextlib
import statistics
import threading
import time

from drive_link import scan
from drive_link.cli.connect import add_bus_arguments, connect_from_args
from drive_link.errors import DriveError
from drive_link.link.drive import Drive
from virtual_drive.launch import virtual_bench


def _pct(xs: list[float], q: float) -> float:
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(q * len(xs)))]


def run(d: Drive, n_reads: int = 300) -> dict[str, float]:
    """Measure on an open drive; returns the figures (also printed)."""
    out: dict[str, float] = {}
    lat = []
    for _ in range(n_reads):
        t0 = time.perf_counter()
        d.read("statusword")
        lat.append((time.perf_counter() - t0) * 1e3)
    out["sdo_read_median_ms"] = statistics.median(lat)
    out["sdo_read_p99_ms"] = _pct(lat, 0.99)

    cap = int(d.read("trace_config.capacity"))
    d.trace.configure(["i_p"], divider=1, length=cap, trigger="immediate")
    d.trace.arm()
    d.trace.wait(10.0)
    lat2: list[float] = []
    stop = threading.Event()

    def status() -> None:
        while not stop.is_set():
            t0 = time.perf_counter()
            d.read("statusword")
            lat2.append((time.perf_counter() - t0) * 1e3)

    th = threading.Thread(target=status)
    th.start()
    t0 = time.perf_counter()
    try:
        raw = d.sdo_trace.upload_block(0x2102, 0)
    finally:
        dt = time.perf_counter() - t0
        stop.set()
        th.join()
    out["block_upload_bytes"] = len(raw)
    out["block_upload_kB_s"] = len(raw) / dt / 1e3
    out["status_read_during_upload_median_ms"] = statistics.median(lat2) if lat2 else float("nan")
    out["status_reads_during_upload"] = len(lat2)

    d.trace.configure(["i_p"], divider=1, length=2048, trigger="immediate")
    d.trace.arm()
    d.trace.wait(10.0)
    t0 = time.perf_counter()
    raw = d.sdo_trace.upload(0x2102, 0)
    out["segmented_upload_kB_s"] = len(raw) / (time.perf_counter() - t0) / 1e3

    t0 = time.perf_counter()
    nodes = scan(d.bus, timeout=0.2)
    out["scan_s"] = time.perf_counter() - t0
    out["scan_nodes"] = len(nodes)

    d.nmt("start")
    live = d.refresh_live()
    time.sleep(0.3)
    live.reset_counters()
    time.sleep(1.0)
    st = live.stats
    for name, s in st["tpdo"].items():
        out[f"{name}_hz"] = s["frames"] / 1.0
    out["bus_load_pct"] = 100 * (st.get("bus_load") or 0.0)
    for k, v in out.items():
        print(f"{k:>38}: {v:.4g}" if isinstance(v, float) else f"{k:>38}: {v}")
    return out


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``python benchmarks/bench_link.py``."""
    ap = argparse.ArgumentParser(allow_abbrev=False, prog="bench_link.py", description=__doc__)
    add_bus_arguments(ap)  # python-can's bus options, --host/--port, --node (as drive-link)
    ap.add_argument("--reads", type=int, default=300)
    ap.add_argument(
        "--drop-rates",
        default="",
        help="own hub only: frame-loss rates for a 32 KB upload test, e.g. 0.01,0.05",
    )
    ap.add_argument("--uploads", type=int, default=10, help="uploads per drop rate")
    args = ap.parse_args(argv)
    hub = None
    with contextlib.ExitStack() as stack:
        if args.interface is None and args.port is None:
            bench = stack.enter_context(virtual_bench(nodes=(args.node,)))
            hub = bench.hub
            args.host, args.port = bench["host"], bench.port
            print(f"virtual drive (child process) on loopback hub 127.0.0.1:{bench.port}, 1 Mbit/s")
        d = connect_from_args(args)
        stack.callback(d.close)
        run(d, args.reads)
        if hub is not None and args.drop_rates:
            lossy_uploads(d, hub, [float(x) for x in args.drop_rates.split(",")], args.uploads)
    return 0


def lossy_uploads(d: Drive, hub, rates: list[float], n: int) -> None:
    """Upload the same 32 KB trace ``n`` times per hub drop rate; print exact/wrong/failed."""
    hub.set_faults(drop_rate=0.0)
    d.trace.configure(["i_p", "speed"], divider=1, length=4000, trigger="immediate")
    d.trace.arm()
    d.trace.wait(10.0)
    ref = d.sdo_trace.upload_block(0x2102, 0)
    for rate in rates:
        hub.set_faults(drop_rate=rate)
        ok = wrong = failed = 0
        t0 = time.perf_counter()
        for _ in range(n):
            try:
                ok_now = d.sdo_trace.upload_block(0x2102, 0) == ref
                ok += ok_now
                wrong += not ok_now
            except DriveError:
                failed += 1
        dt = (time.perf_counter() - t0) / n
        print(
            f"  drop {rate:.3f}: {ok}/{n} exact, {wrong} wrong, {failed} failed, {dt:.2f} s/upload"
        )
    hub.set_faults(drop_rate=0.0)


if __name__ == "__main__":
    raise SystemExit(main())
