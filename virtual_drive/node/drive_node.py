"""The virtual drive as a CANopen CiA 402 node: assembly of the services around the simulator.

>>> import can
>>> from virtual_drive.node import VirtualDrive
>>> bus = can.Bus(interface="virtual", channel="bench", receive_own_messages=False)
>>> drive = VirtualDrive(bus, node_id=1).start()     # boot-up sent, PRE-OPERATIONAL
>>> drive.sim.time                                   # simulated seconds (s)
>>> drive.stop()

Threads: the python-can Notifier thread runs every received frame (SDO servers, NMT, RPDOs,
heartbeat stamps) — all short; the pacing loop (:mod:`.runner`) runs the simulator in chunks and
the periodic services. Simulator calls are serialised by :attr:`VirtualDrive.sim_lock`, so new
gains and setpoints take effect at a chunk (sample) boundary.

Object values: parameters live in the canopen LocalNode's data store (raw bytes, defaults from
the EDS); live values (statusword, measurements, trace data, error objects) are computed on read.
"""

from __future__ import annotations

import errno
import logging
import math
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import can
import canopen
from canopen import objectdictionary as odm
from canopen.node.local import LocalNode
from canopen.sdo import SdoAbortedError

from firmware_protocol import abort_codes
from firmware_protocol.cia402 import CW_HALT, SW_SPEED_ZERO
from firmware_protocol.cob_id import check_cob_id, check_heartbeat_consumers
from firmware_protocol.current_stability import (
    CURRENT_KEYS,
    MOTOR_KEYS,
    check_cascade,
    check_current_gains,
)
from firmware_protocol.entry import LimitError
from firmware_protocol.enums import StoreStatus
from firmware_protocol.od import load_od
from firmware_protocol.stability import check_ip_speed_gains

from . import cia402 as sm
from . import plant, storage
from .cia402 import Cia402StateMachine
from .emcy import DATA_SET_LOST, HEARTBEAT_LOSS, NMT_CONNECTION_LOSS, EmcyManager
from .heartbeat import HeartbeatConsumer, HeartbeatProducer
from .nmt import CMD_RESET_COMMUNICATION, CMD_RESET_NODE, OPERATIONAL, NmtSlave
from .params import ParamChecker
from .pdo import PdoEngine, is_pdo_config
from .recorder import (
    ARMED,
    CMD_ARM,
    CMD_FORCE,
    CMD_STOP,
    RECORDING,
    TraceConfigError,
    TraceRecorder,
)
from .runner import TS, Runner
from .sdo_block import BlockSdoServer

logger = logging.getLogger(__name__)

ABORT_READ_WRITEONLY = abort_codes.READ_WRITE_ONLY
ABORT_WRITE_READONLY = abort_codes.WRITE_READ_ONLY
ABORT_LENGTH = abort_codes.LENGTH
ABORT_INVALID_VALUE = abort_codes.INVALID_VALUE
ABORT_PARAM_INCOMPATIBLE = abort_codes.PARAM_INCOMPATIBLE
ABORT_HARDWARE = abort_codes.HARDWARE
ABORT_STORE = abort_codes.STORE
ABORT_DEVICE_STATE = abort_codes.DEVICE_STATE
ABORT_NO_OBJECT = abort_codes.NO_OBJECT
ABORT_NO_SUBINDEX = abort_codes.NO_SUBINDEX

MODE_CURRENT = -1  #: manufacturer mode: i_p* = setpoints.i_p_ref (A)
MODE_PROFILE_VELOCITY = 3
MODE_PROFILE_TORQUE = 4
SUPPORTED_MODES = (MODE_CURRENT, MODE_PROFILE_VELOCITY, MODE_PROFILE_TORQUE)

#: measurements sub-index → simulator signal name (contracts §1, 0x2040)
MEASUREMENTS = {
    1: "i_p",
    2: "i_a",
    3: "i_b",
    4: "i_c",
    5: "speed",
    6: "v_L",
    7: "e_L",
    8: "m",
    9: "hall_sector",
    10: "i_p_ref",
    11: "speed_ref",
    12: "V_dc",
    13: "T_e",
    14: "theta_e",
}

SPEED_ZERO_RPM = 10.0  #: |speed| below this counts as standstill (end of a stop ramp)
RESET_BRAKE_LIMIT_S = 5.0  #: a deferred reset node completes after this much braking anyway (s)
CURRENT_WINDOW_A = 1.0  #: target reached window in the current modes (A)


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


class VirtualDrive:
    """The virtual drive node on a python-can bus.

    :param bus: any python-can bus (virtual, socketcand to the loopback hub, socketcan).
    :param node_id: CANopen node-ID (1..127; 0x1201 defaults valid for N ≤ 47).
    :param store_path: parameter file for 0x1010/0x1011 (None: store refused with 0x08000020).
    :param speed: simulated seconds per wall-clock second (tests use > 1).
    :param sim: a ready :class:`virtual_drive.sim.Simulator` (default: a new one, PWM-exact).
    """

    def __init__(
        self,
        bus: can.BusABC,
        node_id: int = 1,
        store_path: str | Path | None = None,
        speed: float = 1.0,
        sim: Any = None,
        period: float = 1e-3,
    ) -> None:
        if not 1 <= node_id <= 127:
            raise ValueError(f"node_id must be 1..127, got {node_id}")
        self.bus = bus
        self.node_id = node_id
        self.store_path = Path(store_path) if store_path is not None else None
        self.speed = float(speed)
        self.view = load_od(node_id=node_id)
        self.od = self.view.canopen_od(node_id)
        if sim is None:
            from virtual_drive.sim import Simulator

            sim = Simulator()
        self.sim = sim
        self.sim_lock = threading.RLock()
        self._write_lock = threading.RLock()
        self._send_lock = threading.Lock()
        self.tx_errors = 0
        self.last_tx_ok = time.monotonic()  #: time of the last frame the bus accepted
        self.taps: list[Callable[[dict], None]] = []
        self.live: dict[str, float] = {name: 0.0 for name in MEASUREMENTS.values()}
        self.live["hall_sector"] = 1
        self.store_error: str | None = None
        self.store_status = StoreStatus.DEFAULTS  #: 0x2060, set by every parameter load
        self._pcache: dict[tuple[int, int], Any] = {}

        self.network = canopen.Network(bus)
        self.node = DriveLocalNode(node_id, self.od, self)
        self.network.add_node(self.node)
        self.nmt = NmtSlave(
            node_id,
            self._send,
            on_reset_node=self._reset_application,
            on_reset_communication=self._reset_communication,
            on_state_change=self._on_nmt_change,
            on_abort_connection=self._on_nmt_abort_connection,
            on_boot=self._on_boot,
        )
        self.emcy = EmcyManager(0x80 + node_id, self._send, self.nmt.emcy_allowed)
        self.sdo = BlockSdoServer(
            0x600 + node_id, 0x580 + node_id, self.node, self.nmt.sdo_allowed, send=self._send
        )
        self.node.sdo = self.sdo
        self.sdo2: BlockSdoServer | None = None
        self.hb_producer = HeartbeatProducer(node_id, self._send, lambda: self.nmt.state)
        self.hb_consumer = HeartbeatConsumer(
            self.network.subscribe,
            self.network.unsubscribe,
            self._on_heartbeat_lost,
            self._on_heartbeat_back,
        )
        self.pdo = PdoEngine(
            self.node,
            self._send,
            self.network.subscribe,
            self.network.unsubscribe,
            self.nmt.pdo_allowed,
            lambda: self.nmt.state,
            lambda i, s: self._live_getters.get((i, s)),
            report=self.emcy.raise_error,
            clear=self.emcy.clear_error,
        )
        self.cia402 = Cia402StateMachine(self._options, self._reset_fault)
        self.recorder = TraceRecorder()
        self.checker = ParamChecker(self.view, self._current_by_name)
        self.runner = Runner(self._step, self._periodic, speed=self.speed, period=period)
        self._live_getters = self._make_live_getters()
        # control state (touched by the runner between chunks)
        self._mode = MODE_PROFILE_VELOCITY
        self._sim_mode = "off"
        self._speed_ref = 0.0  # profile output (rpm) fed to the IP loop
        self._i_ref = 0.0  # torque-profile output (A) in the current modes
        self._i_target = 0.0  # where _i_ref is heading (A)
        # since when (sim time, s) |speed - target| <= 0x606D / |speed| <= 0x606F, and for
        # which velocity target the window was measured
        self._window_since: float | None = None
        self._window_target = 0.0
        self._threshold_since: float | None = None
        self._last_fault = None
        self._started = False
        self._reset_deferred_at: float | None = None  # sim time of a deferred reset node
        if self.store_path is not None:
            storage.remove_stale_temps(self.store_path)  # left by a kill during a store
        self._load_parameters()
        # frames reach these only while start() has a Notifier running
        self.network.subscribe(0x000, self.nmt.on_command)
        self.network.subscribe(self.sdo.rx_cobid, self.sdo.on_request)
        self.network.subscribe(0x080, self.pdo.on_sync)

    # -- lifecycle ------------------------------------------------------------------------
    def start(self) -> VirtualDrive:
        """Attach to the bus, send the boot-up message and start the pacing loop."""
        if self._started:
            return self
        self._started = True
        self.network.notifier = can.Notifier(self.bus, self.network.listeners, 0.2)
        self.nmt.boot()
        self.pdo.start()
        self.runner.start()
        logger.info(
            "virtual drive node %d up (speed x%g, store %s)",
            self.node_id,
            self.speed,
            self.store_path or "none",
        )
        return self

    def stop(self) -> None:
        """Stop the pacing loop and detach from the bus (the bus itself is not shut down)."""
        if not self._started:
            return
        self._started = False
        self.runner.stop()
        self.pdo.stop()
        if self.network.notifier is not None:
            self.network.notifier.stop(2.0)
            self.network.notifier = None

    def __enter__(self) -> VirtualDrive:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    # -- bus ------------------------------------------------------------------------------
    def _send(self, cob_id: int, data: bytes) -> None:
        """Put one frame on the bus; never raises (errors are counted in ``tx_errors``).

        A full transmit queue (SocketCAN's ENOBUFS with the default ``txqueuelen 10``, e.g. in
        a 127-frame block-upload burst) is retried for up to 10 ms before the frame is dropped.
        """
        msg = can.Message(arbitration_id=cob_id, data=data, is_extended_id=False)
        for attempt in range(21):
            try:
                with self._send_lock:
                    self.bus.send(msg)
                self.last_tx_ok = time.monotonic()
                return
            except (can.CanError, OSError) as exc:
                full = getattr(exc, "errno", None) == errno.ENOBUFS or "No buffer space" in str(exc)
                if full and attempt < 20:
                    time.sleep(0.0005)
                    continue
                self.tx_errors += 1
                if self.tx_errors < 10 or self.tx_errors % 1000 == 0:
                    logger.warning("send 0x%03X failed: %s", cob_id, exc)
                return

    # -- parameters -----------------------------------------------------------------------
    def _current_by_name(self, name: str) -> float | int:
        e = self.view.entry(name)
        return self.node.stored(e.index, e.subindex)

    def _value(self, index: int, sub: int = 0) -> Any:
        """Present parameter value (cached; every write to the data store clears the cache)."""
        key = (index, sub)
        try:
            return self._pcache[key]
        except KeyError:
            value = self._pcache[key] = self.node.stored(index, sub)
            return value

    def _load_parameters(self) -> None:
        """Stored parameters (or defaults) into the data store and the simulator."""
        self.node.data_store.clear()
        self._pcache.clear()
        stored, self.store_status, self.store_error = self._read_store()
        for (index, sub), raw in stored.items():
            e = self.checker.entry(index, sub)
            try:
                obj = self.node._find_object(index, sub)
                if e is None or not e.persistent or 8 * len(raw) != len(obj):
                    raise ValueError("not a stored parameter")
                e.check(obj.decode_raw(raw))
            except (ValueError, SdoAbortedError) as exc:
                logger.error("stored 0x%04X:%02X ignored: %s", index, sub, exc)
                continue
            self.node.data_store.setdefault(index, {})[sub] = raw
        self._pcache.clear()
        problem = self._rules_broken()
        if problem is not None:  # e.g. a store from before a rule existed: not applied at all
            logger.error("stored parameters break a rule, defaults used: %s", problem)
            self.node.data_store.clear()
            self._pcache.clear()
            self.store_status, self.store_error = StoreStatus.DAMAGED, problem
        self._push_plant()
        self._configure_communication()

    def _rules_broken(self) -> str | None:
        """Why the present parameter set breaks a cross-object or stability rule, or None."""
        values = {
            e.name: self.node.stored(e.index, e.subindex)
            for e in self.view
            if e.data_type in odm.NUMBER_TYPES and e.bit_length
        }
        try:
            self.view.check_constraints(values)
            check_ip_speed_gains(values["speed_controller.k_p"], values["speed_controller.k_i"])
            gains = {k: values[f"current_controller.{k}"] for k in CURRENT_KEYS}
            motor = {k: values[f"motor.{k}"] for k in MOTOR_KEYS}
            check_current_gains(gains, motor)
            check_cascade(
                gains, motor, values["speed_controller.k_p"], values["speed_controller.k_i"]
            )
        except LimitError as exc:
            return str(exc)
        return None

    def _read_store(self) -> tuple[dict[tuple[int, int], bytes], StoreStatus, str | None]:
        """The store file's values, its 0x2060 status and the error text (None if fine)."""
        if self.store_path is None:
            return {}, StoreStatus.DEFAULTS, None
        try:
            stored = storage.load(self.store_path)
        except storage.StoreCorruptError as exc:
            logger.error("parameter file damaged, defaults used: %s", exc)
            return {}, StoreStatus.DAMAGED, str(exc)
        except OSError as exc:
            logger.error("parameter file unreadable, defaults used: %s", exc)
            return {}, StoreStatus.UNREADABLE, str(exc)
        return stored, (StoreStatus.OK if stored else StoreStatus.DEFAULTS), None

    def _push_plant(self) -> None:
        """Every plant/controller object's present value into the simulator."""
        with self.sim_lock:
            for index, (name, kw) in plant.SETTERS.items():
                setter = getattr(self.sim, name, None)
                if setter is None:
                    continue
                values = {key: self._value(index, sub) for sub, key in kw.items()}
                try:
                    setter(**values)
                except (ValueError, TypeError) as exc:
                    logger.error("simulator refused %s(%s): %s", name, values, exc)
            self._apply_current_limit()

    def _apply_current_limit(self) -> None:
        rated = self._value(0x6075) / 1000.0
        cap = self._value(0x6073) / 1000.0 * rated
        limit = min(self._value(0x2020, 3), cap)
        try:
            self.sim.set_speed_gains(current_limit=limit)
        except (ValueError, TypeError) as exc:
            logger.error("current limit %.3g A refused: %s", limit, exc)

    def _configure_communication(self) -> None:
        now = time.monotonic()
        self.hb_producer.set_period(self._value(0x1017), now)
        self.hb_consumer.configure(self._consumer_entries())
        self.emcy.set_cob_id(self._value(0x1014))
        self._bind_sdo2()
        self.pdo.configure()

    def _consumer_entries(self, sub: int = 0, value: int = 0) -> list[int]:
        """0x1016 sub 1..N present values (with ``value`` in place of ``sub`` if given)."""
        count = self._value(0x1016, 0)
        return [value if s == sub else self._value(0x1016, s) for s in range(1, count + 1)]

    def _bind_sdo2(self) -> None:
        rx, tx = self._value(0x1201, 1), self._value(0x1201, 2)
        if self.sdo2 is not None:
            self.network.unsubscribe(self.sdo2.rx_cobid, self.sdo2.on_request)
            self.sdo2 = None
        if rx & 0x80000000 or tx & 0x80000000:
            return
        self.sdo2 = BlockSdoServer(
            rx & 0x7FF, tx & 0x7FF, self.node, self.nmt.sdo_allowed, send=self._send
        )
        self.network.subscribe(self.sdo2.rx_cobid, self.sdo2.on_request)

    def _reset_communication(self) -> None:
        """NMT reset communication: 0x1000–0x1FFF back to stored values or defaults (CiA 301).

        Exception: while the power stage is still on after the 0x6007 reaction (a stop ramp
        still braking) the consumer heartbeat 0x1016 keeps its present value, so the master's
        supervision is never dropped while the motor can turn.
        """
        keep_1016 = self.cia402.torque_enabled
        kept = dict(self.node.data_store.get(0x1016, {})) if keep_1016 else {}
        stored, _status, _error = self._read_store()
        for index in [i for i in self.node.data_store if i < 0x2000]:
            del self.node.data_store[index]
        for (index, sub), raw in stored.items():
            if index < 0x2000 and index in self.od:
                self.node.data_store.setdefault(index, {})[sub] = raw
        if keep_1016:
            self.node.data_store.pop(0x1016, None)
            if kept:
                self.node.data_store[0x1016] = kept
        self._pcache.clear()
        self.pdo.reset_counters()
        self._configure_communication()

    def _reset_application(self) -> bool:
        """NMT reset node: all parameters to stored values, drive to SWITCH ON DISABLED.

        Runs after the 0x6007 reaction. While its stop ramp still brakes the motor the reset is
        deferred (returns False): the pacing loop completes it at standstill (or after
        :data:`RESET_BRAKE_LIMIT_S`), then the node boots. The motor is never left turning under
        a freshly reset, unsupervised application.
        """
        if self.cia402.torque_enabled:
            self._reset_deferred_at = float(self.sim.time)
            logger.info("reset node deferred until the stop ramp ends")
            return False
        self._do_reset_application()
        return True

    def _finish_deferred_reset(self) -> None:
        """Pacing loop: complete a deferred reset node once the motor is braked."""
        started = self._reset_deferred_at
        if started is None:
            return
        braked = not self.cia402.torque_enabled
        if not braked and float(self.sim.time) - started < RESET_BRAKE_LIMIT_S:
            return
        self._reset_deferred_at = None
        with self._write_lock:
            self._do_reset_application()
        self.nmt.finish_reset()

    def _do_reset_application(self) -> None:
        with self.sim_lock:
            self.cia402 = Cia402StateMachine(self._options, self._reset_fault)
            self._set_sim_mode("off")
            self.sim.set_current_ref(0.0)
            self.sim.set_speed_ref(0.0)
            self._speed_ref = 0.0
            self.recorder.stop()
            self.sim.reset_fault()
            self._sim_mode = "off"
            self._last_fault = None
        self.emcy.clear_all()
        self._mode = MODE_PROFILE_VELOCITY
        self._load_parameters()
        return None

    def save_parameters(self) -> None:
        """0x1010 "save": persistent objects' present values to the store file (atomic)."""
        if self.store_path is None:
            raise SdoAbortedError(ABORT_STORE)
        values = {}
        for e in self.view:
            if not e.persistent:
                continue
            values[(e.index, e.subindex)] = LocalNode.get_data(self.node, e.index, e.subindex)
        try:
            storage.save(self.store_path, values)
        except OSError as exc:
            logger.error("store failed: %s", exc)
            raise SdoAbortedError(ABORT_HARDWARE) from exc
        logger.info("parameters stored to %s", self.store_path)
        # the store now holds the parameters in use: healthy again
        self.store_status, self.store_error = StoreStatus.OK, None
        self.emcy.clear_error(DATA_SET_LOST)

    def restore_defaults(self) -> None:
        """0x1011 "load": defaults apply after the next reset node / restart."""
        if self.store_path is None:
            raise SdoAbortedError(ABORT_STORE)
        try:
            storage.save(self.store_path, {})
        except OSError as exc:
            raise SdoAbortedError(ABORT_HARDWARE) from exc
        logger.info("defaults restored in %s (active after reset)", self.store_path)

    # -- reads ----------------------------------------------------------------------------
    def _make_live_getters(self) -> dict[tuple[int, int], Callable[[], Any]]:
        live = self.live
        g: dict[tuple[int, int], Callable[[], Any]] = {
            (0x1001, 0): lambda: self.emcy.error_register,
            (0x2060, 0): lambda: int(self.store_status),
            (0x2070, 1): lambda: self.pdo.missed[0],
            (0x2070, 2): lambda: self.pdo.missed[1],
            (0x2070, 3): lambda: self.pdo.missed[2],
            (0x2070, 4): lambda: self.pdo.missed[3],
            (0x1003, 0): lambda: len(self.emcy.history),
            (0x603F, 0): lambda: self.emcy.last_code,
            (0x6041, 0): self.statusword,
            (0x6061, 0): lambda: self._mode,
            (0x606C, 0): lambda: _clamp_int(live["speed"], 32),
            (0x6077, 0): lambda: _clamp_int(
                live["T_e"] / (self._value(0x6076) / 1000.0) * 1000.0, 16
            ),
            (0x6078, 0): lambda: _clamp_int(
                live["i_p"] / (self._value(0x6075) / 1000.0) * 1000.0, 16
            ),
            (0x6079, 0): lambda: max(0, round(live["V_dc"] * 1000.0)),
            (0x2100, 10): lambda: self.recorder.state,
            (0x2100, 11): lambda: self.recorder.trigger_position,
            (0x2100, 12): lambda: self.recorder.capacity,
            (0x2102, 0): self.recorder.data_bytes,
            (0x5030, 1): lambda: float(self.sim.time),
            (0x5030, 2): lambda: self.speed,
        }
        for k in range(1, 9):
            g[(0x1003, k)] = lambda k=k: (
                self.emcy.history[k - 1] if k <= len(self.emcy.history) else 0
            )
        for sub, name in MEASUREMENTS.items():
            if name == "hall_sector":
                g[(0x2040, sub)] = lambda: int(live["hall_sector"])
            else:
                g[(0x2040, sub)] = lambda name=name: float(live[name])
        return g

    def statusword(self) -> int:
        """0x6041 from the CiA 402 state and the live values."""
        live = self.live
        st = self.cia402
        reached = False
        limit = False
        mode_bits = 0
        if st.state == sm.QUICK_STOP_ACTIVE:
            # CiA 402: in QUICK STOP ACTIVE (0x605A 5..8) bit 10 = the axis is stopped
            reached = st.ramp is None
        elif st.state == sm.OPERATION_ENABLED or st.ramp is not None:
            if self._mode == MODE_PROFILE_VELOCITY:
                reached = self._velocity_reached()
                limit = abs(live["i_p_ref"]) >= 0.999 * self._value(0x2020, 3)
            else:
                reached = (
                    self._i_ref == self._i_target
                    and abs(live["i_p"] - live["i_p_ref"]) <= CURRENT_WINDOW_A
                )
        if self._mode == MODE_PROFILE_VELOCITY and self._held(
            self._threshold_since, self._value(0x6070)
        ):
            mode_bits |= SW_SPEED_ZERO
        return st.statusword(
            target_reached=reached,
            internal_limit=limit,
            warning=bool(self.hb_consumer.lost),
            mode_bits=mode_bits,
        )

    def _velocity_target(self) -> float:
        """Velocity (rpm) bit 10 compares with: 0 during a stop ramp or halt, else 0x60FF."""
        st = self.cia402
        if st.ramp is not None or st.controlword & CW_HALT:
            return 0.0
        return float(self._value(0x60FF))

    def _held(self, since: float | None, time_ms: int) -> bool:
        return since is not None and float(self.sim.time) - since >= time_ms / 1000.0 - 1e-9

    def _velocity_reached(self) -> bool:
        """|speed - target| <= 0x606D continuously for 0x606E ms, for the present target."""
        if self._velocity_target() != self._window_target:
            return False  # target changed since the last chunk: not measured yet
        return self._held(self._window_since, self._value(0x606E))

    def _update_windows(self) -> None:
        """After a chunk: restart or keep the velocity window / threshold timers (sim time)."""
        t = float(self.sim.time)
        speed = float(self.live["speed"])
        target = self._velocity_target()
        inside = abs(speed - target) <= self._value(0x606D)
        if not inside or target != self._window_target:
            self._window_since = t if inside else None
        elif self._window_since is None:
            self._window_since = t
        self._window_target = target
        if abs(speed) <= self._value(0x606F):
            if self._threshold_since is None:
                self._threshold_since = t
        else:
            self._threshold_since = None

    # -- writes ---------------------------------------------------------------------------
    def _before_write(
        self, index: int, sub: int, obj: odm.ODVariable, data: bytes
    ) -> tuple[bool, Callable[[], None] | None]:
        """Check a write and say whether to store it and what to do after storing.

        Raises SdoAbortedError to refuse it (nothing changes).
        """
        value: Any = data if obj.data_type not in odm.NUMBER_TYPES else obj.decode_raw(data)
        if index == 0x1003:
            if sub != 0 or value != 0:
                raise SdoAbortedError(ABORT_INVALID_VALUE)
            return False, self.emcy.clear_history
        if index == 0x1010:
            if value != storage.SAVE_SIGNATURE:
                raise SdoAbortedError(ABORT_STORE)
            self.save_parameters()
            return False, None
        if index == 0x1011:
            if value != storage.LOAD_SIGNATURE:
                raise SdoAbortedError(ABORT_STORE)
            self.restore_defaults()
            return False, None
        if index == 0x20F1:
            self.checker.check(index, sub, value)
            self._apply_gain_set(int(value))
            return False, None
        if index == 0x6060:
            if self.cia402.state == sm.OPERATION_ENABLED:
                raise SdoAbortedError(ABORT_DEVICE_STATE)
            if value not in SUPPORTED_MODES:
                raise SdoAbortedError(ABORT_INVALID_VALUE)
        entry = self.checker.entry(index, sub)
        if entry is not None and entry.config_only and self.cia402.torque_enabled:
            raise SdoAbortedError(ABORT_DEVICE_STATE)  # plant definition: power stage off only
        if is_pdo_config(index):
            self.checker.check(index, sub, value)
            self.pdo.check_write(index, sub, value)
            return True, self.pdo.configure
        value = self.checker.check(index, sub, value)
        if index == 0x1016:
            entries = self._consumer_entries(sub, value)
            try:  # CiA 301: node-ID 1..127, one entry per node, reserved bits 0
                check_heartbeat_consumers(entries, own_node_id=self.node_id)
            except LimitError as exc:
                raise SdoAbortedError(exc.abort_code) from exc
            return True, lambda: self.hb_consumer.configure(entries)
        if index == 0x1017:
            return True, lambda: self.hb_producer.set_period(value, time.monotonic())
        if index == 0x1014:
            self._check_cob_id("emcy", value, self._value(0x1014))
            return True, lambda: self.emcy.set_cob_id(value)
        if index == 0x1201:
            if sub in (1, 2):
                self._check_cob_id("sdo", value, self._value(0x1201, sub))
            return True, self._bind_sdo2
        if index == 0x6040:
            return True, lambda: self.cia402.write_controlword(value)
        if index == 0x6060:
            return True, lambda: setattr(self, "_mode", int(value))
        if index in (0x6073, 0x6075) or (index == 0x2020 and sub == 3):
            return True, self._after_limit_change(index, sub, value)
        if index in plant.SETTERS:
            with self.sim_lock:
                try:
                    plant.apply(self.sim, index, sub, value)
                except plant.PlantError as exc:
                    logger.info("0x%04X:%02X = %r refused: %s", index, sub, value, exc)
                    raise SdoAbortedError(ABORT_INVALID_VALUE) from exc
            return True, None
        if index == 0x2100:
            return self._trace_config_write(sub, value)
        if index == 0x2101:
            self._check_trace_channel(value)
            return True, None
        if index == 0x5010:
            self._fault_write(sub, value)
            return True, None
        if index == 0x5030 and sub == 3:
            return True, self._model_write(value)
        return True, None

    @staticmethod
    def _check_cob_id(kind: str, new: int, old: int) -> None:
        try:
            check_cob_id(kind, new, old)
        except LimitError as exc:
            raise SdoAbortedError(exc.abort_code) from exc

    def _after_limit_change(self, index: int, sub: int, value: Any) -> Callable[[], None]:
        def after() -> None:
            with self.sim_lock:
                self._apply_current_limit()

        if index == 0x2020:
            with self.sim_lock:
                try:
                    plant.apply(self.sim, index, sub, value)
                except plant.PlantError as exc:
                    raise SdoAbortedError(ABORT_INVALID_VALUE) from exc
        return after

    def _apply_gain_set(self, which: int) -> None:
        """0x20F1: staged 0x20F0 → active current (1), speed (2) or both (3) at one boundary."""
        staged = {sub: self._value(0x20F0, sub) for sub in range(1, 14)}
        changes: dict[str, float | int] = {}
        current_kw = {}
        speed_kw = {}
        if which & 1:
            for sub, key in plant.CURRENT_KW.items():
                current_kw[key] = staged[sub]
                changes[f"current_controller.{key}"] = staged[sub]
            changes["gain_set.L_c"] = staged[2]
        if which & 2:
            for sub, key in plant.GAIN_SET_SPEED_KW.items():
                speed_kw[key] = staged[sub]
            changes["speed_controller.current_limit"] = staged[13]
        for name, value in changes.items():
            self.checker.check(*_index_of(self.view, name), value)
        self.checker.check_rules(changes, staged=True)
        if which & 2:
            self.checker.check_speed_gains(staged[11], staged[12])
        self.checker.check_current_set(
            {}, gains=current_kw, speed=(staged[11], staged[12]) if which & 2 else None
        )
        with self.sim_lock:
            old_current = {k: self._value(0x2010, s) for s, k in plant.CURRENT_KW.items()}
            try:
                if current_kw:
                    self.sim.set_current_gains(**current_kw)
                if speed_kw:
                    self.sim.set_speed_gains(**speed_kw)
                    self._apply_current_limit_with(staged[13])
            except (ValueError, TypeError) as exc:
                if current_kw:  # undo a half-applied set: the old one was valid
                    self.sim.set_current_gains(**old_current)
                raise SdoAbortedError(ABORT_INVALID_VALUE) from exc
            store = self.node.data_store
            for sub, key in plant.CURRENT_KW.items():
                if key in current_kw:
                    var = self.node._find_object(0x2010, sub)
                    store.setdefault(0x2010, {})[sub] = var.encode_raw(current_kw[key])
            for sub, key in plant.SPEED_KW.items():
                if key in speed_kw:
                    var = self.node._find_object(0x2020, sub)
                    store.setdefault(0x2020, {})[sub] = var.encode_raw(speed_kw[key])
            self._pcache.clear()
        logger.info("gain set %d applied at t = %.6f s", which, self.sim.time)

    def _apply_current_limit_with(self, speed_limit: float) -> None:
        rated = self._value(0x6075) / 1000.0
        cap = self._value(0x6073) / 1000.0 * rated
        self.sim.set_speed_gains(current_limit=min(speed_limit, cap))

    def _trace_config_write(self, sub: int, value: Any) -> tuple[bool, Callable[[], None] | None]:
        rec = self.recorder
        if sub == 9:
            if value == CMD_STOP:
                return True, rec.stop
            self._configure_recorder()
            if value == CMD_ARM:
                try:
                    rec.arm()
                except TraceConfigError as exc:
                    raise SdoAbortedError(ABORT_INVALID_VALUE) from exc
            elif value == CMD_FORCE:
                rec.force()
            return True, None
        if rec.state in (1, 2):  # armed / recording: configuration is frozen
            raise SdoAbortedError(ABORT_DEVICE_STATE)
        if sub == 5:
            self._check_trace_channel(value, allow_zero=False)
        return True, None

    def _check_trace_channel(self, ref: int, allow_zero: bool = True) -> None:
        if ref == 0 and allow_zero:
            return
        index, sub, bits = (ref >> 16) & 0xFFFF, (ref >> 8) & 0xFF, ref & 0xFF
        if index != 0x2040 or sub not in MEASUREMENTS:
            raise SdoAbortedError(ABORT_INVALID_VALUE)
        if bits != len(self.node._find_object(index, sub)):
            raise SdoAbortedError(ABORT_INVALID_VALUE)

    def _configure_recorder(self) -> None:
        """Copy 0x2100/0x2101 into the recorder (before arming)."""
        rec = self.recorder
        count = self._value(0x2100, 1)
        channels = []
        for k in range(1, count + 1):
            ref = self._value(0x2101, k)
            sub = (ref >> 8) & 0xFF
            if (ref >> 16) != 0x2040 or sub not in MEASUREMENTS:
                raise SdoAbortedError(ABORT_INVALID_VALUE)
            channels.append(MEASUREMENTS[sub])
        src = self._value(0x2100, 5)
        if (src >> 16) != 0x2040 or ((src >> 8) & 0xFF) not in MEASUREMENTS:
            raise SdoAbortedError(ABORT_INVALID_VALUE)
        length = self._value(0x2100, 3)
        pre = self._value(0x2100, 4)
        divider = self._value(0x2100, 2)
        try:
            rec.check(channels, length, pre, divider)
        except TraceConfigError as exc:
            raise SdoAbortedError(ABORT_INVALID_VALUE) from exc
        rec.channels = channels
        rec.length = length
        rec.pre_trigger = pre
        rec.divider = divider
        rec.trigger_source = MEASUREMENTS[(src >> 8) & 0xFF]
        rec.trigger_level = float(self._value(0x2100, 6))
        rec.trigger_edge = self._value(0x2100, 7)
        rec.trigger_mode = self._value(0x2100, 8)

    def _fault_write(self, sub: int, value: Any) -> None:
        """0x5010: 1 inject (0 none, 1 overcurrent, 2 overvoltage, 3 undervoltage), 2 supply V."""
        with self.sim_lock:
            try:
                if sub == 1:
                    self.sim.inject_fault(int(value))
                elif sub == 2:
                    self.sim.set_supply_voltage(float(value))
            except ValueError as exc:
                raise SdoAbortedError(ABORT_INVALID_VALUE) from exc

    def _model_write(self, value: Any) -> Callable[[], None] | None:
        fn = getattr(self.sim, "set_model", None)
        if fn is None:
            raise SdoAbortedError(ABORT_DEVICE_STATE)

        def after() -> None:
            with self.sim_lock:
                fn("pwm" if value == 0 else "averaged")

        return after

    # -- 402 hooks ------------------------------------------------------------------------
    def _options(self) -> dict[str, int]:
        return {
            "quick_stop": self._value(0x605A),
            "shutdown": self._value(0x605B),
            "disable_operation": self._value(0x605C),
            "fault_reaction": self._value(0x605E),
        }

    def _reset_fault(self) -> bool:
        # Called with the CiA 402 lock held: take no drive lock here (the pacing loop takes
        # sim_lock, then the 402 lock); the simulator serialises reset_fault with run itself.
        self.sim.reset_fault()  # leaves the bridge off
        self._sim_mode = "off"
        self._last_fault = None
        self.emcy.clear_all()
        return True

    def _on_nmt_change(self, old: int, new: int) -> None:
        if new == OPERATIONAL:
            self.pdo.configure()

    def _on_heartbeat_lost(self, node_id: int) -> None:
        self.emcy.raise_error(HEARTBEAT_LOSS, bytes([node_id]))
        self._connection_reaction(self._value(0x6007), HEARTBEAT_LOSS)

    def _connection_reaction(self, option: int, code: int) -> None:
        """CiA 402 0x6007: 1 fault (0x605E reaction), 2 disable voltage, 3 quick stop (0x605A)."""
        if option == 1:
            self.cia402.fault(code)
        elif option == 2:
            self.cia402.disable_voltage()
        elif option == 3:
            self.cia402.quick_stop()

    def _on_nmt_abort_connection(self, command: int) -> None:
        """NMT stop / reset communication / reset node: the 0x6007 reaction (CiA 402 §6.3.3).

        Leaving the NMT state in which the master commands the drive while the power stage is
        on is a loss of the connection. Both resets reload the communication objects (RPDO
        mappings and COB-IDs the master commands through may be gone) and reset node resets
        the application: neither may leave the motor turning, so there 0x6007 = 0 (no action)
        acts as 3 (quick stop). NMT stop honours 0.
        """
        if not self.cia402.operation_enabled:
            return
        option = self._value(0x6007)
        if command in (CMD_RESET_NODE, CMD_RESET_COMMUNICATION) and option == 0:
            option = 3
        logger.warning("NMT command 0x%02X while OPERATION ENABLED: 0x6007 = %d", command, option)
        if option == 1:
            self.emcy.raise_error(NMT_CONNECTION_LOSS)  # 0x603F/0x1003 (no frame in STOPPED)
        self._connection_reaction(option, NMT_CONNECTION_LOSS)

    def _on_boot(self) -> None:
        """After every boot-up message: a damaged/unreadable store is reported on the bus
        (EMCY 0x6310 "data set lost", error register bit 0; 0x2060 store_status 2/3)."""
        if self.store_status in (StoreStatus.DAMAGED, StoreStatus.UNREADABLE):
            data = bytes([int(self.store_status)])
            if not self.emcy.raise_error(DATA_SET_LOST, data):
                self.emcy.announce(DATA_SET_LOST, data)  # still active: say it again

    def _on_heartbeat_back(self, node_id: int) -> None:
        if self.cia402.fault_code != HEARTBEAT_LOSS:
            self.emcy.clear_error(HEARTBEAT_LOSS)

    # -- the loop -------------------------------------------------------------------------
    def _set_sim_mode(self, mode: str) -> None:
        if mode != self._sim_mode:
            self.sim.set_mode(mode)
            self._sim_mode = mode

    def _prepare_chunk(self, n: int) -> None:
        """Mode and setpoints for the next ``n`` samples (sim lock held)."""
        st = self.cia402
        dt = n * TS
        if not st.torque_enabled:
            self._set_sim_mode("off")
            self._speed_ref = float(self.live.get("speed", 0.0))  # bumpless start
            self._i_ref = 0.0
            return
        mode = self._mode
        if st.ramp is not None:
            self._ramp_step(dt)
            return
        halt = bool(st.controlword & CW_HALT)
        if mode == MODE_PROFILE_VELOCITY:
            self._set_sim_mode("speed")
            if halt:  # 0x605D: 1 slow-down ramp (0x6084), 2..4 quick-stop ramp (0x6085)
                rate = self._value(0x6084) if self._value(0x605D) == 1 else self._value(0x6085)
                self._speed_ref = _ramp_towards(self._speed_ref, 0.0, rate, rate, dt)
            else:
                target = float(self._value(0x60FF))
                self._speed_ref = _ramp_towards(
                    self._speed_ref, target, self._value(0x6083), self._value(0x6084), dt
                )
            self.sim.set_speed_ref(self._speed_ref)
        else:
            self._set_sim_mode("current")
            self.sim.set_current_ref(self._current_ref(mode, halt, dt))

    def _current_ref(self, mode: int, halt: bool = False, dt: float = 0.0) -> float:
        """i_p* (A) of the current modes: profile torque follows 0x6087 (‰ of rated per s,
        0 = step) toward target_torque, or toward 0 on halt; mode -1 steps to i_p_ref."""
        rated = self._value(0x6075) / 1000.0
        cap = self._value(0x6073) / 1000.0 * rated
        if mode == MODE_PROFILE_TORQUE:
            target = 0.0 if halt else self._value(0x6071) / 1000.0 * rated
            slope = self._value(0x6087) / 1000.0 * rated  # A/s
            target = max(-cap, min(cap, target))
            self._i_ref = _ramp_towards(self._i_ref, target, slope, slope, dt)
        else:
            target = 0.0 if halt else float(self._value(0x2030, 1))
            target = max(-cap, min(cap, target))
            self._i_ref = target
        self._i_target = target
        return max(-cap, min(cap, self._i_ref))

    def _ramp_step(self, dt: float) -> None:
        """Stop ramp of quick stop / slow down / fault reaction, in every mode.

        The IP speed loop is far too slow to follow a stop ramp (its integral path has a time
        constant of about a second with the paper's gains), so the drive brakes in current mode:
        |i_p*| = J α / K_t for the deceleration α of 0x6085 (quick) or 0x6084 (slow; 0 = use
        0x6085), capped by the current limit, until |speed| < 10 rpm; then the ramp ends.
        """
        st = self.cia402
        speed = float(self.live["speed"])
        self._set_sim_mode("current")
        if abs(speed) < SPEED_ZERO_RPM:
            self.sim.set_current_ref(0.0)
            self._speed_ref = 0.0
            st.ramp_done()
            return
        decel = self._value(0x6084) if st.ramp == sm.RAMP_SLOW else 0
        if decel == 0:
            decel = self._value(0x6085)
        alpha = decel * 2.0 * math.pi / 60.0  # rad/s^2
        K_t = self._value(0x2000, 3) * 60.0 / (2.0 * math.pi)  # N m/A (i_p)
        J = self._value(0x5000, 3)
        rated = self._value(0x6075) / 1000.0
        limit = min(self._value(0x2020, 3), self._value(0x6073) / 1000.0 * rated)
        i_brake = min(limit, J * alpha / K_t) if decel > 0 else limit
        self.sim.set_current_ref(-math.copysign(i_brake, speed))

    def _step(self, n: int) -> None:
        """One chunk: setpoints, simulation, faults, recorder, live values (runner thread).

        The full-rate arrays are only asked from the simulator while the recorder is armed or
        recording (or a tap listens): otherwise only the last values are needed, which costs
        a fifth of the CPU time per chunk.
        """
        recorder = self.recorder
        need_rec = bool(self.taps) or recorder.state in (ARMED, RECORDING)
        with self.sim_lock:
            self._prepare_chunk(n)
            rec = self.sim.run(n, record=need_rec)
            fault = self.sim.fault
            last = None if need_rec else self.sim.state
        live = self.live
        if need_rec:
            for name in MEASUREMENTS.values():
                live[name] = float(rec[name][-1])
        else:
            for name in MEASUREMENTS.values():
                live[name] = last[name]
        self._update_windows()
        if fault is not None and fault != self._last_fault:
            self._last_fault = fault
            recorder.note_fault(float(fault.t))
            self.emcy.raise_error(int(fault.code))
            self.cia402.fault(int(fault.code), tripped=True)
            with self.sim_lock:
                self._set_sim_mode("off")
        if need_rec:
            setpoint = "speed_ref" if self._mode == MODE_PROFILE_VELOCITY else "i_p_ref"
            recorder.feed(rec, setpoint=setpoint)
            for tap in self.taps:
                tap(rec)

    def _periodic(self, now: float) -> None:
        if self._reset_deferred_at is not None:
            self._finish_deferred_reset()
        self.hb_consumer.tick(now)
        self.hb_producer.tick(now)


def _ramp_towards(x: float, target: float, accel: float, decel: float, dt: float) -> float:
    """Move ``x`` toward ``target`` at ``accel``/``decel`` (units/s; 0 = step)."""
    if x == target:
        return x
    speeding_up = abs(target) > abs(x) and (
        x == 0 or math.copysign(1, x) == math.copysign(1, target)
    )
    rate = accel if speeding_up else decel
    if rate <= 0:
        return target
    step = rate * dt
    if abs(target - x) <= step:
        return target
    return x + math.copysign(step, target - x)


def _clamp_int(x: float, bits: int) -> int:
    lim = (1 << (bits - 1)) - 1
    if not math.isfinite(x):
        return 0
    return max(-lim - 1, min(lim, round(x)))


def _index_of(view, name: str) -> tuple[int, int]:
    e = view.entry(name)
    return e.index, e.subindex


__all__ = ["MEASUREMENTS", "DriveLocalNode", "VirtualDrive"]
