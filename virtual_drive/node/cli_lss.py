"""``virtual-drive run --unconfigured N``: N drives out of the box, without a node-ID.

Each is an LSS slave (:class:`virtual_drive.node.lss.LssSlave`) with the identity of the EDS
(0x1018: vendor-ID, product code, revision) and its own serial number (``--serial-base``,
``+1``, ...), quiet on the bus but for LSS until a master (``drive-link lss``, canopen's
``LssMaster``) gives it a node-ID; then it boots as the ordinary virtual drive with that node-ID.
With ``--store FILE`` each keeps its LSS configuration in ``FILE-serial<S>.lss.json`` (0x17
"store configuration") and its parameters in ``FILE-node<N>`` as ``--nodes`` does.
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path
from typing import Any

import can

__all__ = ["add_lss_arguments", "run_unconfigured"]

logger = logging.getLogger("virtual_drive.run")


def add_lss_arguments(p: argparse.ArgumentParser) -> None:
    """``--unconfigured N`` and ``--serial-base S`` of ``virtual-drive run``."""
    p.add_argument(
        "--unconfigured",
        type=int,
        metavar="N",
        help="serve N drives without a node-ID (LSS slaves, CiA 305) until an LSS master "
        "(drive-link lss) gives them one",
    )
    p.add_argument(
        "--serial-base",
        type=lambda s: int(s, 0),
        default=1,
        metavar="S",
        help="serial number (0x1018:4) of the first --unconfigured drive; the next get S+1, ...",
    )


def run_unconfigured(
    args: argparse.Namespace, cfg: dict[str, Any], open_bus: Any, stop: Any
) -> int:
    """Serve ``args.unconfigured`` LSS slaves on buses opened by ``open_bus(cfg)`` until
    ``stop.wait`` says so; returns the exit status."""
    from firmware_protocol import load_od

    from .drive_node import VirtualDrive
    from .lss import LssSlave
    from .od_maps import int_default

    n = args.unconfigured
    if not 1 <= n <= 16:
        print(f"virtual-drive: error: --unconfigured must be 1..16, got {n}", file=sys.stderr)
        return 2
    view = load_od()
    vendor, product, revision = (
        int_default(view, f"identity.{k}") for k in ("vendor_id", "product_code", "revision_number")
    )
    slaves: list[LssSlave] = []
    buses: list[can.BusABC] = []
    try:
        for i in range(n):
            serial = (args.serial_base + i) & 0xFFFFFFFF
            bus = open_bus(cfg)
            buses.append(bus)

            def make(node_id: int, bus: can.BusABC = bus) -> VirtualDrive:
                store = None
                if args.store:
                    p = Path(args.store)
                    store = p.with_name(f"{p.stem}-node{node_id}{p.suffix}")
                return VirtualDrive(bus, node_id=node_id, store_path=store, speed=args.speed)

            lss_file = None
            if args.store:
                p = Path(args.store)
                lss_file = p.with_name(f"{p.stem}-serial{serial}.lss.json")
            slaves.append(
                LssSlave(bus, (vendor, product, revision, serial), make, store=lss_file).start()
            )
        serials = ",".join(str(s.identity[3]) for s in slaves)
        print(
            f"virtual-drive: {n} unconfigured drive(s) (serial {serials}) ready on "
            f"{buses[0].channel_info}",
            flush=True,
        )
        while not stop.wait(0.2):
            for s in slaves:
                if s.drive is not None and s.drive.runner.error is not None:
                    print(
                        f"virtual-drive: error: node {s.node_id}: simulation loop stopped: "
                        f"{s.drive.runner.error}",
                        file=sys.stderr,
                    )
                    return 1
        return 0
    finally:
        for s in slaves:
            s.stop()
        for bus in buses:
            bus.shutdown()
