"""One browser's panel: its own inputs (viser ``client.gui``), plots, notices and lease token.

Every browser gets its own handles, so what one browser types never appears in another, and an
action applies exactly the values of the browser that pressed the button (and only if that
browser holds the control lease). Typed numbers are text fields parsed strictly
(:mod:`dashboard._fields`): an invalid entry shows a message right under the field and nothing is
sent. After Apply or Read back the fields show the drive's read-back. Notices appear under the
control that caused them.

Layout: the main area (plots, :mod:`dashboard._gui_plots`) is a wide panel docked left; the
control panel (docked right) holds status, control, the drive buttons, progress, then the tabs
Speed · Current · Tuning · Identify · Captures · Config · Bus · Report (one object each, from
:mod:`dashboard._gui_tabs`).

Who owns what: the :class:`~dashboard._gui_page.Page` (shared by the tabs) owns the browser's
handle, the node shown, the lease token, the echo guard and the plot area; each tab owns its
widgets and their state; the panel owns the status block (bar, controller line, progress) and
composes the rest. Tabs talk to each other only through the callbacks the panel hands them
(Identify → Tuning's IP design, Config → Tuning's read-back, node switch → Tuning, Captures).
Units: rpm, A, µH, mΩ, V/A, A/rpm, 1/sample, N·m, s.
"""

from __future__ import annotations

import contextlib
import html
from typing import Any

import viser

from dashboard._bench import Bench
from dashboard._gui_field import CURRENT_COLORS, SPEED_COLORS, Field, fmt
from dashboard._gui_nodes import NodeSelect
from dashboard._gui_pace import PagePace
from dashboard._gui_page import Page, PageOwner
from dashboard._gui_plots import PLOT_AREA_WIDTH_PX, STRIP_PX, PlotArea
from dashboard._gui_statusbar import BAR_CSS, notices_css
from dashboard._gui_tabs.bus import BusTab
from dashboard._gui_tabs.captures import CapturesTab
from dashboard._gui_tabs.config import ConfigTab
from dashboard._gui_tabs.current import CurrentTab
from dashboard._gui_tabs.identify import IdentifyTab
from dashboard._gui_tabs.report import ReportTab
from dashboard._gui_tabs.speed import SpeedTab, parse_sequence
from dashboard._gui_tabs.tuning import TuningTab

#: requested width of the control panel (px): with the plot area's 1700 px wider than any
#: screen, so viser scales both to the window keeping only its 120 px canvas strip
CONTROL_WIDTH_PX = 800

_fmt = fmt  # older name

__all__ = ["CURRENT_COLORS", "SPEED_COLORS", "Field", "Panel", "parse_sequence"]


class Panel:
    """The GUI of one connected browser: the status block, then one object per tab.

    ``owner``: the GUI serving it (:class:`~dashboard._gui_page.PageOwner`).
    """

    def __init__(self, owner: PageOwner, client: viser.ClientHandle) -> None:
        self.page = Page(owner, client, owner.bench, owner.config)
        self.client = client
        self.cid = client.client_id
        self.pace = PagePace(client)  # live updates only as fast as this page applies them
        self.last_status = ""
        self.last_bar = ""
        self._build()

    # ------------------------------------------------------------------ shared state
    @property
    def bench(self) -> Bench:
        """The node this page shows (the page's; its node selector changes it)."""
        return self.page.bench

    @property
    def token(self) -> str | None:
        """This browser's lease token once it took control."""
        return self.page.token

    @property
    def plot_newest(self) -> float | None:
        """Host time (s) of the newest live sample sent to this page."""
        return self.page.plot_newest

    @plot_newest.setter
    def plot_newest(self, t: float | None) -> None:
        self.page.plot_newest = t

    def holds_control(self) -> bool:
        return self.page.holds_control()

    def notice(self, md: Any, text: str, level: str = "error") -> None:
        self.page.notice(md, text, level)

    # ------------------------------------------------------------------ layout
    def _build(self) -> None:
        page = self.page
        gui = page.gui
        # sent once: the bar's pinning, badges, page-side stale switch and where notices go
        gui.add_html(BAR_CSS + notices_css(CONTROL_WIDTH_PX, PLOT_AREA_WIDTH_PX, STRIP_PX))
        # the status bar: pinned at the top of the panel (BAR_CSS), however far it scrolls
        with gui.add_folder("State", expand_by_default=True):
            self.bar_html = gui.add_html("<div class='bench-statusbar'>connecting …</div>")
            self.nodes = NodeSelect(page, on_switched=self._node_switched)
            self.quick_btn = gui.add_button(
                "Quick stop", color="red", hint="CiA 402 quick stop: the drive brakes and halts"
            )
            self.controller_md = gui.add_markdown("")
            # small and plain: ownership is shown, it does not compete with Quick stop
            self.take_btn = gui.add_button_group("Control", ("Take control",))
        self.control_md = gui.add_markdown("", visible=False)
        self.nodes.notices = self.control_md
        self.status_html = gui.add_html("connecting …")
        if page.config.token is not None:
            self.token_in = gui.add_text(
                "Access token", "", hint="the bench's --token; needed to change anything"
            )
            gui.add_button("Sign in").on_click(lambda e: self.sign_in())
        self.drive_btns = gui.add_button_group("Drive", ("Enable", "Disable", "Fault reset"))
        # a safety control: any connected browser may press it (not only the one in control),
        # and it never waits for a long action (Bench.quick_stop)
        self.quick_btn.on_click(
            page.action(self._quick_stop, self.control_md, needs_control=False)
        )
        self.take_btn.on_click(
            page.action(lambda e: page.take_control(), self.control_md, needs_control=False)
        )
        self.drive_btns.on_click(page.action(self._drive_button, self.control_md))
        self.action_html = gui.add_html("")
        self.cancel_btn = gui.add_button("Cancel action", color="red", visible=False)
        self.cancel_btn.on_click(page.action(self._cancel, self.control_md))
        tabs = gui.add_tab_group()
        with tabs.add_tab("Speed"):
            self.speed = SpeedTab(page)
        with tabs.add_tab("Current"):
            self.current = CurrentTab(page)
        with tabs.add_tab("Tuning"):
            self.tuning = TuningTab(page)
        with tabs.add_tab("Identify"):
            self.identify = IdentifyTab(page, use_ab=self.tuning.use_ab)
        with tabs.add_tab("Captures"):
            self.captures = CapturesTab(page)
        with tabs.add_tab("Config"):
            self.config_tab = ConfigTab(page, on_loaded=self.tuning.load_gains)
        with tabs.add_tab("Bus"):
            self.bus_tab = BusTab(page)
        with tabs.add_tab("Report"):
            self.report = ReportTab(page)
        self.plots: PlotArea = page.build_plots()
        self.captures.show_captures()

    # ------------------------------------------------------------------ control
    def sign_in(self) -> None:
        """Check the token typed in "Access token" (it is not kept on the page)."""
        ok = self.page.sign_in(str(self.token_in.value))
        with self.page.mute():
            self.token_in.value = ""
        self.notice(self.control_md, "signed in" if ok else "wrong token", "ok" if ok else "error")

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

    def _node_switched(self) -> None:
        """The page shows another node: its gains and captures."""
        with contextlib.suppress(Exception):
            self.tuning.load_gains()
        with contextlib.suppress(Exception):
            self.captures.show_captures()

    # ------------------------------------------------------------------ what the GUI pushes
    def load_gains(self) -> None:
        """Read the node's gains into the Tuning tab (a new page, a node switch)."""
        self.tuning.load_gains()

    def show_captures(self) -> None:
        self.captures.show_captures()

    def on_gains(self, g: dict[str, Any]) -> None:
        """The node's gains changed (applied from any page); no bus."""
        self.tuning.on_gains(g)

    def show_nodes(self, rows: list[dict[str, Any]]) -> None:
        self.nodes.show_nodes(rows)

    def fit_readout(self, rotor_shown: bool) -> None:
        self.plots.fit_readout(rotor_shown)

    def show_status(self, text: str) -> None:
        if text != self.last_status:
            self.last_status = text
            self.status_html.content = text

    def show_controller(self, text: str) -> None:
        if self.controller_md.content != text:
            self.controller_md.content = text

    def show_bar(self, text: str) -> None:
        if text != self.last_bar:
            self.last_bar = text
            self.bar_html.content = text

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
