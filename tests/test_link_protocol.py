"""drive_link protocol pieces against independent truths: the contract's OD table
(docs/contracts.md §1), CiA 402 statusword table, CiA 301 SDO abort codes served by canopen's own
LocalNode SDO server, and TPDO frames built here byte by byte."""

from __future__ import annotations

import struct
import threading
import time
import uuid

import can
import canopen
import numpy as np
import pytest

from drive_link.errors import BusError, DriveTimeout, InvalidValue, SdoAbort, UnknownObject
from drive_link.link import cia402
from drive_link.link._connection import acquire, release
from drive_link.link._live import LiveStreams, MappedField, TpdoConfig
from drive_link.link._objects import default_table
from drive_link.link._sdo import SdoChannel
from drive_link.link.bus import bus_settings, open_bus
from firmware_protocol import EDS_PATH

pytestmark = pytest.mark.timeout(60)


# ------------------------------------------------------------------ object table vs contract
@pytest.mark.unit
@pytest.mark.parametrize(
    "name, index, sub, type_name, unit",
    [
        ("device_type", 0x1000, 0, "UNSIGNED32", ""),
        ("controlword", 0x6040, 0, "UNSIGNED16", None),
        ("modes_of_operation", 0x6060, 0, "INTEGER8", None),
        ("target_velocity", 0x60FF, 0, "INTEGER32", "rpm"),
        ("current_controller.L_c", 0x2010, 2, "REAL32", "H"),
        ("current_controller.R_c", 0x2010, 3, "REAL32", None),
        ("speed_controller.k_p", 0x2020, 1, "REAL32", "A/rpm"),
        ("setpoints.i_p_ref", 0x2030, 1, "REAL32", "A"),
        ("measurements.hall_sector", 0x2040, 9, "UNSIGNED8", None),
        ("gain_set.speed_current_limit", 0x20F0, 13, "REAL32", "A"),
        ("trace_config.capacity", 0x2100, 12, "UNSIGNED32", None),
        ("trace_data", 0x2102, 0, "DOMAIN", None),
        ("store_parameters.save_all", 0x1010, 1, "UNSIGNED32", None),
        ("consumer_heartbeat_time.consumer_1", 0x1016, 1, "UNSIGNED32", None),
    ],
)
def test_table_matches_contract(name, index, sub, type_name, unit):
    obj = default_table()[name]
    assert (obj.index, obj.subindex, obj.type_name) == (index, sub, type_name)
    if unit is not None:
        assert obj.unit == unit


@pytest.mark.unit
def test_encode_checks_type_and_limits():
    t = default_table()
    # REAL32 little-endian per CiA 301 (IEEE 754 single)
    assert t["setpoints.i_p_ref"].encode(20.0) == struct.pack("<f", 20.0)
    assert t["target_velocity"].encode(-500) == (-500).to_bytes(4, "little", signed=True)
    # refusals name the limit and the CiA 301 abort code the drive would answer with
    with pytest.raises(InvalidValue, match=r"above the limit.*0x06090031"):
        t["setpoints.i_p_ref"].encode(250.0)  # contract: [-200, 200] A
    with pytest.raises(InvalidValue, match=r"below the limit.*0x06090032"):
        t["setpoints.i_p_ref"].encode(-250.0)
    with pytest.raises(InvalidValue, match=r"UNSIGNED16 range.*0x06090031"):
        t["controlword"].encode(70000)
    with pytest.raises(InvalidValue, match=r"not a finite.*0x06090030"):
        t["current_controller.k_p"].encode(float("nan"))
    with pytest.raises(InvalidValue, match=r"not integral.*0x06090030"):
        t["controlword"].encode(1.5)
    with pytest.raises(InvalidValue, match="not a number"):
        t["controlword"].encode("twelve")
    assert t["controlword"].encode("0x000F") == (15).to_bytes(2, "little")  # CLI text
    with pytest.raises(UnknownObject, match="no object named"):
        t["current_controller.Lc"]
    assert t["modes_of_operation"].decode(b"\xff") == -1
    assert t["current_controller.L_c"].decode(struct.pack("<f", 14.8e-6)) == pytest.approx(14.8e-6)


# ------------------------------------------------------------------ CiA 402 statusword table
@pytest.mark.unit
@pytest.mark.parametrize(
    "sw, state",
    [
        (0x0000, "NOT READY TO SWITCH ON"),
        (0x0250, "SWITCH ON DISABLED"),  # bit 4 voltage enabled, bit 9 remote: ignored bits
        (0x0231, "READY TO SWITCH ON"),
        (0x0233, "SWITCHED ON"),
        (0x0637, "OPERATION ENABLED"),  # bit 10 target reached
        (0x0217, "QUICK STOP ACTIVE"),
        (0x021F, "FAULT REACTION ACTIVE"),
        (0x0218, "FAULT"),
        (0x0238, "FAULT"),  # xxxx xxxx x0xx 1000
    ],
)
def test_statusword_decoding_cia402_table(sw, state):
    assert cia402.state_from_statusword(sw) == state


# ------------------------------------------------------------------ bus settings
def test_bus_settings_hub_shortcut_and_errors():
    kw = bus_settings(host="127.0.0.1", port=1234)
    assert kw == {
        "interface": "socketcand",
        "host": "127.0.0.1",
        "port": 1234,
        "channel": "vcan0",
        "tcp_tune": True,
    }
    assert bus_settings(interface="virtual", channel="x", bitrate=None) == {
        "interface": "virtual",
        "channel": "x",
    }
    with pytest.raises(BusError, match="cannot open CAN bus"):
        open_bus(interface="no_such_interface", channel="x")
    t0 = time.monotonic()
    with pytest.raises(BusError, match=r"no hub at 127\.0\.0\.1:1"):
        open_bus(host="127.0.0.1", port=1)  # nothing listens on port 1
    assert time.monotonic() - t0 < 3.0


# ------------------------------------------------------------------ SDO against canopen's server
@pytest.fixture
def local_node():
    ch = f"t-{uuid.uuid4().hex}"
    srv_bus = can.Bus(interface="virtual", channel=ch)
    net = canopen.Network(srv_bus)
    net.connect()
    node = canopen.LocalNode(5, canopen.import_od(str(EDS_PATH), 5))
    net.add_node(node)
    cli_bus = can.Bus(interface="virtual", channel=ch)
    conn = acquire(bus=cli_bus)
    yield node, conn
    release(conn)
    net.disconnect()
    cli_bus.shutdown()


@pytest.mark.unit
def test_sdo_channel_read_write_and_abort_meaning(local_node):
    node, conn = local_node
    sdo = SdoChannel(conn.network, 5, 0x605, 0x585, timeout=0.3)
    assert struct.unpack("<I", sdo.upload(0x1000, 0))[0] == 0x00020192
    sdo.download(0x2010, 2, struct.pack("<f", 13e-6))
    assert struct.unpack("<f", node.sdo.upload(0x2010, 2))[0] == pytest.approx(13e-6)
    with pytest.raises(SdoAbort) as ei:
        sdo.upload(0x2FFF, 0, name="nothing")
    assert ei.value.code == 0x06020000
    assert "object does not exist" in str(ei.value) and "\n" not in str(ei.value)
    with pytest.raises(SdoAbort) as ei:
        sdo.download(0x1000, 0, b"\0\0\0\0")  # read-only
    assert ei.value.code == 0x06010002


@pytest.mark.unit
def test_sdo_channel_timeout_is_one_line_error(local_node):
    _, conn = local_node
    sdo = SdoChannel(conn.network, 9, 0x609, 0x589, timeout=0.05, retries=1)  # nobody is node 9
    t0 = time.monotonic()
    with pytest.raises(
        DriveTimeout, match=r"node 9 did not answer SDO read of 0x1000:00 \(2 attempts"
    ):
        sdo.upload(0x1000, 0)
    assert time.monotonic() - t0 < 1.0


@pytest.mark.unit
def test_sdo_channel_serialises_threads(local_node):
    """canopen's client has no lock; two threads on one channel must still both succeed."""
    node, conn = local_node
    sdo = SdoChannel(conn.network, 5, 0x605, 0x585, timeout=0.5)
    name = b"a segmented string value that needs many segments" * 2
    node.sdo[0x1008].raw = name.decode()
    errors: list[Exception] = []

    def worker(i: int) -> None:
        try:
            for _ in range(15):
                assert sdo.upload(0x1008, 0) == name
                sdo.download(0x2010, 4, struct.pack("<f", float(i)))
        except Exception as exc:  # collected for the assertion
            errors.append(exc)

    th = [threading.Thread(target=worker, args=(i,)) for i in range(3)]
    for t in th:
        t.start()
    for t in th:
        t.join(30)
    assert not errors


# ------------------------------------------------------------------ TPDO decoding
@pytest.mark.unit
def test_live_streams_decode_rates_and_drops():
    ch = f"t-{uuid.uuid4().hex}"
    # The sender stamps each frame with its time on an exact 20 ms cadence (preserve_timestamps),
    # so the drop estimate does not depend on how punctually this process is scheduled.
    tx = can.Bus(interface="virtual", channel=ch, preserve_timestamps=True)
    rx = can.Bus(interface="virtual", channel=ch)
    conn = acquire(bus=rx)
    cfg = TpdoConfig(
        2,
        0x282,
        0xFF,
        20,
        [
            MappedField("measurements.i_p", 0x2040, 1, 0, 32, "<f", "A"),
            MappedField("measurements.speed", 0x2040, 5, 32, 32, "<f", "rpm"),
        ],
    )
    cfg1 = TpdoConfig(
        1,
        0x182,
        0xFF,
        40,
        [
            MappedField("statusword", 0x6041, 0, 0, 16, "<H", ""),
            MappedField("velocity_actual_value", 0x606C, 0, 16, 32, "<i", "rpm"),
        ],
    )
    live = LiveStreams(conn.network, [cfg, cfg1], conn.monitor, 1_000_000)
    try:
        sent = 0
        sent1 = []
        t0 = time.time()
        for k in range(40):
            t_k = t0 + 0.02 * (k + 1)
            time.sleep(0.002)
            if k in (10, 11, 12):  # three frames lost on the wire
                continue
            data = struct.pack("<ff", 0.5 * k, 100.0 + k)
            tx.send(
                can.Message(timestamp=t_k, arbitration_id=0x282, data=data, is_extended_id=False)
            )
            sent += 1
            if k % 2 == 0:
                d1 = struct.pack("<Hi", 0x0637, -k)
                tx.send(
                    can.Message(
                        timestamp=t_k + 1e-4, arbitration_id=0x182, data=d1, is_extended_id=False
                    )
                )
                sent1.append(-k)
        deadline = time.monotonic() + 5
        while live.stats["frames"] < sent + len(sent1) and time.monotonic() < deadline:
            time.sleep(0.01)
        st = live.stats
        assert st["tpdo"]["TPDO2"]["frames"] == sent
        assert st["tpdo"]["TPDO2"]["dropped"] == 3  # gap of 4 periods of 20 ms
        assert st["tpdo"]["TPDO1"]["dropped"] == 2  # k = 10, 12 missing: gap of 3 periods of 40 ms
        w = live.window(10.0)
        assert len(w["t"]) == sent
        expect_k = np.array([k for k in range(40) if k not in (10, 11, 12)], dtype=float)
        np.testing.assert_allclose(w["measurements.i_p"], 0.5 * expect_k)
        np.testing.assert_allclose(w["measurements.speed"], 100.0 + expect_k)
        # TPDO1 sampled on TPDO2's time base with zero-order hold: last TPDO1 at or before t
        t1, v1 = live.streams()["velocity_actual_value"]
        np.testing.assert_array_equal(v1, sent1)
        for t, got in zip(w["t"], w["velocity_actual_value"], strict=True):
            earlier = v1[t1 <= t]
            if len(earlier):
                assert got == earlier[-1]
            else:
                assert np.isnan(got)
        assert live.units["measurements.speed"] == "rpm"
        assert st["bus_frames_per_s"] > 0
    finally:
        live.close()
        release(conn)
        tx.shutdown()
        rx.shutdown()


@pytest.mark.unit
@pytest.mark.parametrize(
    ("lost", "pause_s", "want"),
    [((), 0.0, 0), ((7, 8), 0.0, 2), ((), 3.0, 0), ((30,), 3.0, 1)],
)
def test_drop_estimate_ignores_jitter_and_pauses(lost, pause_s, want):
    """Frames of a 1 ms event timer arriving up to ±0.45 ms off their slot (batched by a busy
    sender) are not losses; a frame missing from the cadence is; a silence of seconds (NMT
    PRE-OPERATIONAL) is a pause, not thousands of losses."""
    ch = f"t-{uuid.uuid4().hex}"
    tx = can.Bus(interface="virtual", channel=ch, preserve_timestamps=True)
    rx = can.Bus(interface="virtual", channel=ch)
    conn = acquire(bus=rx)
    field = MappedField("measurements.i_p", 0x2040, 1, 0, 32, "<f", "A")
    live = LiveStreams(conn.network, [TpdoConfig(2, 0x282, 0xFF, 1, [field])], conn.monitor, 1e6)
    rng = np.random.default_rng(1)
    try:
        t0 = time.time()
        n = 0
        for k in range(60):
            if k in lost:
                continue
            t_k = t0 + 1e-3 * k + rng.uniform(-0.45e-3, 0.45e-3) + (pause_s if k >= 20 else 0.0)
            msg = can.Message(timestamp=t_k, arbitration_id=0x282, data=struct.pack("<f", k))
            msg.is_extended_id = False
            tx.send(msg)
            n += 1
        deadline = time.monotonic() + 5
        while live.stats["frames"] < n and time.monotonic() < deadline:
            time.sleep(0.01)
        assert live.stats["tpdo"]["TPDO2"]["frames"] == n
        assert live.stats["tpdo"]["TPDO2"]["dropped"] == want
    finally:
        live.close()
        release(conn)
        tx.shutdown()
        rx.shutdown()


# ------------------------------------------------------------ canopen RemoteNode on our channel
@pytest.mark.unit
def test_remote_node_shares_the_locked_channel_and_canopen_pieces_work(local_node):
    """drive_link.link._remote: canopen's TPDO.read(), NMT master and EMCY consumer on our channel,
    against canopen's own LocalNode (its OD and NMT state read in-process are the truth)."""
    from drive_link.link._nmt import send_command
    from drive_link.link._remote import remote_node

    srv, conn = local_node
    sdo = SdoChannel(conn.network, 5, 0x605, 0x585, timeout=0.5)
    node = remote_node(conn.network, 5, default_table().od, sdo)
    name = b"a segmented string value that needs many segments" * 2
    srv.sdo[0x1008].raw = name.decode()
    errors: list[Exception] = []

    def reads() -> None:  # our own transfers on the same channel meanwhile
        try:
            for _ in range(10):
                assert sdo.upload(0x1008, 0) == name
        except Exception as exc:  # collected for the assertion
            errors.append(exc)

    th = threading.Thread(target=reads)
    th.start()
    try:
        node.tpdo.read()
    finally:
        th.join(30)
    assert not errors
    for k, pdo_map in node.tpdo.map.items():
        cob = srv.sdo[0x1800 + k - 1][1].raw
        assert pdo_map.cob_id == cob & 0x1FFFFFFF and pdo_map.enabled == (not cob & 0x80000000)
        count = srv.sdo[0x1A00 + k - 1][0].raw
        refs = [srv.sdo[0x1A00 + k - 1][i].raw for i in range(1, count + 1)]
        assert [(v.index, v.subindex, v.length) for v in pdo_map.map] == [
            (r >> 16, (r >> 8) & 0xFF, r & 0xFF) for r in refs
        ]

    # a mapping naming an object the EDS lacks: canopen raises KeyError, the field is kept by
    # its index (not decoded) and the other fields keep their offsets
    from drive_link.link._live import read_tpdo_configs

    srv.sdo[0x1A00][0].raw = 2
    srv.sdo[0x1A00][1].raw = 0x5FFF0010
    srv.sdo[0x1A00][2].raw = 0x60410010  # statusword, 16 bits
    cfg = read_tpdo_configs(node, default_table())[0]
    assert [(f.name, f.offset, f.bits, f.fmt) for f in cfg.fields] == [
        ("0x5FFF:00", 0, 16, ""),
        ("statusword", 16, 16, "<H"),
    ]

    got: list = []
    node.emcy.subscribe(got.append)
    conn.bus.send(can.Message(arbitration_id=0x85, data=b"\x10\x23", is_extended_id=False))
    srv.emcy.send(0x2310, 0x02, b"\x01")  # canopen's own EMCY producer, CiA 301 layout
    deadline = time.monotonic() + 5
    while not got and time.monotonic() < deadline:
        time.sleep(0.01)
    assert [(e.code, e.register) for e in node.emcy.history] == [(0x2310, 0x02)]  # 2-byte frame
    assert got and got[0].code == 0x2310 and got[0].data[:1] == b"\x01"

    send_command(node.nmt, "stop")
    deadline = time.monotonic() + 5
    while srv.nmt.state != "STOPPED" and time.monotonic() < deadline:
        time.sleep(0.01)
    assert srv.nmt.state == "STOPPED"
    node.remove_network()
    sdo.close()
