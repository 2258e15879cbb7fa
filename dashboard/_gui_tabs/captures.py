"""Captures tab: pick a recorded capture (shown in the main area's Capture tab), download it as
CSV or PNG, record a 50 kHz i_p trace.

Units: samples; the divider divides the 50 kHz rate.
"""

from __future__ import annotations

from typing import Any

from dashboard import _experiments as experiments
from dashboard._fields import NumberSpec
from dashboard._gui_field import Field
from dashboard._gui_page import Page
from dashboard._models import TraceIn, field_bounds

__all__ = ["CapturesTab"]


class CapturesTab:
    """The Captures tab of one page: the capture picked, downloads, a 50 kHz trace."""

    def __init__(self, page: Page) -> None:
        self.page = page
        gui = page.gui
        self.cap_dd = gui.add_dropdown("Capture", ("none",), initial_value="none")
        self.cap_dd.on_update(lambda e: self._on_capture_pick())
        dl = gui.add_button_group("Download", ("CSV", "PNG"))
        self.cap_md = gui.add_markdown("", visible=False)
        dl.on_click(page.action(self._download, self.cap_md, needs_control=False))
        with gui.add_folder("Trace (i_p at 50 kHz)"):
            self.tr_len = Field(
                page, NumberSpec("Length (samples)", 2, 8192, integer=True, unit="samples"), 1000
            )
            self.tr_div = Field(
                page, NumberSpec("Divider", *field_bounds(TraceIn, "divider"), integer=True), 1
            )
            gui.add_button("Capture now").on_click(page.action(self._capture_now, self.cap_md))

    def _capture_now(self, event: Any) -> str:
        cfg = TraceIn.model_validate(
            {"length": int(self.tr_len.value()), "divider": int(self.tr_div.value()),
             "pre_trigger": 0}
        )
        cap = experiments.capture(self.page.bench, cfg)
        return f"capture #{cap.id} recorded (plot: Capture tab)"

    def _picked(self) -> Any:
        if self.cap_dd.value == "none":
            return None
        return self.page.bench.captures.get(int(self.cap_dd.value.split(" ")[0].lstrip("#")))

    def _on_capture_pick(self) -> None:
        if self.page.muted:
            return
        cap = self._picked()
        if cap is not None:
            self.page.plots.show_capture_plot(cap)

    def show_captures(self) -> None:
        """Offer every capture; select and plot the newest."""
        caps = list(self.page.bench.captures.values())
        opts = tuple(f"#{c.id} {c.kind}" for c in caps) or ("none",)
        self.cap_dd.options = opts
        with self.page.mute():
            self.cap_dd.value = opts[-1]
        if caps:
            self.page.plots.show_capture_plot(caps[-1])

    def _download(self, event: Any) -> None:
        from dashboard._export import capture_csv, capture_png

        cap = self._picked()
        if cap is None:
            raise ValueError("no capture yet")
        fmt = event.target.value.lower()
        data = capture_csv(cap) if fmt == "csv" else capture_png(cap)
        self.page.client.send_file_download(
            f"capture_{cap.id}_{cap.kind}.{fmt}", data, save_immediately=True
        )
