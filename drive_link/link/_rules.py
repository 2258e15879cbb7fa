"""Client-side checks of the OD's cross-object rules before a write is sent.

The drive is the authority (it re-checks and aborts); these checks refuse a value before it
goes on the bus, with the drive's own rules:

* :func:`check_rules`: :data:`firmware_protocol.CONSTRAINTS` (e.g. L_c < 2 motor.L) that the
  written names trigger, the other operands read from the drive;
* :func:`check_loops`: the current-loop and cascade rule of
  :mod:`firmware_protocol.current_stability` on the drive's present set with the written values
  in place (:data:`LOOP_NAMES`).

``read(name)`` reads an object's present value (SI units) — :meth:`drive_link.Drive.read`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from firmware_protocol.constraints import CONSTRAINTS
from firmware_protocol.current_stability import (
    CURRENT_KEYS,
    MOTOR_KEYS,
    check_cascade,
    check_current_gains,
)
from firmware_protocol.entry import LimitError

from ..errors import InvalidValue

__all__ = ["LOOP_NAMES", "check_loops", "check_rules"]

Reader = Callable[[str], Any]

LOOP_NAMES = frozenset(
    [f"current_controller.{k}" for k in CURRENT_KEYS]
    + [f"motor.{k}" for k in MOTOR_KEYS]
    + ["speed_controller.k_p", "speed_controller.k_i"]
)
"""Objects whose write the current-loop/cascade rule checks (as the drive does)."""


def check_loops(read: Reader, values: Mapping[str, float | int]) -> None:
    """The current-loop and cascade rule (firmware_protocol.current_stability) on the drive's
    present set (``read``) with ``values`` in place; :class:`InvalidValue` if refused."""

    def present(n: str) -> Any:
        return values[n] if n in values else read(n)

    g = {k: present(f"current_controller.{k}") for k in CURRENT_KEYS}
    m = {k: present(f"motor.{k}") for k in MOTOR_KEYS}
    k_p, k_i = present("speed_controller.k_p"), present("speed_controller.k_i")
    try:
        check_current_gains(g, m)
        check_cascade(g, m, k_p, k_i)
    except LimitError as exc:
        raise InvalidValue(f"refused before sending: {exc}") from None


def check_rules(read: Reader, values: Mapping[str, float | int]) -> None:
    """The OD's cross-object rules (firmware_protocol.CONSTRAINTS, e.g. L_c < 2 motor.L)
    triggered by ``values``; other operands are read with ``read``. :class:`InvalidValue` if
    one does not hold."""
    for c in CONSTRAINTS:
        if not any(n in values for n in c.triggers):
            continue
        operands = {n: float(values[n] if n in values else read(n)) for n in c.names}
        if c.holds(operands):
            continue
        shown = ", ".join(f"{n} = {operands[n]:.6g}" for n in c.names)
        raise InvalidValue(f"refused before sending: {c} does not hold ({shown}): {c.reason}")
