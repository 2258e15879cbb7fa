"""Cross-object rules of the OD that an EDS cannot express (e.g. 0 < L_c < 2 motor.L).

The staged gain set (gain_set 0x20F0) is scratch space with no rule of its own: a staged value is
checked against its own range when written, and the set as a whole against these rules (with the
staged values in place of the active ones) when gain_set_apply (0x20F1) applies it.

Both the drive (before storing a write) and the host (before sending one) enforce them, through
:meth:`firmware_protocol.od.ObjectDictionaryView.check_constraints`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from .entry import Number

__all__ = ["CONSTRAINTS", "Constraint"]

_OPS = ("<", "<=", ">", ">=", "abs<=")


@dataclass(frozen=True)
class Constraint:
    """A cross-object rule the EDS cannot express: ``lhs [* lhs_times] op factor * rhs``.

    ``op`` is one of ``<``, ``<=``, ``>``, ``>=`` or ``abs<=`` (``|lhs| <= factor * rhs``).
    Example: ``Constraint("current_controller.L_c", "<", 2, "motor.L")`` keeps the deadbeat
    loop stable (0 < L_c < 2 L, Valle et al. 2020). Both the drive and the host enforce it.
    """

    lhs: str
    op: str
    factor: float
    rhs: str
    lhs_times: str | None = None
    reason: str = ""
    checked_on: tuple[str, ...] | None = None
    """Names whose presence in the checked values triggers the rule (default: all of them)."""

    def __post_init__(self) -> None:
        if self.op not in _OPS:
            raise ValueError(f"constraint operator {self.op!r} not in {_OPS}")

    @property
    def names(self) -> tuple[str, ...]:
        """Every object name the rule reads."""
        extra = (self.lhs_times,) if self.lhs_times else ()
        return (self.lhs, *extra, self.rhs)

    @property
    def triggers(self) -> tuple[str, ...]:
        """Names that trigger the rule when written (:attr:`checked_on` or :attr:`names`)."""
        return self.checked_on if self.checked_on is not None else self.names

    @property
    def bounds_from_above(self) -> bool:
        """True when the rule is an upper bound on ``lhs`` (a lower bound on ``rhs``)."""
        return self.op in ("<", "<=", "abs<=")

    def __str__(self) -> str:
        left = f"{self.lhs} * {self.lhs_times}" if self.lhs_times else self.lhs
        if self.op == "abs<=":
            left, op = f"|{left}|", "<="
        else:
            op = self.op
        right = self.rhs if self.factor == 1 else f"{self.factor:g} * {self.rhs}"
        return f"{left} {op} {right}"

    def holds(self, values: Mapping[str, Number]) -> bool:
        """Evaluate the rule on ``values`` (every name in :attr:`names` must be present)."""
        left = float(values[self.lhs])
        if self.lhs_times:
            left *= float(values[self.lhs_times])
        right = self.factor * float(values[self.rhs])
        if self.op == "<":
            return left < right
        if self.op == "<=":
            return left <= right
        if self.op == ">":
            return left > right
        if self.op == ">=":
            return left >= right
        return abs(left) <= right


CONSTRAINTS: tuple[Constraint, ...] = (
    Constraint(
        "current_controller.L_c", "<", 2, "motor.L", reason="deadbeat loop stable for L_c < 2 L"
    ),
    Constraint(
        "current_controller.R_c",
        "<=",
        2,
        "motor.R",
        reason="deadbeat loop stable for R_c <= 2 R (with 0 < L_c < 2 L; larger R_c/R can be "
        "unstable, e.g. R_c > 107 R at L_c = L)",
    ),
    Constraint(
        "setpoints.i_p_ref",
        "abs<=",
        1,
        "speed_controller.current_limit",
        reason="pseudo-current reference within the current limit",
    ),
    Constraint(
        "target_velocity", "abs<=", 1, "max_motor_speed", reason="speed reference within 0x6080"
    ),
    Constraint("target_torque", "abs<=", 1, "max_torque", reason="torque reference within 0x6072"),
    Constraint(
        "protection.undervoltage_trip",
        "<",
        1,
        "protection.overvoltage_trip",
        reason="a DC-link window that is not empty",
    ),
    Constraint(
        "trace_config.length",
        "<=",
        1,
        "trace_config.capacity",
        lhs_times="trace_config.channel_count",
        reason="the trace fits in the recorder memory",
    ),
    Constraint(
        "trace_config.pre_trigger",
        "<",
        1,
        "trace_config.length",
        reason="the trigger lies inside the record",
    ),
)
