"""The C sample loop trips with the EMCY and trip-reason macros of the generated header.

Truths: the EDS text (``Description=... (EMCY 0x....)`` of the protection objects 0x2050, read
with configparser, not through firmware_protocol), CiA 402's code meanings (0x2310 overcurrent,
0x3210/0x3220 DC link over/undervoltage), and the simulator's cause of each trip (a current above
the threshold, a supply outside the limits, an injection) against the reason it reports.
"""

from __future__ import annotations

import configparser
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from firmware_protocol import EDS_PATH
from virtual_drive.sim.params import CurrentControllerParams
from virtual_drive.sim.simulator import Simulator

pytestmark = pytest.mark.timeout(120)

LOOP_C = Path(__file__).resolve().parents[1] / "virtual_drive" / "csrc" / "loop.c"


def _eds_emcy(section: str) -> int:
    cp = configparser.RawConfigParser(inline_comment_prefixes=(";",))
    cp.optionxform = str  # type: ignore[assignment,method-assign]
    cp.read(EDS_PATH, encoding="utf-8")
    m = re.search(r"EMCY (0x[0-9A-F]{4})", cp[section]["Description"])
    assert m, section
    return int(m.group(1), 16)


@pytest.mark.unit
def test_loop_c_has_no_raw_emcy_numbers_and_uses_the_header() -> None:
    code = re.sub(r"/\*.*?\*/", "", LOOP_C.read_text(), flags=re.S)
    assert '#include "bldc_drive_od.h"' in code
    raw = {f"0x{c:04x}" for c in (0x2310, 0x3210, 0x3220)}
    found = {lit.lower() for lit in re.findall(r"0x[0-9A-Fa-f]+", code)} & raw
    assert not found, f"raw EMCY numbers in loop.c: {sorted(found)}"
    # every trip names its reason with an OD_TRIP_* macro, none with a bare number
    calls = re.findall(r"\btrip\(\s*\w+\s*,\s*([^,]+),\s*([^)]+)\)", code)
    assert len(calls) == 5, calls
    for emcy, reason in calls:
        assert reason.strip().startswith("OD_TRIP_"), reason
        assert emcy.strip().startswith("OD_TRIP_") or "inject" in emcy, emcy


def test_header_trip_macros_carry_the_eds_emcy_codes(tmp_path: Path) -> None:
    gcc = shutil.which("gcc")
    if gcc is None:
        pytest.fail("gcc is required to check the DSP header")
    expected = {
        "OD_TRIP_OVERCURRENT_EMCY": _eds_emcy("2050sub1"),
        "OD_TRIP_NONFINITE_EMCY": _eds_emcy("2050sub1"),
        "OD_TRIP_DC_OVERVOLTAGE_EMCY": _eds_emcy("2050sub2"),
        "OD_TRIP_DC_UNDERVOLTAGE_EMCY": _eds_emcy("2050sub3"),
    }
    assert list(expected.values()) == [0x2310, 0x2310, 0x3210, 0x3220]  # CiA 402
    reasons = [
        "OD_TRIP_OVERCURRENT",
        "OD_TRIP_NONFINITE",
        "OD_TRIP_DC_OVERVOLTAGE",
        "OD_TRIP_DC_UNDERVOLTAGE",
        "OD_TRIP_INJECTED",
    ]
    body = [f'    printf("{m} %lu\\n", (unsigned long){m});' for m in [*expected, *reasons]]
    src = tmp_path / "trip.c"
    src.write_text(
        "\n".join(['#include "bldc_drive_od.h"', "#include <stdio.h>", "int main(void) {"])
        + "\n"
        + "\n".join(body)
        + "\n    return 0;\n}\n"
    )
    exe = tmp_path / "trip"
    flags = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic"]
    build = subprocess.run(
        [gcc, *flags, f"-I{EDS_PATH.parent}", str(src), "-o", str(exe)],
        capture_output=True,
        text=True,
        timeout=90,
    )
    assert build.returncode == 0, build.stderr[:3000]
    out = subprocess.run([str(exe)], capture_output=True, text=True, timeout=30, check=True)
    got = dict(line.split() for line in out.stdout.splitlines())
    assert {m: int(got[m]) for m in expected} == expected
    numbers = [int(got[m]) for m in reasons]
    assert len(set(numbers)) == len(numbers) and 0 not in numbers  # 0 = no fault


def _running() -> Simulator:
    sim = Simulator()
    sim.set_load(J=1e4)
    sim.set_speed(1000.0)
    sim.set_mode("current")
    sim.set_current_ref(30.0)
    sim.run(500, record=False)
    assert sim.fault is None
    return sim


@pytest.mark.unit
def test_each_real_trip_reports_its_cause_and_code() -> None:
    # a current above the threshold
    sim = _running()
    sim.set_protection(overcurrent_trip=10.0)
    sim.run(50, record=False)
    f = sim.fault
    assert f is not None and f.code == _eds_emcy("2050sub1")
    assert "overcurrent" in f.reason and "non-finite" not in f.reason
    # a diverging current law (L_c = 3 L: the deadbeat loop is unstable) at a high threshold
    sim = Simulator(current=CurrentControllerParams(L_c=3 * 14.8e-6))
    sim.set_load(J=1e4)
    sim.set_protection(overcurrent_trip=60.0)
    sim.set_mode("current")
    sim.set_current_ref(40.0)
    sim.run(5000, record=False)
    f = sim.fault
    assert f is not None and f.code == 0x2310 and "overcurrent" in f.reason
    # the supply above, then below, the DC-link limits
    sim = _running()
    sim.set_supply_voltage(65.0)
    sim.run(5, record=False)
    f = sim.fault
    assert f is not None and f.code == _eds_emcy("2050sub2") and "overvoltage" in f.reason
    sim.set_supply_voltage(30.0)
    sim.reset_fault()
    sim.run(5, record=False)
    f = sim.fault
    assert f is not None and f.code == _eds_emcy("2050sub3") and "undervoltage" in f.reason
    # an injected DC-link fault: the injected code, the reason says so
    sim = _running()
    sim.inject_fault("undervoltage")
    sim.run(5, record=False)
    f = sim.fault
    assert f is not None and f.code == 0x3220 and "injected" in f.reason
