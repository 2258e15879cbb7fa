"""64 KiB trace uploads with drive_link on a real kernel SocketCAN vcan0 inside User-Mode Linux.

    python benchmarks/bench_socketcan_uml.py [--uploads 10] [--timeout 900]

Boots UML with tests/uml/runner.py and, inside, starts ``virtual-drive run --interface socketcan
--channel vcan0``, records one full trace (2 channels × 8,192 REAL32 = 64 KiB) and uploads it
``--uploads`` times with ``Drive.trace.upload`` (SDO block upload on the drive's second SDO
server). An upload counts as a success only if its bytes equal the first complete upload's
(the recorder's buffer does not change between uploads). The drive stays PRE-OPERATIONAL (no
PDOs). Prints one line per upload and a summary with the host's load average before and after.
UML spends about 38 µs per system call: its rates say nothing about a real machine's.
"""

from __future__ import annotations

import argparse
import importlib.util
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def inside(uploads: int) -> int:
    import os
    import subprocess

    from drive_link import Drive

    env = {**os.environ, "VIRTUAL_DRIVE_PARENT_PID": str(os.getpid())}
    vd = subprocess.Popen(
        [sys.executable, "-m", "virtual_drive.cli", "run", "--interface", "socketcan",
         "--channel", "vcan0"],
        stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, env=env,
    )  # fmt: skip
    try:
        assert vd.stdout is not None
        line = vd.stdout.readline()
        if "ready" not in line:
            print(f"virtual drive did not start: {line!r}")
            return 1
        with Drive.connect(interface="socketcan", channel="vcan0", node_id=1) as d:
            from drive_link.link import _sdo_block as sdo_block

            d.trace.configure(["i_p", "speed"], divider=1, length=8192)
            d.trace.arm()
            d.trace.wait(60)
            first: bytes | None = None
            ok, rates = 0, []
            for k in range(1, uploads + 1):
                t0 = time.monotonic()
                try:
                    tr = d.trace.upload()
                except Exception as exc:  # every failure is one line of drive_link's
                    print(f"upload {k}: FAILED after {time.monotonic() - t0:.1f} s: {exc} "
                          f"{sdo_block.last_stats}", flush=True)  # fmt: skip
                    continue
                dt = time.monotonic() - t0
                raw = b"".join(v.tobytes() for v in tr.signals.values())
                first = first or raw
                same = raw == first and len(raw) == 65536
                ok += same
                rates.append(65536 / dt / 1000)
                print(f"upload {k}: {dt:.1f} s, {65536 / dt / 1000:.2f} kB/s, "
                      f"{'exact' if same else 'DIFFERENT DATA'} {sdo_block.last_stats}",
                      flush=True)  # fmt: skip
            med = statistics.median(rates) if rates else float("nan")
            print(f"RESULT {ok}/{uploads} exact 64 KiB uploads, median {med:.2f} kB/s "
                  f"(UML load {Path('/proc/loadavg').read_text().split()[0]})")  # fmt: skip
            return 0 if ok == uploads else 1
    finally:
        vd.terminate()
        vd.wait(30)


def main() -> int:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.split("\n\n")[0])
    ap.add_argument("--uploads", type=int, default=10)
    ap.add_argument("--timeout", type=float, default=900.0, help="wall-time limit of UML, s")
    ap.add_argument("--inside", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.inside:
        return inside(args.uploads)
    spec = importlib.util.spec_from_file_location("uml_runner", ROOT / "tests/uml/runner.py")
    assert spec and spec.loader
    uml = sys.modules.setdefault("uml_runner", importlib.util.module_from_spec(spec))
    spec.loader.exec_module(uml)
    load0 = Path("/proc/loadavg").read_text().split()[:3]
    res = uml.run_in_uml(
        [sys.executable, str(Path(__file__).resolve()), "--inside", "--uploads", str(args.uploads)],
        timeout=args.timeout,
    )
    load1 = Path("/proc/loadavg").read_text().split()[:3]
    print(res.output, end="")
    if res.problem:
        print(f"bench_socketcan_uml: {res.problem}")
        return 3
    print(f"UML run {res.seconds:.0f} s; host load average before {' '.join(load0)}, "
          f"after {' '.join(load1)}")  # fmt: skip
    return int(res.rc or 0)


if __name__ == "__main__":
    sys.exit(main())
