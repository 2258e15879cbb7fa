"""firmware_protocol is the one home of protocol facts (issue 13 §1): abort codes, EMCY codes,
controller types and the paper's constants agree with their independent sources (CiA 301 as
canopen encodes it, the EDS read with configparser, the paper's printed numbers), and every
other package uses the home instead of a copy."""

from __future__ import annotations

import configparser
import math
import re
from pathlib import Path

import pytest
from canopen.emcy import EmcyError
from canopen.sdo import constants as canopen_constants
from canopen.sdo.exceptions import SdoAbortedError

from firmware_protocol import abort_codes, emcy_codes, paper
from firmware_protocol.enums import CONTROLLER_NAMES, CONTROLLER_TYPES, ControllerType
from firmware_protocol.od import EDS_PATH

pytestmark = pytest.mark.unit

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("firmware_protocol", "virtual_drive", "drive_link", "dashboard")

# CiA 301 v4.2 table 22, written out here as the independent truth.
CIA301_TABLE22 = {
    0x05030000, 0x05040000, 0x05040001, 0x05040002, 0x05040003, 0x05040004, 0x05040005,
    0x06010000, 0x06010001, 0x06010002, 0x06020000, 0x06040041, 0x06040042, 0x06040043,
    0x06040047, 0x06060000, 0x06070010, 0x06070012, 0x06070013, 0x06090011, 0x06090030,
    0x06090031, 0x06090032, 0x06090036, 0x060A0023, 0x08000000, 0x08000020, 0x08000021,
    0x08000022, 0x08000023, 0x08000024,
}  # fmt: skip


def _eds() -> configparser.RawConfigParser:
    raw = configparser.RawConfigParser(inline_comment_prefixes=(";",))
    raw.optionxform = str  # type: ignore[assignment,method-assign]
    raw.read(EDS_PATH, encoding="utf-8")
    return raw


def test_abort_codes_cover_cia301_and_agree_with_canopen() -> None:
    names = [n for n in abort_codes.__all__ if isinstance(getattr(abort_codes, n), int)]
    codes = {getattr(abort_codes, n) for n in names}
    assert codes == CIA301_TABLE22
    canopen_codes = {
        v for k, v in vars(canopen_constants).items() if k.startswith("ABORT_") and v > 0xFFFF
    }
    assert codes == canopen_codes
    for code in codes:  # every code has canopen's meaning or the CiA 301 v4.2 wording
        text = abort_codes.meaning(code)
        assert text and text != "unknown abort code"
        assert text.lower() == SdoAbortedError.CODES[code].lower() or (
            code in abort_codes.CIA301_WORDING
        )
    assert abort_codes.meaning(abort_codes.INVALID_VALUE) == "invalid value for parameter"
    assert abort_codes.meaning(0x0609_0099) == "unknown abort code"


def test_emcy_codes_sent_are_described_in_their_cia_class() -> None:
    classes = {0x2: "current", 0x3: "voltage", 0x6: "device software", 0x8: "monitoring"}
    for code in emcy_codes.EMCY_CODES:
        assert code in emcy_codes.MEANINGS
        desc = EmcyError(code, 0, b"", 0.0).get_desc().lower()  # canopen's class of the code
        assert desc == classes[code >> 12]
    assert emcy_codes.describe(0x2311) == emcy_codes.MEANINGS[emcy_codes.OVERCURRENT]
    assert emcy_codes.describe(0x4999) == "temperature"
    assert emcy_codes.describe(0xA000) == "unknown"


def test_controller_types_match_the_eds_enum() -> None:
    raw = _eds()
    for section in ("2010sub1", "20F0sub1"):
        enum = dict(
            (int(v, 0), label.strip().lower())
            for v, _, label in (i.partition(":") for i in raw[section]["Enum"].split(","))
        )
        assert enum == dict(CONTROLLER_NAMES)
    assert dict(CONTROLLER_TYPES) == {"deadbeat": 0, "pi": 1, "predictive": 2}
    assert all(CONTROLLER_TYPES[c.name.lower()] == c for c in ControllerType)


def test_paper_constants_are_the_eds_defaults() -> None:
    raw = _eds()

    def default(section: str) -> float:
        text = raw[section]["DefaultValue"]
        return float(int(text, 16)) if text.lower().startswith("0x") else float(text)

    assert default("2000sub1") == paper.R_TABLE2 == pytest.approx(6.2e-3)  # Table 2: 6.2 mOhm
    assert default("2000sub2") == paper.L_TABLE2 == pytest.approx(14.8e-6)  # 14.8 uH
    assert default("2000sub3") == paper.K_RPM == 0.0125
    assert default("2000sub4") == paper.POLE_PAIRS == 4  # 8 poles
    assert default("2000sub5") == paper.RATED_CURRENT == 100.0
    assert default("2000sub6") == paper.RATED_VOLTAGE == 48.0
    assert default("2010sub2") == paper.L_TABLE2 and default("2010sub3") == paper.R_TABLE2
    assert (default("2010sub4"), default("2010sub5")) == (paper.PI_KP, paper.PI_KI)
    assert (default("2020sub1"), default("2020sub2")) == (paper.IP_KP, paper.IP_KI)
    assert paper.TS == pytest.approx(20e-6)


def test_ip_gains_follow_from_the_speed_model() -> None:
    """Eqs. (28)-(31) with d2 = exp(-2 xi wn Ts) (overview.md) give the printed gains."""
    a, b = paper.SPEED_MODEL
    xi, wn, ts = paper.IP_XI, paper.IP_OMEGA_N, paper.TS
    d1 = -2 * math.exp(-xi * wn * ts) * math.cos(wn * ts * math.sqrt(max(0.0, 1 - xi**2)))
    d2 = math.exp(-2 * xi * wn * ts)
    k_p = (a - d2) / b
    k_i = (d1 + 1 + a - k_p * b) / (k_p * b)
    assert k_p == pytest.approx(paper.IP_KP, rel=2e-3)
    assert k_i == pytest.approx(paper.IP_KI, rel=2e-3)


_COPY_PATTERNS = {
    "abort code": re.compile(r"^\s*\w*ABORT\w*\s*(:\s*\w+\s*)?=\s*0x0[5-8]0", re.M),
    "controller map": re.compile(r"\{\s*0:\s*\"deadbeat\"|\"deadbeat\":\s*0\b"),
    "speed model": re.compile(r"^\s*\w+\s*(:[^=\n]+)?=\s*\(?(0\.9999785|3\.33715e-4)\b", re.M),
    "Table 2 R/L": re.compile(r"=\s*(6\.2e-3|14\.8e-6)\s*$", re.M),
    "EMCY table": re.compile(r"^\s*0x(2310|3210|8130):\s*\"", re.M),
}


@pytest.mark.parametrize("what", sorted(_COPY_PATTERNS))
def test_no_copies_outside_firmware_protocol(what: str) -> None:
    """A fact defined outside its home would drift: the packages import it instead."""
    pattern = _COPY_PATTERNS[what]
    homes = {"firmware_protocol/abort_codes.py", "firmware_protocol/emcy_codes.py",
             "firmware_protocol/paper.py", "firmware_protocol/enums.py"}  # fmt: skip
    hits = []
    for pkg in PACKAGES:
        for path in sorted((ROOT / pkg).rglob("*.py")):
            rel = path.relative_to(ROOT).as_posix()
            if rel in homes:
                continue
            for m in pattern.finditer(path.read_text(encoding="utf-8")):
                line = path.read_text(encoding="utf-8")[: m.start()].count("\n") + 1
                hits.append(f"{rel}:{line}")
    assert not hits, f"{what} copied outside firmware_protocol: {hits}"


def test_controller_name_literals_follow_the_enum() -> None:
    """Static ``Literal`` annotations cannot import the map: they are pinned to it here."""
    import typing

    from dashboard._models import GainsIn
    from drive_link import design

    literal = next(a for a in typing.get_args(GainsIn.model_fields["type"].annotation) if a)
    assert typing.get_args(literal) == tuple(CONTROLLER_TYPES)
    assert tuple(design.CONTROLLERS) == tuple(CONTROLLER_TYPES)


def test_simulator_fault_kinds_follow_the_sim_fault_enum() -> None:
    """0x5010:1 codes 0..3 select the simulator's fault kinds in SimFault's order and EMCY code."""
    from firmware_protocol.enums import SimFault
    from virtual_drive.sim.simulator import FAULT_KINDS

    assert list(FAULT_KINDS.values()) == [
        0,
        emcy_codes.OVERCURRENT,
        emcy_codes.DC_OVERVOLTAGE,
        emcy_codes.DC_UNDERVOLTAGE,
    ]
    names = ["NONE", "OVERCURRENT", "DC_OVERVOLTAGE", "DC_UNDERVOLTAGE"]
    assert [m.name for m in SimFault] == names
