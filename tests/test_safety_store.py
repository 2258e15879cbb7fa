"""Parameter-store health on the bus (CiA 301 §7.5.2.13/14, EMCY 0x6310) and store files.

Truths: CiA 301 Table 21 "0x6310 loss of parameters" (device software / data set) with error
register bit 0 (generic); the contract in /work/coord/COMMON.md for 0x2060 store_status
(0 ok, 1 defaults, 2 damaged, 3 unreadable; EMCY after the boot-up message); POSIX: a process
killed by SIGKILL runs no cleanup, so temporaries must be removed at the next start.
"""

from __future__ import annotations

import json
import os
import signal
import struct
import subprocess
import sys
import time
from pathlib import Path

import pytest
from canopen.sdo import SdoAbortedError
from test_node_support import Bench, emcy_frames

from firmware_protocol import load_od
from virtual_drive.node import storage

pytestmark = pytest.mark.timeout(90)

SAVE = 0x65766173


def boot_then_emcy(b: Bench) -> tuple[float, list]:
    boot = b.log.wait_for(0x701, 2.0, pred=lambda d: d == b"\x00")
    assert boot is not None
    return boot[0], emcy_frames(b.log)


@pytest.mark.unit
def test_no_store_reports_defaults():
    b = Bench()
    try:
        assert b.read("store_status") == 1
        time.sleep(0.1)
        assert emcy_frames(b.log) == []
    finally:
        b.close()


@pytest.mark.unit
def test_saved_store_reports_ok_after_restart(tmp_path):
    path = tmp_path / "params.json"
    b = Bench(store_path=path)
    try:
        assert b.read("store_status") == 1  # no file yet
        b.write("current_controller.k_p", 0.5)
        b.write("store_parameters.save_all", SAVE)
        assert b.read("store_status") == 0
    finally:
        b.close()
    b = Bench(store_path=path)
    try:
        assert b.read("store_status") == 0
        assert b.read("current_controller.k_p") == pytest.approx(0.5)
        time.sleep(0.1)
        assert emcy_frames(b.log) == []
    finally:
        b.close()


@pytest.mark.unit
@pytest.mark.parametrize(
    ("damage", "status"),
    [("flip", 2), ("truncate", 2), ("garbage", 2), ("directory", 3)],
)
def test_damaged_or_unreadable_store_is_reported_on_the_bus(tmp_path, damage, status):
    path = tmp_path / "params.json"
    b = Bench(store_path=path)
    try:
        b.write("current_controller.k_p", 0.5)
        b.write("store_parameters.save_all", SAVE)
    finally:
        b.close()
    text = path.read_bytes()
    if damage == "flip":
        doc = json.loads(text)
        key = next(iter(doc["params"]))
        doc["params"][key] = "ff" * (len(doc["params"][key]) // 2)  # checksum now wrong
        path.write_text(json.dumps(doc))
    elif damage == "truncate":
        path.write_bytes(text[: len(text) // 2])
    elif damage == "garbage":
        path.write_bytes(os.urandom(200))
    else:
        path.unlink()
        path.mkdir()  # reading a directory: an I/O error, not a parse error
    b = Bench(store_path=path)
    try:
        t_boot, _frames = boot_then_emcy(b)
        got = b.log.wait_for(0x81, 2.0, pred=lambda d: d[:2] == b"\x10\x63")
        assert got is not None, "no EMCY 0x6310 after a damaged store"
        t_emcy, data = got
        assert t_emcy >= t_boot  # after the boot-up message
        assert data[2] & 0x01  # error register: generic
        assert data[3] == status
        assert b.read("error_register") & 0x01
        assert b.read("store_status") == status
        assert b.read("current_controller.k_p") == pytest.approx(0.4647)  # defaults in use
        # reset node: loaded again, reported again after the new boot-up
        t0 = time.monotonic()
        b.nmt(0x81)
        boot = b.log.wait_for(0x701, 3.0, since=t0, pred=lambda d: d == b"\x00")
        assert boot is not None
        again = b.log.wait_for(0x81, 2.0, since=boot[0], pred=lambda d: d[:2] == b"\x10\x63")
        assert again is not None
        if damage != "directory":
            # storing the present parameters repairs the store: ok, error cleared
            t1 = time.monotonic()
            b.write("store_parameters.save_all", SAVE)
            assert b.read("store_status") == 0
            assert b.log.wait_for(0x81, 2.0, since=t1, pred=lambda d: d[:3] == b"\x00\x00\x00")
            assert b.read("error_register") == 0
        else:
            with pytest.raises(SdoAbortedError) as exc:  # cannot replace a directory
                b.write("store_parameters.save_all", SAVE)
            assert exc.value.code == 0x06060000
            assert b.read("store_status") == 3
    finally:
        b.close()


def temps(path: Path) -> list[str]:
    return sorted(n for n in os.listdir(path.parent) if n.startswith(f".{path.name}."))


@pytest.mark.unit
def test_stale_temporaries_removed_at_start(tmp_path):
    path = tmp_path / "params.json"
    for k in range(3):
        (tmp_path / f".params.json.stale{k}.tmp").write_bytes(b"{half")
    (tmp_path / ".other.json.x.tmp").write_bytes(b"not ours")
    b = Bench(store_path=path)
    try:
        assert temps(path) == []
        assert (tmp_path / ".other.json.x.tmp").exists()  # another store's file is left alone
    finally:
        b.close()


@pytest.mark.unit
def test_failed_store_leaves_no_temporary(tmp_path, monkeypatch):
    path = tmp_path / "params.json"
    b = Bench(store_path=path)
    try:
        b.write("store_parameters.save_all", SAVE)
        before = path.read_bytes()

        def failing_replace(src, dst):
            raise OSError(28, "No space left on device")

        monkeypatch.setattr(storage.os, "replace", failing_replace)
        with pytest.raises(SdoAbortedError) as exc:
            b.write("store_parameters.save_all", SAVE)
        assert exc.value.code == 0x06060000
        assert temps(path) == []
        assert path.read_bytes() == before
    finally:
        b.close()


_WRITER = """
import importlib.util, sys
# storage.py alone (stdlib only): the package would import canopen and numpy on every round
spec = importlib.util.spec_from_file_location("storage", sys.argv[3])
storage = importlib.util.module_from_spec(spec)
spec.loader.exec_module(storage)
path, k = sys.argv[1], 0
print("ready", flush=True)
while True:
    k += 1
    storage.save(path, {(0x2010, 4): bytes([k % 256, 0, 0, 63]) * 1, (0x2010, 5): b"\\x00" * 4})
"""


def test_kill_9_during_stores_never_tears_and_temps_are_cleaned(tmp_path):
    path = tmp_path / "params.json"
    storage.save(path, {(0x2010, 4): b"\x00\x00\x00\x3f"})
    rounds = 10
    for r in range(rounds):
        proc = subprocess.Popen(
            [sys.executable, "-c", _WRITER, str(path), str(r), storage.__file__],
            stdout=subprocess.PIPE,
            cwd=Path(__file__).resolve().parents[1],
        )
        try:
            assert proc.stdout is not None and proc.stdout.readline().strip() == b"ready"
            time.sleep(0.01 + 0.007 * r)
        finally:
            proc.send_signal(signal.SIGKILL)
            proc.wait(10)
        values = storage.load(path)  # never torn: old or new, checksum intact
        assert values[(0x2010, 4)][1:] == b"\x00\x00\x3f"
        storage.remove_stale_temps(path)
        assert temps(path) == []
    value = struct.unpack("<f", storage.load(path)[(0x2010, 4)])[0]
    assert value > 0


@pytest.mark.unit
def test_stored_set_that_breaks_a_rule_is_not_applied(tmp_path):
    """A store written before a rule existed (R_c = 1 Ohm > 2 motor.R, inside the old static
    limits) passes its checksum but is not applied: defaults, status 2, EMCY 0x6310."""
    path = tmp_path / "params.json"
    e = load_od().entry("current_controller.R_c")
    storage.save(path, {(e.index, e.subindex): struct.pack("<f", 1.0)})
    b = Bench(store_path=path)
    try:
        assert b.read("store_status") == 2
        assert b.read("current_controller.R_c") == pytest.approx(0.0062)
        assert b.log.wait_for(0x81, 2.0, pred=lambda d: d[:2] == b"\x10\x63") is not None
    finally:
        b.close()
