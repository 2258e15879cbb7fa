"""CiA 402 (IEC 61800-7-201) device control definitions: states, statusword and controlword bits.

Protocol definitions only (no bus I/O, no state machine): the virtual drive encodes its state
into the statusword (0x6041) with :data:`STATE_BITS`, the host decodes it with
:func:`state_from_statusword`; both use the same table. Per CiA 402-2 §7.1 (statusword table:
bits 0, 1, 2, 3, 5, 6; controlword table: bits 0..3 and 7).
"""

from __future__ import annotations

__all__ = [
    "CW_DISABLE_OPERATION",
    "CW_DISABLE_VOLTAGE",
    "CW_ENABLE_OPERATION",
    "CW_ENABLE_OPERATION_BIT",
    "CW_ENABLE_VOLTAGE",
    "CW_FAULT_RESET",
    "CW_HALT",
    "CW_QUICK_STOP",
    "CW_QUICK_STOP_BIT",
    "CW_SHUTDOWN",
    "CW_SWITCH_ON",
    "CW_SWITCH_ON_BIT",
    "FAULT",
    "FAULT_REACTION_ACTIVE",
    "NOT_READY_TO_SWITCH_ON",
    "OPERATION_ENABLED",
    "QUICK_STOP_ACTIVE",
    "READY_TO_SWITCH_ON",
    "STATE_BITS",
    "STATUSWORD_STATES",
    "SWITCHED_ON",
    "SWITCH_ON_DISABLED",
    "SW_INTERNAL_LIMIT",
    "SW_REMOTE",
    "SW_SPEED_ZERO",
    "SW_TARGET_REACHED",
    "SW_VOLTAGE_ENABLED",
    "SW_WARNING",
    "state_from_statusword",
]

# -- states ------------------------------------------------------------------------------
NOT_READY_TO_SWITCH_ON = "NOT READY TO SWITCH ON"
SWITCH_ON_DISABLED = "SWITCH ON DISABLED"
READY_TO_SWITCH_ON = "READY TO SWITCH ON"
SWITCHED_ON = "SWITCHED ON"
OPERATION_ENABLED = "OPERATION ENABLED"
QUICK_STOP_ACTIVE = "QUICK STOP ACTIVE"
FAULT_REACTION_ACTIVE = "FAULT REACTION ACTIVE"
FAULT = "FAULT"

#: (mask, value, state) on the statusword: a state is encoded in bits 0, 1, 2, 3, 5, 6;
#: bit 5 (quick stop) is "don't care" where the mask is 0x4F.
STATUSWORD_STATES: tuple[tuple[int, int, str], ...] = (
    (0x4F, 0x00, NOT_READY_TO_SWITCH_ON),
    (0x4F, 0x40, SWITCH_ON_DISABLED),
    (0x6F, 0x21, READY_TO_SWITCH_ON),
    (0x6F, 0x23, SWITCHED_ON),
    (0x6F, 0x27, OPERATION_ENABLED),
    (0x6F, 0x07, QUICK_STOP_ACTIVE),
    (0x4F, 0x0F, FAULT_REACTION_ACTIVE),
    (0x4F, 0x08, FAULT),
)

#: Statusword state bits a drive reports in each state (bits outside the mask cleared).
STATE_BITS: dict[str, int] = {name: value for _mask, value, name in STATUSWORD_STATES}

# -- other statusword bits ---------------------------------------------------------------
SW_VOLTAGE_ENABLED = 1 << 4
SW_WARNING = 1 << 7
SW_REMOTE = 1 << 9
SW_TARGET_REACHED = 1 << 10
SW_INTERNAL_LIMIT = 1 << 11
SW_SPEED_ZERO = 1 << 12  # profile velocity: |speed| <= 0x606F for 0x6070 ms

# -- controlword bits and commands -------------------------------------------------------
CW_SWITCH_ON_BIT = 1 << 0
CW_ENABLE_VOLTAGE = 1 << 1
CW_QUICK_STOP_BIT = 1 << 2  # active low: 0 = quick stop
CW_ENABLE_OPERATION_BIT = 1 << 3
CW_FAULT_RESET = 1 << 7  # rising edge
CW_HALT = 1 << 8  # profile modes: decelerate (0x605D) and hold 0

CW_SHUTDOWN = 0x0006
CW_SWITCH_ON = 0x0007
CW_ENABLE_OPERATION = 0x000F
CW_DISABLE_VOLTAGE = 0x0000
CW_QUICK_STOP = 0x0002
CW_DISABLE_OPERATION = 0x0007


def state_from_statusword(statusword: int) -> str:
    """CiA 402 state name encoded in a statusword (0x6041); ``"UNKNOWN (...)"`` if none."""
    for mask, value, name in STATUSWORD_STATES:
        if statusword & mask == value:
            return name
    return f"UNKNOWN (statusword 0x{statusword:04X})"
