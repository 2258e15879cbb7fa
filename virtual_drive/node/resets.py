"""NMT reset node (deferred while a stop ramp brakes) and the CiA 402 connection-loss reactions.

0x6007 abort_connection_option_code: 1 fault (0x605E reaction), 2 disable voltage, 3 quick stop
(0x605A); applied on a consumer heartbeat timeout (EMCY 0x8130) and when an NMT stop or reset
leaves the commanded state while OPERATION ENABLED (EMCY code 0x8100). After every boot-up a
damaged or unreadable parameter store is reported (EMCY 0x6310).

:class:`Resets` owns the one piece of state of these: when (sim time, s) a reset node was
deferred behind a braking stop ramp (``deferred_at``; None: none pending).
"""

from __future__ import annotations

import logging

from firmware_protocol.enums import StoreStatus
from firmware_protocol.od import load_od

from .emcy import DATA_SET_LOST, HEARTBEAT_LOSS, NMT_CONNECTION_LOSS
from .nmt import CMD_RESET_COMMUNICATION, CMD_RESET_NODE
from .od_maps import RESET_BRAKE_LIMIT_S
from .parts import DriveParts

_OD = load_od()  # where the objects are: the EDS, through firmware_protocol's view
ABORT_CONNECTION_OPTION = _OD.address("abort_connection_option_code")

__all__ = ["Resets"]

logger = logging.getLogger(__name__)


class Resets:
    """Reset node and the connection-loss reactions of drive ``d``."""

    def __init__(self, d: DriveParts) -> None:
        self.d = d
        self.deferred_at: float | None = None  #: sim time (s) of a deferred reset node

    def reset_application(self) -> bool:
        """NMT reset node: all parameters to stored values, drive to SWITCH ON DISABLED.

        Runs after the 0x6007 reaction. While its stop ramp still brakes the motor the reset
        is deferred (returns False): the pacing loop completes it at standstill (or after
        :data:`RESET_BRAKE_LIMIT_S`), then the node boots. The motor is never left turning
        under a freshly reset, unsupervised application.
        """
        d = self.d
        if d.cia402.torque_enabled:
            self.deferred_at = float(d.sim.time)
            logger.info("reset node deferred until the stop ramp ends")
            return False
        self.do_reset_application()
        return True

    def finish_deferred_reset(self) -> None:
        """Pacing loop: complete a deferred reset node once the motor is braked."""
        d = self.d
        started = self.deferred_at
        if started is None:
            return
        braked = not d.cia402.torque_enabled
        if not braked and float(d.sim.time) - started < RESET_BRAKE_LIMIT_S:
            return
        self.deferred_at = None
        with d.node.write_lock:
            self.do_reset_application()
        d.nmt.finish_reset()

    def do_reset_application(self) -> None:
        """The reset itself: a fresh CiA 402 machine, bridge off, recorder stopped, errors
        cleared, profile velocity mode, parameters reloaded."""
        d = self.d
        with d.sim_lock:
            d.reset_state_machine()
            d.ramps.reset()
            d.recorder.stop()
            d.sim.reset_fault()
            d.ramps.bridge_off()
            d.forget_trip()
        d.emcy.clear_all()
        d.parameters.load()

    def connection_reaction(self, option: int, code: int) -> None:
        """CiA 402 0x6007: 1 fault (0x605E reaction), 2 disable voltage, 3 quick stop
        (0x605A)."""
        st = self.d.cia402
        if option == 1:
            st.fault(code)
        elif option == 2:
            st.disable_voltage()
        elif option == 3:
            st.quick_stop()

    def on_heartbeat_lost(self, node_id: int) -> None:
        """A consumer heartbeat (0x1016) timed out: EMCY 0x8130 (data[3] = node), 0x6007
        reaction."""
        d = self.d
        d.emcy.raise_error(HEARTBEAT_LOSS, bytes([node_id]))
        self.connection_reaction(d.node.param(ABORT_CONNECTION_OPTION), HEARTBEAT_LOSS)

    def on_heartbeat_back(self, node_id: int) -> None:
        """The heartbeat is back: the 0x8130 error clears unless it caused the present
        fault."""
        if self.d.cia402.fault_code != HEARTBEAT_LOSS:
            self.d.emcy.clear_error(HEARTBEAT_LOSS)

    def on_nmt_abort_connection(self, command: int) -> None:
        """NMT stop / reset communication / reset node: the 0x6007 reaction (CiA 402 §6.3.3).

        Leaving the NMT state in which the master commands the drive while the power stage
        is on is a loss of the connection. Both resets reload the communication objects (RPDO
        mappings and COB-IDs the master commands through may be gone) and reset node resets
        the application: neither may leave the motor turning, so there 0x6007 = 0 (no
        action) acts as 3 (quick stop). NMT stop honours 0.
        """
        d = self.d
        if not d.cia402.operation_enabled:
            return
        option = d.node.param(ABORT_CONNECTION_OPTION)
        if command in (CMD_RESET_NODE, CMD_RESET_COMMUNICATION) and option == 0:
            option = 3
        logger.warning("NMT command 0x%02X while OPERATION ENABLED: 0x6007 = %d", command, option)
        if option == 1:
            d.emcy.raise_error(NMT_CONNECTION_LOSS)  # 0x603F/0x1003 (no frame in STOPPED)
        self.connection_reaction(option, NMT_CONNECTION_LOSS)

    def on_boot(self) -> None:
        """After every boot-up message: a damaged/unreadable store is reported on the bus
        (EMCY 0x6310 "data set lost", error register bit 0; 0x2060 store_status 2/3)."""
        d = self.d
        status = d.parameters.store_status
        if status in (StoreStatus.DAMAGED, StoreStatus.UNREADABLE):
            data = bytes([int(status)])
            if not d.emcy.raise_error(DATA_SET_LOST, data):
                d.emcy.announce(DATA_SET_LOST, data)  # still active: say it again
