"""The run: every item in order (:data:`ITEMS`), a timing item repeated when the host
stalled in its window, and :func:`run_checks`."""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from ...errors import DriveError
from ...link import cia402
from ...link.drive import Drive
from . import found
from ._base import (
    EVIDENCE,
    FAIL,
    NOT_APPLICABLE,
    NOT_JUDGED,
    PASS,
    CheckFailed,
    CheckResult,
    NotApplicable,
)
from ._host_stall import StallProbe
from ._snapshot import COMM_AREA, FOUND, RESETS, _persistent_snapshot
from .conformance import CONFORMANCE_ITEMS
from .motion import item_cia402, item_halt, item_modes
from .nmt import (
    item_heartbeat,
    item_heartbeat_consumer,
    item_identity,
    item_nmt_bootup,
    item_nmt_reaction,
    item_nmt_stopped,
)
from .parameters import (
    item_cob_id_validation,
    item_config_only,
    item_gain_set,
    item_limits,
    item_store_restore,
    item_store_status,
)
from .streams import item_pdo_rates, item_trace

__all__ = ["ITEMS", "TIMING_ATTEMPTS", "TIMING_ITEMS", "run_checks"]


#: An item: its one-line detail, or (detail, evidence) for the conformance families.
ITEMS: dict[str, Callable[[Drive, dict], str | tuple[str, dict[str, Any]]]] = {
    "identity": item_identity,
    "nmt_bootup": item_nmt_bootup,
    "nmt_stopped": item_nmt_stopped,
    "heartbeat": item_heartbeat,
    "cia402": item_cia402,
    "modes": item_modes,
    "limits": item_limits,
    "gain_set": item_gain_set,
    "store_restore": item_store_restore,
    "pdo_rates": item_pdo_rates,
    "trace": item_trace,
    "heartbeat_consumer": item_heartbeat_consumer,
    "nmt_reaction": item_nmt_reaction,
    "halt": item_halt,
    "cob_id_validation": item_cob_id_validation,
    "config_only": item_config_only,
    "store_status": item_store_status,
    "as_found": found.item_as_found,  # last: what the others left behind
    **CONFORMANCE_ITEMS,  # the pre-certification families (check.conformance)
}


#: Items whose verdict is a time measured on the bus: a host stall in their window makes them
#: run again (at most :data:`TIMING_ATTEMPTS` times), and the verdict says so.
TIMING_ITEMS = frozenset({"heartbeat", "pdo_rates"})


TIMING_ATTEMPTS = 3


def _attempt(n: str, drive: Drive, opts: dict) -> tuple[bool, str, str]:
    """One try of item ``n``: (ok, one-line detail, verdict)."""
    opts.pop(EVIDENCE, None)
    try:
        out = ITEMS[n](drive, opts)
    except NotApplicable as exc:
        return True, str(exc), NOT_APPLICABLE
    except (CheckFailed, DriveError) as exc:
        return False, str(exc), FAIL
    except Exception as exc:  # an item must not stop the run
        return False, f"{type(exc).__name__}: {exc}", FAIL
    if isinstance(out, tuple):  # (detail, evidence)
        out, opts[EVIDENCE] = out
    return True, out, PASS


def _run_item(n: str, drive: Drive, opts: dict) -> tuple[bool, str, str]:
    """One item; a timing item whose window the host stalled in (:class:`StallProbe`) is
    repeated instead of judged, and the verdict names the stalls; stalled every time: not
    judged (failed, saying so)."""
    if n not in TIMING_ITEMS:
        return _attempt(n, drive, opts)
    stalls: list[str] = []
    for _ in range(TIMING_ATTEMPTS):
        with StallProbe() as probe:
            ok, detail, verdict = _attempt(n, drive, opts)
        if not probe.stalled:
            if stalls:
                detail += f" [measured again after the host stalled: {', '.join(stalls)}]"
            return ok, detail, verdict
        stalls.append(probe.describe())
    # neither failed nor passed (issue 29): the measurement says more about the host than about
    # the drive; the run does not fail on it, and the verdict and the summary say so
    return True, (
        f"not judged: the host stalled in all {TIMING_ATTEMPTS} windows ("
        + ", ".join(stalls)
        + f"); last: {detail}"
    ), NOT_JUDGED


def run_checks(
    drive: Drive,
    only: list[str] | None = None,
    skip: list[str] | None = None,
    on_result: Callable[[CheckResult], None] | None = None,
    **opts: object,
) -> list[CheckResult]:
    """Run the items (all, or ``only``, minus ``skip``) in order; never raises for an item."""
    names = [n for n in ITEMS if (not only or n in only) and n not in (skip or [])]
    unknown = [n for n in (only or []) + (skip or []) if n not in ITEMS]
    if unknown:
        raise ValueError(f"unknown check item(s) {', '.join(unknown)}; items: {', '.join(ITEMS)}")
    results = []
    # the items' option bag: the caller's options and what one item hands the next
    bag: dict[str, Any] = dict(opts)
    if any(n in RESETS for n in names) or "as_found" in names:
        try:  # what a reset of the communication reverts, as found (see the module doc)
            bag[FOUND] = _persistent_snapshot(drive, COMM_AREA)
        except DriveError:
            bag[FOUND] = {}  # the items report the drive's silence themselves
    try:  # the error state, left as found at the end (drive_link.workflows.check.found)
        bag[found.ERRORS] = found.take(drive)
    except DriveError:
        pass
    for n in names:
        t0 = time.monotonic()
        ok, detail, verdict = _run_item(n, drive, bag)
        r = CheckResult(
            n, ok, detail, time.monotonic() - t0, verdict, bag.pop(EVIDENCE, None)
        )
        results.append(r)
        if on_result:
            on_result(r)
    try:
        drive.write("controlword", cia402.CW_DISABLE_VOLTAGE)
        if "as_found" not in names:
            found.settle(drive, bag.get(found.ERRORS))
    except DriveError:
        pass
    return results
