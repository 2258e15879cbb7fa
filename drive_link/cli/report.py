"""``drive-link report``: run the paper's experiments on the connected drive, with a progress
bar (stderr) and Ctrl-C (the drive is put back as found), and write report.json and
report.html (:mod:`drive_link.workflows.report`). Exit 0 when no experiment failed, 1 otherwise."""

from __future__ import annotations

import argparse
import json
import sys
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ..link.drive import Drive

__all__ = ["add_parser", "cmd_report"]


def add_parser(sub: argparse._SubParsersAction, bus: argparse.ArgumentParser) -> None:
    """Add the ``report`` command to ``sub`` (``bus``: the parent with the bus options)."""
    from ..workflows.report_ids import EXPERIMENT_IDS

    help = ("commissioning report: the paper's experiments on the connected drive (each leaves "
            "the drive as found), written as one offline report.html and report.json")
    p = sub.add_parser("report", parents=[bus], help=help, description=help)
    p.set_defaults(func=cmd_report, needs_drive=True)
    p.add_argument("--out", default="report", metavar="DIR",
                   help="directory for report.html and report.json (default ./report)")
    p.add_argument("--only", default=None,
                   help="comma-separated experiments (default all): " + ", ".join(EXPERIMENT_IDS))
    p.add_argument("--progress", action="store_true",
                   help="progress bar even when stderr is not a terminal")


def cmd_report(args: argparse.Namespace, d: Drive) -> int:
    from ..workflows.report import run_report, select
    from ..workflows.steps import Hooks

    only = [s.strip() for s in args.only.split(",")] if args.only else None
    select(only)  # unknown names: one line, exit 7, nothing run
    show = not args.json and (sys.stderr.isatty() or args.progress)
    bar: list[Any] = []

    def progress(f: float, text: str) -> None:
        if not show:
            return
        if not bar:
            from tqdm import tqdm

            bar.append(tqdm(total=1000, file=sys.stderr, ascii=" #", mininterval=0.2,
                            bar_format="{l_bar}{bar:30}| {elapsed}"))
        b = bar[0]
        b.set_description_str(text[:60], refresh=False)
        b.update(max(0, int(f * 1000) - b.n))

    def say(text: str) -> None:
        if not args.json:
            print(text, flush=True)

    try:
        rep = run_report(d, only, Hooks(progress=progress, say=say))
    finally:
        if bar:
            bar[0].close()
    js, html = rep.write(args.out)
    failed = [r.id for r in rep.results if r.verdict == "fail"]
    if args.json:
        print(json.dumps({**rep.as_dict(), "files": [str(js), str(html)]}))
    else:
        for r in rep.results:
            print(f"{r.verdict.upper():<15} {r.id:<24} {r.seconds:5.1f} s  {r.reason}")
        load = rep.drive["load_1min"]
        print(f"{len(rep.results) - len(failed)}/{len(rep.results)} not failed in "
              f"{rep.drive['seconds']} s (load {load[0]} → {load[1]}, {rep.drive['cpus']} CPUs)"
              f"; wrote {html} and {js}")
    return 1 if failed else 0
