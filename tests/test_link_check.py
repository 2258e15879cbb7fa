"""`drive-link check` against the virtual drive: every item passes on a conforming node, and a
node with a deliberate defect (its L_c limit check patched out here, in the test) fails the
"limits" item by name with a non-zero exit."""

from __future__ import annotations

import json
import re
import time
import uuid

import can
import pytest
from conftest import RunQueueProbe, heartbeat_explained, min_rate

from drive_link import cli
from drive_link.workflows.check import ITEMS
from drive_link.workflows.gains import apply_gains

pytestmark = [pytest.mark.timeout(90), pytest.mark.unit]


@pytest.fixture
def virtual_node(tmp_path):
    from virtual_drive.node import VirtualDrive

    ch = f"check-{uuid.uuid4().hex}"
    bus = can.Bus(interface="virtual", channel=ch)
    vd = VirtualDrive(bus, node_id=4, store_path=tmp_path / "store.json").start()
    yield vd, ch
    vd.stop()
    bus.shutdown()


def test_check_passes_on_the_virtual_drive(virtual_node, capsys):
    """Every item passes; a TPDO rate below the item's tolerance is accepted only when the
    kernel kept this process (drive and master) waiting enough to explain it (conftest
    RunQueueProbe over the whole run)."""
    _, ch = virtual_node
    probe = RunQueueProbe()
    t0 = time.monotonic()
    rc = cli.main(["check", "--interface", "virtual", "--channel", ch, "--node", "4", "--json"])
    took = time.monotonic() - t0
    wait = probe.stop()
    assert took <= 120.0, took  # the whole pre-certification run (issue 29): 2 minutes at most
    out = capsys.readouterr()
    results = json.loads(out.out)
    failed = [r for r in results if not r["ok"]]
    explained = []
    for r in failed:
        m = re.fullmatch(r"TPDO\d+ at (\d+) Hz, expected (\d+) Hz(?: \(\d+ missed\))?", r["detail"])
        if r["name"] == "pdo_rates" and m and int(m[1]) >= min_rate(int(m[2]), wait, 0.5):
            explained.append(r)
        if r["name"] == "heartbeat" and heartbeat_explained(r["detail"], wait):
            explained.append(r)
    assert rc == 0 or failed == explained, (failed, probe)
    assert [r["name"] for r in results] == list(ITEMS)
    assert out.err == ""


def test_check_names_the_failing_item_on_a_defective_drive(virtual_node, capsys, monkeypatch):
    vd, ch = virtual_node
    real_check = vd.checker.check

    def lax_check(index, subindex, value):  # the defect: L_c is never limit-checked
        if (index, subindex) == (0x2010, 2):
            return value
        return real_check(index, subindex, value)

    monkeypatch.setattr(vd.checker, "check", lax_check)
    argv = ["check", "--interface", "virtual", "--channel", ch, "--node", "4"]
    rc = cli.main([*argv, "--only", "identity,limits,modes"])
    lines = capsys.readouterr().out.splitlines()
    assert rc == 1
    fail = [ln for ln in lines if ln.startswith("FAIL")]
    assert len(fail) == 1 and fail[0].split()[1] == "limits"
    assert "L_c = 2.5 L: accepted, expected SDO abort 0x06090030 or 0x06090031" in fail[0]
    assert any(ln.startswith("PASS  identity") for ln in lines)
    assert lines[-1] == "2/3 passed; failed: limits"


def test_nmt_stopped_fails_on_a_drive_that_answers_sdo_in_stopped(virtual_node, capsys):
    """CiA 301 table 78: no SDO in STOPPED. A drive whose SDO server ignores the NMT state (the
    defect, made here) fails the item by name although the item sends only two requests."""
    vd, ch = virtual_node
    argv = ["check", "--interface", "virtual", "--channel", ch, "--node", "4", "--json"]
    assert cli.main([*argv, "--only", "nmt_stopped"]) == 0, capsys.readouterr().out
    capsys.readouterr()
    vd.sdo._allowed = lambda: True  # the defect: SDO served in every NMT state
    rc = cli.main([*argv, "--only", "nmt_stopped"])
    (r,) = json.loads(capsys.readouterr().out)
    assert rc == 1 and r["name"] == "nmt_stopped" and not r["ok"]
    assert r["detail"] == "SDO answered in STOPPED (CiA 301 table 78 forbids it)"


def test_check_rejects_unknown_items(virtual_node, capsys):
    _, ch = virtual_node
    rc = cli.main(
        ["check", "--interface", "virtual", "--channel", ch, "--node", "4", "--only", "nope"]
    )
    err = capsys.readouterr().err
    assert rc == 7 and err.count("\n") == 1 and "unknown check item(s) nope" in err


def test_check_starts_from_an_enabled_drive_in_current_mode(virtual_node, capsys):
    """A bench leaves the drive OPERATION ENABLED in current mode with the motor turning; CiA 402
    refuses a mode change there (0x08000022), so the 402 and mode items must first bring the
    drive to rest themselves."""
    _, ch = virtual_node
    bus = ["--interface", "virtual", "--channel", ch, "--node", "4"]
    assert cli.main(["nmt", "start", *bus]) == 0
    assert cli.main(["set-current", "10", "--enable", *bus]) == 0  # refused while disabled
    assert cli.main(["enable", *bus]) == 0
    assert "OPERATION ENABLED" in capsys.readouterr().out
    rc = cli.main(["check", *bus, "--only", "cia402,modes", "--json"])
    results = json.loads(capsys.readouterr().out)
    assert rc == 0, [r for r in results if not r["ok"]]


# ------------------------------------------------------------------ issue 10 items
ISSUE10_ITEMS = ("nmt_reaction", "halt", "cob_id_validation", "config_only", "store_status")


@pytest.mark.parametrize("item", ISSUE10_ITEMS)
def test_issue10_item_passes_on_the_virtual_drive(virtual_node, capsys, item):
    """Each safety item of issue 10 against the virtual drive (CiA 301/402 behaviour)."""
    _, ch = virtual_node
    argv = ["check", "--interface", "virtual", "--channel", ch, "--node", "4"]
    rc = cli.main([*argv, "--only", item, "--json"])
    results = json.loads(capsys.readouterr().out)
    assert [r["name"] for r in results] == [item]
    assert rc == 0 and results[0]["ok"], results[0]["detail"]


def test_nmt_reaction_fails_on_a_drive_without_the_0x6007_reaction(virtual_node, capsys):
    """The defect of issue 10: NMT stop / reset communication leave the motor turning."""
    vd, ch = virtual_node
    vd.nmt._on_abort = lambda command: None  # the defect, patched in here
    argv = ["check", "--interface", "virtual", "--channel", ch, "--node", "4"]
    rc = cli.main([*argv, "--only", "nmt_reaction"])
    line = capsys.readouterr().out.splitlines()[0]
    assert rc == 1
    assert line.startswith("FAIL  nmt_reaction")
    assert "NMT stop" in line and ("still at" in line or "still OPERATION ENABLED" in line)


def test_halt_fails_on_a_drive_that_ignores_bit_8(virtual_node, capsys, monkeypatch):
    vd, ch = virtual_node
    real = vd.node.before_write

    def no_halt(index, sub, obj, data):
        if index == 0x6040 and len(data) == 2:
            data = bytes([data[0], data[1] & ~0x01])  # bit 8 never reaches the drive
        return real(index, sub, obj, data)

    monkeypatch.setattr(vd.node, "before_write", no_halt)
    argv = ["check", "--interface", "virtual", "--channel", ch, "--node", "4"]
    rc = cli.main([*argv, "--only", "halt"])
    line = capsys.readouterr().out.splitlines()[0]
    assert rc == 1 and line.startswith("FAIL  halt") and "halt" in line


def test_store_status_fails_on_firmware_without_0x2060(virtual_node, capsys):
    from canopen.sdo import SdoAbortedError

    vd, ch = virtual_node
    real = vd.node.get_data

    def old_firmware(index, subindex, check_readable=False):
        if index == 0x2060:
            raise SdoAbortedError(0x06020000)
        return real(index, subindex, check_readable)

    vd.node.get_data = old_firmware
    argv = ["check", "--interface", "virtual", "--channel", ch, "--node", "4"]
    rc = cli.main([*argv, "--only", "store_status"])
    line = capsys.readouterr().out.splitlines()[0]
    assert rc == 1 and "0x2060 store_status not readable: abort 0x06020000" in line


def test_store_restore_puts_a_tuned_drive_back(virtual_node, capsys):
    """A tuned drive (stored speed gains, slower TPDO1, remapped TPDO4) keeps its settings
    after store_restore, also after the next reset node (they are stored again)."""
    from drive_link import Drive

    _, ch = virtual_node
    with Drive.connect(interface="virtual", channel=ch, node_id=4, heartbeat_ms=None) as d:
        apply_gains(d, {"speed_k_p": 0.3, "speed_k_i": 4e-5})
        d.write("tpdo1_communication.event_timer", 20)
        cob = int(d.read("tpdo4_communication.cob_id"))
        d.write("tpdo4_communication.cob_id", cob | 0x80000000)
        d.write("tpdo4_mapping.number_of_mapped_objects", 0)
        d.write("tpdo4_mapping.mapped_object_1", (0x2040 << 16) | (11 << 8) | 32)
        d.write("tpdo4_mapping.number_of_mapped_objects", 1)
        d.write("tpdo4_communication.cob_id", cob)
        d.store()
    # this session is closed: only the check itself can put the settings back
    argv = ["check", "--interface", "virtual", "--channel", ch, "--node", "4"]
    rc = cli.main([*argv, "--only", "store_restore", "--json"])
    r = json.loads(capsys.readouterr().out)[0]
    assert rc == 0 and r["ok"], r["detail"]
    with Drive.connect(interface="virtual", channel=ch, node_id=4, heartbeat_ms=None) as d:
        d.reset(timeout=8.0)
        g = d.read_gains()
        assert g.speed_k_p == pytest.approx(0.3, rel=1e-6)
        assert g.speed_k_i == pytest.approx(4e-5, rel=1e-6)
        assert int(d.read("tpdo1_communication.event_timer")) == 20
        assert int(d.read("tpdo4_mapping.number_of_mapped_objects")) == 1
        assert int(d.read("tpdo4_mapping.mapped_object_1")) == (0x2040 << 16) | (11 << 8) | 32
        assert int(d.read("tpdo4_communication.cob_id")) == cob


def test_pdo_rates_fails_for_a_drive_that_silently_drops_periods(virtual_node, capsys):
    """The drive sends every other TPDO1 (0x184) while 0x1800:5 says 10 ms and counts nothing
    missed: pdo_rates measures about 50 Hz from the frames' bus timestamps and fails (CiA 301:
    the event timer is the transmission period), whatever the host's own load."""
    vd, ch = virtual_node
    real_send = vd.bus.send
    n = [0]

    def lossy_send(msg, timeout=None):
        if msg.arbitration_id == 0x184:
            n[0] += 1
            if n[0] % 2:
                return None  # dropped inside the drive, not counted in 0x2070
        return real_send(msg, timeout)

    vd.bus.send = lossy_send
    argv = ["check", "--interface", "virtual", "--channel", ch, "--node", "4", "--json"]
    starved = []
    for _ in range(3):
        rc = cli.main([*argv, "--only", "pdo_rates"])
        (result,) = json.loads(capsys.readouterr().out)
        # a drive the host starves misses periods itself and counts them (0x2070): then the
        # silent drops are no longer what decides the rate; measure again
        # (a passing item says "(N missed)", a failing one "+ N Hz missed periods …" over its
        # 1 s window: both about the periods the drive counted)
        detail = result["detail"]
        if result.get("verdict") == "not judged":  # the host stalled in every window
            starved.append(detail[:80])
            continue
        counted = re.search(r"TPDO1 [^,(]*(?:, expected \d+ Hz)? \((\d+) missed\)", detail)
        if not counted or int(counted[1]) <= 10:
            break
        starved.append(result["detail"][:80])
    else:
        pytest.skip(
            f"3 runs not judged or the drive counted its own missed TPDO1 periods: {starved}"
        )
    assert rc == 1 and not result["ok"], result
    m = re.match(r"TPDO1 at (\d+) Hz", result["detail"])
    assert m and 40 <= int(m[1]) <= 60, result["detail"]


def test_resets_keep_what_a_session_set_without_a_store(virtual_node, capsys):
    """nmt_bootup and nmt_reaction reset the node's communication (CiA 301: 0x1000-0x1FFF back
    to their stored values); the check puts back what it found, so TPDO event timers and the
    heartbeat time set by SDO and not stored (the SocketCAN lane's slower streams) survive, and
    the drive sends TPDO2 at the slower rate afterwards (frames counted on the bus)."""
    from drive_link import Drive

    _, ch = virtual_node
    with Drive.connect(interface="virtual", channel=ch, node_id=4, heartbeat_ms=None) as d:
        d.write("tpdo2_communication.event_timer", 50)
        d.write("producer_heartbeat_time", 250)
    argv = ["check", "--interface", "virtual", "--channel", ch, "--node", "4"]
    rc = cli.main([*argv, "--only", "nmt_bootup,nmt_reaction", "--json"])
    results = json.loads(capsys.readouterr().out)
    assert rc == 0 and all(r["ok"] for r in results), results
    with Drive.connect(interface="virtual", channel=ch, node_id=4, heartbeat_ms=None) as d:
        assert int(d.read("tpdo2_communication.event_timer")) == 50
        assert int(d.read("producer_heartbeat_time")) == 250
    with can.Bus(interface="virtual", channel=ch) as spy:
        frames = []
        deadline = time.monotonic() + 1.0
        while (left := deadline - time.monotonic()) > 0:
            m = spy.recv(left)
            if m is not None and m.arbitration_id == 0x284:
                frames.append(m.timestamp)
    # 50 ms: about 20 frames in the second; the default 1 ms timer would send about 1,000
    assert len(frames) <= 40, len(frames)
    assert "communication objects put back as found" in results[0]["detail"]
