"""Supervision in every CiA 402 state (issue 29, item 1): what may change where.

Truths: CiA 402 (IEC 61800-7-201) Table 26 / Figure 11: the drive function is enabled in
OPERATION ENABLED, QUICK STOP ACTIVE and FAULT REACTION ACTIVE, and OPERATION ENABLED is one
controlword away from READY TO SWITCH ON (transitions 3+4), SWITCHED ON (4) and a held QUICK
STOP ACTIVE (16, 0x605A = 5..8); CiA 301 §7.2.8.3.2: a heartbeat consumer that sees no heartbeat
within its time reports it (and a CiA 402 drive applies 0x6007). Everything is measured through
canopen's own master (RemoteNode / SdoClient, stock canopen) on a private virtual bus; the
master produces its own heartbeat (node 0x7F) with python-can's periodic send.

The rule tested row by row is the table "Supervision by state" in virtual_drive/node/README.md.
"""

from __future__ import annotations

import time

import pytest
from canopen.sdo import SdoAbortedError
from conftest import cia402_state
from test_node_support import Bench

pytestmark = pytest.mark.timeout(60)

HOST = 0x7F  #: the master's node-ID (its heartbeat on 0x77F)
ENTRY = (HOST << 16) | 500  #: 0x1016:1 = 0x007F01F4: node 0x7F, 500 ms
STATE_ABORT = 0x08000022
CONFIG = ("motor.L", "motor_rated_current", "protection.overcurrent_trip")


def abort(bench: Bench, name: str, value) -> int | None:
    try:
        bench.write(name, value)
    except SdoAbortedError as exc:
        return exc.code
    return None


def run_at(bench: Bench, rpm: float = 1000.0) -> None:
    bench.write("profile_acceleration", 20000)
    bench.write("target_velocity", int(rpm))
    bench.enable(3)
    assert bench.wait(lambda: bench.read("measurements.speed") > 0.95 * rpm, 10.0)


def reset_communication(bench: Bench) -> None:
    t0 = time.monotonic()
    bench.nmt(0x82)
    boot = bench.log.wait_for(0x701, 5.0, since=t0, pred=lambda d: d == b"\x00")
    assert boot is not None, "no boot-up after reset communication"
    assert bench.wait(lambda: bench.drive.nmt.state == 0x7F)


@pytest.fixture
def bench():
    b = Bench(speed=1.0)
    beat = b.net.send_periodic(0x700 + HOST, b"\x05", 0.1)
    b.beat = beat
    b.write("quick_stop_option_code", 6)
    b.write("consumer_heartbeat_time.consumer_1", ENTRY)
    time.sleep(0.3)  # monitoring starts with the first heartbeat received (CiA 301)
    yield b
    try:
        beat.stop()
    except Exception:
        pass
    b.close()


def test_held_quick_stop_keeps_supervision_through_reset_communication(bench):
    """The issue's sequence: held quick stop (0x1617), NMT reset communication, 0x000F runs the
    motor again; the master's heartbeat then stops: the drive must react (0x6007 = 3 quick
    stop), not run on unsupervised."""
    bench.write("quick_stop_deceleration", 20000)
    run_at(bench)
    bench.write("controlword", 0x0002)
    assert bench.wait(lambda: bench.read("statusword") == 0x1617, 3.0), hex(
        bench.read("statusword")
    )
    reset_communication(bench)
    assert bench.read("consumer_heartbeat_time.consumer_1") == ENTRY
    bench.write("controlword", 0x000F)  # transition 16: back to OPERATION ENABLED
    assert cia402_state(bench.read("statusword")) == "OPERATION ENABLED"
    assert bench.wait(lambda: bench.read("measurements.speed") > 950.0, 10.0)
    t_lost = time.monotonic()
    bench.beat.stop()
    # 500 ms consumer time, then the 0x6007 quick stop (0x6085 = 20000 rpm/s, capped by the
    # current limit: under 0.5 s from 1000 rpm)
    assert bench.wait(lambda: abs(bench.read("measurements.speed")) < 15.0, 3.0)
    assert cia402_state(bench.read("statusword")) == "QUICK STOP ACTIVE"
    emcy = bench.log.wait_for(0x81, 0.5, since=t_lost, pred=lambda d: d[:2] == b"\x30\x81")
    assert emcy is not None, "no EMCY 0x8130 heartbeat loss"


def _reach(bench: Bench, row: str) -> None:
    """Bring the drive into the row's state (a master's controlwords / SDO writes only)."""
    if row == "SWITCH ON DISABLED":
        pass
    elif row == "READY TO SWITCH ON":
        bench.write("controlword", 0x06)
    elif row == "SWITCHED ON":
        bench.write("controlword", 0x06)
        bench.write("controlword", 0x07)
    elif row == "OPERATION ENABLED":
        run_at(bench, 300.0)
    elif row == "QUICK STOP ACTIVE braking":
        run_at(bench, 1000.0)
        bench.write("quick_stop_deceleration", 200)  # 5 s from 1000 rpm
        bench.write("controlword", 0x02)
        assert abs(bench.read("measurements.speed")) > 500.0  # still braking
    elif row == "QUICK STOP ACTIVE held":
        bench.write("quick_stop_deceleration", 20000)
        run_at(bench, 300.0)
        bench.write("controlword", 0x02)
        assert bench.wait(lambda: bench.read("statusword") & 0x0400, 3.0)  # stopped, held
    elif row == "FAULT":
        run_at(bench, 300.0)
        bench.write("sim_fault.inject", 1)  # overcurrent trip
        assert bench.wait(lambda: cia402_state(bench.read("statusword")) == "FAULT")
    else:
        raise AssertionError(row)
    want = row.replace(" braking", "").replace(" held", "")
    assert cia402_state(bench.read("statusword")) == want


#: row -> (configuration-only objects writable, 0x1016 kept by NMT reset communication)
ROWS = {
    "SWITCH ON DISABLED": (True, False),
    "READY TO SWITCH ON": (True, True),
    "SWITCHED ON": (True, True),
    "OPERATION ENABLED": (False, True),
    "QUICK STOP ACTIVE braking": (False, True),
    "QUICK STOP ACTIVE held": (False, True),
    "FAULT": (True, False),
}


@pytest.mark.parametrize("row", list(ROWS))
def test_state_row(bench, row):
    config_writable, keeps_1016 = ROWS[row]
    _reach(bench, row)
    for name in CONFIG:
        got = abort(bench, name, bench.read(name))  # the present value: only the state decides
        assert got == (None if config_writable else STATE_ABORT), (row, name, got)
    reset_communication(bench)
    kept = bench.read("consumer_heartbeat_time.consumer_1")
    assert kept == (ENTRY if keeps_1016 else 0), (row, hex(kept))
    if keeps_1016:  # and it still watches: the master's heartbeat stops -> EMCY 0x8130
        t_lost = time.monotonic()
        bench.beat.stop()
        emcy = bench.log.wait_for(0x81, 2.0, since=t_lost, pred=lambda d: d[:2] == b"\x30\x81")
        assert emcy is not None, f"{row}: heartbeat loss not seen after reset communication"
