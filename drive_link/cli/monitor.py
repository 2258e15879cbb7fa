"""``drive-link monitor``: the raw bus as a live table per CAN-ID with its CANopen meaning
(:class:`drive_link.link.monitor.BusTable`), on a terminal or printed once."""

from __future__ import annotations

import argparse
import sys
import time
from typing import Any

import can

from ..errors import InvalidValue
from ..link.monitor import BusTable, IdFilter, TableFeed, parse_ids, render
from ._common import _emit
from .tools import bus_settings

__all__ = ["add_parsers", "cmd_monitor"]


def cmd_monitor(args: argparse.Namespace) -> int:
    """``drive-link monitor [--show-nodes 1,2] [--ids 0x181,0x700-0x77F] [--seconds S]``."""
    from ..link.bus import open_bus

    nodes = None
    if args.nodes:
        nodes = set()
        for part in args.nodes.split(","):
            try:
                nodes.add(int(part, 0))
            except ValueError:
                raise InvalidValue(f"--show-nodes {args.nodes!r}: node-IDs like 1,2") from None
    keep = IdFilter(nodes, parse_ids(args.ids) if args.ids else None)
    if args.seconds is not None and not 0 < args.seconds < 1e7:
        raise InvalidValue(f"--seconds {args.seconds}: must be a number of seconds > 0")
    interactive = args.seconds is None and sys.stdout.isatty() and not args.json
    seconds = args.seconds if args.seconds is not None else (None if interactive else 2.0)
    settings = {k: v for k, v in bus_settings(args).items() if k != "node"}
    bus = open_bus(**settings)
    table = BusTable(keep=keep)
    notifier = can.Notifier(bus, [TableFeed(table)], timeout=0.1)
    cpu0, t0 = time.process_time(), time.monotonic()
    try:
        if interactive:
            _curses(table)
        else:
            time.sleep(seconds or 0)
    except KeyboardInterrupt:
        pass
    finally:
        notifier.stop(1.0)
        bus.shutdown()
    wall = time.monotonic() - t0
    rows = table.rows()
    out = {
        "frames": table.frames,
        "seconds": round(wall, 3),
        "cpu_percent": round(100 * (time.process_time() - cpu0) / max(wall, 1e-9), 1),
        "rows": rows,
    }
    if interactive:
        return 0
    _emit(args, out, lambda: "\n".join(render(rows, 200)))
    return 0


def _curses(table: BusTable) -> None:  # pragma: no cover - needs a terminal
    import curses

    def loop(scr: Any) -> None:
        curses.curs_set(0)
        scr.nodelay(True)
        while True:
            key = scr.getch()
            if key in (ord("q"), 27):
                return
            if key in (ord("p"), ord(" ")):
                table.pause()
            h, w = scr.getmaxyx()
            lines = render(table.rows(time.time()), w - 1, table.paused)
            lines.append("p/space pause, q quit")
            scr.erase()
            for y, line in enumerate(lines[: h - 1]):
                scr.addnstr(y, 0, line, w - 1)
            scr.refresh()
            time.sleep(0.25)

    curses.wrapper(loop)


def add_parsers(sub: argparse._SubParsersAction, bus: argparse.ArgumentParser) -> None:
    """Register ``monitor`` (``bus``: the parent parser with the bus options)."""
    text = (
        "the raw bus as a live table per CAN-ID (count, rate, age, data) with its CANopen "
        "meaning from the EDS; p pauses, q quits"
    )
    p = sub.add_parser("monitor", parents=[bus], help=text, description=text)
    p.set_defaults(func=cmd_monitor, needs_drive=False)
    p.add_argument(
        "--show-nodes", dest="nodes", default=None, metavar="IDS", help="only these nodes, e.g. 1,2"
    )
    p.add_argument(
        "--ids", default=None, metavar="IDS", help="only these CAN-IDs, e.g. 0x181,0x700-0x77F"
    )
    p.add_argument(
        "--seconds", type=float, default=None, metavar="S",
        help="watch S s, then print the table once (default without a terminal: 2 s)",
    )  # fmt: skip
