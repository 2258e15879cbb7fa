"""How a signal is drawn, shared by the GUI's plots and the PNG exports: its unit (from the
object dictionary, so ``v_L`` is in V and ``hall_sector`` a sector, never "A"), its axis (one
per unit) and its role: the **measurement** drawn on top in the strongest colour, a
**reference** (speed*, i_p*) and a **model** (prediction, fit) thinner and dashed under it,
a derived trace (ī_p, the moving average) in between.

Units: as the OD states them (A, V, rpm, rad, N·m); "sector" for the Hall sector 1..6.
"""

from __future__ import annotations

import dataclasses
import functools

__all__ = [
    "MEASURED_COLORS",
    "SignalStyle",
    "capture_styles",
    "draw_order",
    "unit_of",
]

#: strong colours for measurements (one per unit), muted ones for references and models
MEASURED_COLORS = {"A": "#1e7b34", "rpm": "#1a5fb4", "V": "#6c3483", "sector": "#5d4037"}
DERIVED_COLOR = "#58d68d"
REFERENCE_COLOR = "#e67e22"
MODEL_COLOR = "#c0392b"
OTHER_COLOR = "#34495e"

_DERIVED = {"i_p_avg": ("ī_p", "A")}
_REFERENCES = {"i_p_ref": ("i_p*", "A"), "speed_ref": ("speed*", "rpm")}
_UNIT_NAMES = {"1": "", "N*m": "N·m"}


@dataclasses.dataclass(frozen=True)
class SignalStyle:
    """One series: ``key`` (the capture column), ``label`` (with its unit), ``unit`` (the axis
    it is drawn on), ``role`` ("measured", "derived", "reference", "model"), ``color``,
    ``width`` (px) and ``dash`` (uPlot/matplotlib on-off pattern in px, () = solid)."""

    key: str
    label: str
    unit: str
    role: str
    color: str
    width: float
    dash: tuple[float, ...] = ()

    @property
    def z(self) -> int:
        """Drawing order: the higher, the later (on top)."""
        return {"model": 0, "reference": 1, "derived": 2, "measured": 3}[self.role]


@functools.lru_cache(maxsize=64)
def unit_of(name: str) -> str:
    """The unit of a live/trace signal by its OD name (with or without "measurements."):
    "A", "V", "rpm" ...; "sector" for the Hall sector; "" for a dimensionless one or a name
    the OD does not know."""
    if name.removeprefix("measurements.") == "hall_sector":
        return "sector"
    from firmware_protocol.od import load_od

    od = load_od()
    for full in (name, f"measurements.{name}"):
        try:
            unit = od.entry(full).unit or ""
        except (KeyError, ValueError, AttributeError):
            continue
        return _UNIT_NAMES.get(unit, unit)
    return ""


def _labelled(name: str, unit: str) -> str:
    return f"{name} ({unit})" if unit else name


def capture_styles(kind: str, columns: list[str]) -> list[SignalStyle]:
    """The styles of a capture's columns ("t" left out) in drawing order (measurements
    last, on top). ``kind``: "trace", "current_step" or "identification" (its "model" is the
    fitted speed in rpm; a current step's is the predicted i_p in A)."""
    out: list[SignalStyle] = []
    for k in columns:
        if k == "t":
            continue
        if k == "model":
            unit = "rpm" if kind == "identification" else "A"
            what = "fit" if kind == "identification" else "model"
            out.append(SignalStyle(k, f"{what} ({unit})", unit, "model", MODEL_COLOR, 1.25,
                                   (6.0, 4.0)))
        elif k in _REFERENCES:
            name, unit = _REFERENCES[k]
            out.append(SignalStyle(k, _labelled(name, unit), unit, "reference",
                                   REFERENCE_COLOR, 1.25, (3.0, 3.0)))
        elif k in _DERIVED:
            name, unit = _DERIVED[k]
            out.append(SignalStyle(k, _labelled(name, unit), unit, "derived", DERIVED_COLOR,
                                   1.25))
        else:
            unit = unit_of(k)
            color = MEASURED_COLORS.get(unit, OTHER_COLOR)
            out.append(SignalStyle(k, _labelled(k, unit), unit, "measured", color, 2.0))
    # two measurements of one unit (e.g. v_L and e_L): the second a different colour
    seen: dict[str, int] = {}
    styled: list[SignalStyle] = []
    for s in out:
        if s.role == "measured":
            n = seen.get(s.unit, 0)
            seen[s.unit] = n + 1
            if n:
                s = dataclasses.replace(s, color=("#a04000", "#117864", "#7d3c98")[(n - 1) % 3])
        styled.append(s)
    return draw_order(styled)


def draw_order(styles: list[SignalStyle]) -> list[SignalStyle]:
    """Models first, then references, derived traces, measurements last (drawn on top);
    stable within a role."""
    return sorted(styles, key=lambda s: s.z)
