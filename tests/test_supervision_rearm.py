"""A drive that boots again gets the session's supervision back before any user command.

CiA 301 §7.2.8.3: after a restart the heartbeat consumer 0x1016 holds its stored/default value
(here: off), so a host that configured it must configure it again; CiA 402 §6.3.3: 0x6007 picks
the reaction to the loss. The drive is restarted the way a crashed virtual drive process comes
back: the node object is stopped and a new one (fresh parameters) starts on the same bus. A
sniffer on the bus gives the order of frames as the bus carried them.
"""

from __future__ import annotations

import struct
import threading
import time
import uuid

import can
import pytest
from can.interfaces.virtual import VirtualBus

from drive_link import Drive
from drive_link.link._sdo import SdoChannel
from drive_link.link.supervision import SupervisionError

pytestmark = [pytest.mark.timeout(90), pytest.mark.unit]

NODE = 5
HOST = 0x7F
MARKER_COB = 0x7F0  # a COB-ID no CiA 301 service and no drive object uses
CONSUMER_MS = 1000  # generous: on a busy host (load 25) the host producer thread stalls 300 ms+


class Sniffer(can.Listener):
    """Every frame on the channel, in bus order, with the monotonic time it was seen."""

    def __init__(self, channel: str) -> None:
        self.channel = channel
        self.bus = can.Bus(interface="virtual", channel=channel)
        self.frames: list[tuple[float, int, bytes]] = []
        self.lock = threading.Lock()
        self.notifier = can.Notifier(self.bus, [self], 0.05)

    def on_message_received(self, msg: can.Message) -> None:
        with self.lock:
            self.frames.append((time.monotonic(), msg.arbitration_id, bytes(msg.data)))

    def since(self, t: float) -> list[tuple[float, int, bytes]]:
        """Frames seen since ``t``, up to everything sent on the bus before this call: a marker
        frame is sent and waited for (the sniffer's thread lags the bus on a busy host)."""
        tag = uuid.uuid4().bytes[:8]
        with can.Bus(interface="virtual", channel=self.channel) as marker:
            marker.send(can.Message(arbitration_id=MARKER_COB, data=tag, is_extended_id=False))
        deadline = time.monotonic() + 30.0
        while time.monotonic() < deadline:
            with self.lock:
                if any(cob == MARKER_COB and data == tag for _, cob, data in self.frames):
                    return [f for f in self.frames if f[0] >= t and f[1] != MARKER_COB]
            time.sleep(0.01)
        raise AssertionError("the sniffer did not see its marker frame within 30 s")

    def close(self) -> None:
        self.notifier.stop(1.0)
        self.bus.shutdown()


class NoBootUpBus(VirtualBus):
    """A virtual bus whose boot-up messages are lost (the host can only see the gap)."""

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        if msg.arbitration_id == 0x700 + NODE and bytes(msg.data) == b"\x00":
            return
        super().send(msg, timeout)


class Rig:
    """Virtual drive process stand-in + the session's Drive + a sniffer on one channel."""

    def __init__(self) -> None:
        from virtual_drive.node import VirtualDrive

        self._vd_cls = VirtualDrive
        self.channel = f"sup-{uuid.uuid4().hex}"
        self.sniffer = Sniffer(self.channel)
        self.vbus = can.Bus(interface="virtual", channel=self.channel)
        self.vd = VirtualDrive(self.vbus, node_id=NODE, speed=2.0).start()
        self.drive = Drive.connect(
            interface="virtual", channel=self.channel, node_id=NODE, heartbeat_ms=50,
            host_id=HOST,
        )
        self.events: list[dict] = []
        self.detected = threading.Event()
        self.drive.on_supervision(self._on_event)

    def _on_event(self, ev: dict) -> None:
        self.events.append(ev)
        if ev["event"] == "reboot_detected":
            self.detected.set()

    def restart(self, bus_cls: type[can.BusABC] | None = None, down_s: float = 0.0) -> float:
        """Stop the drive and start a fresh one; returns the time it started."""
        self.vd.stop()
        self.vbus.shutdown()
        time.sleep(down_s)
        if bus_cls is None:
            self.vbus = can.Bus(interface="virtual", channel=self.channel)
        else:
            self.vbus = bus_cls(channel=self.channel)
        t = time.monotonic()
        self.vd = self._vd_cls(self.vbus, node_id=NODE, speed=2.0).start()
        return t

    def close(self) -> None:
        self.drive.close()
        self.vd.stop()
        self.vbus.shutdown()
        self.sniffer.close()


@pytest.fixture
def rig():
    r = Rig()
    yield r
    r.close()


def _consumer_value() -> int:
    return (HOST << 16) | CONSUMER_MS


def _sdo_requests(frames, index: int, sub: int, download: bool) -> list[float]:
    """Times of SDO initiate requests to (index, sub) in ``frames`` (CiA 301 ccs 1 / 2)."""
    out = []
    for t, cob, data in frames:
        if cob != 0x600 + NODE or len(data) < 4:
            continue
        ccs = data[0] >> 5
        if (ccs == 1) == download and ccs in (1, 2) and struct.unpack_from("<HB", data, 1) == (
            index,
            sub,
        ):
            out.append(t)
    return out


def test_restart_rearms_the_consumer_before_the_first_user_command(rig):
    d = rig.drive
    d.configure_heartbeat_consumer(CONSUMER_MS)
    d.write("abort_connection_option_code", 3)  # quick stop on loss (CiA 402 0x6007)
    assert d.status()["boots_seen"] == 0 and d.status()["supervision_rearmed_at"] is None
    t_restart = rig.restart()
    assert rig.detected.wait(5.0), "boot-up not noticed"
    # the first user command after the boot-up was noticed: it must find 0x1016 re-armed
    got = int(d.read("consumer_heartbeat_time.consumer_1"))
    assert got == _consumer_value()
    frames = rig.sniffer.since(t_restart)
    boot = [t for t, cob, data in frames if cob == 0x700 + NODE and data == b"\x00"]
    assert boot, "no boot-up frame on the bus"
    rearm_writes = _sdo_requests(frames, 0x1016, 1, download=True)
    user_reads = _sdo_requests(frames, 0x1016, 1, download=False)
    assert rearm_writes and user_reads
    # in bus order: boot-up, then a re-arm write, then (only then) the user's read; reads
    # the supervisor makes for its comparison come before its write. (A write resent from a
    # pass that began while the drive was down may precede the boot-up: it does not count.)
    after_boot = [t for t in rearm_writes if t >= boot[0]]
    assert after_boot, "0x1016:01 was not written after the boot-up"
    assert after_boot[0] < user_reads[-1], "the user's read went out before the re-arm write"
    st = d.status()
    assert st["boots_seen"] == 1
    assert st["supervision_rearmed_at"] is not None and st["supervision_rearmed_at"].endswith(
        "+00:00"
    )
    # (a busy host may first have produced a heartbeat-gap check, "restart_suspected" /
    # "verified", and one during the re-arm: the boot-up's own outcome is still "rearmed")
    assert _boot_outcome(rig.events)["event"] == "rearmed", [e["event"] for e in rig.events]
    assert "0x1016:01" in _boot_outcome(rig.events)["written"]


_OUTCOMES = ("rearmed", "verified", "rearm_failed")


def _boot_outcome(events: list[dict]) -> dict:
    """The first re-arm outcome reported after the boot-up was noticed."""
    names = [e["event"] for e in events]
    k = names.index("reboot_detected")
    return next(e for e in events[k + 1 :] if e["event"] in _OUTCOMES)


def test_a_late_heartbeat_during_the_boot_rearm_does_not_hide_its_report(rig):
    """On a starved host the restarted drive's next heartbeat can come late while the boot-up's
    re-arm runs: the supervisor checks once more, and the boot-up's re-arm (what it wrote) is
    still reported as "rearmed" before that check's "verified"."""
    d = rig.drive
    d.configure_heartbeat_consumer(CONSUMER_MS)
    sup = d.supervisor
    real = sup.rearm_now
    late = threading.Event()

    def rearm_now(reason: str, boot: bool):
        report = real(reason, boot)
        if boot and not late.is_set():  # what the heartbeat rule queues for a late heartbeat
            late.set()
            with sup._lock:
                sup._pending, sup._ready = "heartbeat resumed after 900 ms", False
                sup._lock.notify_all()
        return report

    sup.rearm_now = rearm_now
    rig.restart()
    assert rig.detected.wait(5.0), "boot-up not noticed"
    assert int(d.read("consumer_heartbeat_time.consumer_1")) == _consumer_value()
    assert late.is_set()
    deadline = time.monotonic() + 5.0
    while "verified" not in [e["event"] for e in rig.events] and time.monotonic() < deadline:
        time.sleep(0.02)
    names = [e["event"] for e in rig.events]
    outcome = _boot_outcome(rig.events)
    assert outcome["event"] == "rearmed" and "0x1016:01" in outcome["written"], names
    assert names.index("rearmed") < names.index("verified"), names
    assert d.boots_seen == 1


def test_user_commands_in_flight_wait_for_the_rearm(rig):
    """A thread hammering statusword reads through the restart: after the boot-up frame at most
    the one request already under way goes out before the consumer is written again."""
    d = rig.drive
    d.configure_heartbeat_consumer(CONSUMER_MS)
    stop = threading.Event()
    errors: list[str] = []

    def hammer() -> None:
        while not stop.is_set():
            try:
                d.read("statusword")
            except Exception as exc:  # timeouts while the drive is down are expected
                errors.append(type(exc).__name__)

    th = threading.Thread(target=hammer, daemon=True)
    th.start()
    try:
        time.sleep(0.2)
        t_restart = rig.restart(down_s=0.05)
        assert rig.detected.wait(5.0)
        deadline = time.monotonic() + 5.0
        while d.supervisor.rearmed_at is None and time.monotonic() < deadline:
            time.sleep(0.02)
        time.sleep(0.2)
    finally:
        stop.set()
        th.join(5.0)
    frames = rig.sniffer.since(t_restart)
    boot_t = next(t for t, cob, data in frames if cob == 0x700 + NODE and data == b"\x00")
    write_t = _sdo_requests(frames, 0x1016, 1, download=True)[0]
    between = [t for t in _sdo_requests(frames, 0x6041, 0, download=False) if boot_t < t < write_t]
    assert len(between) <= 1, f"{len(between)} user reads went out before the re-arm"
    assert int(d.read("consumer_heartbeat_time.consumer_1")) == _consumer_value()
    assert "SupervisionError" not in errors


def test_host_heartbeat_loss_after_a_restart_still_stops_the_motor(rig):
    d = rig.drive
    d.configure_heartbeat_consumer(CONSUMER_MS)
    d.write("abort_connection_option_code", 3)
    rig.restart()
    assert rig.detected.wait(5.0)
    d.nmt("start")
    d.set_mode("speed")
    d.set_speed(300)
    d.enable(timeout=3.0)
    deadline = time.monotonic() + 20.0
    while float(d.read("measurements.speed")) < 200 and time.monotonic() < deadline:
        time.sleep(0.05)
    assert float(d.read("measurements.speed")) >= 200, "motor did not come up to speed"
    n = len(d.emcy_history)
    d.stop_host_heartbeat()
    deadline = time.monotonic() + 10.0
    while time.monotonic() < deadline:
        if any(e.code == 0x8130 for e in d.emcy_history[n:]) and d.state != "OPERATION ENABLED":
            break
        time.sleep(0.05)
    assert any(e.code == 0x8130 for e in d.emcy_history[n:]), "no heartbeat-loss EMCY"
    assert d.state != "OPERATION ENABLED"
    deadline = time.monotonic() + 20.0
    while abs(float(d.read("measurements.speed"))) > 20 and time.monotonic() < deadline:
        time.sleep(0.05)
    assert abs(float(d.read("measurements.speed"))) <= 20, "motor still turning"


def test_reset_communication_by_the_session_rearms(rig):
    d = rig.drive
    d.configure_heartbeat_consumer(CONSUMER_MS)
    d.reset(communication_only=True)
    assert int(d.read("consumer_heartbeat_time.consumer_1")) == _consumer_value()
    assert d.boots_seen == 1


def test_restart_with_a_lost_boot_up_is_caught_by_the_heartbeat_gap(rig):
    d = rig.drive
    d.configure_heartbeat_consumer(CONSUMER_MS)
    d.nmt("start")
    time.sleep(0.3)
    # the drive is down for > 3 x its 100 ms producer time and its boot-up never arrives
    rig.restart(bus_cls=NoBootUpBus, down_s=0.5)
    deadline = time.monotonic() + 8.0
    while d.supervisor.rearmed_at is None and time.monotonic() < deadline:
        time.sleep(0.02)
    assert d.supervisor.rearmed_at is not None
    assert int(d.read("consumer_heartbeat_time.consumer_1")) == _consumer_value()
    assert d.boots_seen == 1
    assert not rig.detected.is_set()  # no boot-up message was seen: the gap rule found it
    assert any(e["event"] == "restart_suspected" for e in rig.events)


def test_unexpected_pre_operational_is_verified_and_rearmed_only_if_settings_were_lost(rig):
    d = rig.drive
    d.configure_heartbeat_consumer(CONSUMER_MS)
    d.nmt("start")
    time.sleep(0.3)
    other = rig.sniffer.bus
    # another master sends the node to PRE-OPERATIONAL: the settings are intact, nothing counted
    other.send(can.Message(arbitration_id=0, data=[0x80, NODE], is_extended_id=False))
    deadline = time.monotonic() + 5.0
    while not any(e["event"] == "verified" for e in rig.events) and time.monotonic() < deadline:
        time.sleep(0.02)
    assert any(e["event"] == "verified" for e in rig.events)
    assert d.boots_seen == 0
    # it then clears 0x1016 behind our back and does it again: the loss is found and repaired
    other.send(can.Message(arbitration_id=0, data=[0x01, NODE], is_extended_id=False))
    time.sleep(0.3)
    SdoChannel.download(d.sdo, 0x1016, 1, b"\0\0\0\0")  # as another master would (no journal)
    other.send(can.Message(arbitration_id=0, data=[0x80, NODE], is_extended_id=False))
    deadline = time.monotonic() + 5.0
    while d.boots_seen == 0 and time.monotonic() < deadline:
        time.sleep(0.02)
    assert d.boots_seen == 1
    assert int(d.read("consumer_heartbeat_time.consumer_1")) == _consumer_value()


def test_failed_rearm_blocks_user_commands_with_one_line(rig):
    d = rig.drive
    d.configure_heartbeat_consumer(CONSUMER_MS)
    rig.vd.stop()  # the drive goes away for good: its re-arm cannot succeed
    d.supervisor.rearm_budget = 0.5
    d.supervisor._on_heartbeat(0x700 + NODE, bytearray(b"\x00"), 0.0)  # a boot-up, then silence
    with pytest.raises(SupervisionError) as exc:
        d.supervisor.wait_ready(timeout=15.0)
        d.read("statusword")
    assert "\n" not in str(exc.value)
    rig.restart()  # a drive again, so that closing the session does not wait out its retries


def test_pdo_settings_the_session_changed_come_back(rig):
    """The session remaps TPDO4 (CiA 301 §7.2.2.3 procedure) and slows TPDO1; after a restart
    both read back as the session left them, not as the drive's defaults."""
    d = rig.drive
    d.configure_heartbeat_consumer(CONSUMER_MS)
    cob = int(d.read("tpdo4_communication.cob_id"))
    speed_ref = (0x2040 << 16) | (11 << 8) | 32
    d.write("tpdo4_communication.cob_id", cob | 0x80000000)
    d.write("tpdo4_mapping.number_of_mapped_objects", 0)
    d.write("tpdo4_mapping.mapped_object_1", speed_ref)
    d.write("tpdo4_mapping.number_of_mapped_objects", 1)
    d.write("tpdo4_communication.cob_id", cob)
    d.write("tpdo1_communication.event_timer", 20)
    rig.restart()
    assert rig.detected.wait(5.0)
    assert int(d.read("tpdo4_mapping.number_of_mapped_objects")) == 1
    assert int(d.read("tpdo4_mapping.mapped_object_1")) == speed_ref
    assert int(d.read("tpdo4_communication.cob_id")) == cob
    assert int(d.read("tpdo1_communication.event_timer")) == 20
    assert int(d.read("consumer_heartbeat_time.consumer_1")) == _consumer_value()
    assert not d.supervisor.last_report.failed


def test_a_restart_during_a_store_does_not_deadlock(rig):
    """store() holds the SDO channel (patience) while the re-arm needs it: the store goes on,
    the re-arm follows, nothing waits for a timeout."""
    d = rig.drive
    d.configure_heartbeat_consumer(CONSUMER_MS)
    with d.sdo.patience(1.0):
        d.supervisor._on_heartbeat(0x700 + NODE, bytearray(b"\x00"), 0.0)  # boot-up arrives
        t0 = time.monotonic()
        d.read("statusword")  # inside patience: goes out at once
        assert time.monotonic() - t0 < 2.0
    d.supervisor.wait_ready(timeout=10.0)
    assert d.supervisor.last_report is not None and not d.supervisor.last_report.failed


def test_producer_time_changed_by_another_master_is_learned(rig):
    """Another master slows the drive's heartbeat to 1 s: after one check the gap rule uses the
    new period (no re-arm on every heartbeat, no boot counted)."""
    d = rig.drive
    d.configure_heartbeat_consumer(CONSUMER_MS)
    SdoChannel.download(d.sdo, 0x1017, 0, struct.pack("<H", 1000))  # not journalled
    time.sleep(3.5)
    checks = [e for e in rig.events if e["event"] in ("verified", "rearmed")]
    assert len(checks) <= 1, checks
    assert d.boots_seen == 0
    SdoChannel.download(d.sdo, 0x1017, 0, struct.pack("<H", 100))


def test_a_late_heartbeat_with_the_drive_silent_meanwhile_is_checked_again(rig):
    """A heartbeat gap (no boot-up) while the drive's SDO answers are lost: the re-arm's
    read-back fails, but that is no proof of a lost supervision; the next user command checks
    once more and goes through when the drive answers again (the settings were intact)."""
    d = rig.drive
    d.configure_heartbeat_consumer(CONSUMER_MS)
    real_send = rig.vd.bus.send
    mute = threading.Event()

    def send(msg, timeout=None):
        if mute.is_set() and msg.arbitration_id == 0x580 + NODE:
            return None  # SDO responses lost (a starved bus or host)
        return real_send(msg, timeout)

    rig.vd.bus.send = send
    d.supervisor.rearm_budget = 0.5
    mute.set()
    sup = d.supervisor
    with sup._lock:  # what the heartbeat rule queues for a late heartbeat
        sup._pending, sup._ready = "heartbeat resumed after 900 ms", False
        sup._lock.notify_all()
    deadline = time.monotonic() + 30.0
    while sup._error is None and time.monotonic() < deadline:
        time.sleep(0.05)
    assert sup._error is not None, "the re-arm's read-back should have failed while muted"
    mute.clear()
    assert d.read("statusword") >= 0  # checked again, then sent
    assert int(d.read("consumer_heartbeat_time.consumer_1")) == _consumer_value()
    assert d.boots_seen == 0  # nothing had been lost: no restart counted
