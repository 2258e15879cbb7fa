"""Benchmark: the host library under each bench condition; prints one row per condition.

    python benchmarks/bench_conditions.py                    # idle, busy, latency, loss1, loss5
    python benchmarks/bench_conditions.py --uploads 20 --only loss1,loss5
    BENCH_CONDITION=vcan0 python benchmarks/bench_conditions.py   # inside the SocketCAN lane

Conditions are those of the scenario matrix (``tests/scenarios/conditions.py``): a loopback hub
(2 ms ± 1 ms latency, 1 % / 5 % seeded frame loss) or SocketCAN ``vcan0``, a ``virtual-drive run``
child process, and for "busy" two CPU-bound processes per core for the whole row.

Columns: 64 KiB trace uploads (16,384 REAL32, SDO block upload on the trace channel) exact /
tries (each compared byte for byte with a reference upload made without faults), their median
throughput, expedited SDO read latency (statusword) median and 99th percentile, the TPDO2 rate
the host received over 2 s (the drive sends it at 1 kHz), and the 1-minute load average at the
end of the row. Prints figures; asserts nothing.
"""

from __future__ import annotations

import argparse
import inspect
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from scenarios.conditions import CONDITIONS, Condition, bench, loadavg, selected

from drive_link import DriveError


def _pct(xs: list[float], q: float) -> float:
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(q * len(xs)))] if xs else float("nan")


def _hub_faults(hub, **faults: float) -> None:
    """hub.set_faults with the keywords this hub version knows (no-op without a hub)."""
    if hub is None:
        return
    known = inspect.signature(hub.set_faults).parameters
    hub.set_faults(**{k: v for k, v in faults.items() if k in known})


def measure(cond: Condition, uploads: int, reads: int) -> dict:
    """Run one condition; returns the row's figures."""
    row: dict = {"condition": cond.name}
    with bench(cond, hub_in_process=True) as b:  # in-process: faults off for the reference
        row["cpu"] = b.hog.tool if b.hog else ""
        d = b.connect()
        try:
            d.nmt("start")
            lat = []
            for _ in range(reads):
                t0 = time.perf_counter()
                d.read("statusword")
                lat.append((time.perf_counter() - t0) * 1e3)
            row["sdo_p50_ms"] = statistics.median(lat)
            row["sdo_p99_ms"] = _pct(lat, 0.99)

            live = d.refresh_live()
            time.sleep(0.3)
            live.reset_counters()
            time.sleep(2.0)
            tpdo = live.stats["tpdo"]
            row["tpdo2_hz"] = tpdo["TPDO2"]["frames"] / 2.0 if "TPDO2" in tpdo else float("nan")

            cap = d.trace.capacity
            d.trace.configure(["i_p"], divider=1, length=cap, trigger="immediate")
            d.trace.arm()
            d.trace.wait(10.0 * cond.slow)
            _hub_faults(b.hub, drop_rate=0.0, delay_s=0.0, jitter_s=0.0)  # reference: no faults
            ref = d.sdo_trace.upload_block(0x2102, 0, "trace_data")
            _hub_faults(b.hub, **b.hub_faults)
            exact = wrong = 0
            rates: list[float] = []
            errors: list[str] = []
            for _ in range(uploads):
                t0 = time.perf_counter()
                try:
                    raw = d.sdo_trace.upload_block(0x2102, 0, "trace_data")
                except DriveError as exc:
                    errors.append(str(exc))
                    continue
                dt = time.perf_counter() - t0
                if raw == ref:
                    exact += 1
                    rates.append(len(raw) / dt / 1e3)
                else:
                    wrong += 1
            row["uploads"] = f"{exact}/{uploads}" + (f" ({wrong} WRONG)" if wrong else "")
            row["kB_s"] = statistics.median(rates) if rates else float("nan")
            row["errors"] = errors
        finally:
            d.close()
        row["load"] = loadavg().split()[0]
    return row


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.split("\n\n")[0])
    ap.add_argument("--uploads", type=int, default=10, help="64 KiB uploads per condition")
    ap.add_argument("--reads", type=int, default=300, help="SDO reads per condition")
    ap.add_argument("--only", default="", help="comma-separated conditions")
    args = ap.parse_args(argv)
    conds = [CONDITIONS[n] for n in args.only.split(",")] if args.only else selected()
    print(f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, load average {loadavg()}")
    head = "| condition | 64 KiB uploads exact | upload kB/s (median) | SDO read p50 / p99 ms "
    print(head + "| TPDO2 Hz | load (1 min) |")
    print("|---|---|---|---|---|---|")
    notes = []
    for c in conds:
        try:
            r = measure(c, args.uploads, args.reads)
        except Exception as exc:  # one row per condition, even if the bench fails
            print(f"| {c.name} | bench failed: {type(exc).__name__}: {exc} | | | | {loadavg()} |")
            continue
        name = c.name + (f" ({r['cpu']})" if r["cpu"] else "")
        print(
            f"| {name} | {r['uploads']} | {r['kB_s']:.1f} | "
            f"{r['sdo_p50_ms']:.2f} / {r['sdo_p99_ms']:.2f} | {r['tpdo2_hz']:.0f} | {r['load']} |",
            flush=True,
        )
        notes += [f"{c.name}: {e}" for e in r["errors"]]
    if "vcan0" not in [c.name for c in conds]:
        print("(vcan0: run with BENCH_CONDITION=vcan0 inside the SocketCAN lane)")
    for n in notes:
        print("failed upload:", n)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
