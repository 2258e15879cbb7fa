"""PDOs of the virtual drive (CiA 301 §7.2.2 / §7.5.2.35–38): event-timer rates, values equal to
the OD, RPDOs writing setpoints through the checks, remapping by canopen's own PDO client in
PRE-OPERATIONAL only. Truth: the default mapping table in docs/contracts.md §1."""

from __future__ import annotations

import itertools
import struct
import time

import can
import pytest
from canopen.sdo import SdoAbortedError
from conftest import RunQueueProbe, min_rate
from test_node_support import Bench

from virtual_drive.hub_protocol import SENDAT_MAX_BACKDATE_S

pytestmark = [pytest.mark.timeout(60), pytest.mark.unit]


@pytest.fixture
def bench():
    b = Bench(speed=1.0)
    yield b
    b.close()


class SendStamps(can.Listener):
    """Send time stamps (python-can's virtual bus stamps a frame when it is sent) per COB-ID."""

    def __init__(self) -> None:
        self.t: dict[int, list[float]] = {}

    def on_message_received(self, msg: can.Message) -> None:
        self.t.setdefault(msg.arbitration_id, []).append(msg.timestamp)


def test_tpdo_rates_follow_event_timers(bench):
    """Every event-timer period ends in a frame or in the drive's missed-period counter 0x2070:
    from the activation (between the NMT start and the first frame) to the last frame,
    frames + missed periods = elapsed / period (a frame is less than one period late against
    its grid point, or the whole periods are counted). Holds on a loaded machine too: a stalled
    drive sends fewer frames but counts them. No TPDO goes out faster than its timer."""
    stamps = SendStamps()
    bench.net.notifier.add_listener(stamps)
    missed0 = {k: bench.read(f"tpdo_missed_events.tpdo{k}") for k in range(1, 5)}
    probe = RunQueueProbe()  # what the kernel gave this process (drive and master) meanwhile
    t_nmt = time.time()  # the virtual bus stamps with time.time()
    bench.nmt(0x01)
    time.sleep(1.0)
    bench.nmt(0x80)
    assert bench.wait(lambda: bench.drive.nmt.state == 0x7F)
    time.sleep(0.1)
    probe.stop()
    missed = {k: bench.read(f"tpdo_missed_events.tpdo{k}") - missed0[k] for k in range(1, 5)}
    for k, period in ((1, 0.010), (2, 0.001), (3, 0.001), (4, 0.010)):
        t = stamps.t.get(0x81 + 0x100 * k, [])
        assert len(t) >= 2, (k, probe)
        total = len(t) + missed[k]
        low = (t[-1] - t[0]) / period + 1  # activation at the latest one period before t[0]
        high = (t[-1] - t_nmt) / period + 1  # activation at the earliest at the NMT start
        # the last frame may lag its grid point by up to a period plus the send path
        slack = 3 + 0.02 * high
        assert low - slack <= total <= high + slack, (k, len(t), missed[k], low, high, probe)
        assert len(t) - 1 <= (t[-1] - t[0]) / period * 1.02 + 2, (k, len(t))  # not faster
    assert len(stamps.t[0x281]) >= min_rate(1000, probe.wait) * 0.9, (len(stamps.t[0x281]), probe)


def test_tpdo_payloads_match_sdo_reads(bench):
    bench.nmt(0x01)
    bench.enable(-1)
    bench.write("setpoints.i_p_ref", 12.0)
    assert bench.wait(lambda: abs(bench.read("measurements.i_p") - 12.0) < 1.0)
    v0 = bench.read("velocity_actual_value")
    t0 = time.monotonic()
    got = bench.log.wait_for(0x181, 1.0, since=t0)
    sw, vel = struct.unpack("<Hi", got[1])
    v1 = bench.read("velocity_actual_value")
    # state bits and remote as the SDO read says (bit 10 may flicker with the current ripple)
    assert sw & 0x6F == 0x27 and sw & 0x26F == bench.read("statusword") & 0x26F
    # the motor accelerates under 12 A: the TPDO's value lies between the reads around it
    assert min(v0, v1) - 2 <= vel <= max(v0, v1) + 2, (v0, vel, v1)
    _, data = bench.log.wait_for(0x281, 1.0, since=t0)
    i_p, _speed = struct.unpack("<ff", data)
    assert abs(i_p - 12.0) < 1.5
    _, data = bench.log.wait_for(0x381, 1.0, since=t0)
    i_p_ref, _speed_ref = struct.unpack("<ff", data)
    assert i_p_ref == pytest.approx(12.0)


def test_rpdos_drive_the_state_machine_and_setpoints(bench):
    bench.nmt(0x01)
    bench.write("modes_of_operation", -1)
    for cw in (0x06, 0x07, 0x0F):
        bench.net.send_message(0x201, struct.pack("<Hi", cw, 0))
        time.sleep(0.01)
    assert bench.wait(lambda: bench.read("statusword") & 0x6F == 0x27)
    bench.net.send_message(0x301, struct.pack("<f", 8.0))
    assert bench.wait(lambda: bench.read("setpoints.i_p_ref") == pytest.approx(8.0))
    # a value the checks refuse is dropped: setpoint unchanged
    bench.net.send_message(0x301, struct.pack("<f", 900.0))
    time.sleep(0.05)
    assert bench.read("setpoints.i_p_ref") == pytest.approx(8.0)
    # RPDOs are ignored outside OPERATIONAL
    bench.nmt(0x80)
    assert bench.wait(lambda: bench.drive.nmt.state == 0x7F)
    bench.net.send_message(0x301, struct.pack("<f", 3.0))
    time.sleep(0.05)
    assert bench.read("setpoints.i_p_ref") == pytest.approx(8.0)


def test_remap_tpdo_with_canopen_pdo_client(bench):
    node = bench.node
    node.tpdo.read()
    tp = node.tpdo[4]
    assert [v.name for v in tp.map] == ["measurements.v_L", "measurements.e_L"]
    tp.clear()
    tp.add_variable("measurements", "i_a")
    tp.add_variable("measurements", "i_b")
    tp.event_timer = 5
    tp.enabled = True
    tp.save()  # PRE-OPERATIONAL: allowed
    # fewer frames for this single-process test: switch the two 1 kHz TPDOs off
    bench.write("tpdo2_communication.cob_id", 0x80000281)
    bench.write("tpdo3_communication.cob_id", 0x80000381)
    assert bench.read("tpdo4_mapping.mapped_object_1") == bench.view.od_reference(
        "measurements.i_a"
    )
    bench.nmt(0x01)
    bench.enable(-1)
    bench.write("setpoints.i_p_ref", 10.0)
    time.sleep(0.2)
    m0 = {k: bench.read(f"tpdo_missed_events.tpdo{k}") for k in (1, 4)}
    t0 = time.monotonic()
    time.sleep(0.5)
    m1 = {k: bench.read(f"tpdo_missed_events.tpdo{k}") for k in (1, 4)}
    frames = bench.log.of(0x481, t0)
    # 5 ms event timer now: twice the periods of TPDO1 (10 ms) over the same window, frames
    # plus the periods the drive counted as missed (robust when the machine starves it)
    n4 = len(frames) + m1[4] - m0[4]
    n1 = len(bench.log.of(0x181, t0)) + m1[1] - m0[1]
    assert 1.6 <= n4 / max(n1, 1) <= 2.4, (n4, n1)
    assert bench.log.of(0x281, t0) == []
    i_a, i_b = struct.unpack("<ff", frames[-1][1])
    assert abs(i_a) + abs(i_b) > 5.0  # phase currents, not voltages
    # in OPERATIONAL the mapping is locked
    with pytest.raises(SdoAbortedError) as exc:
        bench.write("tpdo4_mapping.number_of_mapped_objects", 0)
    assert exc.value.code == 0x08000022


def test_mapping_rules(bench):
    # mapping a valid PDO is refused; sub-entries only with sub0 = 0
    with pytest.raises(SdoAbortedError) as exc:
        bench.write("tpdo2_mapping.number_of_mapped_objects", 0)
    assert exc.value.code == 0x06010000
    bench.write("tpdo2_communication.cob_id", 0x80000281)
    with pytest.raises(SdoAbortedError) as exc:
        bench.write("tpdo2_mapping.mapped_object_1", 0x60410010)
    assert exc.value.code == 0x06010000
    bench.write("tpdo2_mapping.number_of_mapped_objects", 0)
    bench.write("tpdo2_mapping.mapped_object_1", 0x60410010)  # statusword
    bench.write("tpdo2_mapping.mapped_object_2", 0x20F10008)  # write-only object
    with pytest.raises(SdoAbortedError) as exc:
        bench.write("tpdo2_mapping.number_of_mapped_objects", 2)
    assert exc.value.code == 0x06040041
    for k in range(1, 4):
        bench.write(f"tpdo2_mapping.mapped_object_{k}", 0x20400120)  # 3 x 32 bit = 96 bit
    with pytest.raises(SdoAbortedError) as exc:
        bench.write("tpdo2_mapping.number_of_mapped_objects", 3)
    assert exc.value.code == 0x06040042
    # a COB-ID change of a valid PDO is refused
    with pytest.raises(SdoAbortedError) as exc:
        bench.write("tpdo1_communication.cob_id", 0x191)
    assert exc.value.code == 0x06090030
    # reserved transmission types
    with pytest.raises(SdoAbortedError) as exc:
        bench.write("tpdo1_communication.transmission_type", 250)
    assert exc.value.code == 0x06090030


def test_sync_tpdo_every_second_sync(bench):
    bench.write("tpdo1_communication.transmission_type", 2)  # synchronous, every 2nd SYNC
    bench.nmt(0x01)
    time.sleep(0.05)
    t0 = time.monotonic()
    for _ in range(6):
        bench.net.send_message(0x080, b"")
        time.sleep(0.01)
    assert bench.wait(lambda: len(bench.log.of(0x181, t0)) >= 3, 2.0)
    time.sleep(0.05)
    assert len(bench.log.of(0x181, t0)) == 3  # and no more on its (ignored) event timer


def test_emcy_cob_id_invalid_bit_silences_emcy(bench):
    bench.write("cob_id_emcy", 0x80000081)
    bench.nmt(0x01)
    bench.enable(-1)
    t0 = time.monotonic()
    bench.write("sim_fault.inject", 1)
    assert bench.wait(lambda: bench.read("statusword") & 0x4F == 0x08)
    time.sleep(0.05)
    assert bench.log.of(0x81, t0) == []
    assert bench.read("error_code") == 0x2310  # bookkeeping still done


def test_batched_tick_states_no_bus_time_older_than_the_bus_takes():
    """A drive that runs its ticks in batches states each TPDO's bus time (``tick_at``). After
    a stall its catch-up states times long past; the engine states them as at most
    ``stamp_max_age`` ago and counts its event timers and inhibit times from there, so a
    catch-up never puts two frames of one TPDO closer than its event period (CiA 301: one
    late frame, the missed periods counted in 0x2070, no burst)."""
    from virtual_drive.node import VirtualDrive

    bus = can.Bus(interface="virtual", channel="batched-stamps", receive_own_messages=False)
    drive = VirtualDrive(bus, node_id=1)
    sent: list[tuple[float, int]] = []
    drive.pdo._send_many = lambda frames, at=None: sent.extend((at, c) for c, _ in frames)
    try:
        drive.nmt.boot()
        drive.nmt.command(0x01)  # OPERATIONAL: the TPDO table is built (no pacing thread)
        age = drive.pdo.stamp_max_age
        assert 0 < age <= SENDAT_MAX_BACKDATE_S
        stall = age + 0.2
        start = time.monotonic()
        time.sleep(stall)  # the drive was not scheduled for longer than the bus looks back
        now = time.monotonic()
        # its catch-up: the 20 ms chunks since then, nearly back to back
        chunks = int(stall / 0.02) + 1
        for k in range(chunks):
            drive.pdo.tick_at(start + 0.02 * k)
            time.sleep(0.0003)  # (a busy host: the catch-up's chunks 0.3 ms apart)
        done = time.monotonic()
    finally:
        bus.shutdown()
    tpdo2 = [at for at, cob_id in sent if cob_id == 0x281]
    assert tpdo2, sent
    assert min(tpdo2) >= now - age - 1e-6  # never older than the bus takes
    assert max(tpdo2) <= done
    gaps = [b - a for a, b in itertools.pairwise(tpdo2)]
    assert all(g >= 1e-3 - 1e-9 for g in gaps), gaps  # TPDO2's event timer: 1 ms
    missed = drive.pdo.missed[1]
    assert missed >= 0.5 * stall / 1e-3, missed  # the 1 ms periods that passed without a frame
