"""One browser's panel: its own inputs (viser ``client.gui``), plots, notices and lease token.

Every browser gets its own handles, so what one browser types never appears in another, and an
action applies exactly the values of the browser that pressed the button (and only if that
browser holds the control lease). Typed numbers are text fields parsed strictly
(:mod:`dashboard._fields`): an invalid entry shows a message right under the field and nothing is
sent. After Apply or Read back the fields show the drive's read-back. Notices appear under the
control that caused them.

Layout: the main area (plots, :mod:`dashboard._gui_tabs.plots`) is a wide panel docked left; the
control panel (docked right) holds status, control, the drive buttons, progress, then the tabs
Speed · Current · Tuning · Identify · Captures · Config (one module each in
:mod:`dashboard._gui_tabs`).
Units: rpm, A, µH, mΩ, V/A, A/rpm, 1/sample, N·m, s.
"""

from __future__ import annotations

import contextlib
import html
import secrets
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import viser

from dashboard._fields import FieldError
from dashboard._gui_field import CURRENT_COLORS, SPEED_COLORS, Field, fmt
from dashboard._gui_nodes import NodeSelect
from dashboard._gui_pace import PagePace
from dashboard._gui_statusbar import BAR_CSS, notices_css
from dashboard._gui_tabs import (
    BusTab,
    CapturesTab,
    ConfigTab,
    CurrentTab,
    IdentifyTab,
    PlotArea,
    ReportTab,
    SpeedTab,
    TuningTab,
    parse_sequence,
)
from dashboard._gui_tabs.plots import PLOT_AREA_WIDTH_PX, STRIP_PX
from dashboard._gui_words import gui_text
from dashboard._security import token_ok

if TYPE_CHECKING:
    from dashboard._gui import BenchGui

#: requested width of the control panel (px): with the plot area's 1700 px wider than any
#: screen, so viser scales both to the window keeping only its 120 px canvas strip
CONTROL_WIDTH_PX = 800

_fmt = fmt  # older name

__all__ = ["CURRENT_COLORS", "SPEED_COLORS", "Field", "Panel", "parse_sequence"]


class Panel(
    PlotArea,
    SpeedTab,
    CurrentTab,
    TuningTab,
    IdentifyTab,
    CapturesTab,
    ConfigTab,
    BusTab,
    ReportTab,
    NodeSelect,
):
    """The GUI of one connected browser."""

    def __init__(self, owner: BenchGui, client: viser.ClientHandle) -> None:
        self.owner = owner
        self.bench = owner.bench  # the node this page shows (its node selector changes it)
        self.config = owner.config
        self.client = client
        self.cid = client.client_id
        self.gui = client.gui
        self.token: str | None = None  # this browser's lease token once it took control
        self.authenticated = self.config.token is None
        self._muted = 0
        self.gains: dict[str, Any] | None = None
        self.last_status = ""
        self.last_bar = ""
        self.last_legends: tuple[str, str] = ("", "")
        self.pace = PagePace(client)  # live updates only as fast as this page applies them
        self.plot_newest: float | None = None  # host time of the newest sample sent here
        self._build()

    # ------------------------------------------------------------------ helpers
    @contextlib.contextmanager
    def mute(self):
        self._muted += 1
        try:
            yield
        finally:
            self._muted -= 1

    def name(self) -> str:
        return f"browser #{self.cid}"

    def notice(self, md: Any, text: str, level: str = "error") -> None:
        """Show ``text`` under the control that caused it (replaces the previous notice)."""
        icon = {"error": "⚠", "ok": "✓", "info": "ℹ"}.get(level, "")
        stamp = time.strftime("%H:%M:%S")
        md.content = f"{icon} {text} · {stamp}" if text else ""
        md.visible = bool(text)

    def md(self) -> Any:
        """A hidden notice line (shown by :meth:`notice`) right under the last control."""
        return self.gui.add_markdown("", visible=False)

    def holds_control(self) -> bool:
        holder = self.bench.lease.holder
        return holder is not None and self.token is not None and holder.token == self.token

    def _control(self, md: Any) -> bool:
        """True if this browser holds control (taking it when nobody does)."""
        if not self.authenticated:
            self.notice(md, "enter the access token first (this bench requires one)")
            return False
        if self.holds_control():
            return True
        holder = self.bench.lease.holder
        if holder is None:
            self.token = self.token or secrets.token_urlsafe(16)
            self.bench.lease.acquire(self.name(), token=self.token)
            return True
        self.notice(md, f"{holder.client} controls the bench — press 'Take control' to take over")
        return False

    def action(
        self, fn: Callable[[Any], Any], md: Any, *, needs_control: bool = True
    ) -> Callable[[Any], None]:
        """Wrap a callback: lease check, typed values parsed first, errors shown in ``md``."""

        def cb(event: Any) -> None:
            if self._muted:
                return
            if needs_control and not self._control(md):
                return
            try:
                done = fn(event)
            except FieldError as exc:
                self.notice(md, f"{exc} — nothing sent")
            except Exception as exc:  # drive_link speaks CLI: say it with the GUI's controls
                self.notice(md, gui_text(str(exc)) or type(exc).__name__)
            else:
                self.notice(md, done if isinstance(done, str) else "", "ok")
            self.owner.refresh_status()

        return cb

    # ------------------------------------------------------------------ layout
    def _build(self) -> None:
        gui = self.gui
        # sent once: the bar's pinning, badges, page-side stale switch and where notices go
        gui.add_html(BAR_CSS + notices_css(CONTROL_WIDTH_PX, PLOT_AREA_WIDTH_PX, STRIP_PX))
        # the status bar: pinned at the top of the panel (BAR_CSS), however far it scrolls
        with gui.add_folder("State", expand_by_default=True):
            self.bar_html = gui.add_html("<div class='bench-statusbar'>connecting …</div>")
            self._build_node_selector()
            self.quick_btn = gui.add_button(
                "Quick stop", color="red", hint="CiA 402 quick stop: the drive brakes and halts"
            )
            self.controller_md = gui.add_markdown("")
            # small and plain: ownership is shown, it does not compete with Quick stop
            self.take_btn = gui.add_button_group("Control", ("Take control",))
        self.control_md = gui.add_markdown("", visible=False)
        self.status_html = gui.add_html("connecting …")
        if self.config.token is not None:
            self.token_in = gui.add_text(
                "Access token", "", hint="the bench's --token; needed to change anything"
            )
            gui.add_button("Sign in").on_click(lambda e: self._sign_in())
        self.drive_btns = gui.add_button_group("Drive", ("Enable", "Disable", "Fault reset"))
        # a safety control: any connected browser may press it (not only the one in control),
        # and it never waits for a long action (Bench.quick_stop)
        self.quick_btn.on_click(
            self.action(self._quick_stop, self.control_md, needs_control=False)
        )
        self.take_btn.on_click(
            self.action(self._take_control, self.control_md, needs_control=False)
        )
        self.drive_btns.on_click(self.action(self._drive_button, self.control_md))
        self.action_html = gui.add_html("")
        self.cancel_btn = gui.add_button("Cancel action", color="red", visible=False)
        self.cancel_btn.on_click(self.action(self._cancel, self.control_md))
        tabs = gui.add_tab_group()
        with tabs.add_tab("Speed"):
            self._build_speed_tab()
        with tabs.add_tab("Current"):
            self._build_current_tab()
        with tabs.add_tab("Tuning"):
            self._build_tuning_tab()
        with tabs.add_tab("Identify"):
            self._build_identify_tab()
        with tabs.add_tab("Captures"):
            self._build_captures_tab()
        with tabs.add_tab("Config"):
            self._build_config_tab()
        with tabs.add_tab("Bus"):
            self._build_bus_tab()
        with tabs.add_tab("Report"):
            self._build_report_tab()
        self._build_plot_area()
        self.show_captures()

    # ------------------------------------------------------------------ control
    def _sign_in(self) -> None:
        ok = token_ok(self.config.token, str(self.token_in.value).strip() or None)
        self.authenticated = ok
        with self.mute():
            self.token_in.value = ""
        self.notice(self.control_md, "signed in" if ok else "wrong token", "ok" if ok else "error")

    def _take_control(self, event: Any) -> str:
        if not self.authenticated:
            raise PermissionError("enter the access token first (this bench requires one)")
        self.token = self.token or secrets.token_urlsafe(16)
        self.bench.lease.acquire(self.name(), take_over=True, token=self.token)
        return "you control the bench"

    def _drive_button(self, event: Any) -> None:
        cmd = {
            "Enable": "enable",
            "Disable": "disable",
            "Quick stop": "quick_stop",
            "Fault reset": "fault_reset",
        }[event.target.value]
        self.bench.command(cmd)

    def _quick_stop(self, event: Any) -> str:
        return f"quick stop: {self.bench.quick_stop()}"

    def _cancel(self, event: Any) -> str:
        return "cancelling …" if self.bench.cancel_action() else "no action under way"

    # ------------------------------------------------------------------ live updates
    def show_status(self, text: str) -> None:
        if text != self.last_status:
            self.last_status = text
            self.status_html.content = text

    def show_readout(self, text: str) -> None:
        if text != self.readout_html.content:
            self.readout_html.content = text

    def show_bar(self, text: str) -> None:
        if text != self.last_bar:
            self.last_bar = text
            self.bar_html.content = text

    def show_legends(self, speed: str, current: str) -> None:
        if (speed, current) != self.last_legends:
            self.last_legends = (speed, current)
            self.speed_legend.content = speed
            self.current_legend.content = current

    def show_action(self, action: dict | None, sequence: dict | None) -> None:
        if action is not None:
            pct = 100 * action["fraction"]
            left = max(0, action["deadline_in_s"])
            txt = (
                f"<b>{html.escape(action['what'])}</b> {pct:.0f} % · {html.escape(action['text'])}"
                f" · {action['elapsed_s']:.0f} s, gives up in {left:.0f} s"
                f"<div style='height:4px;background:#ddd'><div style='height:4px;width:{pct:.0f}%;"
                "background:#1f618d'></div></div>"
            )
        elif sequence is not None:
            txt = (
                f"<b>sequence</b> step {sequence['step']}/{sequence['steps']} · next at "
                f"{sequence['next_at_s']:g} s of {sequence['total_s']:g} s"
            )
        else:
            txt = ""
        if txt != self.action_html.content:
            self.action_html.content = txt
            self.cancel_btn.visible = action is not None
