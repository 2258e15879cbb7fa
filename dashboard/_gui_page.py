"""What the tabs of one browser's page share: :class:`Page`, passed to each tab.

A page owns: the browser's viser handle (``client``, ``gui``), the node it shows (``bench``:
the node selector changes it), its control-lease token and sign-in, the mute counter that
keeps read-backs from echoing as edits, the notice lines and the action wrapper (lease check,
typed values parsed first, errors shown under the control), and the main plot area
(``plots``, built after the tabs). Everything else a tab shows is the tab's own.

The page knows the GUI that made it only as a :class:`PageOwner` (the other nodes, a node's
bench, "refresh the status", "plot now"), so no tab module imports :mod:`dashboard._gui`.
"""

from __future__ import annotations

import contextlib
import secrets
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any, Protocol

from dashboard._bench import Bench
from dashboard._fields import FieldError
from dashboard._gui_plots import PlotArea
from dashboard._gui_words import gui_text
from dashboard._security import token_ok
from dashboard.config import BenchConfig

__all__ = ["Page", "PageOwner"]


class PageOwner(Protocol):
    """What a page needs from the GUI that serves it (:class:`dashboard._gui.BenchGui`)."""

    bench: Bench  #: the node a new page shows
    config: BenchConfig

    @property
    def nodes(self) -> Any:
        """The nodes on the bus (:class:`dashboard._nodes.Nodes`), or None for one node."""

    def bench_for(self, node: int) -> Bench:
        """The bench of ``node`` (opened on first use)."""

    def refresh_status(self) -> None:
        """Send every page its status now."""

    def wake_plots(self) -> None:
        """Push the live plots now, not at the next tick."""


class Page:
    """One browser's page: its handle, its node, its lease token, notices and actions."""

    def __init__(self, owner: PageOwner, client: Any, bench: Bench, config: BenchConfig) -> None:
        self.owner = owner
        self.client = client
        self.cid: int = client.client_id
        self.gui: Any = client.gui
        self.bench = bench  # the node this page shows (its node selector changes it)
        self.config = config
        self.token: str | None = None  # this browser's lease token once it took control
        self.authenticated = config.token is None
        self.plot_newest: float | None = None  # host time of the newest sample sent here
        self._mute = threading.local()  # per thread: see mute()
        self._plots: PlotArea | None = None

    # ------------------------------------------------------------------ plots
    @property
    def plots(self) -> PlotArea:
        """The main area's plots (built after the control panel's tabs)."""
        if self._plots is None:
            raise RuntimeError("the plot area is not built yet")
        return self._plots

    def build_plots(self) -> PlotArea:
        """Build the main plot area (once, after the tabs: the control panel comes first)."""
        self._plots = PlotArea(self.gui, self.config.live_window_s)
        return self._plots

    # ------------------------------------------------------------------ echo guard
    @contextlib.contextmanager
    def mute(self) -> Iterator[None]:
        """Callbacks fired while muted (a read-back shown in a field) do nothing.

        Per thread: viser calls a field's callbacks in the thread that sets its value, so the
        echo of a value set here is muted, while what the browser sends meanwhile (handled in
        viser's other threads) is not lost (a shared count dropped a keystroke that came in
        while another callback was muted: the L_c box showed 22.2, the Loop tab 22)."""
        self._mute.n = getattr(self._mute, "n", 0) + 1
        try:
            yield
        finally:
            self._mute.n -= 1

    @property
    def muted(self) -> bool:
        return getattr(self._mute, "n", 0) > 0

    # ------------------------------------------------------------------ notices
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

    # ------------------------------------------------------------------ control lease
    def holds_control(self) -> bool:
        holder = self.bench.lease.holder
        return holder is not None and self.token is not None and holder.token == self.token

    def control(self, md: Any) -> bool:
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

    def take_control(self) -> str:
        """Take control of this page's node, from whoever holds it."""
        if not self.authenticated:
            raise PermissionError("enter the access token first (this bench requires one)")
        self.token = self.token or secrets.token_urlsafe(16)
        self.bench.lease.acquire(self.name(), take_over=True, token=self.token)
        return "you control the bench"

    def sign_in(self, typed: str) -> bool:
        """Check the access token typed on this page; True if it is the bench's."""
        self.authenticated = token_ok(self.config.token, typed.strip() or None)
        return self.authenticated

    # ------------------------------------------------------------------ actions
    def action(
        self, fn: Callable[[Any], Any], md: Any, *, needs_control: bool = True
    ) -> Callable[[Any], None]:
        """Wrap a callback: lease check, typed values parsed first, errors shown in ``md``."""

        def cb(event: Any) -> None:
            if self.muted:
                return
            if needs_control and not self.control(md):
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
