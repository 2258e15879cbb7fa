"""Quantities with units in a sweep spec: ``"14.8 uH"``, ``"2 ms"``, ``"1500 rpm"`` (pint).

A bare number is taken in the SI unit of the field (the object dictionary's unit: H, Ohm, V,
s, rpm, N m, ...). The registry is pint's defaults plus the EDS spelling ``Ohm`` (so ``mOhm``
works) and is built on first use (about 0.3 s): a spec of bare numbers never builds it.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Any

__all__ = ["SpecError", "clean", "scale_to", "to_si"]


def clean(v: float) -> float:
    """``v`` to 15 significant digits: 10 uH is 1e-05 H, not 9.999999999999999e-06."""
    return float(f"{v:.15g}")


class SpecError(ValueError):
    """A sweep spec that cannot be used; the message is one line naming the field."""


@lru_cache(maxsize=1)
def _registry() -> Any:
    import pint

    ureg: pint.UnitRegistry[float] = pint.UnitRegistry()  # (magnitudes: plain floats)
    ureg.define("Ohm = ohm")
    return ureg


def scale_to(unit: str, si: str, where: str) -> float:
    """Factor that converts a number in ``unit`` to ``si`` (multiplicative units only)."""
    if unit == si:
        return 1.0
    ureg = _registry()
    try:
        return float(ureg.Quantity(1.0, unit).to(si).magnitude)
    except Exception as exc:  # pint raises several error types
        raise SpecError(f"{where}: unit {unit!r} is not convertible to {si!r} ({exc})") from None


def to_si(value: Any, si: str, where: str) -> float:
    """``value`` (a number in ``si``, or a string with a unit) as a float in ``si``."""
    if isinstance(value, bool):
        raise SpecError(f"{where}: expected a number or a quantity in {si}, got {value!r}")
    if isinstance(value, int | float):
        v = float(value)
    elif isinstance(value, str):
        ureg = _registry()
        try:
            q = ureg.Quantity(value.strip())
        except Exception as exc:
            raise SpecError(f"{where}: {value!r} is not a quantity ({exc})") from None
        if not isinstance(q, ureg.Quantity):
            v = float(q)
        else:
            try:
                v = clean(float(q.to(si).magnitude))
            except Exception as exc:
                raise SpecError(f"{where}: {value!r} is not convertible to {si} ({exc})") from None
    else:
        raise SpecError(f"{where}: expected a number or a quantity in {si}, got {value!r}")
    if not math.isfinite(v):
        raise SpecError(f"{where}: must be finite, got {value!r}")
    return v
