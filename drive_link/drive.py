"""The :class:`Drive`: one CANopen CiA 402 drive on a python-can bus.

It does not know (nor ask) whether the node is the DSP or the virtual drive: everything goes
through the object dictionary of docs/contracts.md §1.

Built on canopen's :class:`~canopen.RemoteNode` (``Drive.node``, see :mod:`drive_link._remote`):
NMT commands (``node.nmt``), the EMCY consumer (``node.emcy``), the TPDO configuration
(``node.tpdo.read()``) and value encoding (the OD's ``ODVariable``) are canopen's. Kept as thin
layers of our own: the per-channel SDO lock with resends (:mod:`drive_link._sdo`, also serving
``node.sdo``), the block-upload client (:mod:`drive_link._sdo_block`), the NMT state / OFFLINE
detection from heartbeats (:mod:`drive_link._nmt`) and the supervision re-arm
(:mod:`drive_link.supervision`).
"""

from __future__ import annotations

import threading
import time
from typing import Any

import can

from firmware_protocol import load_od
from firmware_protocol.cia301 import LOAD_SIGNATURE, SAVE_SIGNATURE
from firmware_protocol.enums import StoreStatus

from . import _connection, _gain_set, _rules, cia402
from ._emcy import Emcy, EmcyListener
from ._gain_set import GAIN_FIELDS, Gains
from ._live import LiveStreams, TpdoConfig, read_tpdo_configs
from ._nmt import HeartbeatMonitor, HeartbeatProducer, send_command
from ._objects import ObjectInfo, ObjectTable, default_table
from ._remote import remote_node
from ._sdo import SdoChannel
from ._stop_guard import StopGuard
from .errors import DriveError, DriveTimeout, InvalidValue, NodeNotFound, StateError
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

#: 0x2060 store_status (U8, ro) values → name (the EDS enumeration, :class:`StoreStatus`).
STORE_STATUS: dict[int, str] = {int(s): s.name.lower() for s in StoreStatus}
STORE_STATUS_INDEX = load_od().entry("store_status").index
CONSUMER_MIN_MS = 1000
"""Shortest default heartbeat consumer time (ms) :meth:`Drive.configure_heartbeat_consumer`
sets: max(CONSUMER_MIN_MS, 3 x the host producer period). 3 x 100 ms was too tight: at load 25
the host's producer thread stalled > 300 ms and the drive quick-stopped with the host alive."""

#: NMT commands confirmed by the next heartbeat, and the state it must report
_NMT_CONFIRM = {"start": "OPERATIONAL", "stop": "STOPPED", "pre-operational": "PRE-OPERATIONAL"}
#: How long Drive.nmt waits for the drive's first heartbeat before it can confirm a command, s.
FIRST_HEARTBEAT_S = 1.5


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
    ):
        if not 1 <= node_id <= 127:
            raise InvalidValue(f"node-ID {node_id} outside 1..127")
        self._conn = conn
        self.node_id = node_id
        self.table = table or default_table()
        net = conn.network
        #: re-applies this session's supervision when the drive restarts (see supervision.py)
        self.supervisor = Supervisor(net, node_id, restart_producer=self._restart_producer)
        self.supervisor.send_heartbeat = self._send_host_heartbeat
        self.sdo = SupervisedSdoChannel(
            net, node_id, 0x600 + node_id, 0x580 + node_id, sdo_timeout, retries
        )
        self.sdo.supervisor = self.supervisor
        self.sdo_trace: SdoChannel = self.sdo
        self.heartbeat = HeartbeatMonitor(net, node_id)
        self.heartbeat.attach_reader(self.read)  # 0x1017 wait + SDO fallback of nmt_state
        #: canopen's view of the node: nmt, emcy, tpdo/rpdo; its sdo is our locked channel
        self.node = remote_node(net, node_id, self.table.od or default_table().od, self.sdo)
        self._emcy: EmcyListener = self.node.emcy
        self._emcy_cob = 0x80 + node_id
        self._producer: HeartbeatProducer | None = None
        self._consumer_configured = False
        self._live: LiveStreams | None = None
        self._live_lock = threading.Lock()
        #: held by the gain path (drive_link.gains.apply_gains): read, stage, apply, read back
        self.gains_lock = threading.RLock()
        self._closed = False
        self.host_id: int | None = None
        #: quick stops sent and the blocks they forbid re-enabling in (drive_link._stop_guard)
        self.stops = StopGuard()
        self.sm = cia402.StateMachine(
            lambda: int(self.read("statusword")),
            lambda cw: self.stops.write_controlword(lambda c: self.write("controlword", c), cw),
        )
        self.trace = Recorder(self)
        conn.active_nodes[node_id] = None

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
        try:
            drive = cls(conn, node_id, sdo_timeout=sdo_timeout, retries=retries)
        except Exception:
            _connection.release(conn)
            raise
        try:
            drive._probe()
            drive.supervisor.attach(drive.sdo)
            drive._setup_trace_channel()
            drive._setup_emcy()
            if heartbeat_ms:
                drive.host_id = host_id
                drive._producer = HeartbeatProducer(conn.bus, host_id, int(heartbeat_ms))
        except BaseException:
            drive.close()
            raise
        return drive

    def _probe(self) -> None:
        try:
            self.device_type = int(self.read("device_type"))
            self._conn.active_nodes[self.node_id] = self.device_type
        except DriveTimeout:
            raise NodeNotFound(
                f"no answer from node {self.node_id} (SDO to 0x{0x600 + self.node_id:03X})"
            ) from None

    def _setup_emcy(self) -> None:
        """Listen on the drive's configured EMCY COB-ID (0x1014) if it is not 0x80 + N."""
        try:
            cob = int(self.read("cob_id_emcy"))
        except DriveError:
            return
        if cob & 0x80000000 or (cob & 0x7FF) == self._emcy_cob:
            return
        net = self._conn.network
        net.unsubscribe(self._emcy_cob, self._emcy.on_emcy)
        self._emcy_cob = cob & 0x7FF
        net.subscribe(self._emcy_cob, self._emcy.on_emcy)

    def _setup_trace_channel(self) -> None:
        """Use the drive's second SDO server (0x1201) for uploads if it has a valid one."""
        try:
            rx = int(self.read("sdo_server_2.cob_id_client_to_server"))
            tx = int(self.read("sdo_server_2.cob_id_server_to_client"))
        except DriveError:
            return  # no second server: uploads share the first channel (still locked)
        if rx & 0x80000000 or tx & 0x80000000:
            return
        trace = SupervisedSdoChannel(
            self._conn.network,
            self.node_id,
            rx & 0x7FF,
            tx & 0x7FF,
            self.sdo.client.RESPONSE_TIMEOUT,
            self.sdo.retries,
        )
        trace.supervisor = self.supervisor
        self.sdo_trace = trace

    def close(self) -> None:
        """Stop the host heartbeat (unconfiguring the drive's consumer if this host set it),
        stop listening, and release the bus (shut down if this drive opened it)."""
        if self._closed:
            return
        self._closed = True
        self.supervisor.close()
        if self._consumer_configured:
            try:
                self.write("consumer_heartbeat_time.consumer_1", 0)
            except DriveError:
                pass
        if self._producer:
            self._producer.stop()
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

    # ------------------------------------------------------------------ OD access
    def info(self, name: str) -> ObjectInfo:
        """Type, unit and limits of an object."""
        return self.table[name]

    def read(self, name: str) -> float | int | str | bytes:
        """Read an object by name (SI units per the OD; REAL32 → float, integers → int)."""
        obj = self.table[name]
        if not obj.readable:
            raise InvalidValue(f"{name} is write-only")
        raw = self.sdo.upload(obj.index, obj.subindex, name)
        return obj.decode(raw)

    def read_many(self, names: list[str]) -> dict[str, float | int | str | bytes]:
        """Read several objects (one SDO each)."""
        return {n: self.read(n) for n in names}

    def write(self, name: str, value: float | int | str | bytes) -> None:
        """Write an object by name after a client-side type and limit check (the drive
        re-checks and may abort: :class:`SdoAbort`).

        An active controller gain (current_controller.*, speed_controller.k_p/k_i/current_limit)
        changes through the one gain path, :func:`drive_link.gains.apply_gains` (its stability
        and margin policy; :class:`drive_link.GainsRefused` if refused, nothing sent); a raw
        write of gain_set_apply (0x20F1) is refused (:class:`InvalidValue`): apply a set with
        :func:`drive_link.gains.apply_gains`."""
        obj = self.table[name]
        if not obj.writable:
            raise InvalidValue(f"{name} is read-only")
        if name == _gain_set.APPLY_NAME:
            raise InvalidValue(
                f"{name}: gain sets are applied by drive_link.gains.apply_gains "
                "(drive-link set-gains), which checks the set's stability and margins first"
            )
        data = obj.encode(value)
        v = obj.check(value)
        if isinstance(v, int | float):
            _rules.check_rules(self.read, {name: v})
        field = _gain_set.ACTIVE_GAIN_FIELD.get(name)
        if field is not None and isinstance(v, int | float):
            from .gains import GainsRefused, apply_gains  # the one gain path, loaded on use

            try:
                apply_gains(self, {field: v})
            except GainsRefused as exc:
                raise GainsRefused(
                    f"{name}: {exc} (gains change through drive_link.gains.apply_gains: "
                    f"drive-link set-gains {field}=... [--force])",
                    exc.check,
                ) from None
            return
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
        "reset node", "reset communication" (waits while supervision is being re-armed)."""
        self.supervisor.wait_ready()
        self.supervisor.expect_nmt(command)
        send_command(self.node.nmt, command)
        target = _NMT_CONFIRM.get(command)
        if target is None:
            return  # resets are confirmed by the boot-up
        if not self.heartbeat.last_time:
            # a one-shot command may run before the drive's first heartbeat arrived: wait for
            # one (a producer time is at most about 1 s in practice); none → nothing confirms
            try:
                self.heartbeat.wait_for(tuple(_NMT_CONFIRM.values()), FIRST_HEARTBEAT_S)
            except DriveTimeout:
                return
        # An NMT command has no answer (CiA 301): on a lossy bus it is lost silently. Repeat it
        # until a heartbeat sent after it reports the target state (idempotent in that state).
        period = self.heartbeat.producer_time or 0.1
        deadline = time.monotonic() + max(3.0, 6 * period)
        while True:
            sent = time.monotonic()
            try:
                self.heartbeat.wait_for((target,), max(0.3, 2.5 * period), after=sent)
                return
            except DriveTimeout:
                if time.monotonic() >= deadline:
                    raise DriveTimeout(
                        f"node {self.node_id}: NMT {command} not confirmed by a heartbeat "
                        f"reporting {target} within {deadline - sent + 2.5 * period:.1f} s"
                    ) from None
            send_command(self.node.nmt, command)

    # ------------------------------------------------------------------ restart supervision
    @property
    def boots_seen(self) -> int:
        """Boot-ups / restarts of the drive noticed during this session."""
        return self.supervisor.boots_seen

    def on_supervision(self, callback) -> None:
        """Call ``callback(event_dict)`` when a drive restart is noticed ("reboot_detected",
        "restart_suspected") and when the session's supervision was re-applied ("rearmed",
        "verified") or could not be ("rearm_failed"); see :mod:`drive_link.supervision`."""
        self.supervisor.subscribe(callback)

    def rearm_supervision(self):
        """Re-apply the session's heartbeat consumer, 0x6007 and PDO settings now."""
        return self.supervisor.rearm()

    def _send_host_heartbeat(self) -> None:
        """One host heartbeat now (besides the periodic ones), if this host produces one."""
        if self._producer is None or self.host_id is None:
            return
        self._conn.network.send_message(0x700 + self.host_id, bytes([0x05]))

    def _restart_producer(self) -> None:
        """Start the host heartbeat again (its periodic task may have died with a bus error)."""
        if self._producer is None or self.host_id is None:
            return
        period = self._producer.period_ms
        self._producer.stop()
        self._producer = HeartbeatProducer(self._conn.bus, self.host_id, period)

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
        if self._producer is None or self.host_id is None:
            raise StateError("no host heartbeat is produced (connect with heartbeat_ms)")
        default = max(CONSUMER_MIN_MS, 3 * self._producer.period_ms)
        t = int(timeout_ms if timeout_ms is not None else default)
        if not 0 < t <= 0xFFFF:
            raise InvalidValue(f"heartbeat consumer time {t} ms outside 1..65535")
        self.write("consumer_heartbeat_time.consumer_1", (self.host_id << 16) | t)
        self._consumer_configured = True
        # CiA 301: the consumer starts watching at the first heartbeat after its configuration
        self._send_host_heartbeat()

    def stop_host_heartbeat(self) -> None:
        """Stop sending the host heartbeat (e.g. to test the drive's consumer reaction)."""
        if self._producer:
            self._producer.stop()
            self._producer = None

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
        """Go to OPERATION ENABLED; :class:`DriveTimeout` / :class:`StateError` otherwise."""
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

    def set_mode(self, mode: str, timeout: float = 0.5) -> None:
        """Select "speed" (3, profile velocity), "current" (-1, pseudo-current) or "torque" (4)
        and wait until modes_of_operation_display confirms it."""
        if mode not in cia402.MODES:
            raise InvalidValue(f"mode {mode!r}: one of {', '.join(cia402.MODES)}")
        value = cia402.MODES[mode]
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
                    f"mode {mode} not confirmed within {timeout:g} s "
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
        :func:`drive_link.gains.apply_gains` (the one gain path)."""
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

    def on_emcy(self, callback) -> None:
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
        :mod:`drive_link._bus_health`."""
        return self._conn.health.snapshot()

    # ------------------------------------------------------------------ summary
    def store_status(self) -> str:
        """Health of the drive's parameter store, 0x2060: "ok" (stored parameters loaded),
        "defaults" (no store), "damaged" / "unreadable" (stored parameters lost: defaults in
        use), or "unknown" (firmware without 0x2060)."""
        from .errors import SdoAbort

        if "store_status" not in self.table:
            index, sub = STORE_STATUS_INDEX, 0
        else:
            obj = self.table["store_status"]
            index, sub = obj.index, obj.subindex
        try:
            raw = self.sdo.upload(index, sub, "store_status")
        except SdoAbort:
            return "unknown"
        if not raw:
            return "unknown"
        return STORE_STATUS.get(raw[0], f"code {raw[0]}")

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
