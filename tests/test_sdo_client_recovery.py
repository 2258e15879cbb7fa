"""drive_link's SDO client recovers from lost, duplicated and damaged frames and never returns
wrong data; canopen 2.4.1's stock block client completes or fails cleanly against the drive.

The drive sits on a python-can ``virtual`` channel behind :class:`LossyBus`, which drops (or
damages) chosen frames in either direction. Truth: the recorder's own buffer read in-process
(``drive.recorder.data_bytes()``) and CRC-16/CCITT from ``binascii.crc_hqx``; the values written
are read back from the drive's data store, not over CAN.
"""

from __future__ import annotations

import binascii
import random
import struct
import threading
import time
import uuid
from collections import Counter
from collections.abc import Callable

import can
import canopen
import pytest
from can.interfaces.virtual import VirtualBus
from canopen.sdo import SdoAbortedError, SdoClient, SdoCommunicationError

from drive_link import Drive, DriveTimeout
from drive_link.link import _sdo_block as sdo_block
from drive_link.link._sdo import SdoChannel
from firmware_protocol import load_od
from virtual_drive.node import VirtualDrive

pytestmark = [pytest.mark.timeout(120), pytest.mark.unit]

L = 14.8e-6
#: rule(direction "tx" (drive sends) | "rx" (drive receives), msg, n-th frame of that COB-ID
#: in that direction) -> None (deliver), "drop", "twice" (deliver two copies) or replacement
#: data bytes
Rule = Callable[[str, can.Message, int], "str | bytes | None"]


class LossyBus(VirtualBus):
    """The drive's end of a virtual channel, with frames dropped or damaged by ``rule``."""

    def __init__(self, channel: str) -> None:
        super().__init__(channel=channel)
        self.rule: Rule | None = None
        self.counts: Counter = Counter()
        self.dropped = 0
        self.doubled = 0
        self._again: can.Message | None = None
        self._lock = threading.Lock()

    def _apply(self, direction: str, msg: can.Message):
        rule = self.rule
        if rule is None:
            return None
        with self._lock:
            key = (direction, msg.arbitration_id)
            self.counts[key] += 1
            action = rule(direction, msg, self.counts[key])
            if action == "drop":
                self.dropped += 1
            elif action == "twice":
                self.doubled += 1
            return action

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        action = self._apply("tx", msg)
        if action == "drop":
            return
        if isinstance(action, bytes):
            msg = can.Message(arbitration_id=msg.arbitration_id, data=action, is_extended_id=False)
        super().send(msg, timeout)
        if action == "twice":
            super().send(msg, timeout)

    def _recv_internal(self, timeout):
        if self._again is not None:
            msg, self._again = self._again, None
            return msg, False
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            left = None if deadline is None else max(0.0, deadline - time.monotonic())
            msg, filtered = super()._recv_internal(left)
            if msg is None:
                return msg, filtered
            action = self._apply("rx", msg)
            if action == "twice":
                self._again = msg
            if action != "drop":
                return msg, filtered

    def set_rule(self, rule: Rule | None) -> None:
        with self._lock:
            self.rule = rule
            self.counts.clear()
            self.dropped = 0
            self.doubled = 0


@pytest.fixture(scope="module")
def rig():
    ch = f"sdo-loss-{uuid.uuid4().hex}"
    drive_bus = LossyBus(ch)
    host_bus = can.Bus(interface="virtual", channel=ch)
    vd = VirtualDrive(drive_bus, node_id=1).start()
    d = Drive.connect(bus=host_bus, node_id=1, heartbeat_ms=None)
    # 16 KiB of trace: 2 channels x 2048 samples, immediate trigger (64 KiB runs through the
    # hub in test_sdo_hub_loss.py; here drive and client share one interpreter). V_dc makes
    # the data non-zero: CRC-16/XMODEM of zero bytes is 0 at any length, so an all-zero trace
    # would hide a lost segment from a client that checks only the CRC (canopen's)
    d.trace.configure(["V_dc", "speed"], length=2048, trigger="immediate")
    d.trace.arm()
    d.trace.wait(20.0)
    truth = vd.recorder.data_bytes()
    assert len(truth) == 16384
    assert binascii.crc_hqx(truth[:-7], 0) != binascii.crc_hqx(truth, 0)
    yield d, vd, drive_bus, truth
    drive_bus.set_rule(None)
    d.close()
    vd.stop()
    drive_bus.shutdown()
    host_bus.shutdown()


@pytest.fixture(autouse=True)
def _lossless_afterwards(rig):
    yield
    rig[2].set_rule(None)


def _upload(d: Drive) -> bytes:
    return d.sdo_trace.upload_block(0x2102, 0, name="trace_data")


def _rx_cobid(d: Drive) -> int:
    return d.sdo_trace.rx_cobid


def test_block_upload_recovers_chosen_losses(rig):
    d, vd, bus, truth = rig  # noqa: RUF059
    tx, rx = d.sdo_trace.tx_cobid, d.sdo_trace.rx_cobid
    drops = {
        ("tx", 1): "initiate response",
        ("tx", 6): "segment 5 of the first sub-block",
        ("tx", 200): "a segment in the second sub-block",
        ("rx", 2): "the start request",
        ("rx", 4): "an acknowledgement",
    }
    seen: list[str] = []

    def rule(direction, msg, n):
        cob = tx if direction == "tx" else rx
        if msg.arbitration_id == cob and (direction, n) in drops:
            seen.append(drops[(direction, n)])
            return "drop"
        return None

    bus.set_rule(rule)
    restarts = d.sdo_trace.restarted
    data = _upload(d)
    assert data == truth
    assert binascii.crc_hqx(data, 0) == binascii.crc_hqx(truth, 0)
    assert len(seen) == len(drops)
    assert d.sdo_trace.restarted == restarts  # recovered inside the transfer
    stats = sdo_block.last_stats
    assert stats["gaps"] >= 1 and stats["resends"] >= 1


def test_block_upload_recovers_lost_end_and_last_segments(rig):
    """The last segment of a sub-block (only silence tells) and the end response are lost."""
    d, vd, bus, truth = rig  # noqa: RUF059
    tx = d.sdo_trace.tx_cobid
    lost = {"last": 0, "end": 0}

    def rule(direction, msg, n):
        if direction != "tx" or msg.arbitration_id != tx:
            return None
        b0 = msg.data[0]
        if b0 == 127 and lost["last"] < 2:  # segment 127 (not the final one)
            lost["last"] += 1
            return "drop"
        if b0 & 0xE3 == 0xC1 and len(msg.data) == 8 and msg.data[3:] == bytes(5):
            if lost["end"] < 1:
                lost["end"] += 1
                return "drop"
        return None

    bus.set_rule(rule)
    assert _upload(d) == truth
    assert lost == {"last": 2, "end": 1}
    assert sdo_block.last_stats["silences"] >= 2


def test_damaged_segment_is_never_accepted(rig):
    """One data byte changed on the way: the CRC catches it, the client restarts the upload
    and returns the right data."""
    d, vd, bus, truth = rig  # noqa: RUF059
    tx = d.sdo_trace.tx_cobid
    hits = []

    def rule(direction, msg, n):
        if direction == "tx" and msg.arbitration_id == tx and n == 40 and not hits:
            hits.append(n)
            data = bytearray(msg.data)
            data[3] ^= 0x01
            return bytes(data)
        return None

    bus.set_rule(rule)
    restarts = d.sdo_trace.restarted
    assert _upload(d) == truth
    assert hits and d.sdo_trace.restarted == restarts + 1


def test_duplicated_frames_both_ways(rig):
    """Every 10th frame the drive sends and every 3rd it receives arrive twice."""
    d, vd, bus, truth = rig

    def rule(direction, msg, n):
        if (direction == "tx" and n % 10 == 0) or (direction == "rx" and n % 3 == 0):
            return "twice"
        return None

    bus.set_rule(rule)
    assert _upload(d) == truth
    assert bus.doubled > 50
    assert d.sdo.upload(0x1008, 0) == vd.node.get_data(0x1008, 0)


def test_random_loss_both_ways(rig):
    """5 % of the frames in both directions lost (seeded): two uploads, each complete and
    exact."""
    d, vd, bus, truth = rig  # noqa: RUF059
    rng = random.Random(5)
    bus.set_rule(lambda direction, msg, n: "drop" if rng.random() < 0.05 else None)
    for _ in range(2):
        assert _upload(d) == truth
    assert bus.dropped > 50


def test_segmented_read_and_write_recover_lost_frames(rig):
    d, vd, bus, truth = rig  # noqa: RUF059
    rx, tx = d.sdo.rx_cobid, d.sdo.tx_cobid
    drop = {("tx", 1), ("tx", 4), ("rx", 7), ("tx", 12)}
    bus.set_rule(
        lambda direction, msg, n: "drop"
        if msg.arbitration_id in (rx, tx) and (direction, n) in drop
        else None
    )
    name = vd.node.get_data(0x1008, 0)
    assert d.sdo.upload(0x1008, 0, name="device_name") == name  # segmented, 18 bytes
    bus.set_rule(
        lambda direction, msg, n: "drop" if direction == "tx" and n == 1 else None
    )  # the write's confirmation is lost: the write is sent again, harmlessly
    d.sdo.download(0x2010, 2, struct.pack("<f", 1.2 * L), name="L_c")
    assert vd.node.stored(0x2010, 2) == pytest.approx(1.2 * L)
    bus.set_rule(None)
    d.sdo.download(0x2010, 2, struct.pack("<f", L), name="L_c")


def test_server_gone_mid_upload_fails_with_one_line_in_bounded_time(rig):
    d, vd, bus, truth = rig  # noqa: RUF059
    tx = d.sdo_trace.tx_cobid
    bus.set_rule(lambda direction, msg, n: "drop" if msg.arbitration_id == tx and n > 50 else None)
    t0 = time.monotonic()
    with pytest.raises(DriveTimeout) as ei:
        _upload(d)
    took = time.monotonic() - t0
    msg = str(ei.value)
    assert "\n" not in msg and "trace_data" in msg
    # 4 attempts; each attempt gives up after 7 unanswered acknowledgements (<= ~10 s) or at
    # the initiate (<= 2.1 s): bounded well below the channel deadline of 60 s
    assert took < 60


def test_canopen_stock_block_client(rig):
    """canopen 2.4.1's own block client (it never resends a lost request): complete without
    loss; under 1 % loss each upload is complete and exact or fails with an SDO error, within
    a bounded time. (canopen never compares the length with the announced size, and after a
    response timeout it acknowledges a segment it then discards: on all-zero data, where the
    CRC is blind, it returned 16377 of 16384 bytes; hence V_dc in the trace.)"""
    d, vd, bus, truth = rig  # noqa: RUF059
    # its own connection, on the second server channel (0x1201): drive_link's session reads
    # the drive over the first one now and then, and two clients on one channel break each
    # other's transfers (CiA 301: one client per server channel)
    net = canopen.Network(can.Bus(interface="virtual", channel=bus.channel_id))
    net.connect()
    sdo = SdoClient(d.sdo_trace.rx_cobid, d.sdo_trace.tx_cobid, load_od().canopen_od(1))
    sdo.network = net
    sdo.RESPONSE_TIMEOUT = 1.0
    net.subscribe(sdo.tx_cobid, sdo.on_response)
    try:
        with sdo.open(0x2102, 0, "rb", block_transfer=True) as f:
            assert f.read() == truth
        rng = random.Random(11)
        bus.set_rule(lambda direction, msg, n: "drop" if rng.random() < 0.01 else None)
        outcomes = Counter()
        for _ in range(4):
            t0 = time.monotonic()
            try:
                with sdo.open(0x2102, 0, "rb", block_transfer=True) as f:
                    data = f.read()
                assert data == truth  # never wrong data
                outcomes["complete"] += 1
            except (SdoCommunicationError, SdoAbortedError):
                outcomes["clean failure"] += 1
            except AttributeError as exc:
                # canopen 2.4.1 bug: BlockUploadStream._end_upload calls self.abort, which
                # does not exist, when the end response is lost: still no data, no hang
                assert "abort" in str(exc)
                outcomes["canopen bug"] += 1
            assert time.monotonic() - t0 < 30
        assert sum(outcomes.values()) == 4
    finally:
        net.disconnect()


def test_block_upload_falls_back_to_segmented_on_a_server_without_block_transfer():
    """canopen's LocalNode answers a block upload request with a normal upload response (CiA
    301 protocol switch): the data still arrives, by segmented upload."""
    ch = f"sdo-fallback-{uuid.uuid4().hex}"
    srv_bus = can.Bus(interface="virtual", channel=ch)
    cli_bus = can.Bus(interface="virtual", channel=ch)
    srv_net = canopen.Network(srv_bus)
    srv_net.connect()
    cli_net = canopen.Network(cli_bus)
    cli_net.connect()
    try:
        local = canopen.LocalNode(5, load_od().canopen_od(5))
        srv_net.add_node(local)
        text = "a device name longer than one segment"
        local.sdo[0x1008].raw = text
        ch5 = SdoChannel(cli_net, 5, 0x605, 0x585, timeout=0.5)
        assert ch5.upload_block(0x1008, 0) == text.encode()
        ch5.close()
    finally:
        srv_net.disconnect()
        cli_net.disconnect()
