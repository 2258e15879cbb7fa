"""The persistent objects as the run found them, and putting them back: after an item that
resets the node's communication (:data:`RESETS`) and after ``store_restore``."""

from __future__ import annotations

from firmware_protocol.index_ranges import COMMUNICATION

from ...errors import DriveError, SdoAbort
from ...link.drive import Drive
from ._base import _expect

__all__ = ["COMM_AREA", "FOUND", "RESETS"]


#: Communication profile area (CiA 301 §7.4.8): what NMT reset communication reverts.
COMM_AREA = COMMUNICATION


def _persistent_snapshot(d: Drive, indices: range | None = None) -> dict[str, bytes]:
    """Raw present value of every stored (persistent, writable, numeric) object (with index
    in ``indices`` when given)."""
    out = {}
    for o in d.table:
        if indices is not None and o.index not in indices:
            continue
        if getattr(o.entry, "persistent", False) and o.writable and o.readable and o.fmt:
            try:
                out[o.name] = d.sdo.upload(o.index, o.subindex, o.name)
            except SdoAbort:
                continue
    return out


def _put_back(
    d: Drive, snapshot: dict[str, bytes], now: dict[str, bytes] | None = None
) -> list[str]:
    """Write back what differs from ``snapshot`` (the drive at rest): configuration objects
    first (the L_c/R_c rules read motor.L/R), gains as whole sets through gain_set (the speed-gain
    rule judges the pair), PDOs by the CiA 301 procedure, then the rest. ``now``: the present
    values if already read. Returns failures."""
    from ...link._gain_set import ACTIVE_GAIN_FIELD
    from ...link.supervision import RearmReport, pdo_group, write_pdo_group
    from ..gains import apply_gains

    if now is None:
        now = {n: d.sdo.upload(d.table[n].index, d.table[n].subindex, n) for n in snapshot}
    differ = [n for n in snapshot if now[n] != snapshot[n]]
    failed: list[str] = []
    gain_names = ACTIVE_GAIN_FIELD

    def raw_write(n: str) -> None:
        o = d.table[n]
        try:
            d.sdo.download(o.index, o.subindex, snapshot[n], n)
        except DriveError as exc:
            failed.append(f"{n}: {exc}")

    for n in differ:
        if getattr(d.table[n].entry, "config_only", False):
            raw_write(n)
    gains = {gain_names[n]: d.table[n].decode(snapshot[n]) for n in differ if n in gain_names}
    if gains:
        try:
            apply_gains(d, gains, force=True)  # the set as found: margins as they were
        except DriveError as exc:
            failed.append(f"gains: {exc}")
    groups: dict[tuple[str, int], list[tuple[int, int]]] = {}
    values: dict[tuple[int, int], bytes] = {}
    for n in differ:
        o = d.table[n]
        g = pdo_group(o.index)
        if g is not None:
            groups.setdefault(g, []).append((o.index, o.subindex))
            values[(o.index, o.subindex)] = snapshot[n]
        elif n not in gain_names and not getattr(o.entry, "config_only", False):
            raw_write(n)
    for g, keys in groups.items():
        # the whole group as found, so the procedure rebuilds a complete mapping
        for o in d.table:
            if pdo_group(o.index) == g and o.name in snapshot:
                values[(o.index, o.subindex)] = snapshot[o.name]
                if (o.index, o.subindex) not in keys:
                    keys.append((o.index, o.subindex))
        report = RearmReport("store_restore put back")
        write_pdo_group(d.sdo, g, keys, values, report)
        failed += [f"{k}: {v}" for k, v in report.failed.items()]
    return failed


#: Items that reset the node's communication (NMT reset communication / reset node).
RESETS = ("nmt_bootup", "store_restore", "nmt_reaction")


#: ``opts`` key of the communication objects as the run found them (name → raw bytes).
FOUND = "comm_found"


def _put_back_comm(d: Drive, opts: dict) -> int:
    """After a reset of the node's communication, while it is PRE-OPERATIONAL: write the
    communication objects back as the run found them (``opts[FOUND]``, taken by
    :func:`run_checks`); returns how many differed. :class:`CheckFailed` naming what could
    not be put back."""
    found: dict[str, bytes] = opts.get(FOUND) or {}
    if not found:
        return 0
    now = {n: d.sdo.upload(d.table[n].index, d.table[n].subindex, n) for n in found}
    differ = sum(now[n] != found[n] for n in found)
    failed = _put_back(d, found, now)
    _expect(not failed, "communication objects not put back after the reset: " + "; ".join(
        failed[:3]))
    return differ
