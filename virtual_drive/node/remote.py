"""Remote frames (RTR) the node receives (CiA 301 §7.2.2.2, §7.2.8.3.1).

canopen's network listener drops remote frames, so the node has its own listener on the
notifier: a remote request for a TPDO whose COB-ID allows RTR (bit 30 = 0) makes the PDO engine
send it now (NMT OPERATIONAL, inhibit time kept). Node guarding (an RTR on 0x700 + node-ID,
0x100C guard time / 0x100D life time factor) is not implemented: the drive's error control is the
heartbeat (CiA 301 allows either; the EDS has no 0x100C/0x100D, SDO access to them aborts
0x06020000), so a guarding request gets no answer. Both are counted.
"""

from __future__ import annotations

from collections.abc import Callable

import can

__all__ = ["RemoteRequests"]


class RemoteRequests(can.Listener):
    """Counts remote frames (``seen``) and the TPDOs sent for them (``answered``)."""

    def __init__(self, on_remote: Callable[[int], bool]) -> None:
        self._on_remote = on_remote
        self.seen = 0
        self.answered = 0

    def on_message_received(self, msg: can.Message) -> None:
        if not msg.is_remote_frame:
            return
        self.seen += 1
        if self._on_remote(msg.arbitration_id):
            self.answered += 1
