"""The canopen LocalNode of the virtual drive: the object dictionary and the parameter store.

:class:`DriveLocalNode` owns the parameter values (canopen's ``data_store``: raw bytes, EDS
defaults where nothing is stored), their decoded cache (:meth:`DriveLocalNode.param`; every
write to the store clears it) and the write lock that serialises writes.

Reads: live values first (the getters :meth:`DriveLocalNode.bind` gives it, :mod:`.reads`),
then the stored value, then the EDS default. Writes: length check, the drive's checks
(``before_write``, :mod:`.writes`, may abort), store, then the follow-up. An RPDO is written as
one: all checks first, then all stores (:meth:`set_data_all`).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import canopen
from canopen import objectdictionary as odm
from canopen.node.local import LocalNode
from canopen.sdo import SdoAbortedError

from firmware_protocol import abort_codes

__all__ = ["BeforeWrite", "DriveLocalNode", "RpdoRefusedError"]

BeforeWrite = Callable[[int, int, odm.ODVariable, bytes], tuple[bool, Callable[[], None] | None]]
"""``before_write(index, sub, obj, data) -> (store, after)``: checks a write (raises
SdoAbortedError to refuse it), says whether to store it and what to run once stored."""

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


def _no_check(
    index: int, sub: int, obj: odm.ODVariable, data: bytes
) -> tuple[bool, Callable[[], None] | None]:
    return True, None


class DriveLocalNode(LocalNode):
    """canopen LocalNode that owns the drive's parameter values and serves its live values.

    Reads: live values first, then the stored value, then the EDS default.
    Writes: length check, ``before_write`` (may abort), store, then its follow-up.
    """

    def __init__(self, node_id: int, od: odm.ObjectDictionary) -> None:
        super().__init__(node_id, od)
        self._no_network = self.network  # (canopen's "no network yet" placeholder)
        self._write_callbacks = []  # canopen's NmtSlave hook is replaced by ours
        self._cache: dict[tuple[int, int], Any] = {}
        #: serialises writes (SDO servers, RPDOs, a deferred reset node)
        self.write_lock = threading.RLock()
        #: ``(index, sub) -> getter`` of the objects computed on read (:meth:`bind`)
        self.live_getters: dict[tuple[int, int], Callable[[], Any]] = {}
        self.before_write: BeforeWrite = _no_check
        self._catch_up: Callable[[], object] = lambda: None

    def bind(
        self,
        before_write: BeforeWrite,
        live_getters: dict[tuple[int, int], Callable[[], Any]],
        catch_up: Callable[[], object],
    ) -> None:
        """Wire the node to the drive: its write checks, its live objects, and ``catch_up``
        (brings the simulation to now before a measurement is read)."""
        self.before_write = before_write
        self.live_getters = live_getters
        self._catch_up = catch_up

    # -- the parameter store ------------------------------------------------------------
    def param(self, address: tuple[int, int]) -> Any:
        """Present parameter value at ``address`` = ``(index, sub)`` (resolved by name from the
        EDS view, ``load_od().address(name)``; cached, every write to the data store clears the
        cache)."""
        try:
            return self._cache[address]
        except KeyError:
            value = self._cache[address] = self.stored(*address)
            return value

    def value(self, index: int, sub: int = 0) -> Any:
        """Present parameter value at ``index``/``sub`` (as :meth:`param`)."""
        return self.param((index, sub))

    def invalidate(self) -> None:
        """Forget the decoded values (after the data store was changed from outside)."""
        self._cache.clear()

    def store_raw(self, index: int, sub: int, raw: bytes) -> None:
        """Put ``raw`` bytes in the data store at ``index``/``sub`` (no checks)."""
        self.data_store.setdefault(index, {})[sub] = raw
        self._cache.clear()

    def find_object(self, index: int, subindex: int) -> odm.ODVariable:
        """The variable at ``index:subindex`` (aborts as :meth:`_find_object`)."""
        return self._find_object(index, subindex)

    def associate_network(self, network: canopen.Network) -> None:
        self.network = network
        self.sdo.network = network
        self.tpdo.network = network
        self.rpdo.network = network
        self.nmt.network = network
        self.emcy.network = network

    def remove_network(self) -> None:
        self.network = self._no_network

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
        # (canopen's ObjectDictionary is an unparameterised Mapping: its values are these)
        group: odm.ODRecord | odm.ODArray = obj
        if subindex not in group.subindices:  # an ODArray would make up any sub-index
            raise SdoAbortedError(ABORT_NO_SUBINDEX)
        return group[subindex]

    def get_data(self, index: int, subindex: int, check_readable: bool = False) -> bytes:
        obj = self._find_object(index, subindex)
        if check_readable and not obj.readable:
            raise SdoAbortedError(ABORT_READ_WRITEONLY)
        live = self.live_getters.get((index, subindex))
        if live is not None:
            if getattr(live, "live_item", None) is not None:  # a measurement (0x2040):
                self._catch_up()  # the value of now, not of the last tick
            value = live()
            if isinstance(value, (bytes, bytearray)):
                return bytes(value)
            return obj.encode_raw(value)
        return super().get_data(index, subindex)

    def stored(self, index: int, subindex: int) -> Any:
        """Decoded parameter value (store, else EDS default), bypassing live values."""
        obj = self._find_object(index, subindex)
        return obj.decode_raw(LocalNode.get_data(self, index, subindex))

    def stored_number(self, index: int, subindex: int) -> float | int:
        """:meth:`stored` of a numeric object; TypeError for a string or domain object."""
        value = self.stored(index, subindex)
        if isinstance(value, (int, float)):
            return value
        raise TypeError(f"0x{index:04X}:{subindex} is not a number: {value!r}")

    def set_data(
        self, index: int, subindex: int, data: bytes, check_writable: bool = False
    ) -> None:
        obj = self._find_object(index, subindex)
        if check_writable and not obj.writable:
            raise SdoAbortedError(ABORT_WRITE_READONLY)
        if obj.data_type in odm.NUMBER_TYPES and 8 * len(data) != len(obj):
            raise SdoAbortedError(ABORT_LENGTH)
        with self.write_lock:
            store, after = self.before_write(index, subindex, obj, bytes(data))
            if store:
                self.data_store.setdefault(index, {})[subindex] = bytes(data)
            self._cache.clear()
            if after is not None:
                after()

    def set_data_all(self, items: list[tuple[int, int, bytes]]) -> None:
        """Write several objects as one (an RPDO): all checks first, then all stores.

        Every value is checked against the present values of the other objects (as SDO writes
        just before the PDO would be). One refusal raises :class:`RpdoRefusedError` and nothing of
        the PDO is applied. The RPDO-mappable objects' checks have no side effects (setpoints,
        controlword, mode, torque/current limits), so checking all before storing any is exact.
        """
        with self.write_lock:
            plans = []
            for index, sub, data in items:
                obj = self._find_object(index, sub)
                try:
                    if not obj.writable:
                        raise SdoAbortedError(ABORT_WRITE_READONLY)
                    if obj.data_type in odm.NUMBER_TYPES and 8 * len(data) != len(obj):
                        raise SdoAbortedError(ABORT_LENGTH)
                    store, after = self.before_write(index, sub, obj, bytes(data))
                except SdoAbortedError as exc:
                    raise RpdoRefusedError(exc.code, index, sub) from exc
                plans.append((index, sub, bytes(data), store, after))
            for index, sub, data, store, _after in plans:
                if store:
                    self.data_store.setdefault(index, {})[sub] = data
            self._cache.clear()
            for *_, after in plans:
                if after is not None:
                    after()
