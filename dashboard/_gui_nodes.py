"""The node selector of a page: which drive on the bus this browser shows and controls.

Every node has its own :class:`dashboard._bench.Bench` (state, plots, captures, control lease;
see :mod:`dashboard._nodes`), so browser A can control node 1 while browser B controls node 2,
and a page watching node 2 sees node 2. The selector lists the nodes the dashboard sees (by
heartbeat or a scan); under it one line per node: its NMT state and who controls it.
"""

from __future__ import annotations

import html
from collections.abc import Callable
from typing import Any

from dashboard._gui_page import Page

__all__ = ["NodeSelect", "nodes_html"]


def nodes_html(rows: list[dict[str, Any]], shown: int) -> str:
    """The nodes as a small table (node, NMT state, CiA 402 state, who controls it)."""
    lines = []
    for r in rows:
        mark = "▶ " if r["node_id"] == shown else ""
        cells = (
            f"{mark}node {r['node_id']}",
            r.get("nmt_state") or "no heartbeat",
            r.get("state") or ("—" if r.get("open") else "not opened"),
            r.get("controller") or "nobody in control",
        )
        lines.append("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in cells) + "</tr>")
    body = "".join(lines)
    return f"<div class='bench-nodes' style='font-size:11px'><table>{body}</table></div>"


class NodeSelect:
    """The "Node" dropdown and the node table of one page; switching the node changes the
    page's bench, then ``on_switched`` redraws what shows that node."""

    def __init__(self, page: Page, on_switched: Callable[[], None]) -> None:
        self.page = page
        self.on_switched = on_switched
        gui = page.gui
        nodes = page.owner.nodes
        ids = nodes.ids() if nodes is not None else [page.bench.node_id]
        self.node_dd = gui.add_dropdown(
            "Node",
            tuple(str(n) for n in ids),
            initial_value=str(page.bench.node_id),
            hint="the drive this page shows and controls; each node has its own control",
        )
        self.nodes_table = gui.add_html("")
        self._nodes_shown = ""
        self.node_dd.on_update(lambda e: self._select_node())
        gui.add_button("Scan the bus", hint="probe every node-ID by SDO (0x1000)").on_click(
            lambda e: self._scan_nodes()
        )
        self.notices: Any = None  # where its notices go (the control notice, set by the panel)

    def _notice(self, text: str, level: str = "error") -> None:
        if self.notices is not None:
            self.page.notice(self.notices, text, level)

    def show_nodes(self, rows: list[dict[str, Any]]) -> None:
        """Update the dropdown's options and the node table (sent only when they changed)."""
        shown = self.page.bench.node_id
        opts = tuple(str(r["node_id"]) for r in rows)
        if opts and opts != tuple(self.node_dd.options):
            with self.page.mute():
                self.node_dd.options = opts
                if self.node_dd.value != str(shown):
                    self.node_dd.value = str(shown)
        txt = nodes_html(rows, shown)
        if txt != self._nodes_shown:
            self._nodes_shown = txt
            self.nodes_table.content = txt

    def _scan_nodes(self) -> None:
        nodes = self.page.owner.nodes
        if nodes is None:
            return
        try:
            rows = nodes.scan()
        except Exception as exc:
            self._notice(f"scan failed: {exc}")
            return
        self.show_nodes(rows)
        found = ", ".join(str(r["node_id"]) for r in rows)
        self._notice(f"nodes on the bus: {found}", "ok")

    def _select_node(self) -> None:
        page = self.page
        if page.muted:
            return
        try:
            node = int(self.node_dd.value)
        except ValueError:
            return
        if node == page.bench.node_id:
            return
        try:
            bench = page.owner.bench_for(node)
        except Exception as exc:
            self._notice(f"node {node}: {exc}")
            with page.mute():
                self.node_dd.value = str(page.bench.node_id)
            return
        page.bench = bench
        page.plot_newest = None  # the plots start again with this node's window
        self.on_switched()
        self._notice(f"this page shows node {node}", "ok")
        page.owner.wake_plots()
        page.owner.refresh_status()
