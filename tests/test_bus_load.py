"""Offered bus load of the default TPDO streams, and the warning of an overloaded bench.

Truths: the drive's default TPDOs (firmware_protocol/OD.md, "PDO" table): TPDO1 statusword (16)
+ velocity (32) every 10 ms, TPDO2 and TPDO3 two REAL32 every 1 ms, TPDO4 two REAL32 every
10 ms; a classical data frame with an 11-bit identifier and n data bytes is 47 + 8·n bits
without stuff bits (ISO 11898-1: SOF 1, id 11, RTR 1, IDE 1, r0 1, DLC 4, CRC 15 + 1,
ACK 2, EOF 7, intermission 3). Stuff bits only add to that.
"""

from __future__ import annotations

import signal
import subprocess
import sys

import pytest

from firmware_protocol.can_bits import frame_bits
from virtual_drive.bus_load import WARN_LOAD, default_tpdo_bits_per_s, overload_warning

pytestmark = pytest.mark.timeout(60)

PER_NODE = 100 * (47 + 8 * 6) + 2 * 1000 * (47 + 8 * 8) + 100 * (47 + 8 * 8)  # bit/s


@pytest.mark.unit
def test_default_streams_offer_the_iso_frame_bits_of_the_od_table():
    assert default_tpdo_bits_per_s() == pytest.approx(PER_NODE)  # 242,600 bit/s
    # a lower bound: the exact length of a real frame (stuff bits included) is never shorter
    assert frame_bits(0x281, bytes(8)) >= 47 + 64
    assert frame_bits(0x181, b"\x27\x02\x00\x00\x00\x00") >= 47 + 48


@pytest.mark.unit
@pytest.mark.parametrize(
    ("nodes", "bitrate", "warned"),
    [(1, 1_000_000, False), (3, 1_000_000, False), (4, 1_000_000, True), (2, 500_000, True)],
)
def test_overload_warning_from_the_offered_load(nodes, bitrate, warned):
    load = nodes * PER_NODE / bitrate
    assert (load >= WARN_LOAD) == warned
    text = overload_warning(nodes, bitrate)
    if not warned:
        assert text is None
    else:
        assert text is not None and f"{load:.0%}" in text
        assert "0x1801:05" in text and "0x1802:05" in text  # TPDO2/3 event timers (CiA 301)


def test_hub_command_warns_on_stderr_when_its_drives_overload_the_bus():
    proc = subprocess.Popen(
        [sys.executable, "-m", "virtual_drive.cli", "hub", "--port", "0", "--nodes", "1-2",
         "--bitrate", "500000"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        lines = [proc.stdout.readline() for _ in range(3)]  # join line, two ready lines
        assert all(lines), (lines, proc.stderr.read() if proc.poll() is not None else "")
        warning = proc.stderr.readline()
        proc.send_signal(signal.SIGTERM)
        proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert warning.startswith("virtual-drive hub: warning: 2 drives"), warning
    assert "97%" in warning and "0.5 Mbit/s" in warning
    assert proc.returncode == 0
