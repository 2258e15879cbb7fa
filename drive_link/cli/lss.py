"""``drive-link lss``: find the drives without a node-ID (CiA 305 LSS fast scan) and give each
one a free node-ID, with canopen's own :class:`canopen.lss.LssMaster`.

A drive out of the box (or one set to 0xFF) has no node-ID and answers nothing but LSS. The
command first lists the node-IDs in use (the ordinary scan), then repeats: fast scan (the
unconfigured slave with the lowest LSS address answers to the end: vendor-ID, product code,
revision, serial number), configure node-ID (the next free one from ``--first-id``), store it
in the drive if ``--store``, switch it back to LSS waiting state, upon which it boots with its
new node-ID (its boot-up message is awaited) — until no unconfigured slave answers.
"""

from __future__ import annotations

import argparse
import threading
import time
from typing import Any

from ._common import _emit
from .tools import bus_settings

__all__ = ["add_parsers", "cmd_lss"]

_LSS_RX = 0x7E4  # slave → master
_LSS_TX = 0x7E5  # master → slave


def add_parsers(sub: argparse._SubParsersAction, bus: argparse.ArgumentParser) -> None:
    """Add ``lss`` to drive-link's sub-commands (``bus``: the parent with the bus options)."""
    text = (
        "LSS (CiA 305): find drives without a node-ID by fast scan and give each the next free "
        "node-ID (canopen's LssMaster)"
    )
    p = sub.add_parser("lss", parents=[bus], help=text, description=text)
    p.set_defaults(func=cmd_lss, needs_drive=False)
    p.add_argument(
        "--first-id", type=int, default=1, metavar="ID",
        help="lowest node-ID to give (default 1; IDs in use on the bus are skipped)",
    )  # fmt: skip
    p.add_argument("--store", action="store_true", help="make each drive store its new node-ID")
    p.add_argument(
        "--lss-timeout", type=float, default=0.1, metavar="S",
        help="wait for an LSS answer, s (default 0.1; fast scan waits this at each 1 bit)",
    )  # fmt: skip
    p.add_argument("--max", type=int, default=127, metavar="N", help="configure at most N drives")


def cmd_lss(args: argparse.Namespace) -> int:
    """See the module docstring; exit 0 also when no unconfigured drive answered."""
    import canopen.lss

    from ..errors import DriveError, InvalidValue
    from ..link import _connection
    from ..link._scan import scan

    if not 1 <= args.first_id <= 127:
        raise InvalidValue(f"--first-id {args.first_id}: must be 1..127")
    if not 0.01 <= args.lss_timeout <= 10:
        raise InvalidValue(f"--lss-timeout {args.lss_timeout:g}: must be 0.01..10 s")
    settings = {k: v for k, v in bus_settings(args).items() if k != "node"}
    conn = _connection.acquire(**settings)
    done: list[dict[str, Any]] = []
    try:
        used = {n.node_id for n in scan(bus=conn.bus)}
        net = conn.network
        lss = canopen.lss.LssMaster()
        lss.network = net
        lss.RESPONSE_TIMEOUT = args.lss_timeout
        net.subscribe(_LSS_RX, lss.on_message_received)
        lss.send_switch_state_global(lss.WAITING_STATE)
        time.sleep(0.05)
        nid = args.first_id
        while len(done) < args.max:
            found, address = _fast_scan(lss, args.lss_timeout)
            if not found or address is None:  # (canopen gives the address when found)
                break
            while nid in used:
                nid += 1
            if nid > 127:
                raise DriveError("no free node-ID left (1..127 in use)")
            try:
                lss.configure_node_id(nid)
                stored: bool | str | None = None  # True, or why the drive refused
                if args.store:
                    try:
                        lss.store_configuration()
                        stored = True
                    except canopen.lss.LssError as exc:
                        stored = f"refused: {exc}"
            except canopen.lss.LssError as exc:
                raise DriveError(f"LSS: node-ID {nid} not taken: {exc}") from None
            booted = _await_boot(net, nid, lambda: lss.send_switch_state_global(0))
            vendor, product, revision, serial = address
            done.append(
                {
                    "node_id": nid,
                    "vendor_id": vendor,
                    "product_code": product,
                    "revision": revision,
                    "serial": serial,
                    "stored": stored,
                    "booted": booted,
                }
            )
            used.add(nid)
        net.unsubscribe(_LSS_RX, lss.on_message_received)
    finally:
        _connection.release(conn)

    def text() -> str:
        if not done:
            return "no unconfigured drive answered the LSS fast scan"
        return "\n".join(
            f"node {d['node_id']}: serial 0x{d['serial']:08X} (vendor 0x{d['vendor_id']:X}, "
            f"product 0x{d['product_code']:X}, revision 0x{d['revision']:X})"
            + ("" if d["booted"] else ", no boot-up seen")
            + (
                ""
                if d["stored"] is None
                else ", stored"
                if d["stored"] is True
                else f", store {d['stored']}"
            )
            for d in done
        )

    _emit(args, done, text)
    return 0


#: A fast scan that failed while an unconfigured drive still answers is repeated this many
#: times, each with twice the LSS timeout of the one before.
SCAN_RETRIES = 4
#: Wait for an answer to "identify non-configured remote slave" after a scan found nobody, s:
#: one frame, so a generous wait costs one second at the end of a run, not one per bit.
IDENTIFY_TIMEOUT = 1.0


def _fast_scan(lss: Any, timeout: float) -> tuple[bool, list[int] | None]:
    """canopen's fast scan with ``lss.RESPONSE_TIMEOUT`` (at least ``timeout``); when it finds
    nobody but an unconfigured drive answers "identify non-configured remote slave" (CiA 305,
    0x4C → 0x50), an answer came later than the LSS timeout at some bit (a busy host, a slow
    adapter): scanned again with twice the timeout, up to :data:`SCAN_RETRIES` times, then an
    error. The timeout that worked stays set for the configure services that follow. canopen's
    ``fast_scan`` returns the same ``(False, None)`` for "nobody there" and for a scan that
    lost its slave half-way, so without this check ``lss`` reported success with drives left
    unconfigured."""
    from ..errors import DriveError

    wait = max(timeout, lss.RESPONSE_TIMEOUT)
    for _attempt in range(SCAN_RETRIES + 1):
        lss.RESPONSE_TIMEOUT = wait
        found, address = lss.fast_scan()
        if found:
            return found, address
        if not _unconfigured_answers(lss.network, max(IDENTIFY_TIMEOUT, wait)):
            return False, None
        time.sleep(wait)  # late answers of the failed scan: past
        lss.send_switch_state_global(lss.WAITING_STATE)  # a slave left half-way: back in
        wait = min(2 * wait, 10.0)
    raise DriveError(
        f"LSS: an unconfigured drive answers, but {SCAN_RETRIES + 1} fast scans "
        f"(LSS timeout {timeout:g} s up to {lss.RESPONSE_TIMEOUT:g} s) did not find its "
        "address: answers later than the timeout (raise --lss-timeout)"
    )


def _unconfigured_answers(net: Any, timeout: float) -> bool:
    """Send "identify non-configured remote slave" (0x4C) and wait up to ``timeout`` s for an
    answer 0x50 (canopen's ``send_identify_non_configured_remote_slave`` does not wait: 0x4C
    is not in its list of services with an answer)."""
    seen = threading.Event()

    def on_answer(can_id: int, data: bytearray, ts: float) -> None:
        if data and data[0] == 0x50:
            seen.set()

    net.subscribe(_LSS_RX, on_answer)
    try:
        net.send_message(_LSS_TX, bytes([0x4C, 0, 0, 0, 0, 0, 0, 0]))
        return seen.wait(timeout)
    finally:
        net.unsubscribe(_LSS_RX, on_answer)


def _await_boot(net: Any, nid: int, switch: Any, timeout: float = 2.0) -> bool:
    """Run ``switch`` (back to LSS waiting) and wait for node ``nid``'s boot-up message."""
    seen = threading.Event()

    def on_hb(can_id: int, data: bytearray, ts: float) -> None:
        if data and data[0] == 0x00:
            seen.set()

    net.subscribe(0x700 + nid, on_hb)
    try:
        switch()
        return seen.wait(timeout)
    finally:
        net.unsubscribe(0x700 + nid, on_hb)
