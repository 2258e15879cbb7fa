"""CiA 402 (IEC 61800-7-201) power drive state machine: controlword in, statusword out.

Pure logic, no bus and no simulator. The drive node feeds it controlwords and faults, asks it
whether the bridge must deliver torque (:attr:`torque_enabled`) and whether a stop ramp is
running (:attr:`ramp`), and reports the end of a ramp with :meth:`ramp_done`.

Option codes (read through ``options()`` at every decision, so SDO writes apply at once):
- 0x605A quick stop: 0 disable drive function; 1 slow-down ramp (0x6084), 2 quick-stop ramp
  (0x6085), 3 current limit, 4 voltage limit → then SWITCH ON DISABLED; 5, 6, 7, 8 the same but
  stay in QUICK STOP ACTIVE. The virtual drive brakes on a speed ramp only: 3/4 act as 2 and
  7/8 act as 6.
- 0x605B shutdown and 0x605C disable operation: 0 disable drive function (coast), 1 slow-down ramp
  then the transition.
- 0x605E fault reaction: 0 disable drive function, 1 slow-down ramp, 2 quick-stop ramp, then FAULT.
  Faults the power stage trips by itself (overcurrent, DC-link) go to FAULT at once.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable

# States and statusword/controlword bits (CiA 402 Tables 28, 30): the protocol package's single
# copy, shared with the host library.
from firmware_protocol.cia402 import (
    CW_ENABLE_OPERATION_BIT,
    CW_ENABLE_VOLTAGE,
    CW_FAULT_RESET,
    CW_QUICK_STOP_BIT,
    CW_SWITCH_ON_BIT,
    FAULT,
    FAULT_REACTION_ACTIVE,
    NOT_READY_TO_SWITCH_ON,
    OPERATION_ENABLED,
    QUICK_STOP_ACTIVE,
    READY_TO_SWITCH_ON,
    SW_INTERNAL_LIMIT,
    SW_REMOTE,
    SW_TARGET_REACHED,
    SW_VOLTAGE_ENABLED,
    SW_WARNING,
    SWITCH_ON_DISABLED,
    SWITCHED_ON,
)
from firmware_protocol.cia402 import STATE_BITS as _STATE_BITS

__all__ = [
    "DISABLE_VOLTAGE",
    "ENABLE_OPERATION",
    "QUICK_STOP",
    "RAMP_QUICK",
    "RAMP_SLOW",
    "SHUTDOWN",
    "SWITCH_ON",
    "Cia402StateMachine",
    "decode_command",
]

logger = logging.getLogger(__name__)


# Commands decoded from controlword bits 0..3 (CiA 402 Table 28)
DISABLE_VOLTAGE = "disable voltage"
QUICK_STOP = "quick stop"
SHUTDOWN = "shutdown"
SWITCH_ON = "switch on"  # also "disable operation" from OPERATION ENABLED
ENABLE_OPERATION = "enable operation"

RAMP_SLOW = "slow"  # profile deceleration 0x6084
RAMP_QUICK = "quick"  # quick stop deceleration 0x6085


#: states with the drive function enabled (CiA 402 Table 26 "power enabled" column)
_DRIVE_FUNCTION_ON = frozenset({OPERATION_ENABLED, QUICK_STOP_ACTIVE, FAULT_REACTION_ACTIVE})
#: states from which one controlword (transitions 3+4, 4, 16) enables operation
_REACH_OPERATION = frozenset(
    {READY_TO_SWITCH_ON, SWITCHED_ON, OPERATION_ENABLED, QUICK_STOP_ACTIVE}
)


def decode_command(controlword: int) -> str:
    """Device control command of a controlword (bit 7, fault reset, handled separately)."""
    if not controlword & CW_ENABLE_VOLTAGE:
        return DISABLE_VOLTAGE
    if not controlword & CW_QUICK_STOP_BIT:
        return QUICK_STOP
    if not controlword & CW_SWITCH_ON_BIT:
        return SHUTDOWN
    if not controlword & CW_ENABLE_OPERATION_BIT:
        return SWITCH_ON
    return ENABLE_OPERATION


class Cia402StateMachine:
    """The drive's device control state machine.

    :param options: returns the option codes as a dict with keys ``quick_stop``, ``shutdown``,
        ``disable_operation``, ``fault_reaction`` (0x605A, 0x605B, 0x605C, 0x605E).
    :param can_reset_fault: returns False while the fault cause persists (fault reset refused).
    :param on_change: called with ``(old, new)`` state names after every transition.
    """

    def __init__(
        self,
        options: Callable[[], dict[str, int]],
        can_reset_fault: Callable[[], bool] = lambda: True,
        on_change: Callable[[str, str], None] = lambda old, new: None,
    ) -> None:
        self._options = options
        self._can_reset = can_reset_fault
        self._on_change = on_change
        self._lock = threading.RLock()
        #: held while a transition runs (a fault reset calls ``can_reset_fault`` inside it): the
        #: drive holds it to apply a trip of its simulator atomically against a reset
        self.lock = self._lock
        self.state = NOT_READY_TO_SWITCH_ON
        self._last_cw = 0
        self.controlword = 0
        self.ramp: str | None = None  # stop ramp running in the current state
        self._after_ramp: str | None = None  # state to enter when the ramp ends
        self.fault_code = 0
        self._set(SWITCH_ON_DISABLED)  # transition 1, automatic after initialisation

    # -- queries --------------------------------------------------------------------------
    @property
    def torque_enabled(self) -> bool:
        """True while the bridge is switching (operation enabled or braking on a ramp)."""
        return self.state == OPERATION_ENABLED or self.ramp is not None

    @property
    def operation_enabled(self) -> bool:
        return self.state == OPERATION_ENABLED and self.ramp is None

    @property
    def drive_function_on(self) -> bool:
        """True where CiA 402 has the drive function enabled (OPERATION ENABLED, QUICK STOP
        ACTIVE, held or braking, FAULT REACTION ACTIVE) or a stop ramp brakes: the plant and
        protection definition (``ConfigOnly`` objects) may not change here. A held quick stop
        stands with the bridge off on the virtual drive, but one controlword (0x000F,
        transition 16) runs the motor again, so it counts as "on"."""
        return self.state in _DRIVE_FUNCTION_ON or self.ramp is not None

    @property
    def can_reach_operation(self) -> bool:
        """True where OPERATION ENABLED is one controlword away without passing SWITCH ON
        DISABLED (READY TO SWITCH ON, SWITCHED ON, OPERATION ENABLED, QUICK STOP ACTIVE) or a
        stop ramp still brakes: supervision (0x1016) must survive a reset communication here."""
        return self.state in _REACH_OPERATION or self.ramp is not None

    def statusword(
        self,
        target_reached: bool = False,
        internal_limit: bool = False,
        warning: bool = False,
        mode_bits: int = 0,
    ) -> int:
        """Statusword from the state and the drive's flags (bits 12/13 mode specific)."""
        sw = _STATE_BITS[self.state] | SW_REMOTE
        if self.state in (SWITCHED_ON, OPERATION_ENABLED, QUICK_STOP_ACTIVE, FAULT_REACTION_ACTIVE):
            sw |= SW_VOLTAGE_ENABLED
        if target_reached:
            sw |= SW_TARGET_REACHED
        if internal_limit:
            sw |= SW_INTERNAL_LIMIT
        if warning:
            sw |= SW_WARNING
        return sw | (mode_bits & 0x3000)

    # -- inputs ---------------------------------------------------------------------------
    def _set(self, new: str, ramp: str | None = None, after: str | None = None) -> None:
        old = self.state
        self.state = new
        self.ramp = ramp
        self._after_ramp = after
        if old != new:
            logger.info("CiA 402 %s -> %s", old, new)
            self._on_change(old, new)

    def _stop(self, option: int, then: str, stay: str) -> None:
        """Leave the present state: coast at once (option 0) or ramp first."""
        if option <= 0:
            self._set(then)
        else:
            ramp = RAMP_SLOW if option in (1, 5) else RAMP_QUICK
            self._set(stay, ramp=ramp, after=then)

    def write_controlword(self, controlword: int) -> None:
        """Apply a controlword (0x6040 write or RPDO)."""
        with self._lock:
            rising_reset = bool(controlword & CW_FAULT_RESET) and not (
                self._last_cw & CW_FAULT_RESET
            )
            self._last_cw = controlword
            self.controlword = controlword
            if self.state == FAULT:
                if rising_reset and self._can_reset():
                    self.fault_code = 0
                    self._set(SWITCH_ON_DISABLED)  # transition 15
                return
            # Outside FAULT bit 7 has no meaning; bits 0..3 still command the device (canopen's
            # BaseNode402, for one, sends 0x80 for "disable voltage").
            cmd = decode_command(controlword)
            st = self.state
            opt = self._options()
            if st in (FAULT, FAULT_REACTION_ACTIVE, NOT_READY_TO_SWITCH_ON):
                return
            if cmd == DISABLE_VOLTAGE:
                if st != SWITCH_ON_DISABLED:
                    self._set(SWITCH_ON_DISABLED)  # 7, 9, 10, 12
                return
            if st == SWITCH_ON_DISABLED:
                if cmd == SHUTDOWN:
                    self._set(READY_TO_SWITCH_ON)  # 2
            elif st == READY_TO_SWITCH_ON:
                if cmd == QUICK_STOP:
                    self._set(SWITCH_ON_DISABLED)  # 7
                elif cmd == SWITCH_ON:
                    self._set(SWITCHED_ON)  # 3
                elif cmd == ENABLE_OPERATION:
                    self._set(SWITCHED_ON)  # 3 + 4
                    self._set(OPERATION_ENABLED)
            elif st == SWITCHED_ON:
                if cmd == QUICK_STOP:
                    self._set(SWITCH_ON_DISABLED)  # 10
                elif cmd == SHUTDOWN:
                    self._set(READY_TO_SWITCH_ON)  # 6
                elif cmd == ENABLE_OPERATION:
                    self._set(OPERATION_ENABLED)  # 4
            elif st == OPERATION_ENABLED:
                if cmd == QUICK_STOP:
                    self._quick_stop(opt["quick_stop"])  # 11
                elif cmd == SHUTDOWN:
                    self._stop(min(opt["shutdown"], 1), READY_TO_SWITCH_ON, OPERATION_ENABLED)
                elif cmd == SWITCH_ON:
                    self._stop(min(opt["disable_operation"], 1), SWITCHED_ON, OPERATION_ENABLED)
                elif cmd == ENABLE_OPERATION and self.ramp is not None:
                    self._set(OPERATION_ENABLED)  # cancel a pending slow-down
            elif st == QUICK_STOP_ACTIVE:
                if cmd == ENABLE_OPERATION and self.ramp is None and opt["quick_stop"] >= 5:
                    self._set(OPERATION_ENABLED)  # 16

    def _quick_stop(self, option: int) -> None:
        if option <= 0:
            self._set(SWITCH_ON_DISABLED)
            return
        if option in (3, 4):
            option = 2
        elif option in (7, 8):
            option = 6
        ramp = RAMP_SLOW if option in (1, 5) else RAMP_QUICK
        after = SWITCH_ON_DISABLED if option <= 4 else QUICK_STOP_ACTIVE
        self._set(QUICK_STOP_ACTIVE, ramp=ramp, after=after)

    def quick_stop(self) -> None:
        """Quick stop from inside the drive (e.g. heartbeat loss with 0x6007 = 3)."""
        with self._lock:
            if self.state == OPERATION_ENABLED:
                self._quick_stop(self._options()["quick_stop"])

    def disable_voltage(self) -> None:
        """Disable voltage from inside the drive (0x6007 = 2)."""
        with self._lock:
            if self.state not in (FAULT, FAULT_REACTION_ACTIVE, SWITCH_ON_DISABLED):
                self._set(SWITCH_ON_DISABLED)

    def fault(self, code: int, tripped: bool = False) -> None:
        """A fault occurred (transition 13). ``tripped``: the power stage is already off."""
        with self._lock:
            if self.state in (FAULT, FAULT_REACTION_ACTIVE):
                return
            self.fault_code = code
            option = self._options()["fault_reaction"]
            if tripped or option <= 0 or not self.torque_enabled:
                self._set(FAULT_REACTION_ACTIVE)
                self._set(FAULT)  # 14
            else:
                ramp = RAMP_SLOW if option == 1 else RAMP_QUICK
                self._set(FAULT_REACTION_ACTIVE, ramp=ramp, after=FAULT)

    def ramp_done(self) -> None:
        """The drive reports that the stop ramp reached standstill."""
        with self._lock:
            if self.ramp is None:
                return
            after = self._after_ramp or self.state
            if after == self.state:
                self.ramp = None
                self._after_ramp = None
            else:
                self._set(after)
