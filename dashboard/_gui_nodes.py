"""The node selector of a page: which drive on the bus this browser shows and controls.

Every node has its own :class:`dashboard._bench.Bench` (state, plots, captures, control lease;
see :mod:`dashboard._nodes`), so browser A can control node 1 while browser B controls node 2,
and a page watching node 2 sees node 2. The selector lists the nodes the dashboard sees (by
heartbeat or a scan); under it one line per node: its NMT state and who controls it.
"""

from __future__ import annotations

import contextlib
import html
from typing import Any

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
    """Mixin of :class:`dashboard._gui_panel.Panel`: the "Node" dropdown and the node table."""

    gui: Any
    bench: Any
    owner: Any
    control_md: Any
    plot_newest: float | None
    gains: Any
    _muted: int

    def _build_node_selector(self) -> None:
        nodes = self.owner.nodes
        ids = nodes.ids() if nodes is not None else [self.bench.node_id]
        self.node_dd = self.gui.add_dropdown(
            "Node",
            tuple(str(n) for n in ids),
            initial_value=str(self.bench.node_id),
            hint="the drive this page shows and controls; each node has its own control",
        )
        self.nodes_table = self.gui.add_html("")
        self._nodes_shown = ""
        self.node_dd.on_update(lambda e: self._select_node())
        self.gui.add_button("Scan the bus", hint="probe every node-ID by SDO (0x1000)").on_click(
            lambda e: self._scan_nodes()
        )

    def show_nodes(self, rows: list[dict[str, Any]]) -> None:
        """Update the dropdown's options and the node table (sent only when they changed)."""
        opts = tuple(str(r["node_id"]) for r in rows)
        if opts and opts != tuple(self.node_dd.options):
            with self.mute():  # type: ignore[attr-defined]
                self.node_dd.options = opts
                if self.node_dd.value != str(self.bench.node_id):
                    self.node_dd.value = str(self.bench.node_id)
        txt = nodes_html(rows, self.bench.node_id)
        if txt != self._nodes_shown:
            self._nodes_shown = txt
            self.nodes_table.content = txt

    def _scan_nodes(self) -> None:
        nodes = self.owner.nodes
        if nodes is None:
            return
        try:
            rows = nodes.scan()
        except Exception as exc:
            self.notice(self.control_md, f"scan failed: {exc}")  # type: ignore[attr-defined]
            return
        self.show_nodes(rows)
        found = ", ".join(str(r["node_id"]) for r in rows)
        self.notice(self.control_md, f"nodes on the bus: {found}", "ok")  # type: ignore[attr-defined]

    def _select_node(self) -> None:
        if self._muted:
            return
        try:
            node = int(self.node_dd.value)
        except ValueError:
            return
        if node == self.bench.node_id:
            return
        try:
            bench = self.owner.bench_for(node)
        except Exception as exc:
            self.notice(self.control_md, f"node {node}: {exc}")  # type: ignore[attr-defined]
            with self.mute():  # type: ignore[attr-defined]
                self.node_dd.value = str(self.bench.node_id)
            return
        self.bench = bench
        self.plot_newest = None  # the plots start again with this node's window
        self.gains = None
        with contextlib.suppress(Exception):
            self.load_gains()  # type: ignore[attr-defined]
        with contextlib.suppress(Exception):
            self.show_captures()  # type: ignore[attr-defined]
        self.notice(self.control_md, f"this page shows node {node}", "ok")  # type: ignore[attr-defined]
        self.owner._wake.set()
        self.owner.refresh_status()
