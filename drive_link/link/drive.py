"""The :class:`Drive`: one CANopen CiA 402 drive on a python-can bus.

It does not know (nor ask) whether the node is the DSP or the virtual drive: everything goes
through the object dictionary of docs/contracts.md §1.

Built on canopen's :class:`~canopen.RemoteNode` (``Drive.node``, see
:mod:`drive_link.link._remote`): NMT commands (``node.nmt``), the EMCY consumer (``node.emcy``), the
TPDO configuration (``node.tpdo.read()``) and value encoding (the OD's ``ODVariable``) are
canopen's. Kept as thin layers of our own: the per-channel SDO lock with resends
(:mod:`drive_link.link._sdo`, also serving ``node.sdo``), the block-upload client
(:mod:`drive_link.link._sdo_block`), the NMT state / OFFLINE detection from heartbeats
(:mod:`drive_link.link._nmt`) and the supervision re-arm (:mod:`drive_link.link.supervision`).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any, overload

import can
import canopen

from firmware_protocol.cia301 import LOAD_SIGNATURE, SAVE_SIGNATURE
from firmware_protocol.enums import ModeOfOperation

from ..errors import DriveError, DriveTimeout, InvalidValue, NodeNotFound
from . import _connection, _drive_probe, _gain_set, _rules, cia402
from ._drive_probe import STORE_STATUS
from ._emcy import Emcy, EmcyListener
from ._gain_set import GAIN_FIELDS, Gains
from ._host_heartbeat import CONSUMER_MIN_MS, HostHeartbeat, confirm_nmt
from ._live import LiveStreams, TpdoConfig, read_tpdo_configs
from ._nmt import HeartbeatMonitor
from ._objects import ObjectInfo, ObjectTable, default_table
from ._remote import remote_node
from ._sdo import SdoChannel
from ._stop_guard import StopGuard
from .od_names import BytesName, FloatName, IntName, TextName
from .supervision import SupervisedSdoChannel, Supervisor
from .trace import Recorder

__all__ = [
    "CONSUMER_MIN_MS",
    "GAIN_FIELDS",
    "LOAD_SIGNATURE",
    "SAVE_SIGNATURE",
    "STORE_STATUS",
    "Drive",
    "Gains",
]

Value = float | int | str | bytes
"""What an object holds (REAL32 float, integer int, VISIBLE_STRING str, DOMAIN bytes)."""


class Drive:
    """One drive. Create with :meth:`connect`; thread-safe; close with :meth:`close`.

    Two SDO channels, each with its own lock: ``sdo`` (server 0x1200: parameters, status) and
    ``sdo_trace`` (server 0x1201: trace uploads), so an upload never blocks status reads.
    """

    def __init__(
        self,
        conn: _connection.Connection,
        node_id: int,
        table: ObjectTable | None = None,
        sdo_timeout: float = 0.3,
        retries: int = 5,
        heartbeat_ms: int | None = None,
        host_id: int = 0x7F,
    ):
        """A session with node ``node_id`` on ``conn`` (see :meth:`connect`, the way to make
        one). Releases ``conn`` if it fails (:class:`NodeNotFound` if nobody answers)."""
        try:
            self._build(conn, node_id, table, sdo_timeout, retries)
        except BaseException:
            _connection.release(conn)
            raise
        try:
            self._start(heartbeat_ms, host_id)
        except BaseException:
            self.close()
            raise

    def _build(
        self,
        conn: _connection.Connection,
        node_id: int,
        table: ObjectTable | None,
        sdo_timeout: float,
        retries: int,
    ) -> None:
        if not 1 <= node_id <= 127:
            raise InvalidValue(f"node-ID {node_id} outside 1..127")
        self._conn = conn
        self.node_id = node_id
        self.table = table or default_table()
        net = conn.network
        #: this host's heartbeat producer and the drive's consumer setting for it
        self.host_heartbeat = HostHeartbeat(net, conn.bus)
        #: re-applies this session's supervision when the drive restarts (see supervision.py)
        self.supervisor = Supervisor(net, node_id, restart_producer=self.host_heartbeat.restart)
        self.supervisor.send_heartbeat = self.host_heartbeat.send_now
        self.sdo = SupervisedSdoChannel(
            net, node_id, 0x600 + node_id, 0x580 + node_id, sdo_timeout, retries
        )
        self.sdo.supervisor = self.supervisor
        self.sdo_trace: SdoChannel = self.sdo
        self.heartbeat = HeartbeatMonitor(net, node_id)
        self.heartbeat.attach_reader(self.read)  # 0x1017 wait + SDO fallback of nmt_state
        #: canopen's view of the node: nmt, emcy, tpdo/rpdo; its sdo is our locked channel
        od = self.table.od or default_table().od
        if od is None:
            raise InvalidValue("the object table has no canopen dictionary")
        self.node = remote_node(net, node_id, od, self.sdo)
        emcy = self.node.emcy
        assert isinstance(emcy, EmcyListener)  # remote_node's consumer
        self._emcy = emcy
        self._emcy_cob = 0x80 + node_id
        self._live: LiveStreams | None = None
        self._live_lock = threading.Lock()
        #: held by the gain path (drive_link.workflows.gains.apply_gains): read, stage, apply, read
        #: back
        self.gains_lock = threading.RLock()
        self._closed = False
        #: quick stops sent and the blocks they forbid re-enabling in (drive_link.link._stop_guard)
        self.stops = StopGuard()
        self.sm = cia402.StateMachine(
            lambda: int(self.read("statusword")),
            lambda cw: self.stops.write_controlword(lambda c: self.write("controlword", c), cw),
        )
        self.trace = Recorder(self)
        conn.active_nodes[node_id] = None

    def _start(self, heartbeat_ms: int | None, host_id: int) -> None:
        """Probe the node (device_type 0x1000), attach supervision, use its second SDO server
        and configured EMCY COB-ID, start the host heartbeat."""
        try:
            self.device_type = int(self.read("device_type"))
        except DriveTimeout:
            raise NodeNotFound(
                f"no answer from node {self.node_id} (SDO to 0x{0x600 + self.node_id:03X})"
            ) from None
        self._conn.active_nodes[self.node_id] = self.device_type
        self.supervisor.attach(self.sdo)
        server = _drive_probe.trace_server(self.read)
        if server is not None:
            trace = SupervisedSdoChannel(
                self._conn.network,
                self.node_id,
                *server,
                self.sdo.client.RESPONSE_TIMEOUT,
                self.sdo.retries,
            )
            trace.supervisor = self.supervisor
            self.sdo_trace = trace
        cob = _drive_probe.emcy_cob(self.read)
        if cob is not None and cob != self._emcy_cob:  # listen where the drive sends
            net = self._conn.network
            net.unsubscribe(self._emcy_cob, self._emcy.on_emcy)
            self._emcy_cob = cob
            net.subscribe(self._emcy_cob, self._emcy.on_emcy)
        if heartbeat_ms:
            self.host_heartbeat.start(host_id, int(heartbeat_ms))

    # ------------------------------------------------------------------ lifecycle
    @classmethod
    def connect(
        cls,
        interface: str | None = None,
        channel: str | int | None = None,
        bitrate: int | None = None,
        node_id: int = 1,
        bus: can.BusABC | None = None,
        heartbeat_ms: int | None = 100,
        host: str | None = None,
        port: int | None = None,
        host_id: int = 0x7F,
        sdo_timeout: float = 0.3,
        retries: int = 5,
        **bus_kwargs: Any,
    ) -> Drive:
        """Connect to node ``node_id`` on a bus opened from python-can settings (``None`` =
        python-can config/env), on the loopback hub (``host``/``port``) or on ``bus``.

        Checks the node answers (device_type 0x1000) and sets up the trace SDO channel
        (0x1201). ``heartbeat_ms``: period of the host heartbeat (0x700 + ``host_id``) sent for
        the drive's consumer (None = none); configure the consumer with
        :meth:`configure_heartbeat_consumer`. Raises :class:`NodeNotFound` if nobody answers.
        """
        conn = _connection.acquire(
            bus=bus,
            interface=interface,
            channel=channel,
            bitrate=bitrate,
            host=host,
            port=port,
            **bus_kwargs,
        )
        return cls(
            conn,
            node_id,
            sdo_timeout=sdo_timeout,
            retries=retries,
            heartbeat_ms=heartbeat_ms,
            host_id=host_id,
        )

    def close(self) -> None:
        """Stop the host heartbeat (unconfiguring the drive's consumer if this host set it),
        stop listening, and release the bus (shut down if this drive opened it)."""
        if self._closed:
            return
        self._closed = True
        self.supervisor.close()
        if self.host_heartbeat.consumer_configured:
            try:
                self.write("consumer_heartbeat_time.consumer_1", 0)
            except DriveError:
                pass
        self.host_heartbeat.stop()
        if self._live:
            self._live.close()
        self.heartbeat.close()
        if self._emcy_cob != 0x80 + self.node_id:  # back where remove_network() expects it
            self._conn.network.unsubscribe(self._emcy_cob, self._emcy.on_emcy)
            self._conn.network.subscribe(0x80 + self.node_id, self._emcy.on_emcy)
        self.node.remove_network()
        self.sdo.close()
        if self.sdo_trace is not self.sdo:
            self.sdo_trace.close()
        self._conn.active_nodes.pop(self.node_id, None)
        _connection.release(self._conn)

    def __enter__(self) -> Drive:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def bus(self) -> can.BusABC:
        """The python-can bus."""
        return self._conn.bus

    @property
    def network(self) -> canopen.Network:
        """canopen's network on this drive's bus (shared by every drive on the bus): for a
        master's own subscriptions and frames (NMT, SYNC, a raw listener)."""
        return self._conn.network

    # ------------------------------------------------------------------ OD access
    def info(self, name: str) -> ObjectInfo:
        """Type, unit and limits of an object."""
        return self.table[name]

    @overload
    def read(self, name: FloatName) -> float: ...
    @overload
    def read(self, name: IntName) -> int: ...
    @overload
    def read(self, name: TextName) -> str: ...
    @overload
    def read(self, name: BytesName) -> bytes: ...
    @overload
    def read(self, name: str) -> Value: ...

    def read(self, name: str) -> Value:
        """Read an object by name (SI units per the OD; REAL32 → float, integers → int,
        VISIBLE_STRING → str, DOMAIN → bytes). Overloaded on the names of
        :mod:`drive_link.link.od_names`: ``drive.read("measurements.speed")`` is a float to a type
        checker."""
        obj = self.table[name]
        if not obj.readable:
            raise InvalidValue(f"{name} is write-only")
        raw = self.sdo.upload(obj.index, obj.subindex, name)
        return obj.decode(raw)

    def read_number(self, name: str) -> float | int:
        """Read a numeric object (any name, e.g. one computed at run time): REAL32 → float,
        integers → int; :class:`InvalidValue` for a string or domain object."""
        v = self.read(name)
        if isinstance(v, str | bytes):
            raise InvalidValue(f"{name} is not a number ({self.table[name].type_name})")
        return v

    def read_many(self, names: list[str]) -> dict[str, Value]:
        """Read several objects (one SDO each)."""
        return {n: self.read(n) for n in names}

    def write(self, name: str, value: Value) -> None:
        """Write an object by name after a client-side type and limit check (the drive
        re-checks and may abort: :class:`SdoAbort`).

        An active controller gain (current_controller.*, speed_controller.k_p/k_i/current_limit)
        changes only through the one gain path, :func:`drive_link.apply_gains` (its stability and
        margin policy): a write of one, once it passed the checks above, is refused with nothing
        sent (:class:`~drive_link.link._gain_set.GainWriteRefused`, an :class:`InvalidValue`;
        ``drive-link write`` routes it to that path), and so is a raw write of gain_set_apply
        (0x20F1): apply a set with :func:`drive_link.apply_gains`."""
        obj = self.table[name]
        if not obj.writable:
            raise InvalidValue(f"{name} is read-only")
        if name == _gain_set.APPLY_NAME:
            raise InvalidValue(
                f"{name}: gain sets are applied by drive_link.apply_gains "
                "(drive-link set-gains), which checks the set's stability and margins first"
            )
        data = obj.encode(value)
        v = obj.check(value)
        if isinstance(v, int | float):
            _rules.check_rules(self.read, {name: v})
        field = _gain_set.ACTIVE_GAIN_FIELD.get(name)
        if field is not None and isinstance(v, int | float):
            raise _gain_set.GainWriteRefused(name, field, v)
        if isinstance(v, int | float) and name in _rules.LOOP_NAMES:
            _rules.check_loops(self.read, {name: v})
        self.sdo.download(obj.index, obj.subindex, data, name)

    # ------------------------------------------------------------------ NMT / heartbeat
    @property
    def nmt_state(self) -> str:
        """NMT state from the drive's last heartbeat ("OPERATIONAL", "PRE-OPERATIONAL",
        "STOPPED", "INITIALISING") or "OFFLINE" if heartbeats stopped."""
        return self.heartbeat.state

    def nmt(self, command: str) -> None:
        """Send an NMT command to this node: "start", "stop", "pre-operational",
        "reset node", "reset communication" (waits while supervision is being re-armed);
        start/stop/pre-operational are repeated until a heartbeat confirms them."""
        self.supervisor.wait_ready()
        self.supervisor.expect_nmt(command)
        confirm_nmt(self.node.nmt, self.heartbeat, command, self.node_id)

    # ------------------------------------------------------------------ restart supervision
    @property
    def boots_seen(self) -> int:
        """Boot-ups / restarts of the drive noticed during this session."""
        return self.supervisor.boots_seen

    def on_supervision(self, callback: Callable[[dict[str, Any]], None]) -> None:
        """Call ``callback(event_dict)`` when a drive restart is noticed ("reboot_detected",
        "restart_suspected") and when the session's supervision was re-applied ("rearmed",
        "verified") or could not be ("rearm_failed"); see :mod:`drive_link.link.supervision`."""
        self.supervisor.subscribe(callback)

    def rearm_supervision(self):
        """Re-apply the session's heartbeat consumer, 0x6007 and PDO settings now."""
        return self.supervisor.rearm()

    def reset(self, communication_only: bool = False, timeout: float = 3.0) -> None:
        """NMT reset node (or communication) and wait for the boot-up message."""
        # The command and the boot-up are single unconfirmed frames that a lossy bus can lose:
        # the reset is sent again (up to 3 times) until a boot-up message arrives.
        for attempt in range(3):
            before = self.heartbeat.boot_count
            self.nmt("reset communication" if communication_only else "reset node")
            try:
                self.heartbeat.wait_boot(timeout, before)
                return
            except DriveTimeout:
                if attempt == 2:
                    raise

    def configure_heartbeat_consumer(self, timeout_ms: int | None = None) -> None:
        """Make the drive watch this host's heartbeat (0x1016 sub1): on loss it reacts per
        abort_connection_option_code (0x6007).

        ``timeout_ms`` defaults to max(:data:`CONSUMER_MIN_MS` = 1000 ms, 3 × the host producer
        period): 1000 ms with the default 100 ms producer. CiA practice puts the consumer time
        at 2-3 × the producer time plus the sender's jitter; the host is a general-purpose OS
        whose producer thread was seen stalling > 300 ms at load 25 (a false heartbeat loss
        quick-stops the motor). The price: a host that really dies is noticed up to ~1 s after
        its last heartbeat instead of 0.3 s; pass a smaller ``timeout_ms`` on a quiet,
        real-time host where faster reaction matters more than false stops."""
        entry = self.host_heartbeat.consumer_entry(timeout_ms)
        self.write("consumer_heartbeat_time.consumer_1", entry)
        self.host_heartbeat.consumer_configured = True
        # CiA 301: the consumer starts watching at the first heartbeat after its configuration
        self.host_heartbeat.send_now()

    @property
    def host_id(self) -> int | None:
        """Node-ID of this host's heartbeat (0x700 + host_id); None if none is produced."""
        return self.host_heartbeat.host_id

    def stop_host_heartbeat(self) -> None:
        """Stop sending the host heartbeat (e.g. to test the drive's consumer reaction)."""
        self.host_heartbeat.stop()

    # ------------------------------------------------------------------ CiA 402
    @property
    def statusword(self) -> int:
        """Statusword 0x6041."""
        return int(self.read("statusword"))

    @property
    def state(self) -> str:
        """CiA 402 state name (e.g. "OPERATION ENABLED")."""
        return self.sm.state

    @property
    def mode(self) -> str:
        """Active mode: "speed", "current", "torque" (or "mode N")."""
        return cia402.mode_name(int(self.read("modes_of_operation_display")))

    def enable(self, timeout: float = cia402.STATE_TIMEOUT_S) -> str:
        """Go to OPERATION ENABLED; :class:`DriveTimeout` / :class:`StateError` otherwise.

        ``timeout``: s each state change may take after its controlword was written."""
        return self.sm.enable(timeout)

    def disable(self, timeout: float = cia402.STATE_TIMEOUT_S) -> str:
        """Disable operation (power stage off, OPERATION ENABLED → SWITCHED ON)."""
        return self.sm.disable(timeout)

    def quick_stop(self, timeout: float = cia402.STATE_TIMEOUT_S) -> str:
        """Quick stop (ramp down per quick_stop_option_code). Counted first: an experiment
        running in another thread does not enable the drive again (:attr:`stops`)."""
        self.stops.note_quick_stop()
        return self.sm.quick_stop(timeout)

    def fault_reset(self, timeout: float = cia402.STATE_TIMEOUT_S) -> str:
        """Reset a fault (→ SWITCH ON DISABLED); :class:`StateError` if the fault persists."""
        return self.sm.fault_reset(timeout)

    def set_mode(self, mode: str | ModeOfOperation, timeout: float = 0.5) -> None:
        """Select "speed" (3, profile velocity), "current" (-1, pseudo-current) or "torque" (4)
        — or the :class:`~firmware_protocol.enums.ModeOfOperation` member — and wait until
        modes_of_operation_display confirms it."""
        value = cia402.mode_value(mode)
        name = cia402.mode_name(value)
        if int(self.read("modes_of_operation_display")) == value:
            return
        self.write("modes_of_operation", value)
        deadline = time.monotonic() + timeout
        while True:
            shown = int(self.read("modes_of_operation_display"))
            if shown == value:
                return
            if time.monotonic() >= deadline:
                raise DriveTimeout(
                    f"mode {name} not confirmed within {timeout:g} s "
                    f"(drive shows {cia402.mode_name(shown)})"
                )
            time.sleep(0.005)

    def set_speed(self, rpm: float) -> None:
        """Speed setpoint target_velocity (0x60FF) in rpm (rounded to an integer)."""
        self.write("target_velocity", round(float(rpm)))

    def set_current(self, amps: float) -> None:
        """Pseudo-current setpoint setpoints.i_p_ref (0x2030:1) in A (used in "current" mode)."""
        self.write("setpoints.i_p_ref", float(amps))

    # ------------------------------------------------------------------ gains
    def read_gains(self) -> Gains:
        """The active controller gains (0x2010, 0x2020). To change them:
        :func:`drive_link.workflows.gains.apply_gains` (the one gain path)."""
        return _gain_set.read_gains(self)

    # ------------------------------------------------------------------ store / restore
    def store(self) -> None:
        """Store all parameters in the drive's non-volatile memory (0x1010:1 = "save")."""
        with self.sdo.patience(3.0):  # writing non-volatile memory takes time
            self.write("store_parameters.save_all", SAVE_SIGNATURE)

    def restore_defaults(self, reset: bool = False, timeout: float = 3.0) -> None:
        """Restore factory defaults (0x1011:1 = "load"); they apply after the next reset node,
        which ``reset=True`` sends (waiting for the boot-up)."""
        with self.sdo.patience(3.0):
            self.write("restore_default_parameters.restore_all", LOAD_SIGNATURE)
        if reset:
            self.reset(timeout=timeout)

    # ------------------------------------------------------------------ EMCY / faults
    @property
    def emcy_history(self) -> list[Emcy]:
        """EMCY messages received from this drive since connect, oldest first."""
        return self._emcy.history

    def on_emcy(self, callback: Callable[[Emcy], None]) -> None:
        """Call ``callback(Emcy)`` for every EMCY (runs on the bus thread: keep it short)."""
        self._emcy.subscribe(callback)

    def error_history(self) -> list[Emcy]:
        """The drive's pre-defined error field 0x1003, newest first."""
        n = int(self.read("pre_defined_error_field.number_of_errors"))
        out = []
        for i in range(1, min(n, 8) + 1):
            v = int(self.read(f"pre_defined_error_field.standard_error_field_{i}"))
            out.append(Emcy(code=v & 0xFFFF, data=(v >> 16).to_bytes(2, "little")))
        return out

    def clear_error_history(self) -> None:
        """Clear 0x1003 (write 0 to sub0)."""
        self.write("pre_defined_error_field.number_of_errors", 0)

    # ------------------------------------------------------------------ live streams
    def read_tpdo_config(self) -> list[TpdoConfig]:
        """The drive's TPDO communication and mapping parameters (0x1800–, 0x1A00–) by SDO
        (canopen's ``TPDO.read()`` over the locked channel)."""
        return read_tpdo_configs(self.node, self.table)

    @property
    def live(self) -> LiveStreams:
        """Live TPDO streams (built on first use from the drive's actual PDO mapping)."""
        with self._live_lock:
            if self._live is None:
                self._live = LiveStreams(
                    self._conn.network,
                    self.read_tpdo_config(),
                    self._conn.monitor,
                    self._conn.bitrate,
                )
            return self._live

    def refresh_live(self) -> LiveStreams:
        """Re-read the PDO mapping (after it was changed) and restart the streams."""
        with self._live_lock:
            if self._live is not None:
                self._live.close()
                self._live = None
        return self.live

    # ------------------------------------------------------------------ bus health
    def bus_health(self) -> dict[str, str | int]:
        """``bus_state`` ("ERROR_ACTIVE", "ERROR_PASSIVE", "BUS_OFF" or "UNKNOWN") and
        ``bus_error_frames`` (error frames received since the bus was opened); see
        :mod:`drive_link.link._bus_health`."""
        return self._conn.health.snapshot()

    # ------------------------------------------------------------------ summary
    def store_status(self) -> str:
        """Health of the drive's parameter store, 0x2060: "ok" (stored parameters loaded),
        "defaults" (no store), "damaged" / "unreadable" (stored parameters lost: defaults in
        use), or "unknown" (firmware without 0x2060)."""
        return _drive_probe.store_status(self.sdo, self.table)

    def status(self) -> dict[str, Any]:
        """A snapshot for displays: NMT and 402 state, mode, key measurements, error register,
        parameter store health and restart supervision (``boots_seen``,
        ``supervision_rearmed_at``)."""
        sw = self.statusword
        sup = self.supervisor.status()
        return {
            "node_id": self.node_id,
            "nmt_state": self.nmt_state,
            "state": cia402.state_from_statusword(sw),
            "statusword": sw,
            "mode": self.mode,
            "error_register": int(self.read("error_register")),
            "error_code": int(self.read("error_code")),
            "speed_rpm": float(self.read("measurements.speed")),
            "i_p_A": float(self.read("measurements.i_p")),
            "i_p_ref_A": float(self.read("measurements.i_p_ref")),
            "speed_ref_rpm": float(self.read("measurements.speed_ref")),
            "V_dc_V": float(self.read("measurements.V_dc")),
            "store_status": self.store_status(),
            "boots_seen": sup["boots_seen"],
            "supervision_rearmed_at": sup["supervision_rearmed_at"],
            "supervision_ready": sup["supervision_ready"],
            **self.bus_health(),
        }
