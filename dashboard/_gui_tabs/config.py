"""Config tab: the drive's writable configuration as a CiA 306 DCF file (download; upload to
compare or apply, all-or-nothing, limits checked first: :mod:`drive_link.workflows.config_dcf`) and
a recording of the bus that other CAN tools open (.asc Vector, .blf, .log candump:
:func:`drive_link.link.record.record_bus`), downloaded when stopped.
"""

from __future__ import annotations

import contextlib
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from dashboard._gui_page import Page
from dashboard._gui_words import CONFIG_FORCE_LABEL, diff_rows
from drive_link.link.record import record_bus
from drive_link.workflows import config_dcf

__all__ = ["RECORD_FORMATS", "ConfigTab", "bus_kwargs"]

RECORD_FORMATS = (".asc", ".blf", ".log")  #: Vector ASCII, Vector binary, candump -L
MAX_RECORD_S = 600.0  #: a recording stops by itself after this (s)


def bus_kwargs(config: Any, hub_port: int | None) -> dict[str, Any]:
    """:func:`drive_link.link.bus.open_bus` keywords for a second connection to the bench's bus."""
    if config.virtual and hub_port is not None:
        return {"host": "127.0.0.1", "port": hub_port, "bitrate": config.bitrate}
    if config.join_hub is not None:
        return {"host": "127.0.0.1", "port": config.join_hub, "bitrate": config.bitrate}
    return {
        "interface": config.interface,
        "channel": config.channel,
        "bitrate": config.bitrate,
        **getattr(config, "bus_options", {}),
    }


class ConfigTab:
    """The Config tab of one page: DCF save and load, a bus recording; ``on_loaded`` is called
    after a DCF file was written to the drive."""

    def __init__(self, page: Page, on_loaded: Callable[[], None]) -> None:
        self.page = page
        self.on_loaded = on_loaded
        gui = page.gui
        gui.add_markdown("**Configuration file (DCF, CiA 306)**")
        save = gui.add_button("Save configuration (.dcf)")
        self.save_md = page.md()
        save.on_click(page.action(self.save_dcf, self.save_md, needs_control=False))
        self.dcf_dry = gui.add_checkbox(
            "Compare only (dry run)", True, hint="show what the file would change; write nothing"
        )
        self.dcf_force = gui.add_checkbox(
            CONFIG_FORCE_LABEL,
            False,
            hint="load a file whose gain set is stable but has poor margins (L_c > 1.5 L, "
            "GM < 2 dB or ‖S‖∞ > 5); an unstable set is refused regardless",
        )
        up = gui.add_upload_button("Load configuration (.dcf)", mime_type=".dcf,text/plain")
        self.cfg_md = gui.add_markdown("", visible=False)
        up.on_upload(page.action(self.load_dcf, self.cfg_md, needs_control=False))
        gui.add_markdown("**Bus recording**")
        self.rec_fmt = gui.add_dropdown("Format", RECORD_FORMATS, initial_value=".asc")
        self.rec_btns = gui.add_button_group("Recording", ("Start recording", "Stop and download"))
        self.rec_md = gui.add_markdown("", visible=False)
        self.rec_btns.on_click(page.action(self.record_button, self.rec_md, needs_control=False))
        self._rec: tuple[threading.Thread, threading.Event, Path, dict] | None = None

    def save_dcf(self, event: Any) -> str:
        with tempfile.TemporaryDirectory() as d:
            path = Path(d) / f"drive_node{self.page.bench.node_id}.dcf"
            with self.page.bench.lock:
                res = config_dcf.save(self.page.bench.drive, path, bitrate=self.page.config.bitrate)
            data = path.read_bytes()
        stamp = time.strftime("%Y%m%d_%H%M%S")
        self.page.client.send_file_download(
            f"drive_node{res['node_id']}_{stamp}.dcf", data, save_immediately=True
        )
        return f"saved {res['objects']} objects of node {res['node_id']}"

    def load_dcf(self, event: Any) -> str | None:
        f = event.target.value
        dry = bool(self.dcf_dry.value)
        force = bool(self.dcf_force.value)
        if not dry and not self.page.control(self.cfg_md):
            return None
        with tempfile.TemporaryDirectory() as d:
            path = Path(d) / Path(f.name).name
            path.write_bytes(f.content)
            with self.page.bench.lock:
                res = config_dcf.load(self.page.bench.drive, path, dry_run=dry, force=force)
        changes = res.get("changes") or []
        rows = diff_rows(changes)
        if dry:
            head = f"{f.name}: {len(changes)} change(s) (dry run, nothing written)"
        else:
            n = res.get("written") or 0
            head = f"{f.name}: {n if isinstance(n, int) else len(n)} object(s) written"
            self.page.bench.setpoints.forget()  # limits and RPDO layouts may have changed
            with contextlib.suppress(Exception):
                self.on_loaded()
        return f"{head}{': ' + rows if rows else ''}"

    def record_button(self, event: Any) -> str | None:
        if event.target.value == "Start recording":
            if self._rec is not None and self._rec[0].is_alive():
                raise ValueError("already recording: stop it first")
            d = Path(tempfile.mkdtemp(prefix="bench_record_"))
            path = d / f"bus_{time.strftime('%Y%m%d_%H%M%S')}{self.rec_fmt.value}"
            stop = threading.Event()
            out: dict[str, Any] = {}
            kw = bus_kwargs(self.page.config, getattr(self.page.bench, "hub_port", None))

            def run() -> None:
                try:
                    out["stats"] = record_bus(kw, path, stop, duration=MAX_RECORD_S)
                except Exception as exc:  # shown when stopped
                    out["error"] = str(exc) or type(exc).__name__

            th = threading.Thread(target=run, name="bench-record", daemon=True)
            th.start()
            self._rec = (th, stop, path, out)
            return f"recording the bus to {path.name} (at most {MAX_RECORD_S:g} s)"
        if self._rec is None:
            raise ValueError("not recording")
        th, stop, path, out = self._rec
        self._rec = None
        stop.set()
        th.join(timeout=10.0)
        if "error" in out:
            raise RuntimeError(f"recording failed: {out['error']}")
        stats = out.get("stats")
        self.page.client.send_file_download(path.name, path.read_bytes(), save_immediately=True)
        frames = stats.frames if stats is not None else "?"
        secs = f"{stats.seconds:.1f}" if stats is not None else "?"
        with contextlib.suppress(OSError):
            path.unlink()
            path.parent.rmdir()
        return f"{path.name}: {frames} frames in {secs} s, downloaded"
