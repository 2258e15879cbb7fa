"""The viser GUI: one panel per browser (:mod:`dashboard._gui_panel`), the shared 3D rotor, and
the two background loops that keep every panel live.

Layout: the plots are the main area, a wide per-browser panel docked left (tabs Live ·
Capture · Loop, :mod:`dashboard._gui_plots`); the control panel is docked right (status,
who controls, Take control, Drive buttons, progress/cancel of a long action, then tabs Speed ·
Current · Tuning · Identify · Captures · Config, one module each in
:mod:`dashboard._gui_tabs`); the 3D rotor (:mod:`dashboard._gui_scene`, off with ``--no-3d``)
gets the strip between them: each browser has its own copy and a "3D rotor" checkbox at the end
of its control panel; unchecked, that browser is sent no scene message and renders no rotor.
Status texts: :mod:`dashboard._gui_status`.

Streaming cannot die silently: the plot loop catches every failure of a tick (counted, shown),
a watchdog in the status loop restarts a plot thread that died or stopped beating, and the page
says "STALE" with the data's age when no fresh data arrives (see :mod:`dashboard._live_plot`).
Every viser send goes through one lock (:mod:`dashboard._gui_guard`).

Control lease: a browser takes control by its first action (or "Take control"); a browser whose
WebSocket closes keeps it LEASE_GRACE_S seconds (a reload), then loses it. A tab that goes
silent without closing is dropped by the WebSocket keepalive (ping every 20 s, 20 s timeout),
then loses the lease LEASE_GRACE_S later.
"""

from __future__ import annotations

import contextlib
import html
import io
import logging
import threading
import time
from typing import Any

import numpy as np
import viser

from dashboard import _live_plot as live_plot
from dashboard._bench import LIVE_SIGNALS, Bench
from dashboard._gui_cast import install_fast_cast
from dashboard._gui_field import CURRENT_COLORS, SPEED_COLORS
from dashboard._gui_field import fmt as _fmt
from dashboard._gui_guard import guard_handshake, install_send_lock, refuse_share_url
from dashboard._gui_pace import answer as pace_answer
from dashboard._gui_panel import CONTROL_WIDTH_PX, Panel
from dashboard._gui_scene import RotorScene
from dashboard._gui_scene import background as scene_background
from dashboard._gui_status import DROP_WINDOW_S, controller_text, legend, status_html
from dashboard._gui_statusbar import badges_html, fresh_badge, readout_html
from dashboard._nodes import Nodes
from dashboard._security import LeaseError, allowed_hosts, allowed_origins
from dashboard.config import BenchConfig

log = logging.getLogger(__name__)

WAKE_TIMEOUT_S = 0.030  #: after a setpoint change, wait at most this for the drive's new reference
MIN_SPAN_SPEED_RPM = 50.0  #: the speed plot's y axis spans at least this (rpm)
MIN_SPAN_I_P_A = 5.0  #: the i_p plot's y axis spans at least this (A)
BRAND_COLOR = (31, 97, 141)  #: steel blue: buttons, tabs, sliders
# CONTROL_WIDTH_PX (dashboard._gui_panel): the requested widths of the control panel (docked
# right) and the plot area (docked left) are together wider than any screen, so viser scales
# both to the window and keeps only its minimum 120 px canvas strip between them (the readout
# column); at 1280 px the controls get 371 px, the plots 789 px.
LEASE_GRACE_S = 10.0  #: a browser whose WebSocket closed loses control after this (s)
PLOT_BUCKETS = 80  #: time buckets per live plot (≤ 3 points each sent: min, max, last)
IDLE_WAIT_S = 1.0  #: with no browser the plot thread wakes this often (s), for the watchdog
WATCHDOG_S = 3.0  #: a plot thread silent for this long is replaced (s)
#: the status loop's period (s): the page's bar is re-sent this often, so data that stopped
#: shows as stale within STALE_AFTER_S + this, and a page that got no tick for PAGE_STALE_S
#: turns stale by itself
STATUS_PERIOD_S = 0.2

# re-exported for tests and older imports
from dashboard._live_plot import min_span_envelope  # noqa: E402

__all__ = ["LEASE_GRACE_S", "BenchGui", "min_span_envelope"]


class BenchGui:
    """One viser server showing one :class:`Bench` to any number of browsers."""

    def __init__(self, bench: Bench, config: BenchConfig, nodes: Nodes | None = None) -> None:
        self.bench = bench  # the bench's own node (--node): a new page shows it
        self.config = config
        self.nodes = nodes  # the other nodes on the bus (a page's node selector), if any
        self._listeners: dict[int, Any] = {}  # id(bench) → its event listener
        self.server: viser.ViserServer | None = None
        self.port = 0
        self.origins: set[str] = set()
        self.panels: dict[int, Panel] = {}
        self._panels_lock = threading.Lock()
        self._stop = threading.Event()
        self._wake = threading.Event()  # a setpoint changed: plot now, not at the next tick
        self._wake_target: tuple[str, float] | None = None  # (live signal, commanded value)
        self._wake_bench: Bench | None = None  # whose setpoint changed
        self._threads: dict[str, threading.Thread] = {}
        self._plot_generation = 0
        self._plot_beat = time.monotonic()  # the plot loop's last heartbeat
        self.plot_restarts = 0  # plot threads replaced by the watchdog
        self.stream_errors = 0  # plot ticks that failed (and were survived)
        self.last_stream_error: str | None = None
        self.frames_sent = 0
        self.last_push = 0.0  # time.monotonic() of the last plot push
        self.newest_t: float | None = None  # host time of the newest plotted sample
        self.last_live: dict[str, np.ndarray] = {}
        self._gone: dict[str, float] = {}  # lease token → time.monotonic() its browser left
        self._drops: list[tuple[float, int]] = []  # (monotonic, dropped total)
        self._drops_by: dict[int, list[tuple[float, int]]] = {}  # the other nodes' (id(bench))
        self._tick = 0  # status ticks sent (makes each tick's bar differ: page-side staleness)
        self.scene: RotorScene | None = None

    # ------------------------------------------------------------------ lifecycle
    def start(self) -> None:
        # (the Report tab's experiments, scipy and matplotlib, are imported by the first
        # report: dashboard._report_loader)
        install_send_lock()
        install_fast_cast()  # viser's per-assignment cast without rebuilding its type hints
        # viser has no authentication: the GUI stays on loopback even when the API is remote
        # (there, a browser must sign in with the token before it can change anything).
        with contextlib.redirect_stdout(io.StringIO()):  # viser prints its URL banner anyway
            self.server = viser.ViserServer(
                host="127.0.0.1", port=self.config.gui_port, verbose=False
            )
        self.port = self.server.get_port()
        self.origins = allowed_origins("127.0.0.1", [self.port, self.config.api_port])
        hosts = allowed_hosts("127.0.0.1")
        guard_handshake(self.port, lambda: hosts, lambda: self.origins, pace_answer)
        refuse_share_url(self.server)
        self.server.gui.configure_theme(
            control_width="large",
            dark_mode=False,
            show_logo=False,
            show_share_button=False,  # and its request is refused (refuse_share_url)
            brand_color=BRAND_COLOR,
        )
        self.server.gui.main_panel.dock_right()
        self.server.gui.main_panel.set_width(CONTROL_WIDTH_PX)  # the plots take the rest
        self.server.on_client_connect(self._on_connect)
        self.server.on_client_disconnect(self._on_disconnect)
        self.scene = (
            RotorScene(self.server, read_theta_e=self._read_theta_e)
            if self.config.scene_3d
            else None
        )
        if self.scene is None:  # a calm strip between the plots and the controls
            self.server.scene.set_background_image(scene_background())
        else:  # θ_e by SDO in the drive watch's worker, never in the status loop
            self.bench.watch.hooks.append(self.scene.maybe_anchor)
        self._attach(self.bench)
        if self.nodes is not None:
            self.nodes.on_new.append(self._attach)
        self._start_plot_thread()
        th = threading.Thread(target=self._status_loop, name="gui-status", daemon=True)
        th.start()
        self._threads["status"] = th

    def stop(self) -> None:
        self._stop.set()
        self._wake.set()
        for th in list(self._threads.values()):
            th.join(timeout=2.0)
        for bench in self._benches():
            with contextlib.suppress(ValueError, KeyError):
                bench.listeners.remove(self._listeners[id(bench)])
        if self.server is not None:
            self.server.stop()

    def _start_plot_thread(self) -> None:
        self._plot_generation += 1
        gen = self._plot_generation
        self._plot_beat = time.monotonic()
        th = threading.Thread(
            target=self._plot_loop, args=(gen,), name=f"gui-plots-{gen}", daemon=True
        )
        th.start()
        self._threads["plots"] = th

    # ------------------------------------------------------------------ nodes
    def _attach(self, bench: Bench) -> None:
        """Follow ``bench``'s lease and events (once per bench)."""
        if id(bench) in self._listeners:
            return

        def on_event(kind: str, data: dict) -> None:
            self._on_bench_event(kind, data, bench)

        self._listeners[id(bench)] = on_event
        bench.lease.on_change(lambda old, new: self._on_lease_change(old, new, bench))
        bench.listeners.append(on_event)

    def _benches(self) -> list[Bench]:
        return self.nodes.benches() if self.nodes is not None else [self.bench]

    def bench_for(self, node: int) -> Bench:
        """The bench of ``node`` (opened on first use; see :class:`dashboard._nodes.Nodes`)."""
        if self.nodes is None:
            if node != self.bench.node_id:
                raise ValueError(f"this bench has node {self.bench.node_id} only")
            return self.bench
        return self.nodes.get(node)

    def _groups(self, panels: list[Panel]) -> list[tuple[Bench, list[Panel]]]:
        """The panels by the bench (node) each one shows, the bench's own node first."""
        groups: dict[int, tuple[Bench, list[Panel]]] = {id(self.bench): (self.bench, [])}
        for p in panels:
            groups.setdefault(id(p.bench), (p.bench, []))[1].append(p)
        return [g for g in groups.values() if g[1]]

    # ------------------------------------------------------------------ clients and control
    def _on_connect(self, client: viser.ClientHandle) -> None:
        panel = Panel(self, client)
        with self._panels_lock:
            self.panels[client.client_id] = panel
        self._wake.set()  # the plot thread starts ticking for this browser
        with contextlib.suppress(Exception):
            panel.load_gains()
        if self.scene is not None:  # its "3D rotor" checkbox and, shown, its rotor
            self.scene.attach(client, shown=self.config.scene_3d_shown)
            box = self.scene.toggles.get(client.client_id)
            if box is not None:  # the readout leaves room for the rotor when it is shown
                panel.fit_readout(bool(box.value))
                box.on_update(lambda e: panel.fit_readout(bool(box.value)))
        self.refresh_status()

    def _on_disconnect(self, client: viser.ClientHandle) -> None:
        if self.scene is not None:
            self.scene.detach(client.client_id)
        with self._panels_lock:
            panel = self.panels.pop(client.client_id, None)
        if (
            panel is not None
            and panel.token is not None
            and any(
                b.lease.holder is not None and b.lease.holder.token == panel.token
                for b in self._benches()
            )
        ):  # the leases it holds (on any node) expire after LEASE_GRACE_S
            self._gone[panel.token] = time.monotonic()
            self.refresh_status()

    def _read_theta_e(self) -> tuple[float, float, int] | None:
        """The drive's electrical angle θ_e (rad, one SDO read), the host time (s,
        ``time.time()``, the live stream's clock) it was read at and its motor's pole pairs
        (the rotor's mechanical angle is θ_e / pole pairs); None while an action holds the
        drive."""
        if not self.bench.lock.acquire(timeout=0.05):
            return None
        try:
            t0 = time.time()
            theta_e = float(self.bench.drive.read("measurements.theta_e"))
            t = (t0 + time.time()) / 2
            pole_pairs = int(self.bench.drive.read("motor.pole_pairs"))
            return theta_e, t, pole_pairs
        finally:
            self.bench.lock.release()

    def wake_plots(self) -> None:
        """Push the live plots now, not at the next tick (a page switched its node)."""
        self._wake.set()

    def panel_list(self) -> list[Panel]:
        with self._panels_lock:
            return list(self.panels.values())

    def _expire_leases(self) -> None:
        """Release the leases (on every node) of a browser gone for more than LEASE_GRACE_S."""
        now = time.monotonic()
        benches = self._benches()
        for token, since in list(self._gone.items()):
            held = [b for b in benches if b.lease.holder and b.lease.holder.token == token]
            if not held:
                self._gone.pop(token, None)
            elif now - since >= LEASE_GRACE_S:
                self._gone.pop(token, None)
                for b in held:
                    with contextlib.suppress(LeaseError):
                        b.lease.release(token)

    def _on_lease_change(self, old: Any, new: Any, bench: Bench | None = None) -> None:
        if new is not None and old is not None and old.token != new.token:
            node = f" (node {bench.node_id})" if bench is not None else ""
            for p in self.panel_list():
                if p.token == old.token:
                    p.notice(p.control_md, f"{new.client} took control from you{node}", "info")
        self.refresh_status()

    # ------------------------------------------------------------------ bench events
    def _on_bench_event(self, kind: str, data: dict, bench: Bench | None = None) -> None:
        """An event of ``bench`` (None: the bench's own node) for the pages that show it."""
        bench = bench or self.bench
        panels = [p for p in self.panel_list() if p.bench is bench]
        if kind == "capture":
            for p in panels:
                with contextlib.suppress(Exception):
                    p.show_captures()
        elif kind == "gains":
            for p in panels:  # from the applied set: no page reads the drive again
                with contextlib.suppress(Exception):
                    p.on_gains(data)  # the Loop tab's applied (grey) curves follow the drive
        elif kind == "setpoint":
            if "rpm" in data:
                self._wake_target = ("measurements.speed_ref", float(data["rpm"]))
            elif "i_p_ref" in data:
                self._wake_target = ("measurements.i_p_ref", float(data["i_p_ref"]))
            self._wake_bench = bench
            self._wake.set()
        elif kind == "error":
            for p in panels:
                with contextlib.suppress(Exception):
                    p.notice(p.control_md, data.get("message", ""))

    # ------------------------------------------------------------------ plots
    def _plot_loop(self, generation: int) -> None:
        """Push the live window to every panel at gui_rate_hz, and at once after a setpoint
        change. A failing tick is counted and survived; a newer generation replaces this one."""
        period = 1.0 / self.config.gui_rate_hz
        next_t = time.monotonic()
        while not self._stop.is_set() and generation == self._plot_generation:
            self._plot_beat = time.monotonic()
            if not self.panels:  # nobody watches: no ticks (a connect or a setpoint wakes us)
                self._wake.wait(IDLE_WAIT_S)
                next_t = time.monotonic()
                continue
            try:
                if self._wake.wait(max(0.0, next_t - time.monotonic())):
                    self._wake.clear()
                    self._push_after_setpoint()
                    next_t = time.monotonic() + period
                    continue
                self.push_plots()
            except Exception as exc:  # never die: count, show, go on
                self.stream_errors += 1
                self.last_stream_error = f"{type(exc).__name__}: {exc}"
                log.warning("live plot tick failed: %s", self.last_stream_error)
                time.sleep(min(0.5, period))
            next_t += period
            if time.monotonic() - next_t > 1.0:
                next_t = time.monotonic()

    def _push_after_setpoint(self) -> None:
        """Push as soon as the plotted window ends with the commanded reference (the drive
        streams it back within a few ms), at most WAKE_TIMEOUT_S after the setpoint change."""
        target = self._wake_target
        deadline = time.monotonic() + WAKE_TIMEOUT_S
        live = (self._wake_bench or self.bench).drive.live
        while target is not None and time.monotonic() < deadline and not self._stop.is_set():
            # the newest value first (cheap), the whole window only once it is there
            if abs(live.latest().get(target[0], float("nan")) - target[1]) <= 1e-3:
                if self.push_plots(require=target):
                    return
            time.sleep(0.001)
        self.push_plots()

    def push_plots(self, require: tuple[str, float] | None = None) -> bool:
        """Send the decimated live window to the plots of every panel whose page has caught up
        (:mod:`dashboard._gui_pace`: a page behind gets the newest window once it caught up,
        never a backlog); with ``require`` = (signal, value) only if the window's last sample
        of that signal equals value. A panel gets only new data (nothing when no sample arrived
        since its last push). Returns whether the data was current enough (see ``require``).
        Each page gets the plots of the node it shows; with ``require``, only the pages of the
        node whose setpoint changed are served."""
        ready = [p for p in self.panel_list() if p.pace.ready()]
        if not ready:
            self.last_push = time.monotonic()  # the loop is alive; the pages are behind
            return True  # nobody to send to: no work
        if require is not None:
            target = self._wake_bench or self.bench
            return self._push_group(target, [p for p in ready if p.bench is target], require)
        for bench, panels in self._groups(ready):
            self._push_group(bench, panels, None)
        return True

    def _push_group(
        self, bench: Bench, ready: list[Panel], require: tuple[str, float] | None
    ) -> bool:
        """:meth:`push_plots` for the pages ``ready`` that show ``bench``."""
        if not ready:
            return True
        names = list(LIVE_SIGNALS)
        w = bench.drive.live.window(self.config.live_window_s, names)
        t = np.asarray(w["t"], dtype=np.float64)
        cols = [np.asarray(w[n], dtype=np.float64) for n in names]
        ok = np.isfinite(t)
        for c in cols:  # NaN before a stream's first frame inside the window
            ok &= np.isfinite(c)
        t, cols = t[ok], [c[ok] for c in cols]
        if len(t) < 2:
            return True
        if require is not None:
            col = cols[names.index(require[0])]
            if abs(col[-1] - require[1]) > 1e-3:
                return False
        newest = float(t[-1])
        if require is None:  # only pages that lack this window
            ready = [p for p in ready if p.plot_newest is None or newest > p.plot_newest]
        self.last_push = time.monotonic()
        if not ready:
            return True  # nothing new: send nothing
        # each plot decimated on its own signals (fewer kept points than over all four);
        # data order (x, reference, measurement, envelope): the measurement drawn on top
        ts, (sp, sp_ref) = live_plot.decimate(t, [cols[0], cols[1]], PLOT_BUCKETS)
        tc, (ip, ip_ref) = live_plot.decimate(t, [cols[2], cols[3]], PLOT_BUCKETS)
        speed = (
            ts - newest,
            sp_ref,
            sp,
            live_plot.min_span_envelope(len(ts), sp, sp_ref, min_span=MIN_SPAN_SPEED_RPM),
        )
        current = (
            tc - newest,
            ip_ref,
            ip,
            live_plot.min_span_envelope(len(tc), ip, ip_ref, min_span=MIN_SPAN_I_P_A),
        )
        for p in ready:
            try:
                p.plots.show_live(speed, current)
                p.plot_newest = newest
                p.pace.sent_update()
            except Exception as exc:  # one broken browser must not stop the others
                self.stream_errors += 1
                self.last_stream_error = f"{type(exc).__name__}: {exc}"
        self.frames_sent += 1
        if bench is not self.bench:
            return True  # the 3D rotor and the freshness below follow the bench's own node
        self.last_live = w
        if self.scene is not None and (self.newest_t is None or newest > self.newest_t):
            with contextlib.suppress(Exception):
                self.scene.update(float(cols[0][-1]), w)
        self.newest_t = max(newest, self.newest_t or newest)
        return True

    # ------------------------------------------------------------------ status
    def _status_loop(self) -> None:
        while not self._stop.wait(STATUS_PERIOD_S):
            try:
                self._watchdog()
                self._expire_leases()
                self.refresh_status()
            except Exception as exc:  # shown on the next good tick; never die
                log.warning("status tick failed: %s", exc)

    def _watchdog(self) -> None:
        """Replace a plot thread that died or stopped beating."""
        th = self._threads.get("plots")
        silent = time.monotonic() - self._plot_beat
        if th is None or not th.is_alive() or silent > WATCHDOG_S:
            self.plot_restarts += 1
            log.warning(
                "live plot thread %s: restarting", "silent" if th and th.is_alive() else "dead"
            )
            self._start_plot_thread()

    def freshness(self, s: dict | None = None) -> tuple[bool, str]:
        """(stale, text) of the live view for the page: the age (s) of the newest sample
        (from ``s`` = :meth:`Bench.state` when given) and of the last plot push."""
        age = None
        if s is not None:
            age = (s.get("ages_s") or {}).get("live")
        else:
            with contextlib.suppress(Exception):
                w = self.bench.drive.live.window(0.5, ["measurements.speed"])
                if len(w["t"]):
                    age = live_plot.data_age_s(float(w["t"][-1]))
        push_age = time.monotonic() - self.last_push if self.last_push else None
        return live_plot.freshness_text(age, push_age)

    def _drop_rate(self, dropped: Any, bench: Bench | None = None) -> float | None:
        """Dropped TPDO frames per second over the last DROP_WINDOW_S, never negative: the
        drive_link total is an estimate from the TPDO cadence that can step back (a late frame
        arrives, a pause closes a count window, the counters are reset); a total below the
        previous one starts the window again instead of giving a negative rate."""
        try:
            total = int(dropped)
        except (TypeError, ValueError):
            return None
        now = time.monotonic()
        key = id(bench) if bench is not None and bench is not self.bench else None
        drops = self._drops if key is None else self._drops_by.get(key, [])
        if drops and total < drops[-1][1]:
            drops = []  # the counter stepped back: a new window
        drops.append((now, total))
        drops = [(t, d) for t, d in drops if now - t <= DROP_WINDOW_S]
        if key is None:
            self._drops = drops
        else:
            self._drops_by[key] = drops
        t0, d0 = drops[0]
        return max(0.0, (total - d0) / (now - t0)) if now - t0 > 0.5 else 0.0

    def refresh_status(self) -> None:
        """Send every caught-up page its status bar (re-sent every tick: the page turns
        stale by itself when the ticks stop), legends and details. Never waits on the drive:
        :meth:`Bench.state` is built from what is known."""
        if self.server is None:
            return
        panels = self.panel_list()
        if not panels:
            return
        self._tick += 1
        if self.nodes is not None:
            rows = self.nodes.listing()
            for p in panels:
                with contextlib.suppress(Exception):
                    p.show_nodes(rows)
        for bench, group in self._groups(panels):
            self._refresh_group(bench, group)

    def _refresh_group(self, bench: Bench, panels: list[Panel]) -> None:
        """:meth:`refresh_status` for the pages that show ``bench``."""
        try:
            s = bench.state()
        except Exception as exc:
            for p in panels:
                p.show_status(f"<b>state unavailable:</b> {html.escape(str(exc))}")
            return
        stale, fresh_txt = self.freshness(s)
        fresh = fresh_badge(stale, fresh_txt, self._tick)
        bar = f"<div class='bench-statusbar'>{badges_html(s)} {fresh}</div>"
        latest: dict = {}
        with contextlib.suppress(Exception):
            latest = bench.drive.live.latest()
        readout = readout_html(s, latest)
        rate = self._drop_rate((s.get("live") or {}).get("dropped"), bench)
        stream = (self.stream_errors, self.plot_restarts, self.last_stream_error)
        status = status_html(s, latest, rate, stale, fresh_txt, stream)
        legends = (
            legend(("speed", "speed*"), "rpm", SPEED_COLORS, fresh, stale, self._tick),
            legend(("i_p", "i_p*"), "A", CURRENT_COLORS, fresh, stale, self._tick),
        )
        ctl = s.get("controller")
        gone = None
        holder = bench.lease.holder
        if holder is not None and holder.token in self._gone:
            gone = LEASE_GRACE_S - (time.monotonic() - self._gone[holder.token])
        for p in panels:
            if not p.pace.ready():
                continue  # this page is behind: it gets the newest status once it caught up
            try:
                p.show_bar(bar)
                p.plots.show_readout(readout)
                p.show_status(status)
                p.plots.show_legends(*legends)
                p.show_action(s.get("action"), s.get("sequence"))
                p.show_controller(controller_text(ctl, p.holds_control(), gone))
                p.pace.sent_update()
            except Exception as exc:
                log.warning("status for browser #%s failed: %s", p.cid, exc)
        if self.scene is not None and bench is self.bench:
            self.scene.show_status(
                f"{_fmt(latest.get('measurements.speed'), '.0f')} rpm · {s.get('state')} · "
                f"i_p {_fmt(latest.get('measurements.i_p'), '.1f')} A"
            )
