"""Bus tab: the raw bus as a table per CAN-ID (count, rate, age, data) with its CANopen meaning,
as ``drive-link monitor`` shows it (:class:`drive_link.link.monitor.BusTable`).

"Watch the bus" opens this browser's own connection to the bench's bus (like the Config tab's
recorder) and redraws the table twice a second; unchecked (the default) it costs nothing.
Filters by node and CAN-ID, and a pause that freezes the table (frames are still counted).
"""

from __future__ import annotations

import html
import threading
import time
from collections.abc import Callable
from typing import Any

import can

from dashboard._gui_page import Page
from dashboard._gui_tabs.config import bus_kwargs
from drive_link.link.bus import open_bus
from drive_link.link.monitor import BusTable, IdFilter, TableFeed, parse_ids

__all__ = ["BusTab", "rows_html"]

MAX_ROWS = 60  #: rows drawn at most (a bus with more IDs shows the lowest)
REFRESH_S = 0.5


def rows_html(rows: list[dict[str, Any]], frames: int, paused: bool) -> str:
    """The table as HTML (every cell escaped)."""
    head = "".join(
        f"<th>{h}</th>" for h in ("ID", "kind", "count", "Hz", "age s", "data", "meaning")
    )
    body = []
    for r in rows[:MAX_ROWS]:
        cells = (r["id"], r["kind"], r["count"], f"{r['rate_hz']:.1f}", f"{r['age_s']:.2f}",
                 r["data"], r["text"])  # fmt: skip
        body.append("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in cells) + "</tr>")
    note = f"{frames} frames" + (" · paused" if paused else "")
    if len(rows) > MAX_ROWS:
        note += f" · {len(rows) - MAX_ROWS} more IDs not shown (filter)"
    return (
        '<div style="font-family:monospace;font-size:11px">'
        f"<div>{html.escape(note)}</div><table><tr>{head}</tr>{''.join(body)}</table></div>"
    )


class BusTab:
    """The Bus tab of one page: its own connection to the bench's bus while watched."""

    def __init__(self, page: Page) -> None:
        self.page = page
        gui = page.gui
        self.bus_on = gui.add_checkbox("Watch the bus", False, hint="per CAN-ID, with its meaning")
        self.bus_nodes = gui.add_text("Nodes", "", hint="e.g. 1,2 (empty: all)")
        self.bus_ids = gui.add_text("CAN-IDs", "", hint="e.g. 0x181,0x700-0x77F (empty: all)")
        self.bus_pause = gui.add_checkbox("Pause", False, hint="freeze the table")
        self.bus_md = page.md()
        self.bus_html = gui.add_html("")
        self._bus: tuple[Any, Any, BusTable] | None = None  # (bus, notifier, table)
        self._bus_lock = threading.Lock()
        self.bus_on.on_update(lambda e: self.on_toggle())
        self.bus_pause.on_update(lambda e: self.on_pause())
        self.bus_nodes.on_update(lambda e: self.on_filter())
        self.bus_ids.on_update(lambda e: self.on_filter())

    def on_toggle(self) -> None:
        """"Watch the bus" changed: open or close this page's connection to the bus."""
        self._bus_guard(self._bus_toggle)

    def on_filter(self) -> None:
        """A filter changed: applied, or refused in one line (the old one stays)."""
        self._bus_guard(self._bus_filter)

    def on_pause(self) -> None:
        """"Pause" changed: the table freezes (frames are still counted) or goes on."""
        self._bus_guard(self._bus_pause_changed)

    @property
    def table(self) -> BusTable | None:
        """The table of the bus being watched (None while not watching)."""
        watch = self._bus
        return watch[2] if watch is not None else None

    def _bus_guard(self, fn: Callable[[], None]) -> None:
        try:
            fn()
        except Exception as exc:
            self.page.notice(self.bus_md, str(exc) or type(exc).__name__)
        else:
            self.page.notice(self.bus_md, "")

    def _bus_keep(self) -> IdFilter:
        nodes_text = str(self.bus_nodes.value).strip()
        nodes = None
        if nodes_text:
            try:
                nodes = {int(p, 0) for p in nodes_text.split(",") if p.strip()}
            except ValueError:
                raise ValueError(f"nodes {nodes_text!r}: node-IDs like 1,2") from None
        ids_text = str(self.bus_ids.value).strip()
        return IdFilter(nodes, parse_ids(ids_text) if ids_text else None)

    def _bus_filter(self) -> None:
        keep = self._bus_keep()  # a bad filter: one line, the old one stays
        if self._bus is not None:
            self._bus[2].keep = keep

    def _bus_pause_changed(self) -> None:
        if self._bus is not None:
            self._bus[2].pause(bool(self.bus_pause.value))

    def _bus_toggle(self) -> None:
        with self._bus_lock:
            if self.bus_on.value and self._bus is None:
                table = BusTable(keep=self._bus_keep())
                page = self.page
                bus = open_bus(**bus_kwargs(page.config, getattr(page.bench, "hub_port", None)))
                notifier = can.Notifier(bus, [TableFeed(table)], timeout=0.1)
                self._bus = (bus, notifier, table)
                threading.Thread(target=self._bus_loop, name="bench-bus-tab", daemon=True).start()
            elif not self.bus_on.value and self._bus is not None:
                self._bus_close()

    def _bus_close(self) -> None:
        bus, notifier, _table = self._bus  # type: ignore[misc]
        self._bus = None
        notifier.stop(1.0)
        bus.shutdown()

    def _bus_loop(self) -> None:
        drawn_paused = False
        while True:
            watch = self._bus
            if watch is None:
                return
            table = watch[2]
            try:
                if not (table.paused and drawn_paused):  # paused: drawn once, then left alone
                    drawn_paused = table.paused
                    self.bus_html.content = rows_html(table.rows(time.time()), table.frames,
                                                      table.paused)  # fmt: skip
            except Exception:  # the page is gone: stop watching
                with self._bus_lock:
                    if self._bus is watch:
                        self._bus_close()
                return
            time.sleep(REFRESH_S)
