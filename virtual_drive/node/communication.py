"""The communication objects (CiA 301): heartbeat 0x1016/0x1017, EMCY 0x1014, the second SDO
server 0x1201, the PDOs, and NMT "reset communication".

:meth:`Communication.configure` applies the present values to the services (after a parameter
load or a reset); the write handlers (:mod:`.writes`) apply single writes through its methods.

:class:`Communication` owns the bindings it makes on the network: the second SDO server
(``sdo2``, None while 0x1201 is invalid) and the CAN-ID it listens to for SYNC
(``sync_can_id``). The services it configures own their own state (heartbeat producer and
consumer, EMCY, PDO engine); the values come from the parameter store.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

import canopen

from firmware_protocol.cob_id import CAN_ID_MASK, COB_INVALID
from firmware_protocol.index_ranges import COMMUNICATION
from firmware_protocol.od import load_od

from . import storage
from .emcy import EmcyManager
from .heartbeat import HeartbeatConsumer, HeartbeatProducer
from .local_node import DriveLocalNode
from .pdo import PdoEngine
from .sdo_block import BlockSdoServer

_OD = load_od()  # where the objects are: the EDS, through firmware_protocol's view
COB_ID_EMCY = _OD.address("cob_id_emcy")
COB_ID_SYNC = _OD.address("cob_id_sync")
CONSUMER_HEARTBEAT_INDEX = _OD.index_of("consumer_heartbeat_time")
CONSUMER_HEARTBEAT_COUNT = _OD.address("consumer_heartbeat_time.highest_sub_index")
PRODUCER_HEARTBEAT = _OD.address("producer_heartbeat_time")
SDO_SERVER_2_RX = _OD.address("sdo_server_2.cob_id_client_to_server")
SDO_SERVER_2_TX = _OD.address("sdo_server_2.cob_id_server_to_client")

__all__ = ["Communication"]


class Communication:
    """The communication objects applied to the services, and NMT reset communication.

    :param node: the parameter store (0x1000-0x1FFF values).
    :param network: the canopen network the services subscribe on.
    :param hb_producer: / :param hb_consumer: heartbeat services (0x1017 / 0x1016).
    :param emcy: EMCY producer (0x1014).
    :param pdo: the PDO engine (SYNC consumer, PDO configuration).
    :param sdo_allowed: NMT gate of the SDO servers.
    :param send: puts one frame on the bus.
    :param store_path: the parameter file (reset communication reloads from it).
    """

    def __init__(
        self,
        node: DriveLocalNode,
        network: canopen.Network,
        hb_producer: HeartbeatProducer,
        hb_consumer: HeartbeatConsumer,
        emcy: EmcyManager,
        pdo: PdoEngine,
        sdo_allowed: Callable[[], bool],
        send: Callable[[int, bytes], None],
        store_path: Path | None,
    ) -> None:
        self.node = node
        self.network = network
        self.hb_producer = hb_producer
        self.hb_consumer = hb_consumer
        self.emcy = emcy
        self.pdo = pdo
        self._sdo_allowed = sdo_allowed
        self._send = send
        self.store_path = store_path
        self.sdo2: BlockSdoServer | None = None  #: the second SDO server (0x1201)
        self.sync_can_id: int | None = None  #: the CAN-ID SYNC is listened to on (0x1005)

    def configure(self) -> None:
        """Heartbeat producer/consumer, EMCY COB-ID, SDO server 2 and PDOs from the present
        values."""
        now = time.monotonic()
        param = self.node.param
        self.hb_producer.set_period(param(PRODUCER_HEARTBEAT), now)
        self.hb_consumer.configure(self.consumer_entries())
        self.emcy.set_cob_id(param(COB_ID_EMCY))
        self.bind_sdo2()
        self.bind_sync()
        self.pdo.configure()

    def bind_sync(self, cob_id: int | None = None) -> None:
        """Listen for SYNC on 0x1005's CAN-ID (``cob_id``: a value being written)."""
        can_id = (self.node.param(COB_ID_SYNC) if cob_id is None else cob_id) & CAN_ID_MASK
        old = self.sync_can_id
        if old == can_id:
            return
        if old is not None:
            self.network.unsubscribe(old, self.pdo.on_sync)
        self.network.subscribe(can_id, self.pdo.on_sync)
        self.sync_can_id = can_id

    def consumer_entries(self, sub: int = 0, value: int = 0) -> list[int]:
        """0x1016 sub 1..N present values (with ``value`` in place of ``sub`` if given)."""
        count = self.node.param(CONSUMER_HEARTBEAT_COUNT)
        index = CONSUMER_HEARTBEAT_INDEX
        return [value if s == sub else self.node.value(index, s) for s in range(1, count + 1)]

    def bind_sdo2(self) -> None:
        """(Re)bind the second SDO server to 0x1201:1/2 (bit 31 set in either: no server)."""
        rx, tx = self.node.param(SDO_SERVER_2_RX), self.node.param(SDO_SERVER_2_TX)
        if self.sdo2 is not None:
            self.network.unsubscribe(self.sdo2.rx_cobid, self.sdo2.on_request)
            self.sdo2 = None
        if rx & COB_INVALID or tx & COB_INVALID:
            return
        self.sdo2 = BlockSdoServer(
            rx & CAN_ID_MASK, tx & CAN_ID_MASK, self.node, self._sdo_allowed, send=self._send
        )
        self.network.subscribe(self.sdo2.rx_cobid, self.sdo2.on_request)

    def reset(self, keep_1016: bool) -> None:
        """NMT reset communication: 0x1000-0x1FFF back to stored values or defaults (CiA 301).

        Exception (``keep_1016``): wherever the drive can go back to OPERATION ENABLED without
        passing SWITCH ON DISABLED after the 0x6007 reaction (READY TO SWITCH ON, SWITCHED ON,
        QUICK STOP ACTIVE held or braking, a stop ramp still braking) the consumer heartbeat
        0x1016 keeps its present value and its monitoring goes on, so the master's supervision
        is never dropped while the motor can turn or be made to turn by one controlword (node
        README, "Supervision by state").
        """
        data_store = self.node.data_store
        kept = dict(data_store.get(CONSUMER_HEARTBEAT_INDEX, {})) if keep_1016 else {}
        stored, _status, _error = storage.load_with_status(self.store_path)
        for index in [i for i in data_store if i < COMMUNICATION.stop]:
            del data_store[index]
        for (index, sub), raw in stored.items():
            if index < COMMUNICATION.stop and index in self.node.object_dictionary:
                data_store.setdefault(index, {})[sub] = raw
        if keep_1016:
            data_store.pop(CONSUMER_HEARTBEAT_INDEX, None)
            if kept:
                data_store[CONSUMER_HEARTBEAT_INDEX] = kept
        self.node.invalidate()
        self.pdo.reset_counters()
        self.configure()
