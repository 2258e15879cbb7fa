"""The parts of a drive node that the write handlers, live reads and resets work with.

:class:`DriveParts` is the public face of :class:`.drive_node.VirtualDrive` that :mod:`.writes`,
:mod:`.reads` and :mod:`.resets` see: the objects the node is composed of, each owning its own
state (see the node README, "Who owns what"). Declared here, below the modules that use it, so
that none of them imports the assembly (:mod:`.drive_node`) that imports them.
"""

from __future__ import annotations

import threading
from typing import Any, Protocol

from .cia402 import Cia402StateMachine
from .communication import Communication
from .emcy import EmcyManager
from .gain_sets import GainSets
from .heartbeat import HeartbeatConsumer, HeartbeatProducer
from .local_node import DriveLocalNode
from .nmt import NmtSlave
from .parameters import ParameterSet
from .params import ParamChecker
from .pdo import PdoEngine
from .ramps import SetpointRamps
from .recorder import TraceRecorder
from .trace_config import TraceConfig

__all__ = ["DriveParts"]


class DriveParts(Protocol):
    """What a drive node is made of (all public attributes of :class:`.VirtualDrive`)."""

    node_id: int
    speed: float  #: simulated seconds per wall-clock second
    sim: Any  #: the :class:`virtual_drive.sim.Simulator`
    sim_lock: threading.RLock
    live: dict[str, float]  #: live values of the last chunk (:data:`.od_maps.MEASUREMENTS`)
    node: DriveLocalNode
    checker: ParamChecker
    nmt: NmtSlave
    emcy: EmcyManager
    pdo: PdoEngine
    hb_producer: HeartbeatProducer
    hb_consumer: HeartbeatConsumer
    cia402: Cia402StateMachine
    recorder: TraceRecorder
    trace: TraceConfig
    ramps: SetpointRamps
    gains: GainSets
    parameters: ParameterSet
    comm: Communication

    def statusword(self) -> int: ...

    def reset_state_machine(self) -> None: ...

    def forget_trip(self) -> None: ...
