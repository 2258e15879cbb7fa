"""The canopen LocalNode of the virtual drive: every read and write goes through the drive.

Reads: live values first (:mod:`.reads`), then the stored value, then the EDS default.
Writes: length check, the drive's checks (:mod:`.writes`, may abort), store, then the follow-up.
An RPDO is written as one: all checks first, then all stores (:meth:`set_data_all`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import canopen
from canopen import objectdictionary as odm
from canopen.node.local import LocalNode
from canopen.sdo import SdoAbortedError

from firmware_protocol import abort_codes

if TYPE_CHECKING:
    from .drive_node import VirtualDrive

__all__ = ["DriveLocalNode", "RpdoRefusedError"]

ABORT_READ_WRITEONLY = abort_codes.READ_WRITE_ONLY
ABORT_WRITE_READONLY = abort_codes.WRITE_READ_ONLY
ABORT_LENGTH = abort_codes.LENGTH
ABORT_NO_OBJECT = abort_codes.NO_OBJECT
ABORT_NO_SUBINDEX = abort_codes.NO_SUBINDEX


class RpdoRefusedError(SdoAbortedError):
    """A value inside an RPDO was refused: ``index``/``subindex`` and the abort ``code``."""

    def __init__(self, code: int, index: int, subindex: int) -> None:
        super().__init__(code)
        self.index = index
        self.subindex = subindex


class DriveLocalNode(LocalNode):
    """canopen LocalNode whose reads and writes go through :class:`VirtualDrive`.

    Reads: live values first, then the stored value, then the EDS default.
    Writes: length check, the drive's checks (may abort), store, then the drive's follow-up.
    """

    def __init__(self, node_id: int, od: odm.ObjectDictionary, drive: VirtualDrive) -> None:
        super().__init__(node_id, od)
        self._drive = drive
        self._write_callbacks = []  # canopen's NmtSlave hook is replaced by ours

    def associate_network(self, network: canopen.Network) -> None:
        self.network = network
        self.sdo.network = network
        self.tpdo.network = network
        self.rpdo.network = network
        self.nmt.network = network
        self.emcy.network = network

    def remove_network(self) -> None:
        self.network = canopen.network._UNINITIALIZED_NETWORK

    def _find_object(self, index: int, subindex: int) -> odm.ODVariable:
        """The variable at ``index:subindex``; CiA 301 aborts 0x06020000 (no object) and
        0x06090011 (no sub-index: also a sub-index other than 0 of a VAR, which canopen's
        LocalNode would otherwise resolve to the VAR itself)."""
        obj = self.object_dictionary.get(index)
        if obj is None:
            raise SdoAbortedError(ABORT_NO_OBJECT)
        if isinstance(obj, odm.ODVariable):
            if subindex != 0:
                raise SdoAbortedError(ABORT_NO_SUBINDEX)
            return obj
        if subindex not in obj.subindices:  # an ODArray would make up any sub-index
            raise SdoAbortedError(ABORT_NO_SUBINDEX)
        return obj.subindices[subindex]

    def get_data(self, index: int, subindex: int, check_readable: bool = False) -> bytes:
        obj = self._find_object(index, subindex)
        if check_readable and not obj.readable:
            raise SdoAbortedError(ABORT_READ_WRITEONLY)
        live = self._drive._live_getters.get((index, subindex))
        if live is not None:
            if getattr(live, "live_item", None) is not None:  # a measurement (0x2040):
                self._drive.runner.catch_up()  # the value of now, not of the last tick
            value = live()
            if isinstance(value, (bytes, bytearray)):
                return bytes(value)
            return obj.encode_raw(value)
        return super().get_data(index, subindex)

    def stored(self, index: int, subindex: int) -> Any:
        """Decoded parameter value (store, else EDS default), bypassing live values."""
        obj = self._find_object(index, subindex)
        return obj.decode_raw(LocalNode.get_data(self, index, subindex))

    def set_data(
        self, index: int, subindex: int, data: bytes, check_writable: bool = False
    ) -> None:
        obj = self._find_object(index, subindex)
        if check_writable and not obj.writable:
            raise SdoAbortedError(ABORT_WRITE_READONLY)
        if obj.data_type in odm.NUMBER_TYPES and 8 * len(data) != len(obj):
            raise SdoAbortedError(ABORT_LENGTH)
        with self._drive._write_lock:
            store, after = self._drive._before_write(index, subindex, obj, bytes(data))
            if store:
                self.data_store.setdefault(index, {})[subindex] = bytes(data)
            self._drive._pcache.clear()
            if after is not None:
                after()

    def set_data_all(self, items: list[tuple[int, int, bytes]]) -> None:
        """Write several objects as one (an RPDO): all checks first, then all stores.

        Every value is checked against the present values of the other objects (as SDO writes
        just before the PDO would be). One refusal raises :class:`RpdoRefusedError` and nothing of
        the PDO is applied. The RPDO-mappable objects' checks have no side effects (setpoints,
        controlword, mode, torque/current limits), so checking all before storing any is exact.
        """
        with self._drive._write_lock:
            plans = []
            for index, sub, data in items:
                obj = self._find_object(index, sub)
                try:
                    if not obj.writable:
                        raise SdoAbortedError(ABORT_WRITE_READONLY)
                    if obj.data_type in odm.NUMBER_TYPES and 8 * len(data) != len(obj):
                        raise SdoAbortedError(ABORT_LENGTH)
                    store, after = self._drive._before_write(index, sub, obj, bytes(data))
                except SdoAbortedError as exc:
                    raise RpdoRefusedError(exc.code, index, sub) from exc
                plans.append((index, sub, bytes(data), store, after))
            for index, sub, data, store, _after in plans:
                if store:
                    self.data_store.setdefault(index, {})[sub] = data
            self._drive._pcache.clear()
            for *_, after in plans:
                if after is not None:
                    after()
