"""Request and response bodies of the REST API (pydantic: a bad body is a 422, nothing applied).

Units are SI as on the drive (A, V, Ω, H, s, rpm) unless a field's name says otherwise.
Gain names are the drive's staged gain-set names (object 0x20F0, docs/contracts.md §1).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

from firmware_protocol.enums import CONTROLLER_NAMES, CONTROLLER_TYPES

TYPE_NAMES = CONTROLLER_NAMES


class Strict(BaseModel):
    """Unknown fields are errors (a typo must not be silently ignored); values are taken as
    typed (pydantic strict mode: no ``"300"`` → 300, no ``true`` → 1, no ``"yes"`` → true) and
    must be finite (no NaN, no ±inf, no 1e400)."""

    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False)


class ControlIn(Strict):
    client: str = Field("script", min_length=1, max_length=64, description="display name")
    take_over: bool = Field(False, description="take control from the present holder (visible)")


class ControlOut(BaseModel):
    token: str | None = None
    client: str | None
    since: float | None = Field(None, description="UNIX s")


class CommandIn(Strict):
    command: Literal["enable", "disable", "quick_stop", "fault_reset"]


class ModeIn(Strict):
    mode: Literal["speed", "current"]


class SpeedIn(Strict):
    rpm: float = Field(..., ge=-4000, le=4000, description="speed setpoint, rpm")


class CurrentIn(Strict):
    i_p_ref: float = Field(..., ge=-200, le=200, description="pseudo-current setpoint i_p*, A")


class SpeedStepIn(Strict):
    delta_rpm: float = Field(..., ge=-4000, le=4000, description="step added to the setpoint, rpm")


class SequenceStep(Strict):
    at_s: float = Field(..., ge=0, le=600, description="time after start, s")
    rpm: float = Field(..., ge=-4000, le=4000)


class SequenceIn(Strict):
    steps: list[SequenceStep] = Field(..., min_length=1, max_length=100)

    @model_validator(mode="after")
    def _ordered(self) -> SequenceIn:
        times = [s.at_s for s in self.steps]
        if times != sorted(times):
            raise ValueError("steps must be in time order (at_s ascending)")
        return self


class LoadIn(Strict):
    T_load: float = Field(..., ge=-20, le=20, description="load torque step, N·m (virtual drive)")


class GainsIn(Strict):
    """A partial gain set; omitted fields keep their live values. Applied as one set."""

    type: Literal["deadbeat", "pi", "predictive"] | None = None
    L_c: float | None = Field(None, gt=0, le=2e-3, description="H; must be < 2·motor.L")
    R_c: float | None = Field(None, ge=0, le=1, description="Ω")
    k_p: float | None = Field(None, ge=0, le=100, description="current PI k_p, V/A")
    k_i: float | None = Field(None, ge=0, le=100, description="current PI k_i, V/A")
    T_BT: float | None = Field(None, ge=0, le=1e-4, description="s")
    T_DD: float | None = Field(None, ge=0, le=1e-4, description="s")
    T_SD: float | None = Field(None, ge=0, le=1e-4, description="s")
    V_G: float | None = Field(None, ge=0, le=10, description="V")
    emf_feedforward: bool | None = None
    speed_k_p: float | None = Field(None, ge=0, le=100, description="IP k_p, A/rpm")
    speed_k_i: float | None = Field(None, ge=0, le=1, description="IP k_i, 1/sample")
    speed_current_limit: float | None = Field(None, ge=0, le=200, description="A")
    force: bool = Field(
        False,
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
    xi: float = Field(1.0, gt=0, le=10, description="damping ratio ξ")
    omega_n: float = Field(2.3, gt=0, le=1000, description="natural frequency ω_n, rad/s")
    a: float | None = Field(
        None, gt=0, lt=1, description="identified pole a; default: last identified"
    )
    b: float | None = Field(None, gt=0, le=1, description="identified gain b, rpm/(A·sample)")


class CurrentStepIn(Strict):
    from_A: float = Field(15.0, ge=-200, le=200)
    to_A: float = Field(20.0, ge=-200, le=200)
    duration_ms: float = Field(2.0, gt=0, le=300, description="recorded after the step, ms")


class TraceIn(Strict):
    channels: list[str] = Field(
        ["measurements.i_p", "measurements.i_p_ref"], min_length=1, max_length=8
    )
    divider: int = Field(1, ge=1, le=5000, description="loop samples (20 µs) per trace sample")
    length: int = Field(1000, ge=2, le=16384, description="samples per channel")
    pre_trigger: int = Field(100, ge=0, le=16383)
    trigger: Literal["immediate", "setpoint_step", "signal", "fault"] = "immediate"
    trigger_level: float | None = Field(None, description="trigger level in the source's unit")
    trigger_edge: Literal["rising", "falling", "either"] = "rising"
    step_to_A: float | None = Field(
        None, ge=-200, le=200, description="with trigger=setpoint_step: i_p* to step to once armed"
    )
    average_samples: int = Field(5, ge=1, le=1000, description="moving-average window for ī_p")

    @model_validator(mode="after")
    def _fits(self) -> TraceIn:
        if self.length * len(self.channels) > 16384:
            raise ValueError("length × channels exceeds the recorder capacity (16384 samples)")
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
    from_A: float = Field(15.0, ge=-200, le=200, description="i_p* before the step, A")
    to_A: float = Field(30.0, ge=-200, le=200, description="i_p* after the step, A")
    duration_s: float = Field(1.0, gt=0, le=20, description="recorded after the step, s")


class Margins(BaseModel):
    stable: bool
    gain_margin_dB: float | None
    phase_margin_deg: float | None
    S_inf: float | None = Field(None, description="‖S‖∞, sensitivity peak")
    poles: list[list[float]] = Field(default_factory=list, description="closed-loop poles [re, im]")
