"""Values typed with units (``20uH``, ``50 A``, ``1000rpm``, ``-1e30``) → numbers in OD units.

One parser for the CLI, the API and the GUI: :func:`parse_value` reads the text with pint (a
kept units library, no hand parsing) and converts it to the unit the object dictionary names
for the object (``current_controller.L_c`` is in H: ``20uH`` → 2e-05; ``target_velocity`` is in
rpm: ``100 rad/s`` → 954.93 rpm, refused as not whole: the object is an integer). A bare number is
taken in the object's unit. Refused in one line (:class:`~drive_link.errors.InvalidValue`):
text that is not a quantity, a wrong dimension (``5 A`` for an object in rpm), ``nan``/``inf``,
a unit on a unit-less object, and a non-whole value for an integer object.

The unit strings of the EDS that pint does not know are mapped here (``Ohm`` → ohm, ``samples``
→ a count dimension); units pint cannot read at all (``permille of motor_rated_torque``) take a
bare number only.
"""

from __future__ import annotations

import math
import re
from functools import lru_cache
from typing import TYPE_CHECKING, Any

from ..errors import InvalidValue

if TYPE_CHECKING:
    import pint

    from ._objects import ObjectInfo

__all__ = [
    "parse_for",
    "parse_quantity",
    "parse_value",
    "registry",
    "unit_of",
]

#: EDS unit text → pint expression where they differ.
_ALIASES = {"1": "dimensionless", "": "dimensionless"}

_HEX = re.compile(r"^[+-]?0[xX][0-9a-fA-F]+$")
_NUMBER = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")


@lru_cache(maxsize=1)
def registry() -> pint.UnitRegistry:
    """The registry every parse uses: pint's defaults plus the EDS spellings ``Ohm`` and
    ``sample(s)`` (a count). Built on first use (about 0.3 s idle): a bare number never
    needs it."""
    import pint

    ureg: pint.UnitRegistry = pint.UnitRegistry(autoconvert_offset_to_baseunit=True)
    ureg.define("sample = [sample] = samples")
    ureg.define("Ohm = ohm")
    return ureg


def _errors() -> tuple[type[BaseException], ...]:
    import pint

    return (pint.errors.PintError, ValueError, TypeError, AttributeError, SyntaxError)


@lru_cache(maxsize=128)
def unit_of(unit: str) -> pint.Quantity | None:
    """The object's unit as a pint quantity (``"100 us"`` → 100 µs), or None if pint cannot
    read it (then only bare numbers are accepted)."""
    ureg = registry()
    text = _ALIASES.get(unit.strip(), unit.strip())
    try:
        q: pint.Quantity = ureg.Quantity(text)
    except _errors():
        return None
    if not isinstance(q, ureg.Quantity):  # a plain number is not a unit
        return None
    return q


def parse_quantity(text: str) -> pint.Quantity:
    """``text`` as a pint quantity (a bare number is dimensionless); :class:`InvalidValue` if it
    is not one, or if its magnitude is nan/inf."""
    ureg = registry()
    s = str(text).strip()
    if not s:
        raise InvalidValue("empty value: not a number")
    if _HEX.match(s):
        return ureg.Quantity(int(s, 16), "dimensionless")
    try:
        q: pint.Quantity = ureg.Quantity(s)
    except _errors() as exc:
        raise InvalidValue(f"{s!r} is not a number or a quantity with a unit ({exc})") from None
    if not isinstance(q, ureg.Quantity):
        q = ureg.Quantity(q, "dimensionless")
    m = q.magnitude
    if not isinstance(m, int | float) or not math.isfinite(float(m)):
        raise InvalidValue(f"{s!r}: not a finite number (nan and inf are refused)")
    return q


def parse_value(
    text: str | float | int, unit: str, *, integer: bool = False, name: str = ""
) -> float | int:
    """Number in ``unit`` (the OD's unit text, e.g. ``"H"``, ``"rpm"``, ``"100 us"``) for the
    typed ``text``; an int when ``integer`` (a non-whole result is refused, never rounded).

    ``name`` names the object in error messages. Numbers (not text) are taken in ``unit``.
    """
    who = f"{name}: " if name else ""
    shown = f" {unit}" if unit and unit != "1" else ""
    if isinstance(text, bool):
        text = int(text)
    if isinstance(text, int | float):
        if not math.isfinite(float(text)):
            raise InvalidValue(f"{who}{text!r}: not a finite number (nan and inf are refused)")
        value: float | int = text
    else:
        s = str(text).strip()
        plain = _plain_number(s)
        if plain is not None:
            return _finish(plain, text, who, shown, integer)
        try:
            q = parse_quantity(s)
        except InvalidValue as exc:
            if _looks_numeric(s):
                raise InvalidValue(f"{who}{exc}") from None
            raise InvalidValue(
                f"{who}{s!r} is not a number (nor a quantity in{shown or ' no unit'})"
            ) from None
        if q.unitless:
            value = q.magnitude
        else:
            target = unit_of(unit)
            if target is None or not unit or unit == "1":
                what = f"takes a plain number in {unit}" if unit and unit != "1" else "has no unit"
                raise InvalidValue(f"{who}{s!r}: the object {what}")
            if "Hz" in s and target.dimensionality == registry().rpm.dimensionality:
                raise InvalidValue(
                    f"{who}{s!r}: Hz is ambiguous for a speed (rev/s or rad/s?); type rpm, "
                    "rps or rad/s"
                )
            try:
                # 15 significant digits: 20uH is 2e-05, not pint's 1.9999999999999998e-05
                value = float(f"{(q / target).to('dimensionless').magnitude:.15g}")
            except _errors():
                raise InvalidValue(
                    f"{who}{s!r} has the wrong dimension: {q.units:~} is not convertible to {unit}"
                ) from None
        if not math.isfinite(float(value)):
            raise InvalidValue(f"{who}{s!r}: not a finite number")
    return _finish(value, text, who, shown, integer)


def _plain_number(s: str) -> int | float | None:
    """``s`` as a number when it is a plain decimal or hex number (no pint needed)."""
    if _HEX.match(s):
        return int(s, 16)
    if _NUMBER.match(s):
        try:
            return int(s)
        except ValueError:
            return float(s)
    return None


def _finish(value: Any, text: Any, who: str, shown: str, integer: bool) -> float | int:
    """``value`` as int (``integer``: a non-whole value is refused) or float; nan/inf (also
    from an overflow such as ``1e400``) refused."""
    if not math.isfinite(float(value)):
        raise InvalidValue(f"{who}{text!r}: not a finite number (nan and inf are refused)")
    if integer:
        f = float(value)
        if isinstance(value, int):
            return value
        r = round(f)
        if abs(f - r) > 1e-9 * max(1.0, abs(f)):
            raise InvalidValue(
                f"{who}{text!r} is {f:.6g}{shown}: the object takes whole numbers "
                f"(type {math.floor(f)} or {math.ceil(f)})"
            )
        return int(r)
    return float(value)


def _looks_numeric(s: str) -> bool:
    return bool(re.match(r"^[+-]?(\d|\.\d|inf|nan)", s, re.IGNORECASE))


def parse_for(obj: ObjectInfo | str, text: str | float | int) -> float | int | str:
    """Value for the OD object ``obj`` (an :class:`~drive_link.link._objects.ObjectInfo` or its
    name) from typed ``text``, in the object's unit and type (strings pass through for
    VISIBLE_STRING), then checked against its limits (:meth:`ObjectInfo.check`). The dashboard's
    entry point."""
    if isinstance(obj, str):
        from ._objects import default_table

        obj = default_table()[obj]
    if not obj.fmt:
        return text if isinstance(text, str) else str(text)
    if obj.enum and isinstance(text, str):
        for v, label in obj.enum:
            if text.strip().lower() == str(label).lower():
                return _number(obj, v)  # an enumerated object: an integer
    integer = not obj.is_float
    value = parse_value(text, obj.unit, integer=integer, name=obj.name)
    return _number(obj, value)


def _number(obj: ObjectInfo, value: float | int) -> float | int:
    """``value`` checked by ``obj`` (an object with a struct format: a number comes back)."""
    checked = obj.check(value)
    if isinstance(checked, str | bytes):
        raise TypeError(f"{obj.name}: {checked!r} is no number")  # (not for a struct format)
    return checked
