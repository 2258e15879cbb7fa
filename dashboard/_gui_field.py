"""Pieces every tab of the viser GUI uses: a typed number field with its error line, number
formatting, the plot colours and uPlot series/plot helpers.

Units: whatever the field's :class:`~dashboard._fields.NumberSpec` label states (rpm, A, µH, …).
"""

from __future__ import annotations

from contextlib import AbstractContextManager
from typing import Any, Protocol

import numpy as np
import viser.uplot as uplot

from dashboard._fields import FieldError, NumberSpec, show

__all__ = [
    "CURRENT_COLORS",
    "PLOT_HEIGHT_PX",
    "SPEED_COLORS",
    "Field",
    "FieldHost",
    "fmt",
    "live_series",
    "series",
]

SPEED_COLORS = ("#1a5fb4", "#e67e22")  #: (measured speed: strong, speed*: muted, dashed)
CURRENT_COLORS = ("#1e7b34", "#c0392b")  #: (measured i_p: strong, i_p*: muted, dashed)
MEASURED_WIDTH_PX = 2.25  #: line width of a measurement (drawn last: on top)
REFERENCE_WIDTH_PX = 1.25  #: line width of a reference (drawn first, dashed)
REFERENCE_DASH = (6, 4)  #: on/off pattern of a reference line (px)
PLOT_HEIGHT_PX = 310  #: height of a main-area plot including its legend (px): two fit in 800 px


def fmt(x: Any, spec: str = ".4g") -> str:
    """``x`` formatted with ``spec``; "–" for None, NaN, inf or a non-number."""
    try:
        f = float(x)
    except (TypeError, ValueError):
        return "–"
    return format(f, spec) if np.isfinite(f) else "–"


def series(labels: tuple[str, ...], colors: tuple[str, ...], x_label: str) -> list[Any]:
    """uPlot series: the x series named ``x_label``, then one line per label/colour."""
    out: list[Any] = [uplot.Series(label=x_label)]
    for lab, col in zip(labels, colors, strict=False):
        out.append(uplot.Series(label=lab, stroke=col, width=1.5))
    return out


def live_series(name: str, unit: str, colors: tuple[str, str], x_label: str) -> list[Any]:
    """uPlot series of a live plot: x, the reference ``name``* (thin, dashed, drawn first)
    and the measurement ``name`` (strong, drawn on top); data order (x, reference,
    measurement)."""
    return [
        uplot.Series(label=x_label),
        uplot.Series(
            label=f"{name}* ({unit})", stroke=colors[1], width=REFERENCE_WIDTH_PX,
            dash=REFERENCE_DASH,
        ),
        uplot.Series(label=f"{name} ({unit})", stroke=colors[0], width=MEASURED_WIDTH_PX),
    ]


class FieldHost(Protocol):
    """A field's home: a page's GUI and its echo guard (:class:`dashboard._gui_page.Page`)."""

    gui: Any

    def mute(self) -> AbstractContextManager[None]:
        """Callbacks fired meanwhile do nothing."""


class Field:
    """A typed number: a text input plus a message line under it (hidden while valid)."""

    def __init__(self, host: FieldHost, spec: NumberSpec, initial: float, hint: str = "") -> None:
        self.host = host
        self.spec = spec
        self.input = host.gui.add_text(spec.label, show(initial), hint=hint or None)
        self.error = host.gui.add_markdown("", visible=False)
        self.input.on_update(lambda e: self.validate())

    def validate(self) -> bool:
        try:
            self.spec.parse(self.input.value)
        except FieldError as exc:
            self._show_error(str(exc))
            return False
        self._show_error("")
        return True

    def _show_error(self, text: str) -> None:
        if text:
            self.error.content = f"⚠ {text} — nothing sent"
            self.error.visible = True
        elif self.error.visible:
            self.error.visible = False
            self.error.content = ""

    def value(self) -> float:
        """The typed value, exactly; FieldError (shown at the field) otherwise."""
        try:
            v = self.spec.parse(self.input.value)
        except FieldError as exc:
            self._show_error(str(exc))
            raise
        self._show_error("")
        return v

    def set(self, x: float) -> None:
        """Show ``x`` (a read-back) in the field without firing its callbacks' echo."""
        with self.host.mute():
            self.input.value = show(x)
        self._show_error("")
