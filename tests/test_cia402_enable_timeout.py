"""``enable``'s timeout bounds the drive, not the link.

CiA 402 (Fig. 4, Table 30): from SWITCH ON DISABLED, OPERATION ENABLED takes transitions 2, 3
and 4, each started by a controlword. On a lossy link every SDO round trip may take a resend;
the time the link needs must not count as the drive "staying" in a state (CI's loss5 row:
"enable: drive stayed in SWITCHED ON for 3 s" from a drive that changes state at once).
Truth: a scripted drive whose statusword follows each controlword at once (Table 30 values),
read over a link that takes 0.25 s per read.
"""

from __future__ import annotations

import time

import pytest

from drive_link.errors import DriveTimeout
from drive_link.link.cia402 import StateMachine

pytestmark = [pytest.mark.timeout(30), pytest.mark.unit]

#: controlword → statusword after it (CiA 402 Table 30 patterns, voltage enabled bit set)
NEXT = {0x06: 0x0231, 0x07: 0x0233, 0x0F: 0x0237}


class _SlowLinkDrive:
    def __init__(self, read_s: float, table: dict[int, int] = NEXT) -> None:
        self.sw = 0x0250  # SWITCH ON DISABLED
        self.read_s = read_s
        self.table = table
        self.written: list[int] = []

    def read(self) -> int:
        time.sleep(self.read_s)
        return self.sw

    def write(self, cw: int) -> None:
        self.written.append(cw)
        self.sw = self.table.get(cw, self.sw)


def test_a_slow_link_does_not_time_out_a_drive_that_changes_state_at_once():
    drv = _SlowLinkDrive(read_s=0.25)
    sm = StateMachine(drv.read, drv.write)
    t0 = time.monotonic()
    assert sm.enable(timeout=0.6) == "OPERATION ENABLED"
    assert time.monotonic() - t0 > 0.6  # (the whole path took longer than one timeout)
    assert drv.written == [0x06, 0x07, 0x0F]


def test_a_drive_that_stays_in_a_state_still_times_out_and_says_where():
    refuses = {**NEXT, 0x0F: 0x0233}  # refuses to enable operation: stays SWITCHED ON
    drv = _SlowLinkDrive(read_s=0.0, table=refuses)
    sm = StateMachine(drv.read, drv.write)
    with pytest.raises(DriveTimeout, match=r"stayed in SWITCHED ON for 0\.3 s"):
        sm.enable(timeout=0.3)
