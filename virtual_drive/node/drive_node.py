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

The node is split by job; this module assembles it (services, lifecycle, bus, parameter
access, CiA 402 hooks, the pacing loop's chunk):

- :mod:`.local_node` the canopen LocalNode whose reads and writes go through the drive;
- :mod:`.writes` every write: checks, then a table of handlers by object index;
- :mod:`.parameters` load / push to the simulator / store / restore the parameter set;
- :mod:`.communication` communication objects (heartbeat, EMCY, SDO server 2, PDOs), NMT reset
  communication; :mod:`.resets` reset node (deferred while braking), 0x6007 reactions;
- :mod:`.gain_sets` the staged gain set 0x20F0/0x20F1 and the current limit;
- :mod:`.trace_config` trace configuration writes and the recorder's set-up;
- :mod:`.ramps` setpoints, profile and stop ramps of the next chunk;
- :mod:`.statusword` 0x6041 and its velocity window / threshold timers;
- :mod:`.reads` objects computed on read; :mod:`.od_maps` measurement and mode maps.
"""

from __future__ import annotations

import errno
import logging
import threading
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any

import can
import canopen
from canopen import objectdictionary as odm

from firmware_protocol import abort_codes
from firmware_protocol.enums import StoreStatus
from firmware_protocol.od import load_od
from virtual_drive.hub_protocol import SENDAT_MAX_BACKDATE_S
from virtual_drive.sim.signals import SIGNALS

from . import communication, parameters, ramps, resets, statusword, storage, writes
from .cia402 import Cia402StateMachine
from .emcy import EmcyManager
from .heartbeat import HeartbeatConsumer, HeartbeatProducer
from .local_node import DriveLocalNode, RpdoRefusedError
from .nmt import OPERATIONAL, NmtSlave
from .od_addresses import (
    DISABLE_OPERATION_OPTION,
    FAULT_REACTION_OPTION,
    QUICK_STOP_OPTION,
    SHUTDOWN_OPTION,
)
from .od_maps import (
    CURRENT_WINDOW_A,
    MEASUREMENTS,
    MODE_CURRENT,
    MODE_PROFILE_TORQUE,
    MODE_PROFILE_VELOCITY,
    RESET_BRAKE_LIMIT_S,
    SPEED_ZERO_RPM,
    SUPPORTED_MODES,
)
from .params import ParamChecker
from .pdo import PdoEngine
from .reads import make_live_getters
from .recorder import ARMED, RECORDING, TraceRecorder
from .remote import RemoteRequests
from .runner import TS, Runner
from .sdo_block import BlockSdoServer
from .tx import make_send_many

__all__ = [
    "CURRENT_WINDOW_A",
    "MEASUREMENTS",
    "MODE_CURRENT",
    "MODE_PROFILE_TORQUE",
    "MODE_PROFILE_VELOCITY",
    "RESET_BRAKE_LIMIT_S",
    "SPEED_ZERO_RPM",
    "SUPPORTED_MODES",
    "TIMED_PERIOD",
    "DriveLocalNode",
    "RpdoRefusedError",
    "VirtualDrive",
]

logger = logging.getLogger(__name__)

#: Samples per piece while a stop ramp runs (1 ms at Ts = 20 µs): see :meth:`VirtualDrive._step`.
RAMP_CHUNK = 50
#: Pacing period (s) on a bus that takes frames with their bus time (``timed_sends``, the
#: loopback hub): one wake-up, one simulator call and one socket write per 10 ms, the TPDOs
#: still 1 ms apart on the bus with the values of their own instant (like a USB adapter that
#: hands over frames in batches with hardware times). Elsewhere (SocketCAN, python-can
#: ``virtual``): 1 ms. The price: TPDOs reach hosts up to 10 ms after their bus time, and the
#: simulation reads new setpoints once per tick (stop ramps still decide every 1 ms,
#: :data:`RAMP_CHUNK`). On this kind of VM a wake-up alone costs 55-72 µs of CPU, so the
#: period sets most of the drive's cost: 5.4 % of a core at 10 ms against 8.6 % at 5 ms in
#: the same hour (benchmarks/bench_realtime.py, load 0.4-0.8). 10 ms once doubled the SDO
#: reply p99 of four drives sharing the bus (3.8 -> 7.2 ms at TPDO2/3 2 ms, bench_nodes.py):
#: a batch stated in the past queued behind a host frame that reached the hub first; the hub
#: now puts such frames in the idle bus time of their stated instants (3.4-3.7 ms).
#: ``--tick-ms`` chooses.
TIMED_PERIOD = 0.010

ABORT_STORE = abort_codes.STORE  # kept for importers of the old module
ABORT_HARDWARE = abort_codes.HARDWARE


class VirtualDrive:
    """The virtual drive node on a python-can bus.

    :param bus: any python-can bus (virtual, socketcand to the loopback hub, socketcan).
    :param node_id: CANopen node-ID (1..127; 0x1201 defaults valid for N ≤ 47).
    :param store_path: parameter file for 0x1010/0x1011 (None: store refused with 0x08000020).
    :param speed: simulated seconds per wall-clock second (tests use > 1).
    :param sim: a ready :class:`virtual_drive.sim.Simulator` (default: a new one, PWM-exact).
    """

    #: s the bus reader waits for a frame before it looks whether :meth:`stop` was called (so
    #: also the longest :meth:`stop` waits for it)
    NOTIFIER_CYCLE: float = 0.2

    def __init__(
        self,
        bus: can.BusABC,
        node_id: int = 1,
        store_path: str | Path | None = None,
        speed: float = 1.0,
        sim: Any = None,
        period: float | None = None,
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
            on_reset_node=partial(resets.reset_application, self),
            on_reset_communication=partial(communication.reset_communication, self),
            on_state_change=self._on_nmt_change,
            on_abort_connection=partial(resets.on_nmt_abort_connection, self),
            on_boot=partial(resets.on_boot, self),
        )
        # default COB-IDs of this node-ID from the EDS (0x80+N, 0x600+N, 0x580+N); 0x1014 is
        # applied by the parameter load below, the first SDO server's are fixed
        self.emcy = EmcyManager(
            int(self.view.entry("cob_id_emcy").default), self._send, self.nmt.emcy_allowed
        )
        self.sdo = BlockSdoServer(
            int(self.view.entry("sdo_server_1.cob_id_client_to_server").default),
            int(self.view.entry("sdo_server_1.cob_id_server_to_client").default),
            self.node,
            self.nmt.sdo_allowed,
            send=self._send,
        )
        self.node.sdo = self.sdo
        self.sdo2: BlockSdoServer | None = None
        self.timed_sends = bool(getattr(bus, "timed_sends", False))
        send_many = make_send_many(self)
        self.hb_producer = HeartbeatProducer(
            node_id,
            self._send,
            lambda: self.nmt.state,
            send_at=(lambda cob_id, data, at: send_many([(cob_id, data)], at))
            if self.timed_sends
            else None,
        )
        self.hb_consumer = HeartbeatConsumer(
            self.network.subscribe,
            self.network.unsubscribe,
            partial(resets.on_heartbeat_lost, self),
            partial(resets.on_heartbeat_back, self),
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
            send_many=send_many,
            align=lambda t: self.runner.align(t),
            # (a bus time the hub still takes after the frames' trip to it)
            stamp_max_age=0.8 * SENDAT_MAX_BACKDATE_S,
        )
        self.cia402 = Cia402StateMachine(self._options, self._reset_fault)
        self.recorder = TraceRecorder()
        self.checker = ParamChecker(self.view, self._current_by_name)
        # the pacing thread also sends the event-driven TPDOs (one wake-up per tick); on a bus
        # that takes frames with their bus time (the loopback hub) the ticks are TIMED_PERIOD
        # apart and each TPDO is sent with its due time and the values of that instant
        if period is None:
            period = TIMED_PERIOD if self.timed_sends else 1e-3
        self.runner = Runner(
            self._step,
            self._periodic,
            speed=self.speed,
            period=period,
            timer=self.pdo.tick,
            timer_at=self.pdo.tick_at if self.timed_sends else None,
            flush=self._flush_timed if self.timed_sends else None,
            step_timed=self._step_timed if self.timed_sends else None,
            due_times=self.pdo.due_times,
        )
        self._live_getters = make_live_getters(self)
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
        #: sim time (s) of the TPDO instant a timed tick is at (None: the simulator's clock)
        self._t_point: float | None = None
        if self.store_path is not None:
            storage.remove_stale_temps(self.store_path)  # left by a kill during a store
        self._load_parameters()
        # frames reach these only while start() has a Notifier running
        self.network.subscribe(0x000, self.nmt.on_command)
        self.network.subscribe(self.sdo.rx_cobid, self.sdo.on_request)
        communication.bind_sync(self)  # SYNC on 0x1005's CAN-ID

    # -- lifecycle ------------------------------------------------------------------------
    def start(self) -> VirtualDrive:
        """Attach to the bus, send the boot-up message and start the pacing loop."""
        if self._started:
            return self
        self._started = True
        self.remote = RemoteRequests(self.pdo.on_remote)  # RTR: TPDOs; no node guarding
        self.network.notifier = can.Notifier(
            self.bus, [*self.network.listeners, self.remote], self.NOTIFIER_CYCLE
        )
        self.nmt.boot()
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
    def _flush_timed(self) -> None:
        """End of a timed tick: the bus writes the TPDOs it held (one write per tick)."""
        try:
            with self._send_lock:
                self.bus.flush()
            self.last_tx_ok = time.monotonic()
        except (can.CanError, OSError) as exc:
            self.tx_errors += 1
            if self.tx_errors < 10 or self.tx_errors % 1000 == 0:
                logger.warning("send of the tick's frames failed: %s", exc)

    def _current_by_name(self, name: str) -> float | int:
        e = self.view.entry(name)
        return self.node.stored(e.index, e.subindex)

    def _param(self, address: tuple[int, int]) -> Any:
        """Present parameter value at ``address`` = ``(index, sub)`` (an :mod:`.od_addresses`
        constant; cached, every write to the data store clears the cache)."""
        try:
            return self._pcache[address]
        except KeyError:
            value = self._pcache[address] = self.node.stored(*address)
            return value

    def _value(self, index: int, sub: int = 0) -> Any:
        """Present parameter value at ``index``/``sub`` (as :meth:`_param`)."""
        key = (index, sub)
        try:
            return self._pcache[key]
        except KeyError:
            value = self._pcache[key] = self.node.stored(index, sub)
            return value

    def _load_parameters(self) -> None:
        """Stored parameters (or defaults) into the data store and the simulator."""
        parameters.load_parameters(self)

    def save_parameters(self) -> None:
        """0x1010 "save": persistent objects' present values to the store file (atomic)."""
        parameters.save_parameters(self)

    def restore_defaults(self) -> None:
        """0x1011 "load": defaults apply after the next reset node / restart."""
        parameters.restore_defaults(self)

    # -- reads ----------------------------------------------------------------------------
    def statusword(self) -> int:
        """0x6041 from the CiA 402 state and the live values (:mod:`.statusword`)."""
        return statusword.statusword(self)

    # -- writes ---------------------------------------------------------------------------
    def _before_write(
        self, index: int, sub: int, obj: odm.ODVariable, data: bytes
    ) -> tuple[bool, Callable[[], None] | None]:
        """Check a write and say whether to store it and what to do after storing
        (:func:`.writes.before_write`: the table of write handlers). Raises SdoAbortedError to
        refuse it (nothing changes)."""
        return writes.before_write(self, index, sub, obj, data)

    # -- 402 hooks ------------------------------------------------------------------------
    def _options(self) -> dict[str, int]:
        return {
            "quick_stop": self._param(QUICK_STOP_OPTION),
            "shutdown": self._param(SHUTDOWN_OPTION),
            "disable_operation": self._param(DISABLE_OPERATION_OPTION),
            "fault_reaction": self._param(FAULT_REACTION_OPTION),
        }

    def _reset_fault(self) -> bool:
        # Called with the CiA 402 lock held: take no drive lock here (the pacing loop takes
        # sim_lock, then the 402 lock); the simulator serialises reset_fault with run itself.
        if self.sim.fault_persists():  # refused at once, as the DSP's next 20 µs sample would
            return False  # (a starved virtual drive otherwise showed SWITCH ON DISABLED first)
        self.sim.reset_fault()  # leaves the bridge off
        self._sim_mode = "off"
        self._last_fault = None
        self.emcy.clear_all()
        return True

    def _on_nmt_change(self, old: int, new: int) -> None:
        if new == OPERATIONAL:
            self.pdo.configure()

    # -- the loop -------------------------------------------------------------------------
    def _step(self, n: int) -> None:
        """``n`` samples (runner thread). A stop ramp decides its brake current from the speed
        once per chunk (:func:`ramps.ramp_step`), so while one runs the samples go in pieces of
        at most :data:`RAMP_CHUNK` (1 ms) whatever the pacing period: a 10 ms tick (as in
        User-Mode Linux) otherwise braked through zero to -27 rpm."""
        if self.cia402.ramp is None:
            self._step_chunk(n)
            return
        while n > 0:
            k = min(n, RAMP_CHUNK)
            self._step_chunk(k)
            n -= k

    def _step_chunk(self, n: int) -> None:
        """One chunk: setpoints, simulation, faults, recorder, live values (runner thread).

        The full-rate arrays are only asked from the simulator while the recorder is armed or
        recording (or a tap listens): otherwise only the last values are needed, which costs
        a fifth of the CPU time per chunk.
        """
        recorder = self.recorder
        need_rec = bool(self.taps) or recorder.state in (ARMED, RECORDING)
        with self.sim_lock:
            ramps.prepare_chunk(self, n)
            if need_rec:
                rec = self.sim.run(n, record=True)
            else:  # the last values only, no dict built or copied
                self.sim.run_into(n, self.live)
            fault = self.sim.fault
        live = self.live
        if need_rec:
            for name in MEASUREMENTS.values():
                live[name] = float(rec[name][-1])
        statusword.update_windows(self)
        if fault is not None and fault != self._last_fault:
            self._on_trip(fault)
        if need_rec:
            setpoint = "speed_ref" if self._mode == MODE_PROFILE_VELOCITY else "i_p_ref"
            recorder.feed(rec, setpoint=setpoint)
            for tap in self.taps:
                tap(rec)

    def _step_timed(self, n: int, at: list[int], at_point: Callable[[int], None]) -> bool:
        """A timed tick's ``n`` samples in one simulator call (runner thread): the live values
        are those of the instant ``at[j]`` samples in when ``at_point(j)`` runs (it sends the
        TPDOs due then), and the velocity windows and a trip are seen at those instants, as
        :meth:`_step_chunk` pieces ending there would see them. Returns False (nothing done)
        while that cannot be: a setpoint ramps (:func:`ramps.ramping`: it moves every
        piece), the recorder or a tap needs the full-rate arrays, or the simulator has no
        ``run_points`` (or not for that many instants)."""
        run_points = getattr(self.sim, "run_points", None)
        if (
            run_points is None
            or len(at) > getattr(self.sim, "MAX_POINTS", 0)
            or self.taps
            or self.recorder.state in (ARMED, RECORDING)
            or ramps.ramping(self)
        ):
            return False
        with self.sim_lock:
            ramps.prepare_chunk(self, n)
            t0 = float(self.sim.time)
            rows = run_points(n, at)
            fault = self.sim.fault
        if fault is not None and fault == self._last_fault:
            fault = None  # (seen before)
        live = self.live
        # the velocity window / threshold timers only show in profile velocity (bits 10, 12):
        # in the other modes they follow at the end of the tick
        windows = self._mode == MODE_PROFILE_VELOCITY
        try:
            for j, k in enumerate(at):
                t = self._t_point = t0 + min(k, n) * TS
                if fault is not None and t > fault.t:
                    self._on_trip(fault)  # from its own sample on, as a 1-sample piece would
                    fault = None
                live.update(zip(SIGNALS, rows[j], strict=True))
                if windows:
                    statusword.update_windows(self)
                at_point(j)
        finally:
            self._t_point = None
        live.update(zip(SIGNALS, rows[-1], strict=True))
        statusword.update_windows(self)
        if fault is not None:
            self._on_trip(fault)
        return True

    def _on_trip(self, fault: Any) -> None:
        """A new trip of the simulator: recorder mark, EMCY, CiA 402 FAULT, bridge off.

        ``fault`` was read with the chunk; a fault reset (SDO thread, under the CiA 402 lock)
        may have cleared it since. Under that lock the trip is applied only if the simulator
        still holds it: a stale one would put the drive back into FAULT just after the reset
        (seen on a busy host, where the pacing thread waits between the two)."""
        with self.cia402.lock:  # (taken before sim_lock, never inside it: as a reset does)
            if self.sim.fault != fault:
                return  # reset meanwhile; a new trip since is seen with the next chunk
            self._last_fault = fault
            self.recorder.note_fault(float(fault.t))
            self.emcy.raise_error(int(fault.code))
            self.cia402.fault(int(fault.code), tripped=True)
        with self.sim_lock:
            ramps.set_sim_mode(self, "off")

    def _periodic(self, now: float) -> None:
        if self._reset_deferred_at is not None:
            resets.finish_deferred_reset(self)
        self.hb_consumer.tick(now)
        self.hb_producer.tick(now)
