"""drive_link.link.units: typed values with units → the OD unit of the object.

Oracle: pint's own conversions of the same quantities written out term by term (a separate
registry, so a wrong alias or a wrong OD unit in drive_link.link.units shows), and SI facts
(1 rpm = 2π/60 rad/s)."""

from __future__ import annotations

import math

import pint
import pytest

from drive_link.errors import InvalidValue
from drive_link.link._objects import default_table
from drive_link.link.units import parse_for, parse_value

pytestmark = pytest.mark.unit

ureg = pint.UnitRegistry()


@pytest.mark.parametrize(
    ("text", "unit", "oracle"),
    [
        ("20uH", "H", ureg.Quantity(20, "microhenry").to("henry").magnitude),
        ("20 µH", "H", 20e-6),
        ("50A", "A", 50.0),
        ("500 mA", "A", 0.5),
        ("-5A", "A", -5.0),
        ("2.5 mohm", "Ohm", 2.5e-3),
        ("1.5 ms", "s", 1.5e-3),
        ("0.3", "s", 0.3),
        ("-1e30", "A", -1e30),
        ("3 s", "ms", 3000.0),
        ("1 ms", "100 us", 10.0),
        ("12 V", "mV", 12000.0),
    ],
)
def test_conversions_match_pint(text, unit, oracle):
    assert parse_value(text, unit) == pytest.approx(oracle, rel=1e-12)


def test_speed_in_rpm_and_rad_per_s():
    assert parse_value("1000rpm", "rpm", integer=True) == 1000
    assert parse_value("1000 rpm", "rpm", integer=True) == 1000
    # 60π rad/s = 1800 rpm exactly (1 rev = 2π rad)
    assert parse_value(f"{60 * math.pi!r} rad/s", "rpm", integer=True) == 1800
    with pytest.raises(InvalidValue, match="whole numbers"):
        parse_value("1000.7", "rpm", integer=True)
    with pytest.raises(InvalidValue, match="Hz is ambiguous"):
        parse_value("50 Hz", "rpm", integer=True)


@pytest.mark.parametrize(
    ("text", "unit", "match"),
    [
        ("5A", "rpm", "wrong dimension"),
        ("20uH", "A", "wrong dimension"),
        ("nan", "A", "nan and inf are refused"),
        ("inf", "rpm", "nan and inf are refused"),
        ("1e400", "A", "nan and inf are refused"),
        ("-inf A", "A", "nan and inf are refused"),
        ("abc", "A", "is not a number"),
        ("", "A", "not a number"),
        ("5 A", "", "has no unit"),
        ("5 V", "permille of motor_rated_torque", "plain number"),
    ],
)
def test_refused_in_one_line(text, unit, match):
    with pytest.raises(InvalidValue, match=match) as exc:
        parse_value(text, unit)
    assert "\n" not in str(exc.value)


def test_parse_for_uses_the_od_unit_type_and_limits():
    t = default_table()
    # the OD's units, read from the EDS view
    assert t["current_controller.L_c"].unit == "H" and t["target_velocity"].unit == "rpm"
    assert parse_for("current_controller.L_c", "20uH") == pytest.approx(20e-6, rel=1e-7)
    assert parse_for("target_velocity", "-100 rpm") == -100
    assert parse_for("modes_of_operation", "pseudo_current") == -1
    assert parse_for("statusword", "0x10") == 16
    with pytest.raises(InvalidValue, match="above the limit"):
        parse_for("current_controller.L_c", "3 mH")  # EDS HighLimit 0.002 H
