"""Request and response bodies of the REST API (pydantic: a bad body is a 422, nothing applied).

Units are SI as on the drive (A, V, Ω, H, s, rpm) unless a field's name says otherwise. A field
with a unit (an OD object's, or ``x-unit`` in its schema) also takes a string of a number and a
unit (``{"L_c": "22.2 uH"}``), converted by pint (:func:`drive_link.link.units.parse_value`, the
CLI's parser) before the bounds are checked; a wrong dimension or nan/inf is a 422 naming the field.
A JSON number is taken in the field's unit, as before; a string without a unit stays refused.
Gain names are the drive's staged gain-set names (object 0x20F0, docs/contracts.md §1).
A field that carries an OD object's value takes its bounds from the EDS (:func:`od_field`;
:func:`od_fields` lists them), so the API cannot drift from what the drive accepts.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationInfo, field_validator, model_validator

from firmware_protocol.enums import CONTROLLER_NAMES, CONTROLLER_TYPES
from firmware_protocol.od import load_od

from ._fields import unit_part

__all__ = [
    "CONTROLLER_TYPES",
    "OD_KEY",
    "TYPE_NAMES",
    "UNIT_KEY",
    "CommandIn",
    "ControlIn",
    "ControlOut",
    "CurrentIn",
    "CurrentStepIn",
    "GainsIn",
    "IPDesignIn",
    "IdentifyIn",
    "LoadIn",
    "Margins",
    "ModeIn",
    "SequenceIn",
    "SequenceStep",
    "SpeedIn",
    "SpeedStepIn",
    "Strict",
    "TraceIn",
    "field_bounds",
    "od_field",
    "od_fields",
    "unit_field",
]

TYPE_NAMES = CONTROLLER_NAMES

OD_KEY = "x-od-object"
"""JSON-schema key naming the OD object that bounds a field (shown in the OpenAPI schema)."""

_NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?")
_NUMBER_THEN_WORD = re.compile(r"\s*[+\-−]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?\s*[^\W\d_]")

UNIT_KEY = "x-unit"
"""JSON-schema key of a field's unit when no OD object names it (``"s"``, ``"ms"``, ``"rad/s"``)."""


def od_field(
    od_name: str, default: Any = ..., *, ge: float | None = None, description: str = ""
) -> Any:
    """A pydantic ``Field`` bounded by the EDS ``LowLimit``/``HighLimit`` of ``od_name``
    (inclusive), its unit in the description. ``ge`` may only raise the low bound (a stricter
    rule of the dashboard, e.g. a trace needs 2 samples)."""
    entry = load_od().entry(od_name)
    low = entry.low
    if ge is not None:
        low = ge if low is None else max(ge, low)
    unit = f"{entry.unit}; " if entry.unit and entry.unit != "1" else ""
    return Field(
        default,
        ge=low,
        le=entry.high,
        description=f"{unit}{description or od_name}",
        json_schema_extra={OD_KEY: od_name},
    )


def unit_field(default: Any = ..., *, unit: str, **kw: Any) -> Any:
    """A pydantic ``Field`` in ``unit`` (pint's spelling): a string such as ``"500 ms"`` is
    converted to it (:class:`Strict`); ``kw`` as for ``Field`` (bounds in ``unit``)."""
    return Field(default, json_schema_extra={UNIT_KEY: unit}, **kw)


def _unit(model: type[BaseModel], field: str) -> str | None:
    """The unit a field's value is in: its OD object's (EDS) or its ``x-unit``; None if none."""
    info = model.model_fields.get(field)
    extra = info.json_schema_extra if info is not None else None
    if not isinstance(extra, dict):
        return None
    if OD_KEY in extra:
        unit = load_od().entry(str(extra[OD_KEY])).unit
    else:
        unit = str(extra.get(UNIT_KEY) or "")
    return unit if unit and unit != "1" else None


def field_bounds(model: type[BaseModel], field: str, scale: float = 1.0) -> tuple[float, float]:
    """(low, high) of a bounded field times ``scale`` (e.g. 1e6 for a GUI field in µH): the
    GUI's number fields take the API's bounds, which are the EDS's (:func:`od_field`)."""
    low = high = None
    for m in model.model_fields[field].metadata:
        low = getattr(m, "ge", getattr(m, "gt", low))
        high = getattr(m, "le", getattr(m, "lt", high))
    if low is None or high is None:
        raise ValueError(f"{model.__name__}.{field} has no lower and upper bound")
    return low * scale, high * scale


def od_fields(model: type[BaseModel]) -> dict[str, str]:
    """Field name -> OD object for the fields of ``model`` bounded by the EDS."""
    out = {}
    for name, info in model.model_fields.items():
        extra = info.json_schema_extra
        if isinstance(extra, dict) and OD_KEY in extra:
            out[name] = str(extra[OD_KEY])
    return out


class Strict(BaseModel):
    """Unknown fields are errors (a typo must not be silently ignored); values are taken as
    typed (pydantic strict mode: no ``"300"`` → 300, no ``true`` → 1, no ``"yes"`` → true) and
    must be finite (no NaN, no ±inf, no 1e400)."""

    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False)

    @field_validator("*", mode="before")
    @classmethod
    def _with_unit(cls, value: Any, info: ValidationInfo) -> Any:
        """A string of a number and a unit (``"22.2 uH"``) in a field with a unit → the number
        in the field's unit (pint); a wrong dimension, nan/inf or a non-whole value for an
        integer field → ValueError (422). Anything else is left to the strict checks."""
        if not isinstance(value, str) or info.field_name is None:
            return value
        unit = _unit(cls, info.field_name)
        if unit is None:
            return value
        if unit_part(value) is None:
            if _NUMBER_THEN_WORD.match(value) and not _NUMBER.fullmatch(value.strip()):
                raise ValueError(
                    f"{info.field_name}: {value!r} is not a number and a unit pint knows "
                    f"(the field is in {unit})"
                )
            return value
        from drive_link.link.units import parse_value

        integer = cls.model_fields[info.field_name].annotation in (int, int | None)
        return parse_value(
            value.strip().replace("−", "-"), unit, integer=integer, name=info.field_name
        )


class ControlIn(Strict):
    client: str = Field(default="script", min_length=1, max_length=64, description="display name")
    take_over: bool = Field(
        default=False, description="take control from the present holder (visible)"
    )


class ControlOut(BaseModel):
    token: str | None = None
    client: str | None
    since: float | None = Field(default=None, description="UNIX s")


class CommandIn(Strict):
    command: Literal["enable", "disable", "quick_stop", "fault_reset"]


class ModeIn(Strict):
    mode: Literal["speed", "current"]


class SpeedIn(Strict):
    rpm: float = od_field("target_velocity", description="speed setpoint")


class CurrentIn(Strict):
    i_p_ref: float = od_field("setpoints.i_p_ref", description="pseudo-current setpoint i_p*")


class SpeedStepIn(Strict):
    delta_rpm: float = od_field("target_velocity", description="step added to the setpoint")


class SequenceStep(Strict):
    at_s: float = unit_field(..., unit="s", ge=0, le=600, description="time after start, s")
    rpm: float = od_field("target_velocity")


class SequenceIn(Strict):
    steps: list[SequenceStep] = Field(..., min_length=1, max_length=100)

    @model_validator(mode="after")
    def _ordered(self) -> SequenceIn:
        times = [s.at_s for s in self.steps]
        if times != sorted(times):
            raise ValueError("steps must be in time order (at_s ascending)")
        return self


class LoadIn(Strict):
    T_load: float = od_field("sim_load.T_load", description="load torque step (virtual drive)")


class GainsIn(Strict):
    """A partial gain set; omitted fields keep their live values. Applied as one set."""

    type: Literal["deadbeat", "pi", "predictive"] | None = None
    L_c: float | None = od_field("gain_set.L_c", None, description="must be < 2·motor.L")
    R_c: float | None = od_field("gain_set.R_c", None)
    k_p: float | None = od_field("gain_set.k_p", None, description="current PI k_p")
    k_i: float | None = od_field("gain_set.k_i", None, description="current PI k_i")
    T_BT: float | None = od_field("gain_set.T_BT", None)
    T_DD: float | None = od_field("gain_set.T_DD", None)
    T_SD: float | None = od_field("gain_set.T_SD", None)
    V_G: float | None = od_field("gain_set.V_G", None)
    emf_feedforward: bool | None = None
    speed_k_p: float | None = od_field("gain_set.speed_k_p", None, description="IP k_p")
    speed_k_i: float | None = od_field("gain_set.speed_k_i", None, description="IP k_i")
    speed_current_limit: float | None = od_field("gain_set.speed_current_limit", None)
    force: bool = Field(
        default=False,
        description="apply a stable set that fails the margin rule (L_c ≤ 1.5 L, GM ≥ 2 dB, "
        "‖S‖∞ ≤ 5); an unstable set is refused regardless",
    )

    def changes(self) -> dict[str, float | int]:
        """The given fields as drive values (type as its code, flags as 0/1)."""
        out: dict[str, float | int] = {}
        for k, v in self.model_dump(exclude_none=True, exclude={"force"}).items():
            if k == "type":
                out[k] = CONTROLLER_TYPES[v]
            elif isinstance(v, bool):
                out[k] = int(v)
            else:
                out[k] = float(v)
        if not out:
            raise ValueError("no gain given")
        return out


class IPDesignIn(Strict):
    xi: float = Field(default=1.0, gt=0, le=10, description="damping ratio ξ")
    omega_n: float = unit_field(
        2.3, unit="rad/s", gt=0, le=1000, description="natural frequency ω_n, rad/s"
    )
    a: float | None = Field(
        default=None, gt=0, lt=1, description="identified pole a; default: last identified"
    )
    b: float | None = Field(
        default=None, gt=0, le=1, description="identified gain b, rpm/(A·sample)"
    )


class CurrentStepIn(Strict):
    from_A: float = od_field("setpoints.i_p_ref", 15.0)
    to_A: float = od_field("setpoints.i_p_ref", 20.0)
    duration_ms: float = unit_field(
        2.0, unit="ms", gt=0, le=300, description="recorded after the step, ms"
    )


class TraceIn(Strict):
    channels: list[str] = Field(
        default=["measurements.i_p", "measurements.i_p_ref"],
        min_length=1,
        max_length=int(load_od().entry("trace_config.channel_count").high or 8),
    )
    divider: int = od_field(
        "trace_config.divider", 1, description="loop samples (20 µs) per trace sample"
    )
    length: int = od_field("trace_config.length", 1000, ge=2, description="samples per channel")
    pre_trigger: int = od_field("trace_config.pre_trigger", 100)
    trigger: Literal["immediate", "setpoint_step", "signal", "fault"] = "immediate"
    trigger_level: float | None = Field(
        default=None, description="trigger level in the source's unit"
    )
    trigger_edge: Literal["rising", "falling", "either"] = "rising"
    step_to_A: float | None = od_field(
        "setpoints.i_p_ref", None, description="with trigger=setpoint_step: i_p* to step to"
    )
    average_samples: int = Field(
        default=5, ge=1, le=1000, description="moving-average window for ī_p"
    )

    @model_validator(mode="after")
    def _fits(self) -> TraceIn:
        capacity = int(load_od().entry("trace_config.capacity").default or 0)
        if self.length * len(self.channels) > capacity:
            raise ValueError(
                f"length × channels exceeds the recorder capacity ({capacity} samples)"
            )
        if self.pre_trigger >= self.length:
            raise ValueError("pre_trigger must be < length")
        if self.trigger == "signal" and self.trigger_level is None:
            raise ValueError("trigger=signal needs trigger_level")
        if len(set(self.channels)) != len(self.channels):
            raise ValueError("channels: each channel once")
        return self

    def checked(self, known: Callable[[str], str]) -> TraceIn:
        """This config with every channel resolved by ``known`` (drive_link's resolver: an OD
        name or a bare measurement name); ValueError names an unknown or non-measurement
        channel (→ 422, nothing stored)."""
        names = []
        for c in self.channels:
            try:
                full = known(c)
            except Exception as exc:
                raise ValueError(f"unknown trace channel {c!r}") from exc
            if not full.startswith("measurements."):
                raise ValueError(f"trace channel {c!r} is not a measurement")
            names.append(full)
        return self.model_copy(update={"channels": names})


class IdentifyIn(Strict):
    from_A: float = od_field("setpoints.i_p_ref", 15.0, description="i_p* before the step")
    to_A: float = od_field("setpoints.i_p_ref", 30.0, description="i_p* after the step")
    duration_s: float = unit_field(
        1.0, unit="s", gt=0, le=20, description="recorded after the step, s"
    )


class Margins(BaseModel):
    stable: bool
    gain_margin_dB: float | None
    phase_margin_deg: float | None
    S_inf: float | None = Field(default=None, description="‖S‖∞, sensitivity peak")
    poles: list[list[float]] = Field(default_factory=list, description="closed-loop poles [re, im]")
