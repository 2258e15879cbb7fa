"""Every limit outside the drive is the EDS's (issue 13 §1): the dashboard's pydantic bounds and
the simulator's parameter checks equal the ``LowLimit``/``HighLimit`` of the object they carry,
read here from the EDS with configparser (independently of firmware_protocol's view)."""

from __future__ import annotations

import configparser
import dataclasses
import re

import pytest
from annotated_types import Ge, Le
from pydantic import ValidationError

from dashboard import _models as models
from firmware_protocol.od import EDS_PATH
from virtual_drive.node import plant
from virtual_drive.sim import params as sim_params

pytestmark = pytest.mark.unit

_SUB = re.compile(r"^([0-9A-Fa-f]{4})sub([0-9A-Fa-f]+)$")


def _eds_limits() -> dict[str, tuple[float | None, float | None, int, int]]:
    """``"object.sub"`` or ``"object"`` -> (LowLimit, HighLimit, index, sub) from the EDS text."""
    raw = configparser.RawConfigParser(inline_comment_prefixes=(";",))
    raw.optionxform = str  # type: ignore[assignment,method-assign]
    raw.read(EDS_PATH, encoding="utf-8")
    objects = {
        s: raw[s]["ParameterName"] for s in raw.sections() if re.fullmatch(r"[0-9A-F]{4}", s)
    }

    def num(text: str | None, data_type: str) -> float | None:
        if text is None:
            return None
        if int(data_type, 0) == 0x08:
            return float(text)
        value = int(text, 0)
        bits = {0x02: 8, 0x03: 16, 0x04: 32}.get(int(data_type, 0))
        if bits and text.lower().startswith("0x") and value >= 1 << (bits - 1):
            value -= 1 << bits
        return value

    out = {}
    for sec in raw.sections():
        m = _SUB.match(sec)
        if m:
            name = f"{objects[m.group(1)]}.{raw[sec]['ParameterName']}"
            idx, sub = int(m.group(1), 16), int(m.group(2), 16)
        elif sec in objects and "DataType" in raw[sec]:
            name, idx, sub = objects[sec], int(sec, 16), 0
        else:
            continue
        s = raw[sec]
        dt = s["DataType"]
        out[name] = (num(s.get("LowLimit"), dt), num(s.get("HighLimit"), dt), idx, sub)
    return out


EDS = _eds_limits()
MODELS = [
    cls
    for cls in vars(models).values()
    if isinstance(cls, type) and issubclass(cls, models.Strict) and cls is not models.Strict
]
#: dashboard rules stricter than the object, with the reason
STRICTER_LOW = {("TraceIn", "length"): 2}  # a trace needs two samples to be a curve


def _bounds(info) -> tuple[float | None, float | None]:
    ge = next((m.ge for m in info.metadata if isinstance(m, Ge)), None)
    le = next((m.le for m in info.metadata if isinstance(m, Le)), None)
    return ge, le


@pytest.mark.parametrize("model", MODELS, ids=lambda m: m.__name__)
def test_pydantic_bounds_are_the_eds_limits(model) -> None:
    for field, od_name in models.od_fields(model).items():
        low, high, _, _ = EDS[od_name]
        ge, le = _bounds(model.model_fields[field])
        assert le == high, (model.__name__, field, od_name)
        assert ge == STRICTER_LOW.get((model.__name__, field), low), (model.__name__, field)


def test_every_numeric_gain_field_is_bound_by_its_object() -> None:
    """GainsIn carries the staged gain set 0x20F0: each numeric field is that object's."""
    bound = models.od_fields(models.GainsIn)
    for field, info in models.GainsIn.model_fields.items():
        if "float" in str(info.annotation):
            assert bound.get(field) == f"gain_set.{field}", field


@pytest.mark.parametrize(
    ("field", "ok", "bad"),
    [("T_BT", 2e-5, 2.0001e-5), ("V_G", 5.0, 5.001), ("L_c", 2e-3, 2.001e-3), ("R_c", 1.0, 1.01)],
)
def test_gains_in_accepts_the_eds_range_only(field, ok, bad) -> None:
    """The drifted copies allowed T_BT <= 1e-4 s and V_G <= 10 V; the EDS says 2e-5 s, 5 V."""
    assert getattr(models.GainsIn(**{field: ok}), field) == ok
    with pytest.raises(ValidationError):
        models.GainsIn(**{field: bad})


#: simulator checks that physics narrows below the object's range, with the effective bound
PHYSICS_HIGH = {
    "InverterParams.T_DD": None,  # T_DD + T_SD < Ts/2 (open): checked together
    "InverterParams.T_SD": None,
}
#: other fields a cross-object rule needs to accept a value at a bound
COMPANIONS = {"ProtectionParams.overvoltage_trip": {"undervoltage_trip": 0.0}}


@pytest.mark.parametrize("key", sorted(sim_params.OD_LIMITS))
def test_sim_checks_are_the_eds_limits(key: str) -> None:
    cls_name, field = key.split(".")
    cls = getattr(sim_params, cls_name)
    low, high, _, _ = EDS[sim_params.OD_LIMITS[key]]
    assert high is not None and low is not None, key
    above = high + 1 if isinstance(high, int) else high * (1 + 1e-6)
    below = low - max(abs(low) * 1e-6, 1e-12) if low != 0 else -1e-12
    if isinstance(low, int) and low != 0:
        below = low - 1
    with pytest.raises(ValueError, match=rf"{key} must be <= {high!r}"):
        cls(**{field: above})
    with pytest.raises(ValueError, match=rf"{key} must be >= {low!r}"):
        cls(**{field: below})
    assert getattr(cls(**{field: low, **COMPANIONS.get(key, {})}), field) == low
    if key in PHYSICS_HIGH or key == "ProtectionParams.undervoltage_trip":
        return  # narrower by physics / below overvoltage_trip by rule
    assert getattr(cls(**{field: high}), field) == high


def test_sim_limits_cover_every_object_the_node_maps_to_the_simulator() -> None:
    """plant.SETTERS (OD index/sub -> simulator field) and OD_LIMITS name the same objects."""
    by_index = {(idx, sub): name for name, (_, _, idx, sub) in EDS.items()}
    owner = {
        "set_motor": "MotorParams",
        "set_current_gains": "CurrentControllerParams",
        "set_speed_gains": "SpeedControllerParams",
        "set_protection": "ProtectionParams",
        "set_load": "LoadParams",
        "set_inverter_nonidealities": "InverterParams",
    }
    for index, (setter, kw) in plant.SETTERS.items():
        for sub, field in kw.items():
            key = f"{owner[setter]}.{field}"
            if field in ("type", "emf_feedforward"):
                continue  # enumerations, checked against enums/the EDS Enum elsewhere
            assert sim_params.OD_LIMITS[key] == by_index[(index, sub)], key


def test_sim_params_defaults_pass_their_own_checks() -> None:
    for name in {k.split(".")[0] for k in sim_params.OD_LIMITS}:
        cls = getattr(sim_params, name)
        assert dataclasses.asdict(cls())  # constructing runs every check


def test_sim_supply_voltage_takes_the_objects_range() -> None:
    """0x5010:2 sim_fault.V_dc_supply: the simulator takes every value the EDS allows (it once
    allowed 0 V, which the simulator refused with 0x06090030 instead of 0x06090032)."""
    from virtual_drive.sim import Simulator

    low, high, _, _ = EDS["sim_fault.V_dc_supply"]
    assert low is not None and low > 0 and high is not None
    sim = Simulator()
    for v in (low, high):
        sim.set_supply_voltage(v)
        assert sim.supply_voltage == v
