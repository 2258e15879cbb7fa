"""``drive-link config save|load|diff FILE.dcf``: the drive's configuration as a CiA 306 DCF
(:mod:`drive_link.workflows.config_dcf`)."""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

from ..link.drive import Drive
from ._common import AddCommand, _emit

__all__ = ["add_parsers"]


def cmd_config(args: argparse.Namespace, d: Drive) -> int:
    from ..workflows import config_dcf

    if args.action == "save":
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", UserWarning)
            out = config_dcf.save(d, args.file, bitrate=args.bitrate)
        notes = [str(w.message) for w in caught]
        if args.json:
            out["warnings"] = notes
        for note in [] if args.json else notes:
            print(f"warning: {note}", file=sys.stderr)
        msg = f"saved {out['objects']} objects of node {out['node_id']} to {out['file']}"
        _emit(args, out, msg)
        return 0
    if args.action == "diff":
        res = config_dcf.diff(d, args.file)
        out = res.as_dict()

        def text() -> str:
            lines = [
                f"{c.name} ({c.index}): drive {c.drive:g}, file {c.file:g} {c.unit}".rstrip()
                for c in res.changes
            ]
            lines.append(f"{len(res.changes)} differ, {res.same} equal")
            return "\n".join(lines)

        _emit(args, out, text)
        return 0
    out = config_dcf.load(d, args.file, dry_run=args.dry_run, force=args.force)
    n = len(out["changes"])
    verb = "would write" if args.dry_run else "wrote"
    _emit(
        args,
        out,
        lambda: "\n".join(
            [
                f"{c['name']}: {c['drive']:g} -> {c['file']:g} {c['unit']}".rstrip()
                for c in out["changes"]
            ]
            + [f"{verb} {n} object{'s' if n != 1 else ''} (the others are equal)"]
        ),
    )
    return 0


def add_parsers(add: AddCommand) -> None:
    """``config save|load|diff FILE.dcf``."""
    p = add(
        "config",
        cmd_config,
        "the drive's configuration (motor, protection, gains, CiA 402 settings) as a CiA 306 "
        "DCF file: save, diff, load (checked first, all or nothing)",
    )
    p.add_argument("action", choices=["save", "load", "diff"], help="save / load / diff")
    p.add_argument("file", type=Path, metavar="FILE.dcf", help="the DCF file")
    p.add_argument(
        "--dry-run", action="store_true", help="load: check and show the changes, write nothing"
    )
    p.add_argument(
        "--force",
        action="store_true",
        help="load: apply a gain set with poor stability margins (an unstable one never)",
    )
