"""Strict parsing of numbers typed into the GUI: no clamping, no sign change, no guessing.

A typed value is either taken exactly as written or refused with a one-line message that the GUI
shows at the field (nothing is sent to the drive). Accepted: an optional sign (ASCII ``-``/``+``
or the typographic minus ``−``), digits with one optional decimal point, an optional exponent.
Refused: empty text, words, ``nan``/``inf``, underscores, several numbers, values outside the
field's range (the message names the range; the value is not moved into it).

A field with a display unit (:attr:`NumberSpec.unit`, e.g. ``"µH"``) also takes a quantity with a
unit, converted by pint through :func:`drive_link.link.units.parse_value` (the CLI's and the API's
parser): ``20uH`` or ``0.02 mH`` in a µH field is 20; ``5 A`` in an rpm field is refused naming
the wrong dimension. A bare number is in the field's unit.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

__all__ = ["FieldError", "NumberSpec", "show", "unit_part"]

_NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?")
#: a plain number then a unit that starts with a letter (``20uH``, ``0.02 mH``, ``6.2 mΩ``)
_WITH_UNIT = re.compile(r"([+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?)\s*([^\W\d_].*)")


class FieldError(ValueError):
    """A typed value that cannot be used; the message names the field and the reason."""


@dataclass(frozen=True)
class NumberSpec:
    """What one GUI number field accepts.

    label: the field's name as shown; lo/hi: inclusive bounds in the field's display unit
    (``lo_open``: lo itself excluded, e.g. L_c > 0); integer: whole numbers only; unit: the
    display unit as pint reads it (``"rpm"``, ``"µH"``, ``"mΩ"``, ``"A/rpm"``): text with a unit is
    converted to it; empty: plain numbers only.
    """

    label: str
    lo: float
    hi: float
    lo_open: bool = False
    integer: bool = False
    unit: str = ""

    def parse(self, text: object) -> float:
        """The value typed, exactly; :class:`FieldError` when it is not a number in range."""
        s = str(text if text is not None else "").strip().replace("−", "-")
        if not s:
            raise FieldError(f"{self.label}: empty — type a number")
        if _NUMBER.fullmatch(s):
            x = float(s)
            if not math.isfinite(x):
                raise FieldError(f"{self.label}: {s} is too large")
            if self.integer and x != int(x):
                raise FieldError(f"{self.label}: {s} is not a whole number")
            shown = s
        elif self.unit:
            x = self._quantity(s, text)
            shown = f"{s} = {show(x)} {self.unit}"
        else:
            raise FieldError(f"{self.label}: {str(text).strip()!r} is not a number")
        below = x <= self.lo if self.lo_open else x < self.lo
        if below or x > self.hi:
            lo_txt = f"> {show(self.lo)}" if self.lo_open else f"≥ {show(self.lo)}"
            raise FieldError(
                f"{self.label}: {shown} is outside the range ({lo_txt} and ≤ {show(self.hi)})"
            )
        return int(x) if self.integer else x

    def _quantity(self, s: str, text: object) -> float:
        """``s`` (a number then a unit, ``20uH``, ``0.02 mH``) in :attr:`unit`, by pint;
        FieldError (one line) for anything else (a unit alone, ``1 2 rpm``, ``2*3 rpm``), a wrong
        dimension, nan/inf, a non-whole value in an integer field."""
        from drive_link.errors import InvalidValue
        from drive_link.link.units import parse_value

        if unit_part(s) is None:
            raise FieldError(
                f"{self.label}: {str(text).strip()!r} is not a number (nor a quantity in "
                f"{self.unit})"
            )
        try:
            return parse_value(s, self.unit, integer=self.integer, name=self.label)
        except InvalidValue as exc:
            raise FieldError(str(exc).replace("the object", "the field")) from None


def unit_part(text: str) -> str | None:
    """The unit of ``text`` when it is one plain number then a unit pint reads (``"20uH"`` →
    ``"uH"``, ``"0.02 mH"`` → ``"mH"``); None otherwise (a bare number, a unit alone, ``1 2 rpm``,
    ``2*3 rpm``, hex): only such text is handed to pint, so nothing else is guessed."""
    m = _WITH_UNIT.fullmatch(str(text).strip().replace("−", "-"))
    if m is None:
        return None
    from drive_link.link.units import registry

    try:
        registry().parse_units(m.group(4))  # the unit part alone: no numbers in it
    except Exception:
        return None
    return m.group(4)


def show(x: float, digits: int = 7) -> str:
    """A value for a text field: up to ``digits`` significant digits, no trailing noise
    (2.9994e-05, 14.8, -0.5, 1000)."""
    if isinstance(x, bool):
        return str(int(x))
    if isinstance(x, int):
        return str(x)
    if not math.isfinite(x):
        return str(x)
    return format(float(x), f".{digits}g")
