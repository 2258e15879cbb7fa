"""NMT slave (CiA 301 §7.2.8): states, commands, boot-up, and which services each state allows.

States and their heartbeat codes: INITIALISING 0x00, STOPPED 0x04, OPERATIONAL 0x05,
PRE-OPERATIONAL 0x7F. Commands arrive on COB-ID 0x000 as ``[command, node_id]`` (node_id 0 = all):
0x01 start, 0x02 stop, 0x80 enter pre-operational, 0x81 reset node, 0x82 reset communication.

Entering STOPPED and both resets first run ``on_abort_connection(command)`` (a CiA 402 drive
applies its 0x6007 reaction there: leaving the NMT service with the power stage on is a loss of
the connection). After either reset the node runs the given reset hook, sends a boot-up message
(0x700+N, data ``[0x00]``) and enters PRE-OPERATIONAL. "Reset node" may be completed later: when
``on_reset_node`` returns False the node stays INITIALISING (no heartbeat, no SDO) until
:meth:`NmtSlave.finish_reset` is called (the drive first brakes the motor to standstill).

Services by state (CiA 301 Table 78):
SDO and EMCY in PRE-OPERATIONAL and OPERATIONAL, PDO only in OPERATIONAL, heartbeat in all
states but INITIALISING.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable

from canopen.nmt import NMT_COMMANDS, NMT_STATES

__all__ = [
    "CMD_PRE_OPERATIONAL",
    "CMD_RESET_COMMUNICATION",
    "CMD_RESET_NODE",
    "CMD_START",
    "CMD_STOP",
    "INITIALISING",
    "OPERATIONAL",
    "PRE_OPERATIONAL",
    "STATE_NAMES",
    "STOPPED",
    "NmtSlave",
]

logger = logging.getLogger(__name__)

_STATE_CODES = {name: code for code, name in NMT_STATES.items()}

# states and commands are canopen's CiA 301 tables (canopen.nmt), under the names used here
INITIALISING = _STATE_CODES["INITIALISING"]  # 0x00
STOPPED = _STATE_CODES["STOPPED"]  # 0x04
OPERATIONAL = _STATE_CODES["OPERATIONAL"]  # 0x05
PRE_OPERATIONAL = _STATE_CODES["PRE-OPERATIONAL"]  # 0x7F

STATE_NAMES = {
    code: NMT_STATES[code] for code in (INITIALISING, STOPPED, OPERATIONAL, PRE_OPERATIONAL)
}

CMD_START = NMT_COMMANDS["OPERATIONAL"]  # 0x01
CMD_STOP = NMT_COMMANDS["STOPPED"]  # 0x02
CMD_PRE_OPERATIONAL = NMT_COMMANDS["PRE-OPERATIONAL"]  # 0x80
CMD_RESET_NODE = NMT_COMMANDS["RESET"]  # 0x81
CMD_RESET_COMMUNICATION = NMT_COMMANDS["RESET COMMUNICATION"]  # 0x82


class NmtSlave:
    """The node's NMT state machine.

    :param node_id: this node's ID (1..127).
    :param send: ``send(cob_id, data)`` puts a frame on the bus.
    :param on_reset_node: called on "reset node" (application and communication parameters).
    :param on_reset_communication: called on both resets (communication parameters).
    :param on_state_change: called with ``(old, new)`` after every change.
    :param on_abort_connection: called with the command before entering STOPPED or a reset.
    :param on_boot: called after every boot-up message (power-on and both resets).
    :param on_reset_node: returns None/True when done, False when :meth:`finish_reset` follows.
    """

    def __init__(
        self,
        node_id: int,
        send: Callable[[int, bytes], None],
        on_reset_node: Callable[[], bool | None] = lambda: None,
        on_reset_communication: Callable[[], None] = lambda: None,
        on_state_change: Callable[[int, int], None] = lambda old, new: None,
        on_abort_connection: Callable[[int], None] = lambda command: None,
        on_boot: Callable[[], None] = lambda: None,
    ) -> None:
        self.node_id = node_id
        self._send = send
        self._on_reset_node = on_reset_node
        self._on_reset_comm = on_reset_communication
        self._on_state_change = on_state_change
        self._on_abort = on_abort_connection
        self._on_boot = on_boot
        self._state = INITIALISING
        self.reset_pending = False
        self._lock = threading.RLock()

    @property
    def state(self) -> int:
        """Current state code (heartbeat byte)."""
        return self._state

    @property
    def state_name(self) -> str:
        return STATE_NAMES[self._state]

    def sdo_allowed(self) -> bool:
        return self._state in (PRE_OPERATIONAL, OPERATIONAL)

    def emcy_allowed(self) -> bool:
        return self._state in (PRE_OPERATIONAL, OPERATIONAL)

    def pdo_allowed(self) -> bool:
        return self._state == OPERATIONAL

    def _set_state(self, new: int) -> None:
        old = self._state
        if new == old:
            return
        self._state = new
        logger.info("NMT %s -> %s", STATE_NAMES[old], STATE_NAMES[new])
        self._on_state_change(old, new)

    def boot(self) -> None:
        """Power-on: initialise, send the boot-up message, enter PRE-OPERATIONAL."""
        with self._lock:
            self._state = INITIALISING
            self._send(0x700 + self.node_id, b"\x00")
            self._set_state(PRE_OPERATIONAL)
        self._on_boot()

    def on_command(self, can_id: int, data: bytes | bytearray, timestamp: float) -> None:
        """Notifier callback for COB-ID 0x000."""
        if len(data) < 2:
            return
        command, target = data[0], data[1]
        if target not in (0, self.node_id):
            return
        self.command(command)

    def command(self, command: int) -> None:
        """Apply one NMT command (unknown commands are ignored, as CiA 301 says)."""
        with self._lock:
            if self._state == INITIALISING:
                return
            if command == CMD_START:
                self._set_state(OPERATIONAL)
            elif command == CMD_STOP:
                if self._state != STOPPED:
                    self._on_abort(command)
                self._set_state(STOPPED)
            elif command == CMD_PRE_OPERATIONAL:
                self._set_state(PRE_OPERATIONAL)
            elif command in (CMD_RESET_NODE, CMD_RESET_COMMUNICATION):
                self._on_abort(command)
                self._set_state(INITIALISING)
                if command == CMD_RESET_NODE and self._on_reset_node() is False:
                    self.reset_pending = True  # finish_reset() completes it
                    return
                self._complete_reset()

    def finish_reset(self) -> None:
        """Complete a deferred reset node: reset communication, boot-up, PRE-OPERATIONAL."""
        with self._lock:
            if not self.reset_pending:
                return
            self.reset_pending = False
            self._complete_reset()

    def _complete_reset(self) -> None:
        with self._lock:
            self._on_reset_comm()
            self._send(0x700 + self.node_id, b"\x00")
            self._set_state(PRE_OPERATIONAL)
        self._on_boot()
