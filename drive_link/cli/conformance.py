"""``drive-link check``: the conformance run (:func:`drive_link.workflows.check.run_checks`) with
one line per item as it finishes and the summary; exit 1 when an item failed."""

from __future__ import annotations

import argparse
import json
from typing import Any

from ..errors import InvalidValue
from ..link.drive import Drive
from ._common import AddCommand

__all__ = ["add_parsers"]


def cmd_check(args: argparse.Namespace, d: Drive) -> int:
    from ..workflows.check import run_checks

    only = args.only.split(",") if args.only else None
    skip = args.skip.split(",") if args.skip else None

    label = {"pass": "PASS", "fail": "FAIL", "not applicable": "N/A ", "not judged": "N/J "}

    def show(r: Any) -> None:
        if not args.json:
            print(f"{label[r.verdict]}  {r.name:<20} {r.detail}", flush=True)

    try:
        results = run_checks(
            d, only=only, skip=skip, on_result=show, rate_tolerance=args.rate_tolerance
        )
    except ValueError as exc:
        raise InvalidValue(str(exc)) from None
    failed = [r.name for r in results if not r.ok]
    na = [r.name for r in results if r.verdict == "not applicable"]
    nj = [r.name for r in results if r.verdict == "not judged"]
    if args.json:
        print(
            json.dumps(
                [
                    {
                        "name": r.name,
                        "ok": r.ok,
                        "verdict": r.verdict,
                        "detail": r.detail,
                        "seconds": r.seconds,
                    }
                    | ({"evidence": r.evidence} if r.evidence else {})
                    for r in results
                ]
            )
        )
    else:
        print(
            f"{len(results) - len(failed) - len(na) - len(nj)}/{len(results) - len(na)} passed"
            + (f"; not applicable: {', '.join(na)}" if na else "")
            + (f"; not judged (host stalls): {', '.join(nj)}" if nj else "")
            + (f"; failed: {', '.join(failed)}" if failed else "")
        )
    return 1 if failed else 0


def add_parsers(add: AddCommand) -> None:
    """``check --only/--skip/--rate-tolerance``."""
    p = add(
        "check",
        cmd_check,
        "conformance run (CiA 301/402 + OD) with pass/fail per item; item store_restore "
        "rewrites the stored parameters (--skip store_restore on a tuned drive)",
    )
    p.add_argument("--only", default=None, help="comma-separated items")
    p.add_argument("--skip", default=None, help="comma-separated items (e.g. store_restore)")
    p.add_argument(
        "--rate-tolerance",
        type=float,
        default=0.25,
        help="allowed relative rate error (unitless, 0.25 = 25 %%)",
    )
