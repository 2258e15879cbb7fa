"""A damaged or unreadable parameter store is visible to the master (issue 10, COMMON.md):
0x2060 store_status (0 ok, 1 defaults, 2 damaged, 3 unreadable), EMCY 0x6310 "loss of
parameters" (CiA 301 table 21, device software / data set) with error register bit 0 after the
boot-up, ``Drive.status()["store_status"]`` and ``drive-link status`` (text and JSON); firmware
without 0x2060 reads as "unknown"."""

from __future__ import annotations

import json
import threading
import time
import uuid
from pathlib import Path

import can
import pytest
from canopen.sdo import SdoAbortedError

from drive_link import Drive, cli
from firmware_protocol import load_od

pytestmark = [pytest.mark.timeout(60), pytest.mark.unit]

NODE = 6
LOSS_OF_PARAMETERS = 0x6310


def _has_2060() -> bool:
    try:
        load_od().entry("store_status")
    except Exception:
        return False
    return True


needs_2060 = pytest.mark.skipif(
    not _has_2060(), reason="0x2060 store_status is not in the EDS yet (drive side, issue 10)"
)


def _stored_file(tmp_path: Path) -> Path:
    """A valid parameter file written by the drive itself (0x1010 save)."""
    from virtual_drive.node import VirtualDrive

    path = tmp_path / "store.json"
    ch = f"store-{uuid.uuid4().hex}"
    bus = can.Bus(interface="virtual", channel=ch)
    vd = VirtualDrive(bus, node_id=NODE, store_path=path).start()
    try:
        with Drive.connect(interface="virtual", channel=ch, node_id=NODE) as d:
            d.store()
    finally:
        vd.stop()
        bus.shutdown()
    assert path.exists()
    return path


class Restartable:
    """A session connected first, then the drive (re)started with a given store file, so the
    EMCY sent right after the boot-up reaches the session."""

    def __init__(self, store_path: Path) -> None:
        from virtual_drive.node import VirtualDrive

        self.cls = VirtualDrive
        self.store_path = store_path
        self.channel = f"store-{uuid.uuid4().hex}"
        self.vbus = can.Bus(interface="virtual", channel=self.channel)
        self.vd = VirtualDrive(self.vbus, node_id=NODE, store_path=store_path).start()
        self.drive = Drive.connect(interface="virtual", channel=self.channel, node_id=NODE)
        self.rearmed = threading.Event()
        self.drive.on_supervision(
            lambda e: self.rearmed.set() if e["event"] == "rearmed" else None
        )

    def restart(self) -> None:
        self.vd.stop()
        self.vbus.shutdown()
        self.rearmed.clear()
        self.vbus = can.Bus(interface="virtual", channel=self.channel)
        self.vd = self.cls(self.vbus, node_id=NODE, store_path=self.store_path).start()
        assert self.rearmed.wait(5.0)

    def close(self) -> None:
        self.drive.close()
        self.vd.stop()
        self.vbus.shutdown()


def _wait_emcy(d: Drive, code: int, since: int, timeout: float = 3.0) -> list:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        hits = [e for e in d.emcy_history[since:] if e.code == code]
        if hits:
            return hits
        time.sleep(0.02)
    return []


@needs_2060
def test_store_status_ok_then_damaged_after_a_restart(tmp_path):
    path = _stored_file(tmp_path)
    r = Restartable(path)
    try:
        d = r.drive
        assert d.status()["store_status"] == "ok"
        assert not [e for e in d.emcy_history if e.code == LOSS_OF_PARAMETERS]
        raw = bytearray(path.read_bytes())
        raw[len(raw) // 2] ^= 0x55  # one flipped byte: checksum or parse fails
        path.write_bytes(bytes(raw))
        n = len(d.emcy_history)
        r.restart()
        hits = _wait_emcy(d, LOSS_OF_PARAMETERS, n)
        assert hits, f"no EMCY 0x6310 (got {[hex(e.code) for e in d.emcy_history[n:]]})"
        assert hits[0].register & 0x01  # generic error bit
        assert "loss of parameters" in hits[0].description
        st = d.status()
        assert st["store_status"] == "damaged"
        assert st["error_register"] & 0x01
        assert any(e.code == LOSS_OF_PARAMETERS for e in d.error_history())  # 0x1003
    finally:
        r.close()


@needs_2060
def test_no_store_file_reads_defaults_and_sends_no_emcy(tmp_path):
    r = Restartable(tmp_path / "absent.json")
    try:
        n = len(r.drive.emcy_history)
        r.restart()
        assert r.drive.status()["store_status"] == "defaults"
        assert not _wait_emcy(r.drive, LOSS_OF_PARAMETERS, n, timeout=0.5)
    finally:
        r.close()


@needs_2060
def test_unreadable_store_is_reported(tmp_path):
    path = tmp_path / "store.json"
    path.mkdir()  # reading it fails with an I/O error (EISDIR), not a parse error
    r = Restartable(path)
    try:
        n = len(r.drive.emcy_history)
        r.restart()
        assert _wait_emcy(r.drive, LOSS_OF_PARAMETERS, n)
        assert r.drive.status()["store_status"] == "unreadable"
    finally:
        r.close()


@needs_2060
def test_drive_link_status_prints_store_status(tmp_path, capsys):
    from virtual_drive.node import VirtualDrive

    path = tmp_path / "store.json"
    path.write_text("{ this is not a parameter file")
    ch = f"store-{uuid.uuid4().hex}"
    bus = can.Bus(interface="virtual", channel=ch)
    vd = VirtualDrive(bus, node_id=NODE, store_path=path).start()
    try:
        argv = ["status", "--interface", "virtual", "--channel", ch, "--node", str(NODE)]
        assert cli.main([*argv, "--json"]) == 0
        st = json.loads(capsys.readouterr().out)
        assert st["store_status"] == "damaged"
        assert st["boots_seen"] == 0
        assert cli.main(argv) == 0
        out = capsys.readouterr().out
        line = next(ln for ln in out.splitlines() if ln.strip().startswith("store_status:"))
        assert "damaged" in line and "defaults in use" in line
    finally:
        vd.stop()
        bus.shutdown()


def test_firmware_without_0x2060_reads_unknown(tmp_path):
    """Older firmware: 0x2060 does not exist (abort 0x06020000) → "unknown", nothing raised."""
    from virtual_drive.node import VirtualDrive

    ch = f"store-{uuid.uuid4().hex}"
    bus = can.Bus(interface="virtual", channel=ch)
    vd = VirtualDrive(bus, node_id=NODE).start()
    real = vd.node.get_data

    def old_firmware(index, subindex, check_readable=False):
        if index == 0x2060:
            raise SdoAbortedError(0x06020000)
        return real(index, subindex, check_readable)

    vd.node.get_data = old_firmware
    try:
        with Drive.connect(interface="virtual", channel=ch, node_id=NODE) as d:
            assert d.store_status() == "unknown"
            assert d.status()["store_status"] == "unknown"
    finally:
        vd.stop()
        bus.shutdown()
