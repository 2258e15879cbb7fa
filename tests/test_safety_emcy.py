"""The trip EMCY codes the drive sends are the ones its EDS, OD.md and C header state.

Truths: the EDS text (``Description=... (EMCY 0x....)`` of the protection objects, read with
configparser, not through firmware_protocol), the generated header's ``OD_EMCY_*`` macros and
CiA 402's code meanings (0x2310 overcurrent at the device output, 0x3210/0x3220 DC link).
"""

from __future__ import annotations

import configparser
import re
import struct
import time

import pytest
from test_node_support import Bench, emcy_frames

from firmware_protocol import EDS_PATH

pytestmark = [pytest.mark.timeout(60), pytest.mark.unit]

HEADER = EDS_PATH.with_name("bldc_drive_od.h")
OD_MD = EDS_PATH.with_name("OD.md")


def eds_code(section: str) -> int:
    cp = configparser.RawConfigParser(inline_comment_prefixes=(";",))
    cp.optionxform = str  # type: ignore[assignment,method-assign]
    cp.read(EDS_PATH, encoding="utf-8")
    m = re.search(r"EMCY (0x[0-9A-F]{4})", cp[section]["Description"])
    assert m, section
    return int(m.group(1), 16)


def header_macro(name: str) -> int:
    m = re.search(rf"^#define {name}\s+(0x[0-9A-F]+)u", HEADER.read_text(), re.M)
    assert m, name
    return int(m.group(1), 16)


@pytest.mark.parametrize(
    ("inject", "section", "macro"),
    [
        (1, "2050sub1", "OD_EMCY_OVERCURRENT"),
        (2, "2050sub2", "OD_EMCY_DC_OVERVOLTAGE"),
        (3, "2050sub3", "OD_EMCY_DC_UNDERVOLTAGE"),
    ],
)
def test_trip_code_matches_eds_header_and_od_md(inject, section, macro):
    expected = eds_code(section)
    assert header_macro(macro) == expected
    assert f"| 0x{expected:04X} | `{macro}` |" in OD_MD.read_text()
    b = Bench()
    try:
        b.enable(-1)
        t0 = time.monotonic()
        b.write("sim_fault.inject", inject)
        got = b.log.wait_for(0x81, 2.0, since=t0)
        assert got is not None
        assert struct.unpack_from("<H", got[1])[0] == expected
        assert b.read("error_code") == expected
        assert [c for _, c, _ in emcy_frames(b.log, since=t0)][:1] == [expected]
    finally:
        b.close()


def test_real_overcurrent_trip_uses_the_same_code():
    """A real overcurrent (threshold lowered below the regulated current), not an injection."""
    b = Bench()
    try:
        b.write("protection.overcurrent_trip", 5.0)
        b.enable(-1)
        t0 = time.monotonic()
        b.write("setpoints.i_p_ref", 20.0)
        got = b.log.wait_for(0x81, 2.0, since=t0)
        assert got is not None
        assert struct.unpack_from("<H", got[1])[0] == eds_code("2050sub1") == 0x2310
    finally:
        b.close()
