"""RPDOs that cannot be processed (CiA 301 §7.2.2.2, Table 21 EMCY codes).

Truths: CiA 301 says an RPDO with fewer data bytes than its mapping is not processed and the
device signals EMCY 0x8210 "PDO not processed due to length error"; a PDO is one consistent
set of values, so when one mapped value is refused none of them may apply (the drive reports
EMCY 0x8200 "protocol error", see OD.md). Frames are sent by canopen's own RPDO map
(``RemoteNode.rpdo``) where possible, raw only for the short frame canopen cannot produce.
"""

from __future__ import annotations

import struct
import time

import pytest
from canopen.profiles.p402 import State402
from test_node_support import Bench, emcy_frames

pytestmark = [pytest.mark.timeout(60), pytest.mark.unit]


@pytest.fixture
def bench():
    b = Bench(speed=1.0)
    b.node.rpdo.read()  # canopen reads the drive's RPDO configuration by SDO
    b.nmt(0x01)
    assert b.wait(lambda: b.drive.nmt.state == 0x05)
    yield b
    b.close()


def state_of(statusword: int) -> str:
    for state, (mask, value) in State402.SW_MASK.items():
        if statusword & mask == value:
            return state
    raise AssertionError(f"statusword 0x{statusword:04X} matches no CiA 402 state")


def wait_emcy(bench: Bench, code: int, since: float):
    got = bench.log.wait_for(
        0x81, 2.0, since=since, pred=lambda d: struct.unpack_from("<H", d)[0] == code
    )
    assert got is not None, f"no EMCY 0x{code:04X}"
    return got[1]


def test_short_rpdo_is_not_processed_and_signalled(bench):
    rpdo1 = bench.node.rpdo[1]
    assert [v.name for v in rpdo1.map] == ["controlword", "target_velocity"]
    t0 = time.monotonic()
    bench.net.send_message(0x201, struct.pack("<Hh", 0x06, 100))  # 4 of 6 bytes
    data = wait_emcy(bench, 0x8210, t0)
    assert data[2] & 0x11 == 0x11  # error register: generic + communication
    assert data[3:6] == bytes([1, 4, 6])  # RPDO1, 4 bytes received, 6 mapped
    assert bench.read("error_register") & 0x10
    assert state_of(bench.read("statusword")) == "SWITCH ON DISABLED"  # 0x06 not applied
    assert bench.read("target_velocity") == 0
    # a complete RPDO is processed and clears the error (error-reset EMCY)
    t1 = time.monotonic()
    rpdo1["controlword"].raw = 0x06
    rpdo1["target_velocity"].raw = 100
    rpdo1.transmit()
    assert bench.wait(lambda: state_of(bench.read("statusword")) == "READY TO SWITCH ON")
    assert bench.read("target_velocity") == 100
    assert bench.log.wait_for(0x81, 2.0, since=t1, pred=lambda d: d[:3] == b"\x00\x00\x00")
    assert bench.read("error_register") == 0


def test_out_of_range_value_drops_the_whole_pdo(bench):
    rpdo1 = bench.node.rpdo[1]
    t0 = time.monotonic()
    rpdo1["controlword"].raw = 0x06  # valid: shutdown -> READY TO SWITCH ON
    rpdo1["target_velocity"].raw = 7000  # above 0x6080 max_motor_speed (4000) and 6000
    rpdo1.transmit()
    data = wait_emcy(bench, 0x8200, t0)
    assert data[3] == 1  # RPDO1
    assert struct.unpack_from("<HB", data, 4) == (0x60FF, 0)
    assert data[7] == 0x31  # abort 0x06090031 value too high
    time.sleep(0.05)
    # nothing of the PDO applied: the controlword in the same frame was dropped as well
    assert state_of(bench.read("statusword")) == "SWITCH ON DISABLED"
    assert bench.read("target_velocity") == 0
    assert bench.drive.pdo.refused_rx == 1
    # the same PDO with a valid velocity applies both objects
    rpdo1["target_velocity"].raw = 500
    rpdo1.transmit()
    assert bench.wait(lambda: state_of(bench.read("statusword")) == "READY TO SWITCH ON")
    assert bench.read("target_velocity") == 500
    codes = [code for _, code, _ in emcy_frames(bench.log, since=t0)]
    assert codes == [0x8200, 0x0000]


def test_rpdo_refused_by_device_state_is_dropped_too(bench):
    """modes_of_operation in OPERATION ENABLED is refused (0x08000022): with a remapped RPDO2
    (mode + pseudo-current) the current setpoint of that frame does not apply either."""
    bench.nmt(0x80)
    assert bench.wait(lambda: bench.drive.nmt.state == 0x7F)
    rpdo2 = bench.node.rpdo[2]
    rpdo2.clear()
    rpdo2.add_variable("setpoints", "i_p_ref")
    rpdo2.add_variable("modes_of_operation")
    rpdo2.enabled = True
    rpdo2.save()
    bench.nmt(0x01)
    assert bench.wait(lambda: bench.drive.nmt.state == 0x05)
    bench.enable(-1)
    t0 = time.monotonic()
    rpdo2["setpoints.i_p_ref"].raw = 5.0
    rpdo2["modes_of_operation"].raw = 3
    rpdo2.transmit()
    data = wait_emcy(bench, 0x8200, t0)
    assert data[3] == 2 and struct.unpack_from("<HB", data, 4) == (0x6060, 0)
    assert data[7] == 0x22
    assert bench.read("setpoints.i_p_ref") == 0.0
    bench.write("controlword", 0x00)
