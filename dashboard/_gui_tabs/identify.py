"""Identify tab: a current step in current mode, G(z) = b/(z − a) fitted to the speed
(paper Fig. 16); the data and the fit are drawn in the main area's Capture tab.

Units: A, s; a dimensionless, b rpm/(A·sample) at Ts = 20 µs.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from dashboard import _experiments as experiments
from dashboard._fields import NumberSpec
from dashboard._gui_field import Field, fmt
from dashboard._gui_page import Page
from dashboard._models import IdentifyIn, field_bounds

__all__ = ["IdentifyTab"]


class IdentifyTab:
    """The Identify tab of one page; "Use a, b in IP design" hands a, b to ``use_ab``."""

    def __init__(self, page: Page, use_ab: Callable[[float, float], str]) -> None:
        self.page = page
        self.use_ab = use_ab
        gui = page.gui
        gui.add_markdown(
            "Current step in current mode; fit G(z) = b/(z − a) to the speed (Fig. 16). "
            "The drive is put back as found afterwards."
        )
        self.id_from = Field(
            page,
            NumberSpec(
                "Identify from (A)", *field_bounds(IdentifyIn, "from_A"), unit="A"
            ),
            15.0,
        )
        self.id_to = Field(
            page, NumberSpec("Identify to (A)", *field_bounds(IdentifyIn, "to_A"), unit="A"), 30.0
        )
        self.id_dur = Field(
            page, NumberSpec("Duration (s)", 0.0, 20.0, lo_open=True, unit="s"), 1.0
        )
        self.id_btns = gui.add_button_group("Identification", ("Run", "Use a, b in IP design"))
        self.id_md = gui.add_markdown("", visible=False)
        self.id_btns.on_click(page.action(self._identify_button, self.id_md, needs_control=False))

    def _identify_button(self, event: Any) -> str | None:
        if event.target.value != "Run":
            ident = self.page.bench.identified
            if not ident:
                raise ValueError("run an identification first")
            return self.use_ab(float(ident["a"]), float(ident["b"]))
        if not self.page.control(self.id_md):
            return None
        body = IdentifyIn(
            from_A=self.id_from.value(), to_A=self.id_to.value(), duration_s=self.id_dur.value()
        )
        res = experiments.identify(self.page.bench, body)
        return (
            f"a = **{res['a']:.8f}**, b = **{res['b']:.6g}** rpm/(A·sample) at Ts = 20 µs · "
            f"fit RMS error {fmt(res['rms_error_rpm'], '.3g')} rpm (plot: Capture tab)"
        )
