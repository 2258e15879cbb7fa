"""NMT commands while the power stage is on (CiA 402 §6.3.3 0x6007, CiA 301 §7.2.8.2.1).

Truths: CiA 402 lists "NMT stopped state entered", "reset application" and "reset communication"
among the abort-connection events whose reaction 0x6007 defines (3 = quick stop, which then
follows 0x605A); CiA 301 says a reset node sends its boot-up message once the reset is complete
and reset communication restores the communication objects to their stored values. Measured
through a canopen master (RemoteNode/SdoClient) and the frames it sees on the virtual bus.
"""

from __future__ import annotations

import time

import pytest
from canopen.profiles.p402 import State402
from test_node_support import Bench

pytestmark = [pytest.mark.timeout(90), pytest.mark.unit]

SPIN_A = 50.0  #: pseudo-current that spins the default load to ~800 rpm (A)
COAST_AFTER_S = 0.5  #: coasting from 400 rpm leaves > 200 rpm after this (J/B_tot ≈ 0.93 s)


def state_of(statusword: int) -> str:
    for state, (mask, value) in State402.SW_MASK.items():
        if statusword & mask == value:
            return state
    raise AssertionError(f"statusword 0x{statusword:04X} matches no CiA 402 state")


@pytest.fixture
def bench():
    b = Bench(speed=1.0)
    yield b
    b.close()


def spin(bench: Bench, rpm: float = 400.0) -> None:
    bench.write("quick_stop_deceleration", 20000)
    bench.enable(-1)
    bench.write("setpoints.i_p_ref", SPIN_A)
    assert bench.wait(lambda: bench.read("measurements.speed") > rpm, 15.0)


def boot_after(bench: Bench, t0: float, timeout: float = 5.0):
    return bench.log.wait_for(0x701, timeout, since=t0, pred=lambda d: d == b"\x00")


def test_nmt_stop_while_enabled_quick_stops(bench):
    spin(bench)
    assert bench.read("abort_connection_option_code") == 3
    bench.nmt(0x02)  # STOPPED: no SDO, no PDO; the master lost its way to command the drive
    time.sleep(COAST_AFTER_S)
    bench.nmt(0x80)  # back to PRE-OPERATIONAL to look
    assert bench.wait(lambda: bench.drive.nmt.state == 0x7F)
    assert abs(bench.read("measurements.speed")) < 15.0
    # 0x605A = 2: quick stop ramp, then SWITCH ON DISABLED
    assert state_of(bench.read("statusword")) == "SWITCH ON DISABLED"


def test_nmt_stop_with_option_fault_goes_to_fault(bench):
    bench.write("abort_connection_option_code", 1)
    spin(bench)
    bench.nmt(0x02)
    time.sleep(COAST_AFTER_S)
    bench.nmt(0x80)
    assert bench.wait(lambda: bench.drive.nmt.state == 0x7F)
    assert state_of(bench.read("statusword")) == "FAULT"
    assert abs(bench.read("measurements.speed")) < 15.0  # 0x605E = 2: quick-stop ramp first


def test_nmt_stop_with_option_none_keeps_running(bench):
    """0x6007 = 0 is "no action": the configured choice is honoured for NMT stop."""
    bench.write("abort_connection_option_code", 0)
    spin(bench)
    bench.nmt(0x02)
    time.sleep(0.2)
    bench.nmt(0x80)
    assert bench.wait(lambda: bench.drive.nmt.state == 0x7F)
    assert state_of(bench.read("statusword")) == "OPERATION ENABLED"
    bench.write("controlword", 0x02)  # quick stop before the fixture closes


def test_reset_node_while_enabled_boots_only_at_standstill(bench):
    spin(bench)
    before = bench.read("measurements.speed")
    t0 = time.monotonic()
    bench.nmt(0x81)
    boot = boot_after(bench, t0)
    assert boot is not None, "no boot-up after reset node"
    bench.wait(lambda: bench.drive.nmt.state == 0x7F)
    # the boot-up came after the stop ramp: the motor stands, the application is reset
    assert abs(bench.read("measurements.speed")) < 15.0, before
    assert state_of(bench.read("statusword")) == "SWITCH ON DISABLED"
    assert bench.read("modes_of_operation_display") == 3  # application parameters reset
    # no heartbeat of the node between the reset command and its boot-up (INITIALISING)
    beats = [t for t, d in bench.log.of(0x701, t0) if t < boot[0]]
    assert beats == []


def test_reset_node_with_option_none_still_stops_the_motor(bench):
    bench.write("abort_connection_option_code", 0)
    spin(bench)
    t0 = time.monotonic()
    bench.nmt(0x81)
    assert boot_after(bench, t0) is not None
    bench.wait(lambda: bench.drive.nmt.state == 0x7F)
    assert abs(bench.read("measurements.speed")) < 15.0
    assert bench.read("abort_connection_option_code") == 3  # default again after the reset


def test_reset_communication_with_option_none_still_stops_the_motor(bench):
    bench.write("abort_connection_option_code", 0)
    spin(bench)
    t0 = time.monotonic()
    bench.nmt(0x82)
    assert boot_after(bench, t0) is not None
    assert bench.wait(lambda: bench.drive.nmt.state == 0x7F)
    # the ramp ends below 10 rpm, then SWITCH ON DISABLED (0x605A = 2)
    assert bench.wait(lambda: state_of(bench.read("statusword")) == "SWITCH ON DISABLED", 3.0)
    assert abs(bench.read("measurements.speed")) < 15.0


def test_reset_communication_while_enabled_quick_stops_and_keeps_supervision(bench):
    host = 0x7E
    entry = (host << 16) | 500
    bench.write("consumer_heartbeat_time.consumer_1", entry)  # configured, not stored
    spin(bench)
    t0 = time.monotonic()
    bench.nmt(0x82)
    assert boot_after(bench, t0) is not None
    assert bench.wait(lambda: bench.drive.nmt.state == 0x7F)
    # the power stage was still braking at the reset: supervision kept
    assert bench.read("consumer_heartbeat_time.consumer_1") == entry
    # the ramp ends below 10 rpm, then SWITCH ON DISABLED (0x605A = 2)
    assert bench.wait(lambda: state_of(bench.read("statusword")) == "SWITCH ON DISABLED", 3.0)
    assert abs(bench.read("measurements.speed")) < 15.0


def test_reset_communication_at_rest_restores_stored_values(tmp_path):
    """CiA 301: reset communication reloads 0x1000-0x1FFF from the store: a stored consumer
    entry survives, an unstored change is dropped (the motor cannot run: nothing is enabled)."""
    b = Bench(speed=1.0, store_path=tmp_path / "p.json")
    try:
        stored = (0x7E << 16) | 400
        b.write("consumer_heartbeat_time.consumer_1", stored)
        b.write("store_parameters.save_all", 0x65766173)
        b.write("consumer_heartbeat_time.consumer_1", (0x7E << 16) | 900)
        t0 = time.monotonic()
        b.nmt(0x82)
        assert boot_after(b, t0) is not None
        assert b.wait(lambda: b.drive.nmt.state == 0x7F)
        assert b.read("consumer_heartbeat_time.consumer_1") == stored
    finally:
        b.close()


def test_canopen_basenode402_nmt_stop_quick_stops(bench):
    """The same through canopen's own CiA 402 master (BaseNode402: PDO-based state walk)."""
    import can
    import canopen
    from canopen.profiles.p402 import BaseNode402

    bench.write("quick_stop_deceleration", 20000)
    bus = can.Bus(interface="virtual", channel=bench.channel)
    net = canopen.Network(bus)
    net.connect()
    try:
        node = BaseNode402(1, bench.view.canopen_od(1))
        net.add_node(node)
        node.sdo.RESPONSE_TIMEOUT = 2.0
        node.nmt.wait_for_heartbeat(2.0)
        node.setup_402_state_machine()
        node.nmt.state = "OPERATIONAL"
        node.op_mode = "PROFILED TORQUE"
        node.sdo["target_torque"].raw = 500  # 50 A
        node.state = "OPERATION ENABLED"
        assert bench.wait(lambda: node.sdo["measurements"]["speed"].raw > 400, 15.0)
        node.nmt.state = "STOPPED"
        time.sleep(COAST_AFTER_S)
        node.nmt.state = "PRE-OPERATIONAL"
        assert bench.wait(lambda: bench.drive.nmt.state == 0x7F)
        assert abs(node.sdo["measurements"]["speed"].raw) < 15.0
        assert state_of(node.sdo["statusword"].raw) == "SWITCH ON DISABLED"
    finally:
        net.disconnect()
