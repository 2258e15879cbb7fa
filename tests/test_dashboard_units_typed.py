"""Values typed with units in the dashboard: the GUI's number fields and the REST API's bodies
take ``20uH``, ``0.02 mH``, ``1000rpm``, converted to the field's unit; a wrong dimension, nan/inf
or a non-whole value for an integer field is refused in one line and nothing is sent.

Truths: a fresh pint registry (independent of drive_link's) for every conversion, and the drive's
own read-back (``GET /api/gains`` reads the objects) for what was applied.
"""

from __future__ import annotations

import struct

import pint
import pytest
from fastapi.testclient import TestClient

from dashboard._fields import FieldError, NumberSpec
from dashboard._gui_tabs.speed import parse_sequence
from dashboard._models import GainsIn, SequenceIn, TraceIn
from dashboard.app import create_app
from dashboard.config import BenchConfig

pytestmark = pytest.mark.timeout(120)

U = pint.UnitRegistry()
L = 14.8e-6  # motor.L, H (paper)

LC_UH = NumberSpec("L_c (µH)", 0.0, 2000.0, lo_open=True, unit="µH")
RC_MOHM = NumberSpec("R_c (mΩ)", 0.0, 1000.0, unit="mΩ")
SPEED = NumberSpec("Speed setpoint (rpm)", -6000, 6000, integer=True, unit="rpm")
PLAIN = NumberSpec("L_c / L", 0.0, 3.0, lo_open=True)


def f32(x: float) -> float:
    return struct.unpack("<f", struct.pack("<f", x))[0]


# ---------------------------------------------------------------- GUI fields
@pytest.mark.unit
@pytest.mark.parametrize(
    "spec,text,oracle",
    [
        (LC_UH, "20uH", "20 uH"),
        (LC_UH, "0.02 mH", "0.02 mH"),
        (LC_UH, "1.48e-5 H", "1.48e-5 H"),
        (RC_MOHM, "0.0062 ohm", "0.0062 ohm"),
        (SPEED, "1000rpm", "1000 rpm"),
        (SPEED, "−20 rpm", "-20 rpm"),
    ],
)
def test_field_converts_a_unit_like_pint(spec, text, oracle):
    want = U(oracle).to(U(spec.unit.replace("Ω", "ohm")).units).magnitude
    assert spec.parse(text) == pytest.approx(want, rel=1e-12)
    assert spec.parse("20") == 20  # a bare number is in the field's unit, as before


@pytest.mark.unit
@pytest.mark.parametrize(
    "spec,text,match",
    [
        (SPEED, "5 A", "wrong dimension"),
        (LC_UH, "22.2 A", "wrong dimension"),
        (SPEED, "1000.5rpm", "whole numbers"),
        (SPEED, "100 rad/s", "whole numbers"),  # 954.93 rpm: refused, never rounded
        (LC_UH, "1 H", "outside the range"),  # 1e6 µH: refused, not clamped
        (LC_UH, "-1 uH", "outside the range"),
        (LC_UH, "1e400 uH", "finite"),
        (LC_UH, "nan uH", "not a number"),
        (LC_UH, "uH", "not a number"),  # a unit alone is not a value
        (LC_UH, "1 2 uH", "not a number"),  # nor two numbers
        (LC_UH, "abc", "not a number"),
        (PLAIN, "1 m", "not a number"),  # a field without a unit takes plain numbers only
    ],
)
def test_field_refuses_in_one_line(spec, text, match):
    with pytest.raises(FieldError, match=match) as exc:
        spec.parse(text)
    msg = str(exc.value)
    assert msg.startswith(spec.label) and "\n" not in msg
    if match == "wrong dimension":
        assert text.split()[-1] in msg and spec.unit in msg


@pytest.mark.unit
def test_sequence_with_units():
    steps = parse_sequence("0 s:1000 rpm, 500ms:1500rpm, 2:0")
    assert steps == [(0.0, 1000), (pytest.approx(U("500 ms").to("s").magnitude), 1500), (2.0, 0.0)]
    with pytest.raises(FieldError, match="wrong dimension"):
        parse_sequence("0 s:5 A")


# ---------------------------------------------------------------- API models
@pytest.mark.unit
def test_models_take_units_and_keep_strictness():
    assert GainsIn.model_validate({"L_c": "22.2 uH"}).L_c == pytest.approx(
        U("22.2 uH").to("H").magnitude, rel=1e-15
    )
    assert GainsIn.model_validate({"R_c": "6.2 mOhm"}).R_c == pytest.approx(6.2e-3, rel=1e-15)
    assert GainsIn.model_validate({"L_c": 2e-5}).L_c == 2e-5  # JSON numbers: as before
    seq = SequenceIn.model_validate({"steps": [{"at_s": "250 ms", "rpm": "1500 rpm"}]})
    assert seq.steps[0].at_s == pytest.approx(0.25) and seq.steps[0].rpm == 1500
    assert TraceIn.model_validate({"length": "2000 samples"}).length == 2000
    for body in (
        {"L_c": "22.2 A"},  # wrong dimension
        {"L_c": "3 mH"},  # converted, then above the EDS HighLimit (2 mH)
        {"L_c": "1e400 uH"},
        {"L_c": "1.4e-5"},  # a string without a unit stays refused (strict)
        {"L_c": "22.2 uHH"},
        {"length": "1000.5 samples"},
    ):
        with pytest.raises(ValueError):
            GainsIn.model_validate(body) if "L_c" in body else TraceIn.model_validate(body)


# ---------------------------------------------------------------- API on the virtual drive
@pytest.fixture(scope="module")
def client():
    cfg = BenchConfig(virtual=True, speed_factor=4.0, gui_port=0)
    with TestClient(create_app(cfg, gui=False), base_url="http://127.0.0.1:8000") as c:
        yield c


def test_api_gains_with_units(client):
    hdr = {
        "X-Control-Token": client.post(
            "/api/control", json={"client": "pytest-units", "take_over": True}
        ).json()["token"]
    }
    before = client.get("/api/gains").json()
    r = client.put("/api/gains", json={"L_c": "22.2 A"}, headers=hdr)
    assert r.status_code == 422
    assert "wrong dimension" in r.text and "L_c" in r.text
    r = client.put("/api/gains", json={"L_c": "nan uH"}, headers=hdr)
    assert r.status_code == 422
    assert client.get("/api/gains").json() == before  # nothing changed on the drive
    try:
        r = client.put("/api/gains", json={"L_c": "20 uH"}, headers=hdr)
        assert r.status_code == 200, r.text
        with_unit = client.get("/api/gains").json()["L_c"]
        assert with_unit == f32(U("20 uH").to("H").magnitude)
        r = client.put("/api/gains", json={"L_c": 20e-6}, headers=hdr)
        assert r.status_code == 200 and client.get("/api/gains").json()["L_c"] == with_unit
    finally:
        client.put("/api/gains", json={"L_c": before["L_c"]}, headers=hdr)
    assert client.get("/api/gains").json()["L_c"] == pytest.approx(before["L_c"])
    assert before["L_c"] == pytest.approx(f32(L))
