"""Issue 29's symptoms checked on a real kernel SocketCAN (vcan0 inside User-Mode Linux), run by
the SocketCAN lane after tests/uml/vcan_checks.py (tests/test_socketcan_lane.py collects it; the
file name keeps it out of ordinary collection; outside UML it skips: no vcan0).

One ``virtual-drive`` process (node 9, PRE-OPERATIONAL but for the RTR check) serves every check
here; the independent master is stock canopen's own (``canopen.Network`` + ``RemoteNode`` with the
EDS, objects by their CiA 301/402 index), the master heartbeat is python-can's periodic send (the
kernel's broadcast manager), the sniffer is a raw python-can socket of its own. Checks:

* the held-quick-stop supervision sequence of issue 29, once, exactly as filed;
* protocol bytes (CiA 301 §7.2.4.3): a 1-byte SDO frame gets no answer; an invalid command
  specifier's abort names the request's own index/sub-index; drive_link's block-upload
  acknowledgements keep bytes 3..7 zero;
* a remote frame for a TPDO gets the TPDO, one on 0x700 + N gets nothing (node guarding absent);
* a dead drive (SIGSTOP): drive_link's call fails with NodeGone within its documented bound
  (drive_link/link/supervision.py: the host's consumer time, then one SDO timeout; once gone, one
  heartbeat period plus one SDO timeout).

Not here: the inhibit time on the bus and the SYNC/RPDO latency of issue 29. UML spends about
38 µs per system call, so gaps and latencies measured inside it say nothing about the drive or a
real machine (../shared/notes/socketcan-in-uml.md); those are checked on the host's hub
(tests/test_bus_timing.py, tests/test_sync_cob_id.py).
"""

from __future__ import annotations

import os
import signal
import struct
import threading
import time
from pathlib import Path

import can
import pytest

pytestmark = pytest.mark.timeout(300)

if not Path("/sys/class/net/vcan0").exists():
    pytest.skip("vcan0 exists only inside the SocketCAN lane (UML)", allow_module_level=True)

N = 9  #: node-ID of this module's drive (vcan_checks' drive is node 1; a scenario may follow)
HOST = 0x7F  #: the master's node-ID (heartbeat on 0x77F)
#: 0x1016:1 = 0x007F07D0: node 0x7F, 2 s. Issue 29 used 500 ms (0x007F01F4); inside UML on a
#: busy host (ci35, load 8.3) the master's 100 ms heartbeat stalled past that and the drive,
#: rightly, never ran: the sequence under test is the same with a consumer time UML keeps
ENTRY = (HOST << 16) | 2000
ABORT_COMMAND = 0x05040001  #: CiA 301: command specifier not valid or unknown
TIMEOUT = 5.0  #: SDO response timeout of the master (UML on a busy host)
#: Scheduling slack inside UML (s): a Python thread there waits on a busy one-CPU kernel.
SLACK_S = 1.0


class Sniffer:
    """Every frame on vcan0 seen by a raw socket of its own: (monotonic time, message)."""

    def __init__(self) -> None:
        self.bus = can.Bus(interface="socketcan", channel="vcan0")
        self.frames: list[tuple[float, can.Message]] = []
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._t = threading.Thread(target=self._run, daemon=True)
        self._t.start()

    def _run(self) -> None:
        while not self._stop.is_set():
            m = self.bus.recv(0.2)
            if m is not None:  # kernel time stamps are wall-clock: to monotonic
                t = m.timestamp - time.time() + time.monotonic()
                with self._lock:
                    self.frames.append((t, m))

    def since(self, t0: float, cob: int, remote: bool = False) -> list[tuple[float, bytes]]:
        with self._lock:
            return [(t, bytes(m.data)) for t, m in self.frames if t >= t0 and
                    m.arbitration_id == cob and m.is_remote_frame == remote]  # fmt: skip

    def wait_for(self, cob: int, timeout: float, since: float, pred=None) -> bytes | None:
        end = time.monotonic() + timeout
        while True:
            got = [d for _, d in self.since(since, cob) if pred is None or pred(d)]
            if got:
                return got[0]
            if time.monotonic() > end:
                return None
            time.sleep(0.02)

    def close(self) -> None:
        self._stop.set()
        self._t.join(2)
        self.bus.shutdown()


class Bench:
    """The drive process, canopen's master and the sniffer, shared by the module."""

    def __init__(self) -> None:
        import canopen
        from vcan_checks import start  # the lane's start-up helper (waits for "ready")

        from firmware_protocol import EDS_PATH

        bus = ["--interface", "socketcan", "--channel", "vcan0"]
        self.proc = start(["virtual-drive", "run", *bus, "--node", str(N)], "ready")
        self.sniff = Sniffer()
        self.net = canopen.Network()
        self.net.connect(interface="socketcan", channel="vcan0")
        self.node = self.net.add_node(N, canopen.import_od(str(EDS_PATH), N))
        self.node.sdo.RESPONSE_TIMEOUT = TIMEOUT

    def r(self, index: int, sub: int | None = None):
        obj = self.node.sdo[index]
        return (obj if sub is None else obj[sub]).raw

    def w(self, index: int, value, sub: int | None = None) -> None:
        obj = self.node.sdo[index]
        (obj if sub is None else obj[sub]).raw = value

    def nmt(self, command: int) -> None:
        self.net.send_message(0, bytes([command, N]))

    def raw_sdo(self, frame: bytes, timeout: float) -> bytes | None:
        """``frame`` on 0x600 + N as it is (its own length); the first answer on 0x580 + N."""
        t0 = time.monotonic()
        self.net.bus.send(can.Message(arbitration_id=0x600 + N, data=frame, is_extended_id=False))
        return self.sniff.wait_for(0x580 + N, timeout, since=t0)

    def wait(self, pred, timeout: float) -> bool:
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if pred():
                return True
            time.sleep(0.05)
        return pred()

    def close(self) -> None:
        self.net.disconnect()
        self.sniff.close()
        from vcan_checks import stop

        stop(self.proc)


@pytest.fixture(scope="module")
def bench():
    b = Bench()
    yield b
    b.close()


#: CiA 402 Table 30 (the masks written out here, not the product's copy): mask, value, state.
STATES = (
    (0x4F, 0x40, "SWITCH ON DISABLED"),
    (0x6F, 0x27, "OPERATION ENABLED"),
    (0x6F, 0x07, "QUICK STOP ACTIVE"),
    (0x4F, 0x08, "FAULT"),
)


def state(sw: int) -> str:
    return next((name for mask, v, name in STATES if sw & mask == v), f"0x{sw:04X}")


# --------------------------------------------------------------------------- protocol bytes
def test_one_byte_sdo_frame_gets_no_answer(bench):
    assert bench.raw_sdo(b"\x40", 1.0) is None, "a 1-byte SDO frame was answered"
    assert bench.r(0x1000) == 0x00020192  # and the service goes on (CiA 402 device type)


def test_invalid_command_specifier_abort_names_the_request(bench):
    first = bench.raw_sdo(struct.pack("<BHB4x", 0x40, 0x6041, 0), TIMEOUT)  # upload statusword
    assert first is not None and first[0] & 0xE0 == 0x40, first
    got = bench.raw_sdo(struct.pack("<BHB4x", 0xE0, 0x1018, 1), TIMEOUT)  # ccs 7: no such thing
    assert got is not None, "no abort to an invalid command specifier"
    cmd, index, sub, code = struct.unpack("<BHBI", got)
    assert (cmd, code) == (0x80, ABORT_COMMAND), got.hex()
    assert (index, sub) == (0x1018, 1), f"abort names 0x{index:04X}:{sub:02X}"


def test_sdo_block_acks_keep_reserved_bytes_zero(bench):
    from drive_link.link._sdo import SdoChannel

    t0 = time.monotonic()
    ch = SdoChannel(bench.net, N, 0x600 + N, 0x580 + N, timeout=2.0)
    try:
        name = ch.upload_block(0x1008, 0)  # device name by block upload (drive_link's client)
    finally:
        ch.close()
    assert name.decode().strip()
    time.sleep(0.5)
    acks = [d for _, d in bench.sniff.since(t0, 0x600 + N) if d[0] & 0xE3 == 0xA2]
    ends = [d for _, d in bench.sniff.since(t0, 0x580 + N) if d[0] & 0xE3 == 0xC1]
    assert acks and ends, bench.sniff.since(t0, 0x600 + N)
    for d in acks:
        assert len(d) == 8 and d[3:] == bytes(5), f"client ack {d.hex()}: reserved bytes 3..7"
    for d in ends:
        assert len(d) == 8 and d[3:] == bytes(5), f"server end {d.hex()}: reserved bytes 3..7"


# --------------------------------------------------------------------------- remote frames
def test_tpdo_answers_a_remote_frame_node_guarding_is_absent(bench):
    """CiA 301 §7.5.2.35: a TPDO with COB-ID bit 30 = 0 may be requested by a remote frame;
    the drive declares node guarding absent, so an RTR on 0x700 + N gets nothing."""
    b = bench
    b.w(0x1800, 0x80000180 + N, 1)
    b.w(0x1800, 0, 5)  # no event timer: TPDO1 only when requested
    b.w(0x1800, 0x180 + N, 1)  # bit 30 = 0: RTR allowed
    for k in (1, 2, 3):  # TPDO2..4 off: nothing else in OPERATIONAL
        b.w(0x1800 + k, 0x80000180 + 0x100 * k + N, 1)
    b.w(0x1017, 0)  # no heartbeat on 0x700 + N to confuse with a guarding answer
    b.nmt(0x01)
    try:
        time.sleep(1.0)
        t0 = time.monotonic()
        time.sleep(0.5)
        assert b.sniff.since(t0, 0x180 + N) == [], "TPDO1 sent unrequested"
        t0 = time.monotonic()
        b.net.bus.send(can.Message(arbitration_id=0x180 + N, is_remote_frame=True, dlc=6,
                                   is_extended_id=False))  # fmt: skip
        assert b.sniff.wait_for(0x180 + N, 5.0, since=t0) is not None, "no TPDO1 for the RTR"
        time.sleep(1.0)
        got = b.sniff.since(t0, 0x180 + N)
        assert len(got) == 1 and len(got[0][1]) == 6, got  # one 6-byte TPDO1
        t0 = time.monotonic()
        b.net.bus.send(can.Message(arbitration_id=0x700 + N, is_remote_frame=True, dlc=1,
                                   is_extended_id=False))  # fmt: skip
        time.sleep(1.5)
        assert b.sniff.since(t0, 0x700 + N) == [], "an answer to a node-guarding RTR"
    finally:
        b.nmt(0x80)  # PRE-OPERATIONAL: no PDOs for the checks below
        b.w(0x1017, 100)


# --------------------------------------------------------------------------- supervision
def test_held_quick_stop_keeps_supervision_through_reset_communication(bench):
    """Issue 29's sequence, once: 0x605A = 6, 0x1016:1 = ENTRY, run, controlword 0x0002
    (held QUICK STOP ACTIVE, 0x1617), NMT reset communication, 0x000F runs the motor again; the
    master's heartbeat then stops: EMCY 0x8130 (CiA 301 heartbeat consumer) and the drive stops
    (0x6007 = 3 by default: quick stop)."""
    b = bench
    beat = b.net.send_periodic(0x700 + HOST, b"\x05", 0.1)
    try:
        b.w(0x605A, 6)
        b.w(0x1016, ENTRY, 1)
        time.sleep(0.5)  # monitoring starts with the first heartbeat received
        b.w(0x6083, 20000)  # profile acceleration, rpm/s
        b.w(0x6085, 20000)  # quick stop deceleration, rpm/s
        b.w(0x60FF, 1000)  # target velocity, rpm
        b.w(0x6060, 3)  # profile velocity
        t_run = time.monotonic()
        for cw in (0x06, 0x07, 0x0F):
            b.w(0x6040, cw)
        assert b.wait(lambda: b.r(0x606C) > 950, 20.0), (
            f"{b.r(0x606C)} rpm, statusword {b.r(0x6041):#06x}, EMCY since the start: "
            f"{[d.hex() for _, d in b.sniff.since(t_run - 1.0, 0x80 + N)]}"
        )
        b.w(0x6040, 0x0002)
        assert b.wait(lambda: b.r(0x6041) == 0x1617, 10.0), hex(b.r(0x6041))
        t0 = time.monotonic()
        b.nmt(0x82)
        assert b.sniff.wait_for(0x700 + N, 10.0, since=t0, pred=lambda d: d == b"\x00"), \
            "no boot-up after reset communication"  # fmt: skip
        assert b.r(0x1016, 1) == ENTRY
        b.w(0x6040, 0x000F)  # transition 16: back to OPERATION ENABLED
        assert state(b.r(0x6041)) == "OPERATION ENABLED"
        assert b.wait(lambda: b.r(0x606C) > 950, 20.0), f"{b.r(0x606C)} rpm"
    finally:
        t_lost = time.monotonic()
        beat.stop()
    emcy = b.sniff.wait_for(0x80 + N, 10.0, since=t_lost, pred=lambda d: d[:2] == b"\x30\x81")
    assert emcy is not None, "no EMCY 0x8130 after the master's heartbeat stopped"
    assert b.wait(lambda: abs(b.r(0x606C)) < 15, 20.0), f"still {b.r(0x606C)} rpm"
    assert state(b.r(0x6041)) == "QUICK STOP ACTIVE"


# --------------------------------------------------------------------------- dead drive
def test_a_stopped_drive_fails_a_call_with_node_gone_in_time(bench):
    """drive_link with its heartbeat supervision: the drive process is SIGSTOPped (no heartbeat,
    no SDO answer); a read fails with NodeGone once the host's consumer time and one SDO timeout
    are over, and then each call within one heartbeat period plus one SDO timeout, after one
    request (drive_link/link/supervision.py), plus :data:`SLACK_S` for UML's scheduling."""
    from drive_link import Drive, errors
    from drive_link.link.supervision import consumer_min_s

    b = bench
    d = Drive.connect(interface="socketcan", channel="vcan0", node_id=N, sdo_timeout=1.0)
    stopped = False
    try:
        producer_s = int(d.read("producer_heartbeat_time")) / 1000.0
        assert producer_s == pytest.approx(0.1)
        timeout_s = d.sdo.client.RESPONSE_TIMEOUT
        consumer_s = max(consumer_min_s(), 3 * producer_s)  # the documented host consumer time
        time.sleep(0.5)
        os.kill(b.proc.pid, signal.SIGSTOP)
        stopped = True
        t_stop = time.monotonic()
        time.sleep(0.3)  # a heartbeat sent just before the stop reaches the sniffer
        beats = [t for t, _ in b.sniff.since(t_stop - 5.0, 0x700 + N)]
        assert beats, "no heartbeat of the drive on the bus"
        t_last = beats[-1]
        gone = getattr(errors, "NodeGone", ())  # (absent before issue 29)
        with pytest.raises(errors.DriveError) as exc:
            d.read("statusword")
        t_fail = time.monotonic()
        bound = consumer_s + timeout_s + SLACK_S
        assert t_fail - t_last <= bound, f"{exc.value!r} {t_fail - t_last:.2f} s after the " \
            f"last heartbeat (bound {bound:.2f} s)"  # fmt: skip
        assert isinstance(exc.value, gone) and f"node {N} is gone" in str(exc.value), exc.value
        t1 = time.monotonic()
        with pytest.raises(gone):
            d.write("target_velocity", 10)
        took = time.monotonic() - t1
        assert took <= producer_s + timeout_s + SLACK_S, f"{took:.2f} s"
        time.sleep(0.3)
        requests = b.sniff.since(t1, 0x600 + N)
        assert len(requests) == 1, requests  # one request, no resends
    finally:
        if stopped:
            os.kill(b.proc.pid, signal.SIGCONT)
        d.close()
