"""``drive-link check``: a conformance run against any node (DSP or virtual drive).

Each item exercises what the object dictionary (docs/contracts.md §1), CiA 301 and CiA 402
promise and reports pass/fail with a one-line detail, or "not applicable" where the drive lacks
what it tests (``store_restore`` on a drive without a parameter store; it does not fail the
run). Items leave the drive disabled, in OPERATIONAL, with the parameters they touched restored;
"store_restore" rewrites the drive's stored parameters (skip it with ``--skip store_restore`` on
a tuned drive). The last item, ``as_found``, checks that the run left the error code, error
register, error history and communication objects as it found them (:mod:`.found`).

Items that reset the node's communication (:data:`RESETS`: NMT reset communication or reset
node) put the communication objects back as the run found them, while the node is still
PRE-OPERATIONAL: CiA 301 §7.3.2.2 reverts 0x1000–0x1FFF to their stored values, so PDO event
timers, mappings or a heartbeat time set without a store (a user's session; the SocketCAN
lane slows the TPDOs from 2,200 to 60 frames/s this way) would otherwise come back at their
defaults. Without that, the items after ``nmt_bootup`` ran on the default streams: inside
User-Mode Linux (about 800 frames/s in all) they starved the drive's SDO server, the trace
upload's initiate went unanswered for 5.7 s and every later item failed.

One module per family of items: :mod:`.nmt` (CiA 301 NMT and heartbeat), :mod:`.motion` (CiA
402 state machine, modes, halt), :mod:`.parameters` (limits, gain sets, store/restore,
COB-ID validation, configuration-only objects, store status), :mod:`.streams` (PDO rates,
trace), :mod:`.conformance` (the pre-certification families: EDS, OD against the EDS, SDO
aborts and transfers, SYNC/PDO, EMCY) and :mod:`.found` (``as_found``); :mod:`.run` runs them
in order (:data:`ITEMS`); :mod:`._base` holds what they share, :mod:`._snapshot` the
communication objects as found, :mod:`._host_stall` the stall probe of the timing items.
"""

from __future__ import annotations

from ._base import (
    FAIL,
    NOT_APPLICABLE,
    NOT_JUDGED,
    PASS,
    CheckFailed,
    CheckResult,
    NotApplicable,
)
from .run import ITEMS, TIMING_ATTEMPTS, TIMING_ITEMS, run_checks

__all__ = [
    "FAIL",
    "ITEMS",
    "NOT_APPLICABLE",
    "NOT_JUDGED",
    "PASS",
    "TIMING_ATTEMPTS",
    "TIMING_ITEMS",
    "CheckFailed",
    "CheckResult",
    "NotApplicable",
    "run_checks",
]
