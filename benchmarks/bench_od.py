"""Print timing figures of the OD view: ``python benchmarks/bench_od.py``.

Figures: EDS parse (uncached), ``canopen_od()`` build, ``Entry.check`` and
``check_constraints`` per call (both run on every SDO write by the drive and before every host
write), header + Markdown rendering. Wall-clock, best of several repeats, on this machine; the
load average (/proc/loadavg) is printed beside them.
"""

from __future__ import annotations

import argparse
import os
import time
import timeit
from collections.abc import Callable

from firmware_protocol.generate import render_header, render_markdown
from firmware_protocol.od import EDS_PATH, _load_cached, load_od  # _load_cached: the uncached parse

__all__ = ["main"]


def _best(fn: Callable[[], object], number: int, repeat: int = 5) -> float:
    """Best time per call in seconds."""
    return min(timeit.repeat(fn, number=number, repeat=repeat)) / number


def main(argv: list[str] | None = None) -> None:
    """Run the benchmarks and print one line per figure (``--help``: only the usage)."""
    argparse.ArgumentParser(
        prog="bench_od.py", description=__doc__.splitlines()[0], allow_abbrev=False
    ).parse_args(argv)
    stat = EDS_PATH.stat()
    parse = _best(
        lambda: _load_cached.__wrapped__(
            EDS_PATH.resolve(), 1, stat.st_ino, stat.st_mtime_ns, stat.st_size
        ),
        number=3,
    )
    view = load_od()
    entry = view.entry("current_controller.L_c")
    enum_entry = view.entry("modes_of_operation")
    rows = [
        ("load_od() uncached parse of the EDS", parse, "ms", 1e3),
        ("load_od() cached", _best(load_od, number=10000), "us", 1e6),
        ("view.canopen_od() fresh dictionary", _best(view.canopen_od, number=3), "ms", 1e3),
        ("Entry.check(REAL32)", _best(lambda: entry.check(20e-6), number=20000), "us", 1e6),
        ("Entry.check(enumerated I8)", _best(lambda: enum_entry.check(3), number=20000), "us", 1e6),
        (
            "view.check_constraints({L_c})",
            _best(lambda: view.check_constraints({"current_controller.L_c": 20e-6}), number=5000),
            "us",
            1e6,
        ),
        ("render_header()", _best(lambda: render_header(view), number=3), "ms", 1e3),
        ("render_markdown()", _best(lambda: render_markdown(view), number=3), "ms", 1e3),
    ]
    load = " ".join(f"{x:.2f}" for x in os.getloadavg())
    print(
        f"firmware_protocol benchmark ({len(view)} entries, {time.strftime('%Y-%m-%d')}, "
        f"load average {load})"
    )
    for label, seconds, unit, scale in rows:
        print(f"  {label:<40} {seconds * scale:8.2f} {unit}")


if __name__ == "__main__":
    main()
