"""Print what starting the product's processes costs: ``python benchmarks/bench_start.py``.

Figures (CPU time of the child, user + system, mean of ``--runs``; load average beside them):
``drive-link --help`` (interpreter, imports, the OD and the parser), and ``virtual-drive --hub``
from start to its ready line, then SIGINT (what each virtual drive a test or a dashboard starts
costs before it does anything), and ``drive-dashboard --virtual`` (its virtual drive child
included) until its API answers, then SIGINT. The environment is this one's: run it once as
it is and once with ``OPENBLAS_NUM_THREADS=1`` to see numpy's OpenBLAS thread pool, and before
and after ``python -m compileall drive_link virtual_drive firmware_protocol`` where
``PYTHONDONTWRITEBYTECODE`` is set.
"""

from __future__ import annotations

import argparse
import os
import resource
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

__all__ = ["main"]

BIN = Path(sys.executable).parent


def _child_cpu() -> float:
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def help_cost() -> float:
    """CPU s of one ``drive-link --help``."""
    before = _child_cpu()
    subprocess.run([str(BIN / "drive-link"), "--help"], stdout=subprocess.DEVNULL, check=True)
    return _child_cpu() - before


def drive_start_cost(timeout: float = 60.0) -> tuple[float, float]:
    """(CPU s, wall s to the ready line) of one ``virtual-drive --hub --hub-port 0``."""
    before, t0 = _child_cpu(), time.monotonic()
    cmd = [str(BIN / "virtual-drive"), "--hub", "--hub-port", "0"]
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    assert p.stdout is not None  # (stdout=PIPE)
    ready = None
    deadline = t0 + timeout
    for line in p.stdout:
        if "ready" in line:
            ready = time.monotonic() - t0
            break
        if time.monotonic() > deadline:
            break
    p.send_signal(signal.SIGINT)
    p.communicate(timeout=timeout)
    if ready is None:
        raise SystemExit("bench_start.py: virtual-drive printed no ready line")
    return _child_cpu() - before, ready


def dashboard_start_cost(timeout: float = 120.0) -> tuple[float, float]:
    """(CPU s, wall s until ``/api/state`` answers) of one ``drive-dashboard --virtual``, its
    virtual drive child included, stopped by SIGINT (Ctrl-C) once its API answered."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    before, t0 = _child_cpu(), time.monotonic()
    cmd = [str(BIN / "drive-dashboard"), "--virtual", "--port", str(port), "--gui-port", "0"]
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    ready = None
    while ready is None and time.monotonic() < t0 + timeout and p.poll() is None:
        try:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/api/state", timeout=5) as r:
                if r.status == 200:
                    ready = time.monotonic() - t0
        except OSError:
            time.sleep(0.05)
    p.send_signal(signal.SIGINT)
    p.wait(timeout=timeout)
    if ready is None:
        raise SystemExit("bench_start.py: drive-dashboard's API never answered")
    return _child_cpu() - before, ready


def main(argv: list[str] | None = None) -> None:
    """Run the benchmarks and print one line per figure (``--help``: only the usage)."""
    ap = argparse.ArgumentParser(
        prog="bench_start.py", description=__doc__.splitlines()[0], allow_abbrev=False
    )
    ap.add_argument("--runs", type=int, default=5, help="starts per figure (default 5)")
    args = ap.parse_args(argv)
    if args.runs < 1:
        ap.error(f"--runs must be at least 1, got {args.runs}")
    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    blas = os.environ.get("OPENBLAS_NUM_THREADS", "unset")
    print(f"process start (load average {load}; OPENBLAS_NUM_THREADS {blas})")
    helps = [help_cost() for _ in range(args.runs)]
    print(f"  drive-link --help                 {sum(helps) / len(helps):6.3f} CPU-s")
    starts = [drive_start_cost() for _ in range(args.runs)]
    cpu = sum(c for c, _ in starts) / len(starts)
    wall = sum(w for _, w in starts) / len(starts)
    print(f"  virtual-drive start to ready      {cpu:6.3f} CPU-s ({wall:.2f} s)")
    dashes = [dashboard_start_cost() for _ in range(args.runs)]
    cpu = sum(c for c, _ in dashes) / len(dashes)
    wall = sum(w for _, w in dashes) / len(dashes)
    print(f"  drive-dashboard --virtual to API  {cpu:6.3f} CPU-s ({wall:.2f} s)")


if __name__ == "__main__":
    main()
