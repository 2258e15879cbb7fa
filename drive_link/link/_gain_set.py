"""The drive's gain sets: the :class:`Gains` it holds and the staged set mechanism.

The drive changes a gain set atomically: the whole set is staged in gain_set (0x20F0) and
applied with gain_set_apply (0x20F1: 1 current set, 2 speed set, 3 both); the drive validates
the set as a whole and aborts with nothing changed if any value is refused.

:func:`stage_and_apply` is that mechanism and nothing more: the one public way to change gains
is :func:`drive_link.workflows.gains.apply_gains`, which checks the policy (stability, margins) and
then calls it. :meth:`drive_link.Drive.write` refuses an active gain object
(:class:`GainWriteRefused`, naming that path; ``drive-link write`` routes it there) and a raw write
of gain_set_apply.
"""

from __future__ import annotations

from collections.abc import Mapping
from contextlib import AbstractContextManager
from dataclasses import asdict, dataclass, fields
from typing import Any, Protocol

from firmware_protocol.current_stability import CURRENT_KEYS
from firmware_protocol.entry import f32

from ..errors import DriveError, InvalidValue
from . import _rules
from ._objects import ObjectTable
from ._sdo import SdoChannel

__all__ = [
    "ACTIVE_GAIN_FIELD",
    "APPLY_NAME",
    "GAIN_FIELDS",
    "GAIN_OBJECTS",
    "GainSetDrive",
    "GainWriteRefused",
    "Gains",
    "read_gains",
    "stage_and_apply",
]


@dataclass(frozen=True)
class Gains:
    """Controller gains as the drive holds them (SI units).

    Current loop (0x2010): ``type`` (0 deadbeat eq. 15, 1 PI eq. 22, 2 predictive eq. 23/25),
    ``L_c`` (H), ``R_c`` (Ω), ``k_p``/``k_i`` (V/A, PI), ``T_BT``/``T_DD``/``T_SD`` (s),
    ``V_G`` (V), ``emf_feedforward`` (0/1). Speed loop (0x2020): ``speed_k_p`` (A/rpm),
    ``speed_k_i`` (1/sample), ``speed_current_limit`` (A).
    """

    type: int
    L_c: float
    R_c: float
    k_p: float
    k_i: float
    T_BT: float
    T_DD: float
    T_SD: float
    V_G: float
    emf_feedforward: int
    speed_k_p: float
    speed_k_i: float
    speed_current_limit: float

    def to_dict(self) -> dict[str, float | int]:
        """Plain dict of every field."""
        return asdict(self)


GAIN_FIELDS: tuple[str, ...] = tuple(f.name for f in fields(Gains))

#: Gains field → (current/speed set bit, OD name of the active value, OD name of the staged one).
GAIN_OBJECTS: dict[str, tuple[int, str, str]] = {
    **{
        f: (1, f"current_controller.{f}", f"gain_set.{f}")
        for f in CURRENT_KEYS  # the current-loop set, as the drive's rule names it
    },
    "speed_k_p": (2, "speed_controller.k_p", "gain_set.speed_k_p"),
    "speed_k_i": (2, "speed_controller.k_i", "gain_set.speed_k_i"),
    "speed_current_limit": (2, "speed_controller.current_limit", "gain_set.speed_current_limit"),
}
#: OD name of an active gain object → its :class:`Gains` field.
ACTIVE_GAIN_FIELD: dict[str, str] = {active: f for f, (_s, active, _st) in GAIN_OBJECTS.items()}
#: The object that applies a staged set (0x20F1).
APPLY_NAME = "gain_set_apply"


class GainWriteRefused(InvalidValue):
    """:meth:`drive_link.Drive.write` of an active gain object, refused with nothing sent: a gain
    changes only through :func:`drive_link.apply_gains` (its stability and margin policy).
    ``field`` is the gain's name there (``L_c``, ``speed_k_p`` …), ``value`` the value, already
    checked against the object's limits and the OD's cross-object rules."""

    def __init__(self, name: str, field: str, value: float | int) -> None:
        super().__init__(
            f"{name}: a controller gain changes only through drive_link.apply_gains, which checks "
            f"the set's stability and margins first (drive-link set-gains {field}=... [--force], "
            f"or drive-link write {name} VALUE)"
        )
        self.name = name
        self.field = field
        self.value = value


class GainSetDrive(Protocol):
    """What the gain path needs of a drive (:class:`drive_link.Drive` is one)."""

    @property
    def table(self) -> ObjectTable: ...

    @property
    def sdo(self) -> SdoChannel: ...

    @property
    def gains_lock(self) -> AbstractContextManager[Any]:
        """Held across read, stage, apply and read back (one operation per drive)."""
        ...

    def read(self, name: str) -> Any: ...

    def read_gains(self) -> Gains: ...


def read_gains(drive: GainSetDrive) -> Gains:
    """The active controller gains (0x2010, 0x2020), one SDO upload each."""

    def read(f: str) -> Any:
        return drive.read(GAIN_OBJECTS[f][1])

    return Gains(
        type=int(read("type")),
        L_c=float(read("L_c")),
        R_c=float(read("R_c")),
        k_p=float(read("k_p")),
        k_i=float(read("k_i")),
        T_BT=float(read("T_BT")),
        T_DD=float(read("T_DD")),
        T_SD=float(read("T_SD")),
        V_G=float(read("V_G")),
        emf_feedforward=int(read("emf_feedforward")),
        speed_k_p=float(read("speed_k_p")),
        speed_k_i=float(read("speed_k_i")),
        speed_current_limit=float(read("speed_current_limit")),
    )


def stage_and_apply(
    drive: GainSetDrive,
    changes: Mapping[str, float | int],
    present: Mapping[str, float | int] | None = None,
    motor: Mapping[str, float] | None = None,
) -> Gains:
    """Stage the set(s) whose values ``changes`` changes in 0x20F0 (the whole set, from
    ``present`` with ``changes`` in place), apply them with 0x20F1 and return the set as the
    drive now holds it.

    ``present`` (the full active set) and ``motor`` (motor.R/L/... values by their short names)
    are what the caller already holds; ``present`` is read from the drive when not given (13
    uploads), and a rule operand neither holds is read. A value equal to the present one (as
    float32 for a REAL32) is no change; a set none of whose values change is not staged, and
    with nothing changed nothing is sent. Then: the staged set(s) (10 current, 3 speed
    downloads), one apply, one upload per changed REAL32 (an integer is applied exactly or the
    apply aborts).

    Checks each staged value against its object's limits and the OD's cross-object rules
    (L_c < 2 motor.L) first; no policy beyond the drive's own: call
    :func:`drive_link.workflows.gains.apply_gains`, which does. Raises :class:`InvalidValue` for
    unknown names or refused values (nothing sent), :class:`drive_link.SdoAbort` if the drive
    refuses the set (nothing changed), :class:`DriveError` if a read-back differs.
    """
    unknown = [k for k in changes if k not in GAIN_OBJECTS]
    if unknown:
        raise InvalidValue(
            f"unknown gain(s) {', '.join(unknown)}; known: {', '.join(GAIN_FIELDS)}"
        )
    table = drive.table
    with drive.gains_lock:
        base = dict(present) if present is not None else drive.read_gains().to_dict()
        merged = {**base, **changes}
        changed = [k for k, v in changes.items() if not _same(base.get(k), v)]
        if not changed:  # the drive holds this set already
            return Gains(**merged)  # type: ignore[arg-type]
        sets = 0
        for k in changed:
            sets |= GAIN_OBJECTS[k][0]
        staged = [f for f in GAIN_FIELDS if GAIN_OBJECTS[f][0] & sets]
        for f in staged:
            table[GAIN_OBJECTS[f][2]].check(merged[f])
        # the staged set is checked as the objects it becomes (the drive checks it so at apply)
        known: dict[str, float | int] = {GAIN_OBJECTS[f][1]: v for f, v in merged.items()}
        known.update({f"motor.{k}": v for k, v in (motor or {}).items()})

        def read(name: str) -> Any:
            return known[name] if name in known else drive.read(name)

        _rules.check_rules(read, {GAIN_OBJECTS[f][1]: merged[f] for f in staged})
        for f in staged:
            name = GAIN_OBJECTS[f][2]
            obj = table[name]
            drive.sdo.download(obj.index, obj.subindex, obj.encode(merged[f]), name)
        apply = table[APPLY_NAME]
        drive.sdo.download(apply.index, apply.subindex, apply.encode(sets), APPLY_NAME)
        after: dict[str, float | int] = dict(merged)
        for f in staged:
            if isinstance(merged[f], float):
                after[f] = f32(float(merged[f]))  # what a REAL32 holds
        for f in changed:
            if not isinstance(merged[f], float):
                continue  # an integer is applied exactly (or the apply was aborted)
            got = drive.read(GAIN_OBJECTS[f][1])
            if got != after[f]:
                raise DriveError(f"gain {f}: drive reads back {got!r} after applying {merged[f]!r}")
            after[f] = float(got)
    return Gains(**after)  # type: ignore[arg-type]


def _same(held: float | int | None, value: float | int) -> bool:
    """True if the drive holding ``held`` already holds ``value`` (REAL32: compared as float32)."""
    if held is None:
        return False
    if isinstance(value, float) or isinstance(held, float):
        return f32(float(held)) == f32(float(value))
    return held == value
