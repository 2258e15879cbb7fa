"""Checks every SDO/RPDO write must pass before the drive stores it.

Order: the object's own limits and type (:meth:`firmware_protocol.od.Entry.check`: NaN/inf and
non-integral → 0x06090030, above → 0x06090031, below → 0x06090032), then the cross-object rules
of :data:`firmware_protocol.od.CONSTRAINTS` with the other objects' present values (e.g.
``current_controller.L_c < 2 motor.L``: the deadbeat loop is unstable for L_c ≥ 2L). The staged
gain set (0x20F0) is scratch space: a staged value is checked against its own range only (any
order of staging works), and the set as a whole, against itself, when 0x20F1 applies it
(:mod:`.gain_sets`). Speed-loop gains must form a stable IP loop
(:func:`firmware_protocol.stability.check_ip_speed_gains`): a write of 0x2020:1/2 is checked with
the other gain's present value, the staged pair 0x20F0:11/12 when it is applied. Current-loop
gain sets must be admissible (:func:`firmware_protocol.current_stability.check_current_gains`:
closed-loop poles, predictive feed-forward and compensation bounds): a write of any 0x2010:1..10
or of motor.R/L/rated_current/V_dc_nominal is checked on the whole active set with the new
value in place, the staged set 0x20F0:1..10 when 0x20F1 applies it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

from canopen.sdo import SdoAbortedError

from firmware_protocol import abort_codes
from firmware_protocol.current_stability import (
    CURRENT_KEYS,
    MOTOR_KEYS,
    check_cascade,
    check_current_gains,
)
from firmware_protocol.od import Entry, LimitError, ObjectDictionaryView
from firmware_protocol.stability import check_ip_speed_gains

__all__ = ["STAGED_SET", "ParamChecker"]

Number = int | float

ABORT_INVALID_VALUE = abort_codes.INVALID_VALUE
ABORT_VALUE_TOO_HIGH = abort_codes.VALUE_TOO_HIGH
ABORT_VALUE_TOO_LOW = abort_codes.VALUE_TOO_LOW

STAGED_SET = "gain_set"
"""OD object of the staged gain set (0x20F0)."""
_IP_GAINS = ("speed_controller.k_p", "speed_controller.k_i")
_CURRENT = tuple(f"current_controller.{k}" for k in CURRENT_KEYS)
_MOTOR = tuple(f"motor.{k}" for k in MOTOR_KEYS)


class ParamChecker:
    """Limit and physics checks against the OD view.

    :param view: the OD view (limits, constraints).
    :param current: ``current(name)`` returns the value the drive holds now for ``name``.
    """

    def __init__(self, view: ObjectDictionaryView, current: Callable[[str], Number]) -> None:
        self.view = view
        self._current = current
        self._by_index: dict[tuple[int, int], Entry] = {(e.index, e.subindex): e for e in view}

    def entry(self, index: int, subindex: int) -> Entry | None:
        return self._by_index.get((index, subindex))

    def check(self, index: int, subindex: int, value: object) -> object:
        """Return the value as stored (REAL32 rounded), or raise SdoAbortedError."""
        entry = self._by_index.get((index, subindex))
        if entry is None:
            return value
        value = self.check_range(entry, value)
        if entry.object_name == STAGED_SET:
            return value  # scratch space: the set is checked as a whole when applied
        if isinstance(value, (int, float)):
            self.check_rules({entry.name: value}, staged=False)
            if entry.name in _IP_GAINS:
                gains = {n: self._current(n) for n in _IP_GAINS} | {entry.name: value}
                self.check_speed_gains(*(gains[n] for n in _IP_GAINS))
            if entry.name in _CURRENT or entry.name in _MOTOR or entry.name in _IP_GAINS:
                self.check_current_set({entry.name: value})
        return value

    @staticmethod
    def check_range(entry: Entry, value: object) -> object:
        """``value`` against ``entry``'s own type and limits only (returned as stored), or
        SdoAbortedError (0x06090030/31/32)."""
        try:
            return entry.check(value)
        except LimitError as exc:
            raise SdoAbortedError(exc.abort_code) from exc

    def check_current_set(
        self,
        changes: Mapping[str, Number],
        gains: Mapping[str, Number] | None = None,
        speed: tuple[Number, Number] | None = None,
    ) -> None:
        """The current-loop rule and the cascade rule on the active current set (or ``gains``,
        keys :data:`CURRENT_KEYS`, e.g. the staged set) and the active IP pair (or ``speed``)
        with ``changes`` (full OD names) in place, as SdoAbortedError."""
        g = {
            k: changes.get(n, gains[k] if gains is not None and k in gains else self._current(n))
            for k, n in zip(CURRENT_KEYS, _CURRENT, strict=True)
        }
        m = {k: changes.get(n, self._current(n)) for k, n in zip(MOTOR_KEYS, _MOTOR, strict=True)}
        if speed is None:
            k_p, k_i = (changes.get(n, self._current(n)) for n in _IP_GAINS)
        else:
            k_p, k_i = speed
        try:
            check_current_gains(g, m)
            check_cascade(g, m, k_p, k_i)
        except LimitError as exc:
            raise SdoAbortedError(exc.abort_code) from exc

    @staticmethod
    def check_speed_gains(k_p: Number, k_i: Number) -> None:
        """The IP speed loop's stability rule (OD.md), as SdoAbortedError."""
        try:
            check_ip_speed_gains(float(k_p), float(k_i))
        except LimitError as exc:
            raise SdoAbortedError(exc.abort_code) from exc

    def check_rules(self, changes: Mapping[str, Number], staged: bool) -> None:
        """Cross-object rules for ``changes`` (names → new values) with present values.

        ``staged`` is True when the staged gain set is applied as a whole (0x20F1).
        """
        rules = {c for name in changes for c in self.view.constraints_for(name)}
        if not rules:
            return
        changed = next(iter(changes)) if len(changes) == 1 else None
        for c in rules:
            values = {n: changes[n] if n in changes else self._current(n) for n in c.names}
            if c.holds(values):
                continue
            lhs_written = changed is None or changed in (c.lhs, c.lhs_times)
            too_high = c.bounds_from_above == lhs_written
            raise SdoAbortedError(ABORT_VALUE_TOO_HIGH if too_high else ABORT_VALUE_TOO_LOW)
