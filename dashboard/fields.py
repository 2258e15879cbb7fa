"""Strict parsing of numbers typed into the GUI: no clamping, no sign change, no guessing.

A typed value is either taken exactly as written or refused with a one-line message that the GUI
shows at the field (nothing is sent to the drive). Accepted: an optional sign (ASCII ``-``/``+``
or the typographic minus ``−``), digits with one optional decimal point, an optional exponent.
Refused: empty text, words, ``nan``/``inf``, underscores, several numbers, values outside the
field's range (the message names the range; the value is not moved into it).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

__all__ = ["FieldError", "NumberSpec", "show"]

_NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?")


class FieldError(ValueError):
    """A typed value that cannot be used; the message names the field and the reason."""


@dataclass(frozen=True)
class NumberSpec:
    """What one GUI number field accepts.

    label: the field's name as shown; lo/hi: inclusive bounds in the field's display unit
    (``lo_open``: lo itself excluded, e.g. L_c > 0); integer: whole numbers only.
    """

    label: str
    lo: float
    hi: float
    lo_open: bool = False
    integer: bool = False

    def parse(self, text: object) -> float:
        """The value typed, exactly; :class:`FieldError` when it is not a number in range."""
        s = str(text if text is not None else "").strip().replace("−", "-")
        if not s:
            raise FieldError(f"{self.label}: empty — type a number")
        if not _NUMBER.fullmatch(s):
            raise FieldError(f"{self.label}: {str(text).strip()!r} is not a number")
        x = float(s)
        if not math.isfinite(x):
            raise FieldError(f"{self.label}: {s} is too large")
        if self.integer and x != int(x):
            raise FieldError(f"{self.label}: {s} is not a whole number")
        below = x <= self.lo if self.lo_open else x < self.lo
        if below or x > self.hi:
            lo_txt = f"> {show(self.lo)}" if self.lo_open else f"≥ {show(self.lo)}"
            raise FieldError(
                f"{self.label}: {s} is outside the range ({lo_txt} and ≤ {show(self.hi)})"
            )
        return int(x) if self.integer else x


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
