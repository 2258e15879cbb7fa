"""The communication objects (CiA 301): heartbeat 0x1016/0x1017, EMCY 0x1014, the second SDO
server 0x1201, the PDOs, and NMT "reset communication".

:func:`configure_communication` applies the present values to the services (after a parameter
load or a reset); the write handlers (:mod:`.writes`) apply single writes.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

from firmware_protocol.cob_id import CAN_ID_MASK, COB_INVALID
from firmware_protocol.index_ranges import COMMUNICATION

from . import storage
from .od_addresses import (
    COB_ID_EMCY,
    COB_ID_SYNC,
    CONSUMER_HEARTBEAT_COUNT,
    CONSUMER_HEARTBEAT_INDEX,
    PRODUCER_HEARTBEAT,
    SDO_SERVER_2_RX,
    SDO_SERVER_2_TX,
)
from .sdo_block import BlockSdoServer

if TYPE_CHECKING:
    from .drive_node import VirtualDrive

__all__ = [
    "bind_sdo2",
    "bind_sync",
    "configure_communication",
    "consumer_entries",
    "reset_communication",
]


def configure_communication(d: VirtualDrive) -> None:
    """Heartbeat producer/consumer, EMCY COB-ID, SDO server 2 and PDOs from the present values."""
    now = time.monotonic()
    d.hb_producer.set_period(d._param(PRODUCER_HEARTBEAT), now)
    d.hb_consumer.configure(consumer_entries(d))
    d.emcy.set_cob_id(d._param(COB_ID_EMCY))
    bind_sdo2(d)
    bind_sync(d)
    d.pdo.configure()


def bind_sync(d: VirtualDrive, cob_id: int | None = None) -> None:
    """Listen for SYNC on 0x1005's CAN-ID (``cob_id``: a value being written)."""
    can_id = (d._param(COB_ID_SYNC) if cob_id is None else cob_id) & CAN_ID_MASK
    old = getattr(d, "_sync_can_id", None)
    if old == can_id:
        return
    if old is not None:
        d.network.unsubscribe(old, d.pdo.on_sync)
    d.network.subscribe(can_id, d.pdo.on_sync)
    d._sync_can_id = can_id


def consumer_entries(d: VirtualDrive, sub: int = 0, value: int = 0) -> list[int]:
    """0x1016 sub 1..N present values (with ``value`` in place of ``sub`` if given)."""
    count = d._param(CONSUMER_HEARTBEAT_COUNT)
    index = CONSUMER_HEARTBEAT_INDEX
    return [value if s == sub else d._value(index, s) for s in range(1, count + 1)]


def bind_sdo2(d: VirtualDrive) -> None:
    """(Re)bind the second SDO server to 0x1201:1/2 (bit 31 set in either: no server)."""
    rx, tx = d._param(SDO_SERVER_2_RX), d._param(SDO_SERVER_2_TX)
    if d.sdo2 is not None:
        d.network.unsubscribe(d.sdo2.rx_cobid, d.sdo2.on_request)
        d.sdo2 = None
    if rx & COB_INVALID or tx & COB_INVALID:
        return
    d.sdo2 = BlockSdoServer(
        rx & CAN_ID_MASK, tx & CAN_ID_MASK, d.node, d.nmt.sdo_allowed, send=d._send
    )
    d.network.subscribe(d.sdo2.rx_cobid, d.sdo2.on_request)


def reset_communication(d: VirtualDrive) -> None:
    """NMT reset communication: 0x1000-0x1FFF back to stored values or defaults (CiA 301).

    Exception: wherever the drive can go back to OPERATION ENABLED without passing SWITCH ON
    DISABLED after the 0x6007 reaction (READY TO SWITCH ON, SWITCHED ON, QUICK STOP ACTIVE held
    or braking, a stop ramp still braking) the consumer heartbeat 0x1016 keeps its present value
    and its monitoring goes on, so the master's supervision is never dropped while the motor
    can turn or be made to turn by one controlword (node README, "Supervision by state").
    """
    keep_1016 = d.cia402.can_reach_operation
    kept = dict(d.node.data_store.get(CONSUMER_HEARTBEAT_INDEX, {})) if keep_1016 else {}
    stored, _status, _error = storage.load_with_status(d.store_path)
    for index in [i for i in d.node.data_store if i < COMMUNICATION.stop]:
        del d.node.data_store[index]
    for (index, sub), raw in stored.items():
        if index < COMMUNICATION.stop and index in d.od:
            d.node.data_store.setdefault(index, {})[sub] = raw
    if keep_1016:
        d.node.data_store.pop(CONSUMER_HEARTBEAT_INDEX, None)
        if kept:
            d.node.data_store[CONSUMER_HEARTBEAT_INDEX] = kept
    d._pcache.clear()
    d.pdo.reset_counters()
    configure_communication(d)
