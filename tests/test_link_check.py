"""`drive-link check` against the virtual drive: every item passes on a conforming node, and a
node with a deliberate defect (its L_c limit check patched out here, in the test) fails the
"limits" item by name with a non-zero exit."""

from __future__ import annotations

import json
import uuid

import can
import pytest

from drive_link import cli
from drive_link.check import ITEMS

pytestmark = pytest.mark.timeout(90)


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
    _, ch = virtual_node
    rc = cli.main(["check", "--interface", "virtual", "--channel", ch, "--node", "4", "--json"])
    out = capsys.readouterr()
    results = json.loads(out.out)
    failed = [r for r in results if not r["ok"]]
    assert rc == 0, failed
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
    assert cli.main(["set-current", "10", *bus]) == 0
    assert cli.main(["enable", *bus]) == 0
    assert "OPERATION ENABLED" in capsys.readouterr().out
    rc = cli.main(["check", *bus, "--only", "cia402,modes", "--json"])
    results = json.loads(capsys.readouterr().out)
    assert rc == 0, [r for r in results if not r["ok"]]
