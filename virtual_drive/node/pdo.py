"""PDOs coupled to the object dictionary (CiA 301 §7.2.2, §7.5.2.35–38).

canopen's LocalNode keeps PDOs apart from its OD; this engine reads the communication
(0x1400+/0x1800+) and mapping (0x1600+/0x1A00+) parameters from the node and

- RPDO: decodes a received frame by its mapping and writes the mapped objects as one through the
  node's checked ``set_data_all``: a frame shorter than the mapping is not processed (EMCY 0x8210,
  data RPDO number, bytes received, bytes mapped); a value the checks refuse drops the WHOLE PDO
  (none of its objects apply; EMCY 0x8200, data RPDO number, index, sub-index, low byte of the
  abort code). Extra bytes beyond the mapping are ignored. The next RPDO processed in full
  clears both errors (error-reset EMCY when none is left);
- TPDO: encodes the mapped objects' live values and sends them on the event timer (transmission
  type 0xFE/0xFF, sub 5 in ms) or every n-th SYNC (types 1–240). Event-driven TPDOs are sent
  by :meth:`PdoEngine.tick`, run by the drive's pacing thread (or by :meth:`PdoEngine.start`'s
  own thread), which sleeps until the exact due time (not only the 1 ms pacing tick), so
  an inhibit time (sub 3, 100 µs units) of 2 ms gives 500 Hz, not the next tick: a frame is
  never sent before ``last transmission + inhibit`` nor before its event-timer grid point. A
  frame that is late by whole event periods is sent once (no burst); the periods passed
  without a frame are counted in 0x2070 tpdo_missed_events (frames + missed = elapsed/period);
- only in NMT OPERATIONAL.

Configuration writes are checked as CANopenNode does it (CiA 301 rules): the COB-ID follows
:func:`firmware_protocol.cob_id.check_cob_id` (no restricted CAN-ID, no 29-bit frame, no new
CAN-ID while the PDO is valid: 0x06090030); transmission types 241–253 are refused (0x06090030); a
inhibit time (sub 3) cannot change while the PDO is valid (CiA 301 §7.5.2.35/37: 0x06090030); a
mapping entry can only be written with sub0 = 0 and the PDO invalid (0x06010000); sub0 checks that
each mapped object exists (0x06020000 / 0x06090011), may be mapped (0x06040041) and that the total
fits 64 bits (0x06040042). Mapping and COB-IDs may be changed in PRE-OPERATIONAL only
(0x08000022 otherwise).
"""

from __future__ import annotations

import logging
import math
import operator
import struct
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from math import floor as _floor

from canopen import objectdictionary as odm
from canopen.sdo import SdoAbortedError

from firmware_protocol import abort_codes
from firmware_protocol.cob_id import CAN_ID_MASK, COB_BIT30, COB_INVALID, check_cob_id
from firmware_protocol.emcy_codes import RPDO_LENGTH, RPDO_VALUE
from firmware_protocol.entry import LimitError
from firmware_protocol.index_ranges import RPDO_COMM, RPDO_MAP, TPDO_COMM, TPDO_MAP
from firmware_protocol.od import load_od

from .local_node import DriveLocalNode
from .nmt import OPERATIONAL

_OD = load_od()  # where the objects are: the EDS, through firmware_protocol's view
N_RPDO = int(_OD.device_info["NrOfRXPDO"])
N_TPDO = int(_OD.device_info["NrOfTXPDO"])
PDO_COB_ID_SUB = _OD.address("tpdo1_communication.cob_id")[1]
PDO_TRANSMISSION_TYPE_SUB = _OD.address("tpdo1_communication.transmission_type")[1]
PDO_INHIBIT_TIME_SUB = _OD.address("tpdo1_communication.inhibit_time")[1]
PDO_EVENT_TIMER_SUB = _OD.address("tpdo1_communication.event_timer")[1]
PDO_MAPPED_COUNT_SUB = _OD.address("tpdo1_mapping.number_of_mapped_objects")[1]
PDO_MAX_MAPPED = len(_OD.sub_names("tpdo1_mapping"))
"""Mapping entries a PDO has (sub 1..8)."""
for _kind, _n in (("rpdo", N_RPDO), ("tpdo", N_TPDO)):  # every PDO: the same sub-indices
    for _k in range(1, _n + 1):
        if (
            _OD.address(f"{_kind}{_k}_communication.cob_id")[1] != PDO_COB_ID_SUB
            or _OD.address(f"{_kind}{_k}_communication.transmission_type")[1]
            != PDO_TRANSMISSION_TYPE_SUB
            or _OD.address(f"{_kind}{_k}_communication.inhibit_time")[1] != PDO_INHIBIT_TIME_SUB
            or len(_OD.sub_names(f"{_kind}{_k}_mapping")) != PDO_MAX_MAPPED
        ):
            raise ValueError(f"{_kind.upper()}{_k}'s parameters are laid out unlike TPDO1's")

__all__ = ["PDO_INVALID", "PdoEngine", "is_pdo_config"]

logger = logging.getLogger(__name__)

PDO_INVALID = COB_INVALID
ABORT_INVALID_VALUE = abort_codes.INVALID_VALUE
ABORT_UNSUPPORTED_ACCESS = abort_codes.UNSUPPORTED_ACCESS
ABORT_CANNOT_MAP = abort_codes.PDO_CANNOT_MAP
ABORT_LENGTH_EXCEEDED = abort_codes.PDO_LENGTH_EXCEEDED
ABORT_DEVICE_STATE = abort_codes.DEVICE_STATE

_FMT = {
    odm.BOOLEAN: "?",
    odm.INTEGER8: "b",
    odm.INTEGER16: "h",
    odm.INTEGER32: "i",
    odm.UNSIGNED8: "B",
    odm.UNSIGNED16: "H",
    odm.UNSIGNED32: "I",
    odm.REAL32: "f",
    odm.INTEGER64: "q",
    odm.UNSIGNED64: "Q",
    odm.REAL64: "d",
}


def is_pdo_config(index: int) -> bool:
    return (
        RPDO_COMM <= index < RPDO_COMM + N_RPDO
        or RPDO_MAP <= index < RPDO_MAP + N_RPDO
        or TPDO_COMM <= index < TPDO_COMM + N_TPDO
        or TPDO_MAP <= index < TPDO_MAP + N_TPDO
    )


@dataclass
class _Tpdo:
    number: int
    cob_id: int
    trans_type: int
    event_s: float
    inhibit_s: float
    pack: Callable[..., bytes]
    getters: list[Callable[[], float | int]]
    #: when every mapped object is a live measurement: the dict they live in and an
    #: ``operator.itemgetter`` returning their values as a tuple (one C call per frame)
    live: dict | None = None
    pick: Callable[[dict], tuple] | None = None
    next_due: float = 0.0  # monotonic time of the next transmission (event-driven types)
    last_sent: float = -1e9
    sync_count: int = 0
    rtr: bool = False  #: COB-ID bit 30 = 0: a remote request (RTR) makes it send now


def _next_after(t: _Tpdo, at: float) -> float:
    """When event-driven ``t``, sent on time at ``at`` (s), is due next: one event period on,
    but not before its inhibit time has passed (CiA 301 §7.5.2.35)."""
    return at + (t.inhibit_s if t.inhibit_s > t.event_s else t.event_s)


@dataclass
class _Rpdo:
    number: int
    cob_id: int
    entries: list[tuple[int, int, int, int]] = field(default_factory=list)  # idx, sub, off, len
    size: int = 0


class PdoEngine:
    """Runs the node's PDOs.

    :param node: the local node (``object_dictionary``, ``get_data``, ``set_data``).
    :param send: ``send(cob_id, data)``.
    :param subscribe: ``subscribe(cob_id, callback)`` / ``unsubscribe(cob_id, callback)``.
    :param allowed: True in NMT OPERATIONAL.
    :param nmt_state: returns the NMT state code (0x7F pre-operational).
    :param fast_getter: ``(index, sub) → callable`` returning the live value, or None to read
        through ``node.get_data`` (slower).
    :param send_many: ``send_many([(cob_id, data), ...], at=None)`` puts the TPDOs due at one
        instant on the bus at once (one socket write on the hub client; ``at``: their due
        time, see :meth:`tick_at`); default: ``send`` each.
    :param align: ``align(t)`` → the first pacing tick at or after ``t``: event timers start
        there, so the frames are sent in the tick's wake-up (no second wake-up per period).
    :param stamp_max_age: the oldest bus time (s before now) the bus takes from
        ``send_many(frames, at)`` (:data:`virtual_drive.hub_protocol.SENDAT_MAX_BACKDATE_S`
        less a margin on the hub); see :meth:`tick_at`.
    """

    def __init__(
        self,
        node: DriveLocalNode,
        send: Callable[[int, bytes], None],
        subscribe: Callable,
        unsubscribe: Callable,
        allowed: Callable[[], bool],
        nmt_state: Callable[[], int],
        fast_getter: Callable[[int, int], Callable[[], float | int] | None] = lambda i, s: None,
        report: Callable[[int, bytes], object] = lambda code, data: None,
        clear: Callable[[int], object] = lambda code: None,
        send_many: Callable[..., None] | None = None,
        align: Callable[[float], float] = lambda t: t,
        stamp_max_age: float = math.inf,
    ) -> None:
        self.node = node
        self._send = send
        self._send_many = send_many
        #: oldest bus time (s before now) :meth:`tick_at` states; older ones are moved up
        self.stamp_max_age = stamp_max_age
        self._align = align
        self._subscribe = subscribe
        self._unsubscribe = unsubscribe
        self._allowed = allowed
        self._nmt_state = nmt_state
        self._fast_getter = fast_getter
        self._report = report
        self._clear = clear
        self._rx_error = False
        self.tpdos: list[_Tpdo] = []
        # tick's cache: the earliest due time of the table it last saw (configure() makes a
        # new table, so a changed configuration is never missed)
        self._earliest = 0.0
        self._tpdos_seen: list[_Tpdo] | None = None
        #: due_times' plan: (the table it was made from, {due time: [TPDOs due then]}, the
        #: table's event-driven TPDOs)
        self._plan: tuple[list[_Tpdo], dict[float, list[_Tpdo]], list[_Tpdo]] | None = None
        self.rpdos: dict[int, _Rpdo] = {}
        self.missed = [0] * N_TPDO  #: 0x2070: event periods without a frame, per TPDO
        self._wake = threading.Event()
        self._stopping = threading.Event()
        self._thread: threading.Thread | None = None
        self.sent = 0
        self.dropped_rx = 0  # RPDOs shorter than their mapping
        self.refused_rx = 0  # mapped values the write checks refused

    # -- helpers --------------------------------------------------------------------------
    def _u(self, index: int, sub: int) -> int:
        value = self.node.find_object(index, sub).decode_raw(self.node.get_data(index, sub))
        if isinstance(value, int):  # (the PDO parameters are UNSIGNED8..32)
            return value
        raise TypeError(f"0x{index:04X}:{sub} is not an integer: {value!r}")

    def _mapped(self, map_index: int) -> list[tuple[int, int, int]]:
        count = self._u(map_index, PDO_MAPPED_COUNT_SUB)
        out = []
        for s in range(1, count + 1):
            entry = self._u(map_index, s)
            out.append(((entry >> 16) & 0xFFFF, (entry >> 8) & 0xFF, entry & 0xFF))
        return out

    # -- configuration --------------------------------------------------------------------
    def configure(self) -> None:
        """(Re)build the PDO tables from the OD (after writes and NMT resets)."""
        for rpdo in self.rpdos.values():
            self._unsubscribe(rpdo.cob_id, self._on_rpdo)
        self.rpdos = {}
        for k in range(N_RPDO):
            cob = self._u(RPDO_COMM + k, PDO_COB_ID_SUB)
            if cob & PDO_INVALID:
                continue
            cob_id = cob & CAN_ID_MASK
            rpdo = _Rpdo(k + 1, cob_id)
            off = 0
            for index, sub, bits in self._mapped(RPDO_MAP + k):
                rpdo.entries.append((index, sub, off, bits // 8))
                off += bits // 8
            rpdo.size = off
            self.rpdos[cob_id] = rpdo
            self._subscribe(cob_id, self._on_rpdo)
        tpdos = []
        now = time.monotonic()
        for k in range(N_TPDO):
            cob = self._u(TPDO_COMM + k, PDO_COB_ID_SUB)
            if cob & PDO_INVALID:
                continue
            fmt = "<"
            getters = []
            for index, sub, _bits in self._mapped(TPDO_MAP + k):
                obj = self.node.find_object(index, sub)
                if obj.data_type is None:  # (canopen's ODVariable: a type from the EDS)
                    raise KeyError(f"0x{index:04X}:{sub} has no data type")
                fmt += _FMT[obj.data_type]
                getters.append(self._getter(index, sub, obj))
            event_ms = self._u(TPDO_COMM + k, PDO_EVENT_TIMER_SUB)
            items = [getattr(g, "live_item", None) for g in getters]
            pairs: list[tuple[dict, str]] = [it for it in items if it is not None]
            live = items[0][0] if items and items[0] is not None else None
            if len(items) < 2 or len(pairs) < len(items) or any(d is not live for d, _ in pairs):
                live = None
            tpdos.append(
                _Tpdo(
                    number=k + 1,
                    cob_id=cob & CAN_ID_MASK,
                    trans_type=self._u(TPDO_COMM + k, PDO_TRANSMISSION_TYPE_SUB),
                    event_s=event_ms / 1000.0,
                    inhibit_s=self._u(TPDO_COMM + k, PDO_INHIBIT_TIME_SUB) * 100e-6,
                    pack=struct.Struct(fmt).pack,
                    getters=getters,
                    live=live,
                    pick=None if live is None else operator.itemgetter(*(n for _, n in pairs)),
                    next_due=self._align(now + event_ms / 1000.0),
                    rtr=not cob & COB_BIT30,
                )
            )
        self.tpdos = tpdos
        self._wake.set()  # the timer thread recomputes its next wake-up

    def _getter(
        self, index: int, sub: int, obj: odm.ODVariable
    ) -> Callable[[], float | int]:
        fast = self._fast_getter(index, sub)
        if fast is not None:
            return fast
        node = self.node

        def read() -> float | int:
            value = obj.decode_raw(node.get_data(index, sub))
            if isinstance(value, (int, float)):  # (a mappable object is a number)
                return value
            raise TypeError(f"0x{index:04X}:{sub} is not a number: {value!r}")

        return read

    def check_write(self, index: int, sub: int, value: int) -> None:
        """Validate a write to a PDO parameter; raises SdoAbortedError to refuse it."""
        is_comm = TPDO_COMM <= index < TPDO_COMM + N_TPDO or RPDO_COMM <= index < RPDO_COMM + N_RPDO
        if is_comm:
            if sub == PDO_COB_ID_SUB:
                old = self._u(index, PDO_COB_ID_SUB)
                if self._nmt_state() == OPERATIONAL and value != old:
                    raise SdoAbortedError(ABORT_DEVICE_STATE)
                kind = "tpdo" if index >= TPDO_COMM else "rpdo"
                try:
                    check_cob_id(kind, value, old)  # CiA 301 restricted IDs, bits 29..11
                except LimitError as exc:
                    raise SdoAbortedError(exc.abort_code) from exc
            elif sub == PDO_TRANSMISSION_TYPE_SUB and 241 <= value <= 253:
                raise SdoAbortedError(ABORT_INVALID_VALUE)
            elif (
                sub == PDO_INHIBIT_TIME_SUB
                and value != self._u(index, PDO_INHIBIT_TIME_SUB)
                and not self._u(index, PDO_COB_ID_SUB) & PDO_INVALID
            ):
                raise SdoAbortedError(ABORT_INVALID_VALUE)  # inhibit time of a valid PDO
            return
        # mapping objects
        if self._nmt_state() == OPERATIONAL:
            raise SdoAbortedError(ABORT_DEVICE_STATE)
        receive = index < TPDO_MAP
        comm = index - (RPDO_MAP - RPDO_COMM if receive else TPDO_MAP - TPDO_COMM)
        if not self._u(comm, PDO_COB_ID_SUB) & PDO_INVALID:
            raise SdoAbortedError(ABORT_UNSUPPORTED_ACCESS)
        if sub != PDO_MAPPED_COUNT_SUB:
            if self._u(index, PDO_MAPPED_COUNT_SUB) != 0:
                raise SdoAbortedError(ABORT_UNSUPPORTED_ACCESS)
            return
        if value > PDO_MAX_MAPPED:
            raise SdoAbortedError(ABORT_LENGTH_EXCEEDED)
        total = 0
        for s in range(1, value + 1):
            entry = self._u(index, s)
            m_index, m_sub, bits = (entry >> 16) & 0xFFFF, (entry >> 8) & 0xFF, entry & 0xFF
            obj = self.node.find_object(m_index, m_sub)  # 0x06020000 / 0x06090011
            if not obj.pdo_mappable or len(obj) != bits or obj.data_type not in _FMT:
                raise SdoAbortedError(ABORT_CANNOT_MAP)
            if (receive and not obj.writable) or (not receive and not obj.readable):
                raise SdoAbortedError(ABORT_CANNOT_MAP)
            total += bits
        if total > 64:
            raise SdoAbortedError(ABORT_LENGTH_EXCEEDED)

    # -- runtime --------------------------------------------------------------------------
    def _on_rpdo(self, can_id: int, data: bytes, timestamp: float) -> None:
        if not self._allowed():
            return
        rpdo = self.rpdos.get(can_id)
        if rpdo is None:
            return
        if len(data) < rpdo.size:
            self.dropped_rx += 1
            self._rx_error = True
            self._report(RPDO_LENGTH, bytes([rpdo.number, len(data), rpdo.size]))
            return
        items = [(i, s, bytes(data[off : off + size])) for i, s, off, size in rpdo.entries]
        try:
            self.node.set_data_all(items)
        except SdoAbortedError as exc:
            index, sub = getattr(exc, "index", 0), getattr(exc, "subindex", 0)
            self.refused_rx += 1
            self._rx_error = True
            self._report(
                RPDO_VALUE, bytes([rpdo.number]) + struct.pack("<HBB", index, sub, exc.code & 0xFF)
            )
            if self.refused_rx <= 10 or self.refused_rx % 1000 == 0:
                logger.warning(
                    "RPDO%d dropped: 0x%04X:%02X refused (0x%08X), %d refused so far",
                    rpdo.number,
                    index,
                    sub,
                    exc.code,
                    self.refused_rx,
                )
            return
        if self._rx_error:
            self._rx_error = False
            self._clear(RPDO_LENGTH)
            self._clear(RPDO_VALUE)

    # -- event timer thread ---------------------------------------------------------------
    def start(self) -> None:
        """Start the event-timer thread (sleeps until the earliest due TPDO)."""
        if self._thread is not None:
            return
        self._stopping.clear()
        self._thread = threading.Thread(target=self._timer_loop, name="tpdo-timer", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        thread, self._thread = self._thread, None
        if thread is None:
            return
        self._stopping.set()
        self._wake.set()
        thread.join(2.0)

    def reset_counters(self) -> None:
        """0x2070 back to 0 (reset communication)."""
        self.missed = [0] * N_TPDO

    def _timer_loop(self) -> None:
        while not self._stopping.is_set():
            try:
                delay = self.tick(time.monotonic())
            except Exception:  # never let the timer die: log and go on
                logger.exception("TPDO timer")
                delay = 0.01
            if self._wake.wait(delay):
                self._wake.clear()

    def tick(self, now: float) -> float:
        """Send the event-driven TPDOs due at ``now``; return the seconds until the next one.

        A TPDO is due at its event-timer grid point, but never before its last transmission
        plus the inhibit time (CiA 301: minimum spacing). Lateness by whole event periods is
        counted in :attr:`missed` and the grid is kept (one frame, no burst). The frames due
        together go out in one ``send_many``.
        """
        return max(0.0, self._tick(now, False) - time.monotonic())

    def tick_at(self, at: float) -> float:
        """:meth:`tick` for a drive that runs its ticks in batches: the simulation stands at
        ``at`` (monotonic s, in the past), the TPDOs due then carry its values and are sent
        with ``at`` as their bus time (``send_many(frames, at)``); the inhibit time counts from
        ``at``. Returns the monotonic time the next TPDO is due.

        A time more than :attr:`stamp_max_age` s ago (the drive was not scheduled for that
        long) is stated as that long ago instead, and the event timers and inhibit times count
        from it: the bus would otherwise take the frames of a catch-up as all sent at its own
        oldest time and put them back to back, closer than their inhibit time."""
        floor = time.monotonic() - self.stamp_max_age
        if at < floor:
            return self._tick(floor, True)
        plan = self._plan
        if plan is not None and plan[0] is self.tpdos and self._allowed():
            planned = plan[1].pop(at, None)
            if planned is not None:  # (due_times found them due exactly then: none missed)
                self._send_tpdos(planned, at, True)
                for t in planned:
                    t.next_due = _next_after(t, at)
                earliest = at + 0.05
                for t in plan[2]:  # (every event-driven TPDO: another may be due first)
                    if t.next_due < earliest:
                        earliest = t.next_due
                return earliest
        return self._tick(at, True)

    def due_times(self, until: float) -> list[float]:
        """The instants (monotonic s, up to ``until``) :meth:`tick_at` will send event-driven
        TPDOs at, in order, from the present table (nothing is sent): a batched tick runs its
        simulation in one call and keeps the values of these instants. :meth:`tick_at` then
        sends the TPDOs planned for each instant without searching the table again (unless
        it was reconfigured meanwhile)."""
        tpdos = self.tpdos
        if not self._allowed():
            self._plan = None
            return []
        plan: dict[float, list[_Tpdo]] = {}
        event = [t for t in tpdos if t.event_s > 0 and t.trans_type >= 0xFE]
        for t in event:
            due = t.next_due
            while due <= until:
                # one instant to the µs: timers of different periods that meet (every 30 ms
                # for 2, 3 and 10 ms) differ there by the rounding of their sums, and the
                # TPDOs of one instant go in table order (lowest COB-ID first, as the bus's
                # arbitration would take them), not in the order of those rounding errors
                plan.setdefault(_floor(due * 1e6 + 0.5) * 1e-6, []).append(t)
                due = _next_after(t, due)
        self._plan = (tpdos, plan, event)
        return sorted(plan)

    def _tick(self, now: float, stamped: bool) -> float:
        idle = 0.05
        self._plan = None  # (a plan holds from due_times to the end of that tick only)
        if not self._allowed():
            return now + idle
        if now < self._earliest and self._tpdos_seen is self.tpdos:
            return self._earliest  # nothing due and nothing reconfigured: no work
        due: list[tuple[_Tpdo, int]] = []
        for t in self.tpdos:
            if t.event_s > 0 and t.trans_type >= 0xFE and now >= t.next_due:
                periods = int((now - t.next_due) // t.event_s)
                if periods:
                    self.missed[t.number - 1] = (self.missed[t.number - 1] + periods) & 0xFFFFFFFF
                due.append((t, periods))
        if due:
            self._send_tpdos([t for t, _ in due], now, stamped)
            # the inhibit time counts from the end of this send: on a busy host the send
            # itself may be delayed, and the next frame must still be inhibit_s later
            done = now if stamped else time.monotonic()
            for t, periods in due:
                grid = t.next_due + (periods + 1) * t.event_s
                if stamped and grid < now + t.event_s - 1e-9:
                    # a frame stated late (a catch-up): the next one slot later on the grid,
                    # never closer than the event period (CiA 301 restarts the event timer
                    # with each transmission; the slot it covered had its frame)
                    grid += t.event_s
                t.next_due = max(grid, done + t.inhibit_s) if t.inhibit_s > 0 else grid
        earliest = now + idle
        tpdos = self.tpdos
        for t in tpdos:
            if t.event_s > 0 and t.trans_type >= 0xFE and t.next_due < earliest:
                earliest = t.next_due
        self._earliest, self._tpdos_seen = earliest, tpdos
        return earliest

    def on_sync(self, can_id: int, data: bytes | bytearray, timestamp: float) -> None:
        """SYNC (0x080): synchronous TPDOs of type 1–240 go out every n-th SYNC."""
        if not self._allowed():
            return
        now = time.monotonic()
        for t in self.tpdos:
            if 1 <= t.trans_type <= 240:
                t.sync_count += 1
                if t.sync_count >= t.trans_type:
                    t.sync_count = 0
                    self._send_tpdo(t, now)

    def on_remote(self, can_id: int) -> bool:
        """A remote frame (RTR) on ``can_id``: a TPDO with that COB-ID whose bit 30 allows RTR
        is sent now (NMT OPERATIONAL only, never within its inhibit time, CiA 301
        §7.2.2.2); returns whether one was sent."""
        if not self._allowed():
            return False
        now = time.monotonic()
        for t in self.tpdos:
            if t.cob_id == can_id and t.rtr:
                if now - t.last_sent < t.inhibit_s:
                    return False
                self._send_tpdo(t, now)
                return True
        return False

    def _payload(self, t: _Tpdo) -> bytes | None:
        try:
            pick = t.pick  # (set with live: the measurements' one itemgetter)
            if pick is not None and t.live is not None:
                return t.pack(*pick(t.live))
            return t.pack(*[g() for g in t.getters])
        except (struct.error, SdoAbortedError) as exc:
            logger.warning("TPDO%d not sent: %s", t.number, exc)
            return None

    def _send_tpdo(self, t: _Tpdo, now: float) -> None:
        payload = self._payload(t)
        if payload is None:
            return
        self._send(t.cob_id, payload)
        t.last_sent = now
        self.sent += 1

    def _send_tpdos(self, tpdos: list[_Tpdo], now: float, stamped: bool = False) -> None:
        if self._send_many is None or (len(tpdos) == 1 and not stamped):
            for t in tpdos:
                self._send_tpdo(t, now)
            return
        frames = []
        for t in tpdos:
            payload = self._payload(t)
            if payload is not None:
                frames.append((t.cob_id, payload))
                t.last_sent = now
        if frames:
            self._send_many(frames, now if stamped else None)
            self.sent += len(frames)
