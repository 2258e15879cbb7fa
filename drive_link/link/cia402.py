"""A thin CiA 402 (IEC 61800-7-201) power drive state machine, host side.

The drive owns the state machine; the host writes controlword commands and watches the
statusword until the requested state is reached or a timeout expires. States and commands follow
CiA 402-2 §7.1 (figure 7, tables 3 and 4).

Why not canopen 2.4.1's ``BaseNode402``: it does not do the job on a lossy, slow link.
Its timeouts are fixed class constants of 0.4–0.8 s (a state change under frame loss needs
several SDO round trips with resends: we wait 3 s); a mode change the drive never confirms is
logged as a warning and the call returns as if it had worked (we raise :class:`DriveTimeout`);
``setup_402_state_machine()`` asserts on the NMT state (#309); and its mode wait polls 0x6061 in
a busy loop. Its state tables agree with ours (both are the standard's).
"""

from __future__ import annotations

import time
from collections.abc import Callable

# States, statusword bits and controlword commands (CiA 402-2 tables 3 and 4) are the
# protocol package's single copy, shared with the virtual drive.
from firmware_protocol.cia402 import (
    CW_DISABLE_OPERATION,
    CW_DISABLE_VOLTAGE,
    CW_ENABLE_OPERATION,
    CW_FAULT_RESET,
    CW_QUICK_STOP,
    CW_SHUTDOWN,
    CW_SWITCH_ON,
    FAULT,
    FAULT_REACTION_ACTIVE,
    OPERATION_ENABLED,
    QUICK_STOP_ACTIVE,
    READY_TO_SWITCH_ON,
    SW_INTERNAL_LIMIT,
    SW_REMOTE,
    SW_TARGET_REACHED,
    SW_WARNING,
    SWITCH_ON_DISABLED,
    SWITCHED_ON,
    state_from_statusword,
)
from firmware_protocol.cia402 import NOT_READY_TO_SWITCH_ON as NOT_READY
from firmware_protocol.enums import ModeOfOperation

from ..errors import DriveTimeout, InvalidValue, StateError

__all__ = [
    "CW_DISABLE_OPERATION",
    "CW_DISABLE_VOLTAGE",
    "CW_ENABLE_OPERATION",
    "CW_FAULT_RESET",
    "CW_QUICK_STOP",
    "CW_SHUTDOWN",
    "CW_SWITCH_ON",
    "FAULT",
    "FAULT_REACTION_ACTIVE",
    "MODES",
    "MODE_NAMES",
    "NOT_READY",
    "OPERATION_ENABLED",
    "QUICK_STOP_ACTIVE",
    "READY_TO_SWITCH_ON",
    "STATE_TIMEOUT_S",
    "SWITCHED_ON",
    "SWITCH_ON_DISABLED",
    "SW_INTERNAL_LIMIT",
    "SW_REMOTE",
    "SW_TARGET_REACHED",
    "SW_WARNING",
    "StateMachine",
    "mode_name",
    "mode_value",
    "state_from_statusword",
]

#: Default bound of one state change, s. The drive itself answers within a few ms; the rest is
#: the link: a state change is several SDO round trips, and each lost frame costs a resend after
#: 0.3 s, 0.6 s, 1.2 s (:class:`drive_link.link._sdo.SdoChannel`). 3 s ran out at 5 % frame loss on
#: a busy host (full suite, CI); 10 s bounds a refusal just as well.
STATE_TIMEOUT_S = 10.0

#: modes_of_operation (0x6060) values by host name (values from the EDS enumeration).
MODES: dict[str, int] = {
    "speed": int(ModeOfOperation.PROFILE_VELOCITY),
    "torque": int(ModeOfOperation.PROFILE_TORQUE),
    "current": int(ModeOfOperation.PSEUDO_CURRENT),
}
MODE_NAMES: dict[int, str] = {v: k for k, v in MODES.items()}


def mode_value(mode: str | ModeOfOperation) -> int:
    """modes_of_operation value of a host name ("speed", "current", "torque") or a
    :class:`ModeOfOperation` member; :class:`InvalidValue` otherwise."""
    if isinstance(mode, ModeOfOperation):
        return int(mode)
    if mode not in MODES:
        raise InvalidValue(f"mode {mode!r}: one of {', '.join(MODES)}")
    return MODES[mode]


def mode_name(value: int) -> str:
    """Host name of a modes_of_operation value ("speed", "torque", "current" or "mode N")."""
    return MODE_NAMES.get(value, f"mode {value}")


class StateMachine:
    """Drive the 402 state machine through ``read_statusword()`` / ``write_controlword(cw)``.

    ``poll_s`` is the statusword polling period in s; ``settle_s`` how long a fault reset
    must hold (s) before it counts as done.
    """

    def __init__(
        self,
        read_statusword: Callable[[], int],
        write_controlword: Callable[[int], None],
        poll_s: float = 0.005,
        settle_s: float = 0.1,
    ):
        self.read_statusword = read_statusword
        self.write_controlword = write_controlword
        self.poll_s = poll_s
        self.settle_s = settle_s

    @property
    def state(self) -> str:
        """Present state name, read from the drive."""
        return state_from_statusword(self.read_statusword())

    def _wait(
        self, targets: tuple[str, ...], timeout: float, what: str, fail_on_fault: bool = True
    ) -> str:
        deadline = time.monotonic() + timeout
        while True:
            state = self.state
            if state in targets:
                return state
            if fail_on_fault and state in (FAULT, FAULT_REACTION_ACTIVE) and FAULT not in targets:
                raise StateError(f"{what} failed: the drive is in {state} (run fault-reset)")
            if time.monotonic() >= deadline:
                raise DriveTimeout(
                    f"{what}: drive stayed in {state} for {timeout:g} s "
                    f"(expected {' or '.join(targets)})"
                )
            time.sleep(self.poll_s)

    def _step(self, cw: int, targets: tuple[str, ...], timeout: float, what: str) -> str:
        self.write_controlword(cw)
        return self._wait(targets, timeout, what)

    def enable(self, timeout: float = STATE_TIMEOUT_S) -> str:
        """Go to OPERATION ENABLED via the shortest legal path (transitions 2, 3, 4 / 16).

        ``timeout``: s each transition may take after its controlword was written (the time the
        link needs to write it is not the drive's)."""
        what = "enable"
        for _ in range(6):
            state = self.state
            if state == OPERATION_ENABLED:
                return state
            if state in (FAULT, FAULT_REACTION_ACTIVE):
                raise StateError(f"enable refused: the drive is in {state} (run fault-reset first)")
            if state == NOT_READY:
                self._wait((SWITCH_ON_DISABLED,), timeout, what)
            elif state == QUICK_STOP_ACTIVE:
                self._step(
                    CW_ENABLE_OPERATION, (OPERATION_ENABLED, SWITCH_ON_DISABLED), timeout, what
                )
            elif state == SWITCH_ON_DISABLED:
                self._step(CW_SHUTDOWN, (READY_TO_SWITCH_ON,), timeout, what)
            elif state == READY_TO_SWITCH_ON:
                self._step(CW_SWITCH_ON, (SWITCHED_ON,), timeout, what)
            elif state == SWITCHED_ON:
                self._step(CW_ENABLE_OPERATION, (OPERATION_ENABLED,), timeout, what)
            else:
                raise StateError(f"enable: drive reports {state}")
        state = self.state
        if state == OPERATION_ENABLED:
            return state
        raise StateError(f"enable: the drive left each state it reached and is in {state} now")

    def disable(self, timeout: float = STATE_TIMEOUT_S) -> str:
        """Disable the power stage: OPERATION ENABLED → SWITCHED ON (transition 5).

        From QUICK STOP ACTIVE the voltage is disabled instead (transition 12).
        """
        state = self.state
        if state in (SWITCHED_ON, READY_TO_SWITCH_ON, SWITCH_ON_DISABLED, FAULT, NOT_READY):
            return state
        if state == QUICK_STOP_ACTIVE:
            return self._step(CW_DISABLE_VOLTAGE, (SWITCH_ON_DISABLED,), timeout, "disable")
        return self._step(
            CW_DISABLE_OPERATION, (SWITCHED_ON, SWITCH_ON_DISABLED), timeout, "disable"
        )

    def disable_voltage(self, timeout: float = STATE_TIMEOUT_S) -> str:
        """Go to SWITCH ON DISABLED (transitions 7, 9, 10, 12)."""
        if self.state in (SWITCH_ON_DISABLED, FAULT):
            return self.state
        return self._step(CW_DISABLE_VOLTAGE, (SWITCH_ON_DISABLED,), timeout, "disable voltage")

    def quick_stop(self, timeout: float = STATE_TIMEOUT_S) -> str:
        """Quick stop (transition 11); returns QUICK STOP ACTIVE or, after the stop,
        SWITCH ON DISABLED (quick_stop_option_code 0..4)."""
        state = self.state
        if state != OPERATION_ENABLED:
            return self.disable_voltage(timeout)
        return self._step(
            CW_QUICK_STOP, (QUICK_STOP_ACTIVE, SWITCH_ON_DISABLED), timeout, "quick stop"
        )

    def fault_reset(self, timeout: float = STATE_TIMEOUT_S) -> str:
        """Reset a fault (transition 15: rising edge of controlword bit 7) to SWITCH ON DISABLED."""
        state = self.state
        if state not in (FAULT, FAULT_REACTION_ACTIVE):
            return state
        if state == FAULT_REACTION_ACTIVE:
            self._wait((FAULT,), timeout, "fault reset")
        self.write_controlword(CW_DISABLE_VOLTAGE)
        self.write_controlword(CW_FAULT_RESET)
        try:
            self._wait((SWITCH_ON_DISABLED,), timeout, "fault reset", fail_on_fault=False)
            time.sleep(self.settle_s)  # a fault whose cause persists comes straight back
            state = self.state
            if state in (FAULT, FAULT_REACTION_ACTIVE):
                raise DriveTimeout(state)
            return state
        except DriveTimeout:
            raise StateError(
                f"fault reset refused: drive still in {self.state} (fault condition persists?)"
            ) from None
        finally:
            self.write_controlword(CW_DISABLE_VOLTAGE)
