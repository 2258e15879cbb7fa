"""The ``as_found`` item of ``drive-link check``: the run leaves no error behind.

:func:`take` (by :func:`drive_link.workflows.check.run_checks`, before the first item) reads the
error code (0x603F), the error register (0x1001) and the error history (0x1003, every entry); the
communication objects are the snapshot ``run_checks`` takes anyway. :func:`settle` (at the end)
clears the history again when the run found it empty (the items add entries on purpose: a
heartbeat loss, a lost connection; CiA 301 allows only clearing it, so a history that had entries
keeps the run's on top); :func:`item_as_found` does that and reports what still differs.
"""

from __future__ import annotations

from typing import Any

from ...errors import DriveError
from ...link.drive import Drive
from ._base import CheckFailed
from ._snapshot import FOUND

__all__ = ["ERRORS", "HISTORY", "item_as_found", "settle", "take"]

#: ``opts`` key of the error objects as found (see :func:`take`).
ERRORS = "errors_found"
#: The history's entry count (0x1003:0; writing 0 clears the history).
HISTORY = "pre_defined_error_field.number_of_errors"


def take(d: Drive) -> dict[str, Any]:
    """Error code, error register and the error history (entry count and entries, newest
    first) as they are now."""
    return {
        "error_code": int(d.read("error_code")),
        "error_register": int(d.read("error_register")),
        "history": [e.code for e in d.error_history()],
    }


def settle(d: Drive, found: dict[str, Any] | None) -> str:
    """Clear the error history if the run found it empty and left entries; returns what was
    done (empty: nothing)."""
    if not found or found["history"]:
        return ""
    added = int(d.read(HISTORY))
    if not added:
        return ""
    d.clear_error_history()
    return f"the {added} history entr{'y' if added == 1 else 'ies'} the run added cleared"


def item_as_found(d: Drive, opts: dict) -> str:
    """After the other items: 0x603F, 0x1001, 0x1003 and the communication objects
    (0x1000–0x1FFF, persistent ones) as the run found them (the history cleared when it was
    empty; one that had entries keeps the run's entries on top, said here)."""
    found = opts.get(ERRORS)
    if found is None:
        raise CheckFailed("the drive's error state could not be read before the run")
    done = settle(d, found)
    now = take(d)
    # an error the run left behind is one the drive shows now and did not show at the start; an
    # error it showed at the start and has since cleared (its cause ended: a heartbeat the
    # drive missed before the run) is said, not failed
    keys = ("error_code", "error_register")
    differ = [f"{k} 0x{found[k]:X} → 0x{now[k]:X}" for k in keys if now[k] not in (0, found[k])]
    cleared = [
        f"{k} 0x{found[k]:X} found at the start has cleared"
        for k in keys
        if found[k] and not now[k]
    ]
    kept = "; " + ", ".join(cleared) if cleared else ""
    if found["history"]:
        new = len(now["history"]) - len(found["history"])
        if now["history"][max(new, 0) :] != found["history"][: len(now["history"])]:
            differ.append("error history rewritten")
        elif new > 0:
            kept += f"; {new} history entries added on top of the {len(found['history'])} found"
    elif now["history"]:
        differ.append(f"error history {[hex(c) for c in now['history']]} not cleared")
    comm = opts.get(FOUND) or {}
    for name, raw in comm.items():
        o = d.table[name]
        try:
            if d.sdo.upload(o.index, o.subindex, name) != raw:
                differ.append(f"{name} changed")
        except DriveError as exc:
            differ.append(f"{name}: {exc}")
    if differ:
        raise CheckFailed("not as found: " + "; ".join(differ[:4]))
    return (
        f"error code 0x{now['error_code']:04X}, error register 0x{now['error_register']:02X}, "
        f"error history and {len(comm)} communication objects as found"
        + (f" ({done})" if done else "")
        + kept
    )
