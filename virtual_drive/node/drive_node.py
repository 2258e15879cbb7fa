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

The node is composed of parts that own their state (node README, "Who owns what"); this
module assembles them and wires them through their public methods (lifecycle, the CiA 402
hooks, the pacing loop's chunk):

- :class:`.DriveLocalNode` the parameter store: values, cache, write lock, live getters;
- :mod:`.writes` every write: checks, then a table of handlers by object index;
- :class:`.ParameterSet` load / push to the simulator / store / restore the parameter set;
- :class:`.Communication` communication objects (heartbeat, EMCY, SDO server 2, PDOs), NMT
  reset communication; :class:`.Resets` reset node (deferred while braking), 0x6007 reactions;
- :class:`.GainSets` the staged gain set 0x20F0/0x20F1 and the current limit;
- :class:`.TraceConfig` trace configuration writes and the recorder's set-up;
- :class:`.SetpointRamps` setpoints, profile and stop ramps of the next chunk;
- :class:`.StatusWord` 0x6041 and its velocity window / threshold timers;
- :class:`.Transmitter` every frame sent; :mod:`.reads` objects computed on read.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any

import can
import canopen

from firmware_protocol import abort_codes
from firmware_protocol.enums import StoreStatus
from firmware_protocol.od import load_od
from virtual_drive.hub_protocol import SENDAT_MAX_BACKDATE_S
from virtual_drive.sim.signals import SIGNALS

from . import writes
from .cia402 import Cia402StateMachine
from .communication import Communication
from .emcy import EmcyManager
from .gain_sets import GainSets
from .heartbeat import HeartbeatConsumer, HeartbeatProducer
from .local_node import DriveLocalNode, RpdoRefusedError
from .nmt import OPERATIONAL, NmtSlave
from .od_maps import (
    CURRENT_WINDOW_A,
    MEASUREMENTS,
    MODE_CURRENT,
    MODE_PROFILE_TORQUE,
    MODE_PROFILE_VELOCITY,
    RESET_BRAKE_LIMIT_S,
    SPEED_ZERO_RPM,
    SUPPORTED_MODES,
    int_default,
)
from .parameters import ParameterSet
from .params import ParamChecker
from .pdo import PdoEngine
from .ramps import SetpointRamps
from .reads import make_live_getters
from .recorder import ARMED, RECORDING, TraceRecorder
from .remote import RemoteRequests
from .resets import Resets
from .runner import TS, Runner
from .sdo_block import BlockSdoServer
from .statusword import StatusWord
from .trace_config import TraceConfig
from .tx import Transmitter

_OD = load_od()  # where the objects are: the EDS, through firmware_protocol's view
QUICK_STOP_OPTION = _OD.address("quick_stop_option_code")
SHUTDOWN_OPTION = _OD.address("shutdown_option_code")
DISABLE_OPERATION_OPTION = _OD.address("disable_operation_option_code")
FAULT_REACTION_OPTION = _OD.address("fault_reaction_option_code")

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

    runner: Runner  # (made after the PDO engine, whose ``align`` reads it)

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
        self._store_path = Path(store_path) if store_path is not None else None
        self.speed = float(speed)
        self.view = load_od(node_id=node_id)
        self.od = self.view.canopen_od(node_id)
        if sim is None:
            from virtual_drive.sim import Simulator

            sim = Simulator()
        self.sim = sim
        self.sim_lock = sim_lock = threading.RLock()
        self.tx = tx = Transmitter(bus)  # the send side: lock, error count, batched sends
        self.timed_sends = tx.timed_sends
        self.taps: list[Callable[[dict], None]] = []
        self.live: dict[str, float] = {name: 0.0 for name in MEASUREMENTS.values()}
        self.live["hall_sector"] = 1
        self._started = False
        self._last_fault: Any = None  # the simulator's trip last acted on

        self.network = canopen.Network(bus)
        # the object dictionary and parameter store; wired to the drive's checks below
        self.node = node = DriveLocalNode(node_id, self.od)
        self.network.add_node(node)
        self.resets = resets = Resets(self)  # reset node, 0x6007 reactions
        self.nmt = NmtSlave(
            node_id,
            tx.send,
            on_reset_node=resets.reset_application,
            on_reset_communication=self._reset_communication,
            on_state_change=self._on_nmt_change,
            on_abort_connection=resets.on_nmt_abort_connection,
            on_boot=resets.on_boot,
        )
        # default COB-IDs of this node-ID from the EDS (0x80+N, 0x600+N, 0x580+N); 0x1014 is
        # applied by the parameter load below, the first SDO server's are fixed
        self.emcy = EmcyManager(
            int_default(self.view, "cob_id_emcy"), tx.send, self.nmt.emcy_allowed
        )
        self.sdo = BlockSdoServer(
            int_default(self.view, "sdo_server_1.cob_id_client_to_server"),
            int_default(self.view, "sdo_server_1.cob_id_server_to_client"),
            node,
            self.nmt.sdo_allowed,
            send=tx.send,
        )
        node.sdo = self.sdo
        self.hb_producer = HeartbeatProducer(
            node_id,
            tx.send,
            lambda: self.nmt.state,
            send_at=tx.send_at if self.timed_sends else None,
        )
        self.hb_consumer = HeartbeatConsumer(
            self.network.subscribe,
            self.network.unsubscribe,
            resets.on_heartbeat_lost,
            resets.on_heartbeat_back,
        )
        self.pdo = PdoEngine(
            node,
            tx.send,
            self.network.subscribe,
            self.network.unsubscribe,
            self.nmt.pdo_allowed,
            lambda: self.nmt.state,
            lambda i, s: node.live_getters.get((i, s)),
            report=self.emcy.raise_error,
            clear=self.emcy.clear_error,
            send_many=tx.send_many,
            align=lambda t: self.runner.align(t),
            # (a bus time the hub still takes after the frames' trip to it)
            stamp_max_age=0.8 * SENDAT_MAX_BACKDATE_S,
        )
        self.cia402 = Cia402StateMachine(self._options, self._reset_fault)
        self.recorder = TraceRecorder()
        self.trace = TraceConfig(node, self.recorder)
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
            flush=tx.flush if self.timed_sends else None,
            step_timed=self._step_timed if self.timed_sends else None,
            due_times=self.pdo.due_times,
        )
        # control state (touched by the runner between chunks)
        self.ramps = SetpointRamps(sim, node.param, self.live)
        self.status = StatusWord(sim, node.param, self.live, self.ramps)
        self.gains = GainSets(node, self.checker, sim, sim_lock)
        self.comm = Communication(
            node,
            self.network,
            self.hb_producer,
            self.hb_consumer,
            self.emcy,
            self.pdo,
            self.nmt.sdo_allowed,
            tx.send,
            self.store_path,
        )
        self.parameters = ParameterSet(
            node,
            self.checker,
            self.store_path,
            sim,
            sim_lock,
            self.emcy,
            self.gains,
            self.comm.configure,
        )
        node.bind(partial(writes.before_write, self), make_live_getters(self), self.runner.catch_up)
        self.parameters.load()
        # frames reach these only while start() has a Notifier running
        self.network.subscribe(0x000, self.nmt.on_command)
        self.network.subscribe(self.sdo.rx_cobid, self.sdo.on_request)
        self.comm.bind_sync()  # SYNC on 0x1005's CAN-ID

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
    @property
    def tx_errors(self) -> int:
        """Frames the bus refused (:attr:`.Transmitter.tx_errors`)."""
        return self.tx.tx_errors

    @property
    def last_tx_ok(self) -> float:
        """Monotonic time of the last frame the bus accepted."""
        return self.tx.last_tx_ok

    # -- parameters -----------------------------------------------------------------------
    def _current_by_name(self, name: str) -> float | int:
        e = self.view.entry(name)
        return self.node.stored_number(e.index, e.subindex)

    @property
    def store_path(self) -> Path | None:
        """The parameter file for 0x1010/0x1011 (None: store refused)."""
        return self._store_path

    @property
    def store_status(self) -> StoreStatus:
        """0x2060 as the last parameter load found the store (:class:`.ParameterSet`)."""
        return self.parameters.store_status

    def save_parameters(self) -> None:
        """0x1010 "save": persistent objects' present values to the store file (atomic)."""
        self.parameters.save()

    def restore_defaults(self) -> None:
        """0x1011 "load": defaults apply after the next reset node / restart."""
        self.parameters.restore_defaults()

    def _reset_communication(self) -> None:
        """NMT reset communication (0x1016 kept where one controlword can enable the
        motor: :meth:`.Communication.reset`)."""
        self.comm.reset(keep_1016=self.cia402.can_reach_operation)

    # -- reads ----------------------------------------------------------------------------
    def statusword(self) -> int:
        """0x6041 from the CiA 402 state and the live values (:class:`.StatusWord`)."""
        return self.status.statusword(self.cia402, warning=bool(self.hb_consumer.lost))

    # -- 402 hooks ------------------------------------------------------------------------
    def _options(self) -> dict[str, int]:
        return {
            "quick_stop": self.node.param(QUICK_STOP_OPTION),
            "shutdown": self.node.param(SHUTDOWN_OPTION),
            "disable_operation": self.node.param(DISABLE_OPERATION_OPTION),
            "fault_reaction": self.node.param(FAULT_REACTION_OPTION),
        }

    def reset_state_machine(self) -> None:
        """Reset node: a fresh CiA 402 machine (SWITCH ON DISABLED)."""
        self.cia402 = Cia402StateMachine(self._options, self._reset_fault)

    def forget_trip(self) -> None:
        """The simulator's trip was reset: a new one is acted on again."""
        self._last_fault = None

    def _reset_fault(self) -> bool:
        # Called with the CiA 402 lock held: take no drive lock here (the pacing loop takes
        # sim_lock, then the 402 lock); the simulator serialises reset_fault with run itself.
        if self.sim.fault_persists():  # refused at once, as the DSP's next 20 µs sample would
            return False  # (a starved virtual drive otherwise showed SWITCH ON DISABLED first)
        self.sim.reset_fault()  # leaves the bridge off
        self.ramps.bridge_off()
        self._last_fault = None
        self.emcy.clear_all()
        return True

    def _on_nmt_change(self, old: int, new: int) -> None:
        if new == OPERATIONAL:
            self.pdo.configure()

    # -- the loop -------------------------------------------------------------------------
    def _step(self, n: int) -> None:
        """``n`` samples (runner thread). A stop ramp decides its brake current from the speed
        once per chunk (:meth:`.SetpointRamps.ramp_step`), so while one runs the samples go in
        pieces of at most :data:`RAMP_CHUNK` (1 ms) whatever the pacing period: a 10 ms tick
        (as in User-Mode Linux) otherwise braked through zero to -27 rpm."""
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
            self.ramps.prepare_chunk(self.cia402, n)
            if need_rec:
                rec = self.sim.run(n, record=True)
            else:  # the last values only, no dict built or copied
                self.sim.run_into(n, self.live)
            fault = self.sim.fault
        live = self.live
        if need_rec:
            for name in MEASUREMENTS.values():
                live[name] = float(rec[name][-1])
        self.status.update_windows(self.cia402)
        if fault is not None and fault != self._last_fault:
            self._on_trip(fault)
        if need_rec:
            setpoint = "speed_ref" if self.ramps.mode == MODE_PROFILE_VELOCITY else "i_p_ref"
            recorder.feed(rec, setpoint=setpoint)
            for tap in self.taps:
                tap(rec)

    def _step_timed(self, n: int, at: list[int], at_point: Callable[[int], None]) -> bool:
        """A timed tick's ``n`` samples in one simulator call (runner thread): the live values
        are those of the instant ``at[j]`` samples in when ``at_point(j)`` runs (it sends the
        TPDOs due then), and the velocity windows and a trip are seen at those instants, as
        :meth:`_step_chunk` pieces ending there would see them. Returns False (nothing done)
        while that cannot be: a setpoint ramps (:meth:`.SetpointRamps.ramping`: it moves every
        piece), the recorder or a tap needs the full-rate arrays, or the simulator has no
        ``run_points`` (or not for that many instants)."""
        run_points = getattr(self.sim, "run_points", None)
        if (
            run_points is None
            or len(at) > getattr(self.sim, "MAX_POINTS", 0)
            or self.taps
            or self.recorder.state in (ARMED, RECORDING)
            or self.ramps.ramping(self.cia402)
        ):
            return False
        with self.sim_lock:
            self.ramps.prepare_chunk(self.cia402, n)
            t0 = float(self.sim.time)
            rows = run_points(n, at)
            fault = self.sim.fault
        if fault is not None and fault == self._last_fault:
            fault = None  # (seen before)
        live = self.live
        # the velocity window / threshold timers only show in profile velocity (bits 10, 12):
        # in the other modes they follow at the end of the tick
        windows = self.ramps.mode == MODE_PROFILE_VELOCITY
        status = self.status
        try:
            for j, k in enumerate(at):
                t = status.t_point = t0 + min(k, n) * TS
                if fault is not None and t > fault.t:
                    self._on_trip(fault)  # from its own sample on, as a 1-sample piece would
                    fault = None
                live.update(zip(SIGNALS, rows[j], strict=True))
                if windows:
                    self.status.update_windows(self.cia402)
                at_point(j)
        finally:
            status.t_point = None
        live.update(zip(SIGNALS, rows[-1], strict=True))
        self.status.update_windows(self.cia402)
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
            self.ramps.set_sim_mode("off")

    def _periodic(self, now: float) -> None:
        if self.resets.deferred_at is not None:
            self.resets.finish_deferred_reset()
        self.hb_consumer.tick(now)
        self.hb_producer.tick(now)
