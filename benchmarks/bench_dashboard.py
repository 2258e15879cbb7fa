"""Benchmarks of drive-dashboard in a real headless Chromium; prints figures (no pass/fail).

Figures (goals from the issue):
  1. step-to-plot latency: from the click on "+ step" to the first redraw of the speed plot
     that draws a frame whose speed* series shows the new setpoint (goal ≤ 100 ms);
  2. plot refresh rate: redraws per second of the speed plot's canvas (goal ≥ 20 Hz);
  3. server CPU: the dashboard process alone (the virtual drive and the loopback hub run in a
     separate ``virtual-drive run --hub`` process), in % of one core, with no browser (goal
     ≤ 5 %), one browser streaming the live plots (goal ≤ 8 %) and three (goal ≤ 25 %), and
     the bytes on the socket to the one streaming tab (kernel tcp_info, ``ss -tin``; goal
     ≤ 0.5 MB/s);
  4. time to usable: from ``page.goto`` to the Enable button visible and the speed plot redrawn
     with new data twice (goal ≤ 5 s idle machine, ≤ 15 s busy host).

How: the page gets an init script that timestamps (performance.now()) every canvas redraw
(uPlot clears its canvas on every redraw) and every click; the page clock is mapped onto
Python's (offset measured to about 1 ms). viser's WebSocket runs in a worker, so frame arrival
is timed in Python: Playwright delivers each frame while the script waits in
page.wait_for_timeout (a few ms late at most, which only lengthens the figure). Python decodes
the frame (viser's wire format: zstd-compressed msgpack + 8-byte aligned raw arrays) to find the
first one whose speed* series ends at the new setpoint; the first redraw of the speed plot at or
after its arrival is the one that shows the step. CPU is utime + stime of the dashboard process from
/proc over a window of wall time.

The dashboard runs as users get it (the 3D rotor exists, its checkbox unchecked: it costs
nothing); ``--3d`` shows it on every page (``drive-dashboard --show-3d``).

  5. the 3D rotor's cost (with ``--3d``, or alone with ``--rotor``): one browser streaming at
     500 rpm, the dashboard's CPU and the browser's (every Chromium process), WebGL draw calls/s
     and rotor scene messages/s received by the page, with the rotor shown, hidden (the page's
     "3D rotor" checkbox unchecked) and for reference without it (``--no-3d``). Goal: hidden
     costs what ``--no-3d`` costs (no scene message, only the empty scene's 1 Hz heartbeat).

Every figure is printed with the load average (1 min) at the time it was taken.

Run: python benchmarks/bench_dashboard.py [--steps 6] [--window 10] [--browsers 3] [--3d]
     [--rotor] [--hogs 4]
"""

from __future__ import annotations

import argparse
import contextlib
import os
import statistics
import subprocess
import sys
import time

import msgspec
import numpy as np
import zstandard
from _socket_bytes import bytes_sent

from dashboard._gui_pace import PagePace
from dashboard.browser import free_port, launch, run_dashboard, stop_process
from dashboard.config import GUI_RATE_HZ

INIT_JS = """
(() => {
  const draws = new Map();
  window.__draws = draws;
  const orig = CanvasRenderingContext2D.prototype.clearRect;
  CanvasRenderingContext2D.prototype.clearRect = function (...a) {
    const c = this.canvas;
    if (!draws.has(c)) draws.set(c, []);
    draws.get(c).push(performance.now());
    return orig.apply(this, a);
  };
  window.__clicks = [];
  document.addEventListener('pointerdown', () => window.__clicks.push(performance.now()), true);
})();
"""

SPEED_CANVAS_DRAWS = """
() => { const c = document.querySelector('.uplot canvas'); return (window.__draws.get(c) || []); }
"""


def cpu_seconds(pid: int) -> float:
    """utime + stime of ``pid`` in seconds (/proc/<pid>/stat fields 14 and 15)."""
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def clock_offset(page) -> float:
    """Python time.monotonic() (ms) minus the page's performance.now() (ms), ± 1 ms."""
    best = None
    for _ in range(5):
        t0 = time.monotonic() * 1e3
        tp = page.evaluate("performance.now()")
        t1 = time.monotonic() * 1e3
        if best is None or t1 - t0 < best[0]:
            best = (t1 - t0, (t0 + t1) / 2 - tp)
    return best[1]


def decode_frame(payload: bytes) -> list[dict]:
    """viser's wire format → the list of message dicts, arrays put back as numpy."""
    n_inner = int.from_bytes(payload[0:8], "little")
    n_comp = int.from_bytes(payload[8:16], "little")
    inner = zstandard.ZstdDecompressor().decompress(payload[16 : 16 + n_comp], n_inner)
    obj = msgspec.msgpack.decode(inner)
    off = 16 + n_comp
    buffers = []
    for length in obj.get("binaryBufferLengths", ()):
        off += (8 - off % 8) % 8
        buffers.append(payload[off : off + length])
        off += length

    def fix(v):
        if isinstance(v, dict):
            if "__binary_index" in v and "dtype" in v:
                return np.frombuffer(buffers[v["__binary_index"]], dtype=v["dtype"])
            return {k: fix(x) for k, x in v.items()}
        if isinstance(v, list):
            return [fix(x) for x in v]
        return v

    return fix(obj["messages"])


def shows_setpoint(messages: list[dict], target: float) -> bool:
    """True if a uPlot data update has a second array (speed*: data order x, reference,
    measurement, envelope; the measurement is drawn last, on top) ending at ``target``."""
    for m in messages:
        if m.get("type") != "GuiUpdateMessage":
            continue
        for v in m.get("updates", {}).values():
            if isinstance(v, list) and len(v) >= 3 and all(isinstance(a, np.ndarray) for a in v):
                ref = v[1]
                if ref.size and abs(float(ref[-1]) - target) < 0.5:
                    return True
    return False


class _Sink:
    data: tuple = ((), (), ())
    content = ""
    visible = False


class _SimulatedViewer:
    """Stands in for a browser's panel: plot handles that keep what is assigned."""

    def __init__(self, bench) -> None:
        self.bench = bench  # the node it shows (the plot thread groups panels by bench)
        self.speed_plot, self.current_plot = _Sink(), _Sink()
        self.plots = _SimulatedPlots(self)
        self.controller_md = _Sink()
        self.cid, self.token = -1, None
        self.plot_newest = None
        self.pace = PagePace(object())  # no page: never held back


    def __getattr__(self, name: str):  # status, readout, legends ...: nothing to show
        return _NoOp()


class _NoOp:
    """Any call or attribute, at any depth, does nothing."""

    def __call__(self, *a, **k) -> None:
        return None

    def __getattr__(self, name: str) -> _NoOp:
        return self


class _SimulatedPlots(_NoOp):
    """The panel's plots: keep what the plot thread shows (x, reference, measurement, envelope);
    everything else does nothing."""

    def __init__(self, viewer: _SimulatedViewer) -> None:
        self.viewer = viewer

    def show_live(self, speed: tuple, current: tuple) -> None:
        self.viewer.speed_plot.data, self.viewer.current_plot.data = speed, current


def server_side_latency(hub_port: int, steps: int) -> list[float]:
    """In this process: setpoint command → the speed plot's data ends at the new setpoint (ms).

    The same app as the command (FastAPI lifespan + viser GUI) on the running hub; a viewer is
    simulated so that plots are pushed. Separates the server's share from the browser's.
    """
    from fastapi.testclient import TestClient

    from dashboard.app import create_app
    from dashboard.config import BenchConfig

    out = []
    cfg = BenchConfig(join_hub=hub_port, gui_port=0, api_port=free_port(), scene_3d=False)
    with TestClient(create_app(cfg)) as client:
        gui, bench = client.app.state.gui, client.app.state.bench
        gui.panels[-1] = _SimulatedViewer(bench)  # one (simulated) viewer: plots are pushed
        bench.drive.enable(timeout=2.0)
        time.sleep(1.0)
        for k in range(steps):
            target = 500.0 if k % 2 == 0 else 0.0
            t0 = time.monotonic()
            bench.set_speed(target)
            while time.monotonic() - t0 < 1.0:
                d = gui.panels[-1].speed_plot.data
                if len(d[1]) and abs(d[1][-1] - target) < 0.5:
                    break
                time.sleep(0.0005)
            out.append((time.monotonic() - t0) * 1e3)
            time.sleep(0.5)
        bench.drive.disable()
    return out


#: counts WebGL draw calls (the 3D canvas's rendering work) and animation frames in the page
GL_COUNT_JS = """
(() => {
  window.__gl = 0;
  for (const P of [WebGLRenderingContext.prototype, WebGL2RenderingContext.prototype]) {
    for (const f of ['drawElements', 'drawArrays', 'drawElementsInstanced',
                     'drawArraysInstanced']) {
      const orig = P[f];
      if (orig) P[f] = function (...a) { window.__gl++; return orig.apply(this, a); };
    }
  }
})();
"""


def browser_pids(browser) -> list[int]:
    """Every process of one Playwright-launched Chromium (browser, renderers, GPU, utility)."""
    cdp = browser.new_browser_cdp_session()
    try:
        info = cdp.send("SystemInfo.getProcessInfo")["processInfo"]
    finally:
        cdp.detach()
    return [int(p["id"]) for p in info]


def cpu_of(pids: list[int]) -> float:
    """utime + stime (s) summed over ``pids`` (processes gone meanwhile count 0)."""
    total = 0.0
    for pid in pids:
        with contextlib.suppress(OSError):
            total += cpu_seconds(pid)
    return total


def rotor_figures(page, browser, dash_pid: int, window: float, frames: list) -> str:
    """Server CPU, browser CPU, WebGL draw calls/s and rotor scene messages/s over ``window``
    s, each with the load average (1 min) at its end; one line of text."""
    pids = browser_pids(browser)
    n_frames = len(frames)
    gl0 = page.evaluate("window.__gl")
    s0, b0, w0 = cpu_seconds(dash_pid), cpu_of(pids), time.monotonic()
    page.wait_for_timeout(window * 1e3)
    dt = time.monotonic() - w0
    server = (cpu_seconds(dash_pid) - s0) / dt * 100
    chromium = (cpu_of(pids) - b0) / dt * 100
    gl = (page.evaluate("window.__gl") - gl0) / dt
    scene = sum(scene_messages(decode_frame(pl)) for _, pl in frames[n_frames:]) / dt
    return (
        f"server {server:.1f} % · browser {chromium:.1f} % (all its processes) · "
        f"{gl:.0f} WebGL draws/s · {scene:.1f} rotor scene messages/s "
        f"[load {os.getloadavg()[0]:.1f}]"
    )


def scene_messages(messages: list[dict]) -> int:
    """How many of ``messages`` create, change or remove a node of the 3D rotor view."""
    return sum(1 for m in messages if str(m.get("name", "")).startswith(ROTOR_PREFIXES))


ROTOR_PREFIXES = ("/motor", "/rotor", "/stator", "/floor", "/shaft", "/status", "/legend")


def rotor_cost(window: float) -> list[str]:
    """The 3D rotor's cost with one browser streaming the live plots at 500 rpm: dashboard with
    the rotor shown, hidden (the page's "3D rotor" checkbox off) and without it (``--no-3d``).
    Returns the lines to print (a virtual drive of its own, as :func:`main`)."""
    from playwright.sync_api import sync_playwright

    from dashboard.browser import click as click_el

    hub_port = free_port()
    drive = subprocess.Popen(
        [sys.executable, "-m", "virtual_drive.cli", "run", "--hub", "--hub-port", str(hub_port),
         "--log-level", "ERROR"],
        stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
    )
    lines = []
    try:
        assert "ready" in drive.stdout.readline(), "virtual drive did not start"
        for variant in ("3d", "no-3d"):
            extra = ["--show-3d"] if variant == "3d" else ["--no-3d"]
            with run_dashboard(["--join-hub", str(hub_port), *extra]) as running, \
                    sync_playwright() as p:
                browser = launch(p)
                page = browser.new_page(viewport={"width": 1280, "height": 800})
                page.add_init_script(GL_COUNT_JS)
                frames: list[tuple[float, bytes]] = []

                def on_ws(ws, frames=frames):
                    if "/api/" not in ws.url:
                        ws.on("framereceived", lambda pl: isinstance(pl, bytes)
                              and frames.append((time.monotonic(), pl)))

                page.on("websocket", on_ws)
                page.goto(running.gui_url)
                page.get_by_role("button", name="Enable").wait_for(timeout=120_000)
                click_el(page, page.get_by_role("button", name="Enable"))
                page.wait_for_timeout(1000)
                click_el(page, page.get_by_role("button", name="+ step"))  # 500 rpm
                page.wait_for_timeout(3000)
                if variant == "3d":
                    lines.append("3D rotor shown:  " + rotor_figures(
                        page, browser, running.proc.pid, window, frames))
                    box = page.get_by_label("3D rotor", exact=True)
                    if box.count():
                        click_el(page, box)
                        page.wait_for_timeout(2000)
                        lines.append("3D rotor hidden: " + rotor_figures(
                            page, browser, running.proc.pid, window, frames))
                    else:
                        lines.append("3D rotor hidden: (this dashboard has no '3D rotor' toggle)")
                else:
                    lines.append("--no-3d:         " + rotor_figures(
                        page, browser, running.proc.pid, window, frames))
                browser.close()
    finally:
        stop_process(drive)
    head = (f"3D rotor cost, 1 browser streaming at 500 rpm, {window:.0f} s windows, "
            f"{os.cpu_count()} cores (server: the dashboard process; browser: every Chromium "
            "process, software WebGL):")
    return [head, *("  " + ln for ln in lines)]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=6, help="speed steps for the latency figure")
    ap.add_argument("--window", type=float, default=10.0, help="CPU / refresh window, s")
    ap.add_argument(
        "--3d",
        dest="scene",
        action="store_true",
        help="the 3D rotor shown on every page (--show-3d); by default the dashboard runs as "
        "users get it: the rotor's checkbox unchecked",
    )
    ap.add_argument(
        "--browsers", type=int, default=3, help="browsers for the many-viewer CPU figure"
    )
    ap.add_argument(
        "--rotor",
        action="store_true",
        help="only the 3D rotor's cost: shown vs hidden vs --no-3d (1 browser)",
    )
    ap.add_argument(
        "--plot-rate", type=float, metavar="HZ",
        help=f"drive-dashboard --plot-rate HZ (default: the dashboard's, {GUI_RATE_HZ:g})",
    )
    ap.add_argument(
        "--hogs", type=int, default=0,
        help="stress-ng --cpu N in a separate session meanwhile (the busy-host figures)",
    )
    args = ap.parse_args(argv)
    if args.rotor:
        print("\n".join(rotor_cost(args.window)))
        return 0
    from playwright.sync_api import sync_playwright

    hogs = None
    if args.hogs:
        hogs = subprocess.Popen(
            ["stress-ng", "--cpu", str(args.hogs), "--quiet"], start_new_session=True
        )
        time.sleep(2.0)
    load_start = os.getloadavg()[0]
    hub_port = free_port()
    drive = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "virtual_drive.cli",
            "run",
            "--hub",
            "--hub-port",
            str(hub_port),
            "--log-level",
            "ERROR",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
    )
    stack = contextlib.ExitStack()
    try:
        ready = drive.stdout.readline()
        assert "ready" in ready, f"virtual drive did not start: {ready!r}"
        args_dash = ["--join-hub", str(hub_port)] + (["--show-3d"] if args.scene else [])
        if args.plot_rate is not None:
            args_dash += ["--plot-rate", repr(args.plot_rate)]
        running = stack.enter_context(run_dashboard(args_dash))
        dash, url = running.proc, running.gui_url
        gui_port = int(url.rstrip("/").rsplit(":", 1)[1])
        time.sleep(2.0)
        c0, w0 = cpu_seconds(dash.pid), time.monotonic()
        time.sleep(args.window / 2)
        idle_cpu = (cpu_seconds(dash.pid) - c0) / (time.monotonic() - w0) * 100
        idle_load = os.getloadavg()[0]

        frames: list[tuple[int, bytes]] = []
        with sync_playwright() as p:
            browser = launch(p)
            page = browser.new_page(viewport={"width": 1280, "height": 800})
            page.add_init_script(INIT_JS)

            def on_ws(ws):
                if "/api/" in ws.url:
                    return

                def on_frame(payload):
                    # runs while Playwright waits (page.wait_for_timeout), so promptly
                    if isinstance(payload, (bytes, bytearray)):
                        frames.append((time.monotonic() * 1e3, bytes(payload)))

                ws.on("framereceived", on_frame)

            page.on("websocket", on_ws)
            t_open = time.monotonic()
            page.goto(url)
            enable = page.get_by_role("button", name="Enable")
            enable.wait_for(timeout=120_000)
            t_enable = time.monotonic() - t_open
            while len(page.evaluate(SPEED_CANVAS_DRAWS)) < 3 and time.monotonic() - t_open < 120:
                page.wait_for_timeout(20)  # first draw is the empty plot; then two with data
            t_usable = time.monotonic() - t_open
            usable_load = os.getloadavg()[0]

            def click(name: str) -> None:
                button = page.get_by_role("button", name=name)
                button.scroll_into_view_if_needed()
                box = button.bounding_box()
                page.mouse.click(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)

            click("Enable")
            page.wait_for_timeout(2000)
            offset = clock_offset(page)

            # --- refresh rate, server CPU and bytes on the socket while this browser streams
            d0 = len(page.evaluate(SPEED_CANVAS_DRAWS))
            s0 = bytes_sent(gui_port)
            c0, w0 = cpu_seconds(dash.pid), time.monotonic()
            page.wait_for_timeout(args.window * 1e3)
            stream_cpu = (cpu_seconds(dash.pid) - c0) / (time.monotonic() - w0) * 100
            s1 = bytes_sent(gui_port)
            socket_mbs = sum(v - s0.get(k, 0) for k, v in s1.items()) / (
                time.monotonic() - w0) / 1e6
            stream_load = os.getloadavg()[0]
            d1 = page.evaluate(SPEED_CANVAS_DRAWS)
            span_ms = d1[-1] - d1[d0] if len(d1) > d0 + 1 else float("nan")
            refresh_hz = (len(d1) - 1 - d0) / span_ms * 1e3 if span_ms > 0 else float("nan")

            # --- step-to-plot latency
            latencies = []
            target = 0.0
            for k in range(args.steps):
                sign = +1 if k % 2 == 0 else -1
                target += sign * 500.0
                n_frames = len(frames)
                n_clicks = len(page.evaluate("window.__clicks"))
                click("+ step" if sign > 0 else "− step")
                page.wait_for_timeout(1500)
                t_click = page.evaluate("window.__clicks")[n_clicks] + offset
                hit = next(
                    (t for t, pl in frames[n_frames:] if shows_setpoint(decode_frame(pl), target)),
                    None,
                )
                if hit is None:
                    print(f"step {k + 1}: no frame with speed* = {target:.0f} rpm found")
                    continue
                draws = [d + offset for d in page.evaluate(SPEED_CANVAS_DRAWS)]
                t_draw = next((d for d in draws if d >= hit), float("nan"))
                latencies.append(t_draw - t_click)
                print(
                    f"step {k + 1} to {target:+.0f} rpm: frame arrived "
                    f"{hit - t_click:6.1f} ms, drawn {t_draw - t_click:6.1f} ms after the click"
                )
                page.wait_for_timeout(1000)

            step_load = os.getloadavg()[0]

            # --- server CPU with more browsers streaming (one Chromium process each)
            more = [launch(p) for _ in range(max(0, args.browsers - 1))]
            for b in more:
                pg = b.new_page(viewport={"width": 1280, "height": 800})
                pg.goto(url)
                pg.get_by_role("button", name="Enable").wait_for(timeout=120_000)
            page.wait_for_timeout(3000)
            c0, w0 = cpu_seconds(dash.pid), time.monotonic()
            page.wait_for_timeout(args.window * 1e3)
            many_cpu = (cpu_seconds(dash.pid) - c0) / (time.monotonic() - w0) * 100
            many_load = os.getloadavg()[0]
            for b in more:
                b.close()
            browser.close()
        server_ms = server_side_latency(hub_port, args.steps)
    finally:
        stack.close()  # the dashboard first, then the drive and its hub
        stop_process(drive)
        if hogs is not None:
            stop_process(hogs)
    rotor = rotor_cost(args.window) if args.scene else []

    print()
    if args.hogs:
        print(f"busy host: stress-ng --cpu {args.hogs} in a separate session throughout")
    print(
        f"machine: {os.cpu_count()} cores, load average {load_start:.1f} at the start, "
        f"{os.getloadavg()[0]:.1f} at the end (other work on the machine skews every figure)"
    )
    if latencies:
        print(
            f"step-to-plot latency: median {statistics.median(latencies):.0f} ms, "
            f"max {max(latencies):.0f} ms over {len(latencies)} steps (goal <= 100 ms median, "
            f"<= 250 ms max) [load {step_load:.1f}]"
        )
    print(
        f"  of which server side (command -> plot data sent): median "
        f"{statistics.median(server_ms):.1f} ms, max {max(server_ms):.1f} ms"
    )
    print(
        f"speed plot refresh in the browser: {refresh_hz:.1f} Hz (goal >= 20 Hz) "
        f"[load {stream_load:.1f}]"
    )
    print(
        f"traffic to the one streaming tab: {socket_mbs:.3f} MB/s on the socket (kernel "
        f"tcp_info bytes_sent of the GUI port's connections; goal <= 0.5 MB/s) "
        f"[load {stream_load:.1f}]"
    )
    print(
        f"page usable (Enable visible, speed plot moving): {t_usable:.1f} s after opening "
        f"(Enable at {t_enable:.1f} s; goal <= 5 s idle, <= 15 s busy) [load {usable_load:.1f}]"
    )
    print(
        f"dashboard server CPU, % of one core: {idle_cpu:.1f} % with no browser (goal <= 5 %) "
        f"[load {idle_load:.1f}]; {stream_cpu:.1f} % with one browser streaming (goal <= 8 %) "
        f"[load {stream_load:.1f}]; {many_cpu:.1f} % with {max(1, args.browsers)} browsers "
        f"(goal <= 25 %) [load {many_load:.1f}]"
    )
    for ln in rotor:
        print(ln)
    return 0


if __name__ == "__main__":
    sys.exit(main())
