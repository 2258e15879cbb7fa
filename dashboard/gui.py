"""The viser GUI: drive state, speed and current plots, tuning, identification, captures, 3D rotor.

Layout (control panel, top to bottom): status, control buttons, live plots of speed and i_p with
their references (refreshed at ``config.gui_rate_hz``), then tabs Speed · Current · Tuning ·
Identify · Captures. Every action goes through :class:`dashboard.bench.Bench` and needs the
control lease; values shown after an action are the ones read back from the drive.
"""

from __future__ import annotations

import contextlib
import io
import secrets
import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import viser
import viser.uplot as uplot

from dashboard import experiments, tuning
from dashboard.bench import LIVE_SIGNALS, Bench, Capture
from dashboard.config import BenchConfig
from dashboard.export import capture_csv, capture_png
from dashboard.gui_scene import RotorScene
from dashboard.gui_scene import background as scene_background
from dashboard.models import CONTROLLER_TYPES
from dashboard.security import allowed_origins, origin_ok

WAKE_TIMEOUT_S = 0.030  #: after a setpoint change, wait at most this for the drive's new reference
SPEED_COLORS = ("#1f77b4", "#ff7f0e")
CURRENT_COLORS = ("#2ca02c", "#d62728")
MIN_SPAN_SPEED_RPM = 50.0  #: the speed plot's y axis spans at least this (rpm)
MIN_SPAN_I_P_A = 5.0  #: the i_p plot's y axis spans at least this (A)
BRAND_COLOR = (31, 97, 141)  #: steel blue: buttons, tabs, sliders


def _series(
    labels: tuple[str, ...], colors: tuple[str, ...], x_label: str
) -> tuple[uplot.Series, ...]:
    out: list[uplot.Series] = [uplot.Series(label=x_label)]
    for lab, col in zip(labels, colors, strict=False):
        out.append(uplot.Series(label=lab, stroke=col, width=1.5))
    return tuple(out)


def _span_series(label: str) -> uplot.Series:
    """An invisible series that only widens the y auto-scale (see :func:`min_span_envelope`)."""
    return uplot.Series(label=label, stroke="rgba(0,0,0,0)", width=0, points={"show": False})


def min_span_envelope(n: int, *series: np.ndarray, min_span: float) -> np.ndarray:
    """``n`` values whose first and last are the centre of ``series`` ∓ ``min_span``/2 (the
    centre snapped to ``min_span``/10 so the axis stays still at steady state), the rest the
    centre: drawn invisibly, it makes uPlot's y auto-scale at least ``min_span`` wide (units of
    the series) without hiding larger swings."""
    lo = min(float(np.min(c)) for c in series)
    hi = max(float(np.max(c)) for c in series)
    q = min_span / 10
    centre = round((lo + hi) / 2 / q) * q
    out = np.full(n, centre, dtype=np.float64)
    out[0], out[-1] = centre - min_span / 2, centre + min_span / 2
    return out


def _fmt(x: Any, spec: str = ".4g") -> str:
    try:
        f = float(x)
    except (TypeError, ValueError):
        return "–"
    return format(f, spec) if np.isfinite(f) else "–"


class BenchGui:
    """One viser server showing one :class:`Bench`."""

    def __init__(self, bench: Bench, config: BenchConfig) -> None:
        self.bench = bench
        self.config = config
        self.server: viser.ViserServer | None = None
        self.port = 0
        self._stop = threading.Event()
        self._wake = threading.Event()  # a setpoint changed: plot now, not at the next tick
        self._wake_target: tuple[str, float] | None = None  # (live signal, commanded value)
        self._threads: list[threading.Thread] = []
        self._tokens: dict[int, str] = {}  # viser client id -> lease token
        self._muted = 0  # >0 while the server itself sets input values (no echo)
        self.frames_sent = 0
        self.last_live: dict[str, np.ndarray] = {}

    # ------------------------------------------------------------------ lifecycle
    def start(self) -> None:
        # viser has no authentication: the GUI stays on loopback even when the API is remote.
        # Its URL banner prints even with verbose=False: keep stdout for the one URL we print.
        with contextlib.redirect_stdout(io.StringIO()):
            self.server = viser.ViserServer(
                host="127.0.0.1", port=self.config.gui_port, verbose=False
            )
        self.port = self.server.get_port()
        self.origins = allowed_origins("127.0.0.1", [self.port, self.config.api_port])
        self._guard_origin()
        self.server.gui.configure_theme(
            control_width="large",
            dark_mode=False,
            show_logo=False,
            show_share_button=False,  # it would open a public tunnel
            brand_color=BRAND_COLOR,
        )
        self.server.gui.main_panel.dock_right()
        self.server.on_client_connect(self._on_connect)
        self.server.on_client_disconnect(self._on_disconnect)
        self._build()
        self.bench.lease.on_change(self._on_lease_change)
        self.bench.listeners.append(self._on_bench_event)
        for target, name in ((self._plot_loop, "gui-plots"), (self._status_loop, "gui-status")):
            th = threading.Thread(target=target, name=name, daemon=True)
            th.start()
            self._threads.append(th)

    def stop(self) -> None:
        self._stop.set()
        self._wake.set()
        for th in self._threads:
            th.join(timeout=2.0)
        with contextlib.suppress(ValueError):
            self.bench.listeners.remove(self._on_bench_event)
        if self.server is not None:
            self.server.stop()

    # ------------------------------------------------------------------ clients and control
    def _on_connect(self, client: viser.ClientHandle) -> None:
        self._refresh_status()

    def _guard_origin(self) -> None:
        """Close a viser WebSocket opened from a foreign page (viser checks no Origin).

        Hooks viser's transport-level connect callback (private API of viser 1.1: the public
        ``on_client_connect`` fires only after the first camera message, and a foreign page
        could read the GUI and send clicks before that). Runs on viser's event loop before
        any message is sent to the new connection.
        """
        ws_server = self.server._websock_server

        async def guard(client_conn: Any) -> None:
            conn = ws_server._live_connections.get(client_conn.client_id)
            if conn is None:
                return
            origin = conn.request.headers.get("Origin") if conn.request is not None else None
            if not origin_ok(origin, self.origins):
                await conn.close(1008, "origin not allowed")

        ws_server.on_client_connect(guard)

    def _on_disconnect(self, client: viser.ClientHandle) -> None:
        self._tokens.pop(client.client_id, None)

    def _client_name(self, client_id: int | None) -> str:
        return f"browser #{client_id}"

    def _control(self, event: Any) -> bool:
        """True if the event's browser holds control (taking it when nobody does)."""
        cid = event.client_id
        token = self._tokens.get(cid)
        holder = self.bench.lease.holder
        if holder is not None and token is not None and holder.token == token:
            return True
        if holder is None:
            token = token or secrets.token_urlsafe(16)
            self._tokens[cid] = token
            self.bench.lease.acquire(self._client_name(cid), token=token)
            return True
        if event.client is not None:
            event.client.add_notification(
                "Watching",
                f"{holder.client} controls the bench. Press 'Take control' to take over.",
                auto_close_seconds=4.0,
                color="yellow",
            )
        return False

    def _take_control(self, event: Any) -> None:
        cid = event.client_id
        token = self._tokens.get(cid) or secrets.token_urlsafe(16)
        self._tokens[cid] = token
        self.bench.lease.acquire(self._client_name(cid), take_over=True, token=token)

    def _on_lease_change(self, old: Any, new: Any) -> None:
        if self.server is None:
            return
        if new is not None and old is not None and old.token != new.token:
            for client in self.server.get_clients().values():
                client.add_notification(
                    "Control taken over",
                    f"{new.client} took control from {old.client}.",
                    auto_close_seconds=6.0,
                    color="orange",
                )
        self._refresh_status()

    def _action(
        self, fn: Callable[[Any], Any], *, needs_control: bool = True
    ) -> Callable[[Any], None]:
        """Wrap a GUI callback: lease check, errors shown as a notification to that browser."""

        def cb(event: Any) -> None:
            if self._muted:
                return
            if needs_control and not self._control(event):
                return
            try:
                fn(event)
            except Exception as exc:
                if event.client is not None:
                    event.client.add_notification(
                        "Refused",
                        str(exc) or type(exc).__name__,
                        auto_close_seconds=8.0,
                        color="red",
                    )
            self._refresh_status()

        return cb

    @contextlib.contextmanager
    def _mute(self):
        self._muted += 1
        try:
            yield
        finally:
            self._muted -= 1

    # ------------------------------------------------------------------ layout
    def _build(self) -> None:
        gui = self.server.gui
        self.status_md = gui.add_markdown("connecting …")
        self.controller_md = gui.add_markdown("")
        self.take_btn = gui.add_button(
            "Take control", color="orange", hint="Take control from the holder"
        )
        self.take_btn.on_click(self._action(self._take_control, needs_control=False))
        with gui.add_folder("Drive"):
            for label, cmd, color in (
                ("Enable", "enable", "green"),
                ("Disable", "disable", "gray"),
                ("Quick stop", "quick_stop", "red"),
                ("Fault reset", "fault_reset", "yellow"),
            ):
                b = gui.add_button(label, color=color)
                b.on_click(self._action(lambda e, c=cmd: self.bench.command(c)))
        self.speed_plot = self._live_plot(
            "Speed", ("speed (rpm)", "speed* (rpm)"), SPEED_COLORS, MIN_SPAN_SPEED_RPM, "rpm"
        )
        self.current_plot = self._live_plot(
            "Pseudo current i_p", ("i_p (A)", "i_p* (A)"), CURRENT_COLORS, MIN_SPAN_I_P_A, "A"
        )
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
        self.scene = RotorScene(self.server) if self.config.scene_3d else None
        if self.scene is None:  # a calm canvas instead of an empty white one
            self.server.scene.set_background_image(scene_background())
            self.server.scene.add_label(
                "/no_3d", "3D rotor view off (--no-3d)", position=(0.0, 0.0, 0.0)
            )

    def _live_plot(
        self,
        title: str,
        labels: tuple[str, str],
        colors: tuple[str, str],
        min_span: float,
        unit: str,
    ) -> Any:
        """A live uPlot of (t, measured, reference) over the last ``live_window_s`` seconds."""
        x0 = np.linspace(-self.config.live_window_s, 0.0, 2)
        zero = np.zeros(2)
        # the live window always ends at t = 0: a fixed x range (zoom still works) instead of
        # auto-scaling, which sometimes left a plot stuck on a stale x range in the browser
        live_x = {"x": uplot.Scale(time=False, range=(-self.config.live_window_s, 0.0))}
        return self.server.gui.add_uplot(
            (x0, zero, zero, zero),
            (*_series(labels, colors, "t (s)"), _span_series(f"y span ≥ {min_span:g} {unit}")),
            scales=live_x,
            axes=(uplot.Axis(label="t (s)"), uplot.Axis()),
            title=title,
            aspect=2.2,
        )

    def _build_speed_tab(self) -> None:
        gui = self.server.gui
        self.speed_in = gui.add_number("Speed setpoint (rpm)", 0.0, min=-4000, max=4000, step=10)
        gui.add_button("Set speed").on_click(
            self._action(lambda e: self.bench.set_speed(self.speed_in.value))
        )
        self.step_size = gui.add_number("Step size (rpm)", 500.0, min=1, max=4000, step=10)
        row = gui.add_button("+ step")
        row.on_click(self._action(lambda e: self._step(+1)))
        gui.add_button("− step").on_click(self._action(lambda e: self._step(-1)))
        self.sequence_in = gui.add_text(
            "Sequence (s:rpm, …)",
            "0:1000, 3:1500, 6:1000, 9:0",
            hint="time after start in s : setpoint in rpm",
        )
        gui.add_button("Run sequence").on_click(self._action(self._run_sequence))
        gui.add_button("Stop sequence").on_click(self._action(lambda e: self.bench.stop_sequence()))
        self.load_in = gui.add_number("Load torque (N·m)", 0.0, min=-20, max=20, step=0.1)
        b = gui.add_button(
            "Apply load step",
            disabled=not self.bench.virtual,
            hint="virtual drive only: sim_load.T_load",
        )
        b.on_click(self._action(lambda e: self.bench.set_load(self.load_in.value)))

    def _step(self, sign: int) -> None:
        rpm = self.bench.step_speed(sign * float(self.step_size.value))
        with self._mute():
            self.speed_in.value = rpm

    def _run_sequence(self, event: Any) -> None:
        steps = []
        for part in self.sequence_in.value.split(","):
            if not part.strip():
                continue
            at, _, rpm = part.partition(":")
            steps.append((float(at), float(rpm)))
        if not steps or [s[0] for s in steps] != sorted(s[0] for s in steps):
            raise ValueError("sequence: give 'time:rpm' pairs in time order")
        if any(abs(r) > 4000 or t < 0 for t, r in steps):
            raise ValueError("sequence: rpm within ±4000 and times ≥ 0")
        self.bench.start_sequence(steps)

    def _build_current_tab(self) -> None:
        gui = self.server.gui
        self.i_in = gui.add_number("i_p* (A)", 0.0, min=-200, max=200, step=0.5)
        gui.add_button("Set current").on_click(
            self._action(lambda e: self.bench.set_current(self.i_in.value))
        )
        with gui.add_folder("Current step test (Fig. 13)"):
            self.step_from = gui.add_number("From (A)", 15.0, min=-200, max=200, step=0.5)
            self.step_to = gui.add_number("To (A)", 20.0, min=-200, max=200, step=0.5)
            self.avg_n = gui.add_number("Moving average (samples)", 1, min=1, max=1000, step=1)
            gui.add_button("Run current step").on_click(self._action(self._current_step))
            self.step_md = gui.add_markdown("")
            self.step_plot = gui.add_uplot(
                (np.zeros(2), np.zeros(2), np.zeros(2), np.zeros(2), np.zeros(2)),
                _series(
                    ("i_p", "ī_p", "i_p*", "model"),
                    ("#2ca02c", "#9467bd", "#d62728", "#7f7f7f"),
                    "t (ms)",
                ),
                scales={"x": uplot.Scale(time=False, auto=True)},
                title="Current step at 50 kHz",
                aspect=2.0,
            )

    def _current_step(self, event: Any) -> None:
        from dashboard.models import CurrentStepIn

        body = CurrentStepIn(from_A=self.step_from.value, to_A=self.step_to.value, duration_ms=2.0)
        res = experiments.current_step(self.bench, body, average_samples=int(self.avg_n.value))
        self._show_step(res)

    def _show_step(self, res: dict) -> None:
        cap: Capture = self.bench.captures[res["capture"]["id"]]
        c = cap.columns
        self.step_plot.data = (
            c["t"] * 1e3,
            c["i_p"],
            c["i_p_avg"],
            c["i_p_ref"],
            c["model"],
        )
        m = res["metrics"]
        self.step_md.content = (
            f"**{res['controller']}**: rise {_fmt(m.get('rise_time_s', np.nan) * 1e6, '.0f')} µs · "
            f"settling {_fmt(m.get('settling_time_s', np.nan) * 1e6, '.0f')} µs · "
            f"overshoot {_fmt(m.get('overshoot_pct'), '.1f')} % · "
            f"steady-state error {_fmt(m.get('steady_state_error_A'), '.3f')} A · "
            f"model RMS error {_fmt(res.get('model_rms_error_A'), '.3f')} A"
        )

    def _build_tuning_tab(self) -> None:
        gui = self.server.gui
        self.type_in = gui.add_dropdown(
            "Current controller", tuple(CONTROLLER_TYPES), initial_value="deadbeat"
        )
        self.Lc_uH = gui.add_number("L_c (µH)", 14.8, min=0.01, max=2000.0, step=0.01)
        self.Lc_ratio = gui.add_number("L_c / L", 1.0, min=0.001, max=3.0, step=0.001)
        self.Rc_mOhm = gui.add_number("R_c (mΩ)", 6.2, min=0.0, max=1000.0, step=0.01)
        self.kp_i = gui.add_number("PI k_p (V/A)", 0.4647, min=0.0, max=100.0, step=0.0001)
        self.ki_i = gui.add_number("PI k_i (V/A)", 0.0492, min=0.0, max=100.0, step=0.0001)
        self.kp_w = gui.add_number("IP k_p (A/rpm)", 0.2113, min=0.0, max=100.0, step=0.0001)
        self.ki_w = gui.add_number("IP k_i (1/sample)", 2.9994e-5, min=0.0, max=1.0, step=1e-9)
        with gui.add_folder("IP design from ξ, ω_n (eqs. 28–31)", expand_by_default=False):
            self.xi_in = gui.add_number("ξ", 1.0, min=0.01, max=10.0, step=0.01)
            self.wn_in = gui.add_number("ω_n (rad/s)", 2.3, min=0.01, max=1000.0, step=0.01)
            self.a_in = gui.add_number("a", 0.9999785, min=0.0, max=0.99999999, step=1e-7)
            self.b_in = gui.add_number(
                "b (rpm/A per sample)", 3.33715e-4, min=1e-9, max=1.0, step=1e-9
            )
            gui.add_button("Compute IP gains").on_click(
                self._action(self._design_ip, needs_control=False)
            )
        self.preview_md = gui.add_markdown("")
        self.force_in = gui.add_checkbox(
            "Override margin check",
            False,
            hint="apply a stable set with poor margins (L_c > 1.5 L, GM < 2 dB or ‖S‖∞ > 5); "
            "an unstable set is refused regardless",
        )
        gui.add_button("Apply gains", color="green").on_click(self._action(self._apply_gains))
        gui.add_button("Read back").on_click(
            self._action(lambda e: self._load_gains(), needs_control=False)
        )
        self.readback_md = gui.add_markdown("")
        gui.add_button("Store to drive").on_click(self._action(self._store))
        self.diff_md = gui.add_markdown("")
        for h in (self.type_in, self.Rc_mOhm, self.kp_i, self.ki_i, self.kp_w, self.ki_w):
            h.on_update(self._action(lambda e: self._preview(), needs_control=False))
        self.Lc_uH.on_update(self._action(self._on_Lc_uH, needs_control=False))
        self.Lc_ratio.on_update(self._action(self._on_Lc_ratio, needs_control=False))

    def _motor_L(self) -> float:
        return (
            float(self.gains.get("motor_L", 14.8e-6)) if getattr(self, "gains", None) else 14.8e-6
        )

    def _on_Lc_uH(self, event: Any) -> None:
        with self._mute():
            self.Lc_ratio.value = round(self.Lc_uH.value * 1e-6 / self._motor_L(), 6)
        self._preview()

    def _on_Lc_ratio(self, event: Any) -> None:
        with self._mute():
            self.Lc_uH.value = round(self.Lc_ratio.value * self._motor_L() * 1e6, 6)
        self._preview()

    def _changes(self) -> dict[str, float | int]:
        return {
            "type": CONTROLLER_TYPES[self.type_in.value],
            "L_c": float(self.Lc_uH.value) * 1e-6,
            "R_c": float(self.Rc_mOhm.value) * 1e-3,
            "k_p": float(self.kp_i.value),
            "k_i": float(self.ki_i.value),
            "speed_k_p": float(self.kp_w.value),
            "speed_k_i": float(self.ki_w.value),
        }

    def _preview(self) -> None:
        try:
            p = tuning.preview(self.bench, self._changes())
        except Exception as exc:
            self.preview_md.content = f"**Not applicable:** {exc}"
            return
        self.preview_md.content = tuning.preview_markdown(p)

    def _apply_gains(self, event: Any) -> None:
        tuning.apply(self.bench, self._changes(), force=bool(self.force_in.value))
        with self._mute():
            self.force_in.value = False  # an override is for one apply only
        self._load_gains()

    def _store(self, event: Any) -> None:
        tuning.store(self.bench)
        self._show_diff()

    def _design_ip(self, event: Any) -> None:
        d = tuning.design_ip(
            self.bench, self.xi_in.value, self.wn_in.value, self.a_in.value, self.b_in.value
        )
        with self._mute():
            self.kp_w.value = float(d["speed_k_p"])
            self.ki_w.value = float(d["speed_k_i"])
        self._preview()

    def _load_gains(self) -> None:
        """Show the gains read back from the drive and put them into the inputs."""
        g = tuning.read_gains(self.bench)
        self.gains = g
        with self._mute():
            self.type_in.value = g["type"]
            self.Lc_uH.value = round(g["L_c"] * 1e6, 6)
            self.Lc_ratio.value = round(g["L_c"] / g["motor_L"], 6)
            self.Rc_mOhm.value = round(g["R_c"] * 1e3, 6)
            self.kp_i.value = g["k_p"]
            self.ki_i.value = g["k_i"]
            self.kp_w.value = g["speed_k_p"]
            self.ki_w.value = g["speed_k_i"]
        self.readback_md.content = tuning.readback_markdown(g)
        self._preview()
        self._show_diff()

    def _show_diff(self) -> None:
        try:
            self.diff_md.content = tuning.diff_markdown(tuning.stored_diff(self.bench))
        except Exception as exc:
            self.diff_md.content = f"stored values: {exc}"

    def _build_identify_tab(self) -> None:
        gui = self.server.gui
        gui.add_markdown(
            "Current step in current mode; fit G(z) = b/(z − a) to the speed (Fig. 16)."
        )
        self.id_from = gui.add_number("Identify from (A)", 15.0, min=-200, max=200, step=0.5)
        self.id_to = gui.add_number("Identify to (A)", 30.0, min=-200, max=200, step=0.5)
        self.id_dur = gui.add_number("Duration (s)", 1.0, min=0.05, max=20.0, step=0.05)
        gui.add_button("Run identification").on_click(self._action(self._identify))
        self.id_md = gui.add_markdown("")
        self.id_plot = gui.add_uplot(
            (np.zeros(2), np.zeros(2), np.zeros(2)),
            _series(("speed (rpm)", "model (rpm)"), ("#1f77b4", "#7f7f7f"), "t (s)"),
            scales={"x": uplot.Scale(time=False, auto=True)},
            title="Identification: data and fit",
            aspect=2.0,
        )
        gui.add_button("Use a, b in IP design").on_click(
            self._action(self._use_identified, needs_control=False)
        )

    def _identify(self, event: Any) -> None:
        from dashboard.models import IdentifyIn

        res = experiments.identify(
            self.bench,
            IdentifyIn(
                from_A=self.id_from.value, to_A=self.id_to.value, duration_s=self.id_dur.value
            ),
        )
        cap = self.bench.captures[res["capture"]["id"]]
        c = cap.columns
        self.id_plot.data = (c["t"], c["speed"], c["model"])
        self.id_md.content = (
            f"a = **{res['a']:.8f}**, b = **{res['b']:.6g}** rpm/(A·sample) at Ts = 20 µs · "
            f"fit RMS error {_fmt(res['rms_error_rpm'], '.3g')} rpm"
        )

    def _use_identified(self, event: Any) -> None:
        ident = self.bench.identified
        if not ident:
            raise ValueError("run an identification first")
        with self._mute():
            self.a_in.value = float(ident["a"])
            self.b_in.value = float(ident["b"])
        self._design_ip(event)

    def _build_captures_tab(self) -> None:
        gui = self.server.gui
        self.cap_dd = gui.add_dropdown("Capture", ("none",), initial_value="none")
        gui.add_button("Download CSV").on_click(
            self._action(lambda e: self._download(e, "csv"), needs_control=False)
        )
        gui.add_button("Download PNG").on_click(
            self._action(lambda e: self._download(e, "png"), needs_control=False)
        )
        with gui.add_folder("Trace (i_p at 50 kHz)"):
            self.tr_len = gui.add_number("Length (samples)", 1000, min=2, max=8192, step=1)
            self.tr_div = gui.add_number("Divider", 1, min=1, max=5000, step=1)
            gui.add_button("Capture now").on_click(self._action(self._capture_now))

    def _capture_now(self, event: Any) -> None:
        from dashboard.models import TraceIn

        experiments.capture(
            self.bench,
            TraceIn(length=int(self.tr_len.value), divider=int(self.tr_div.value), pre_trigger=0),
        )

    def _download(self, event: Any, fmt: str) -> None:
        if self.cap_dd.value == "none" or event.client is None:
            raise ValueError("no capture yet")
        cap = self.bench.captures[int(self.cap_dd.value.split(" ")[0].lstrip("#"))]
        data = capture_csv(cap) if fmt == "csv" else capture_png(cap)
        event.client.send_file_download(
            f"capture_{cap.id}_{cap.kind}.{fmt}", data, save_immediately=True
        )

    # ------------------------------------------------------------------ updates
    def _on_bench_event(self, kind: str, data: dict) -> None:
        if kind == "capture":
            opts = tuple(f"#{c.id} {c.kind}" for c in self.bench.captures.values())
            self.cap_dd.options = opts
            with self._mute():
                self.cap_dd.value = opts[-1]
        elif kind == "gains":
            with contextlib.suppress(Exception):
                self._load_gains()
        elif kind == "setpoint":
            if "rpm" in data:
                self._wake_target = ("measurements.speed_ref", float(data["rpm"]))
            elif "i_p_ref" in data:
                self._wake_target = ("measurements.i_p_ref", float(data["i_p_ref"]))
            self._wake.set()
            with self._mute():
                if "rpm" in data:
                    self.speed_in.value = float(data["rpm"])
                if "i_p_ref" in data:
                    self.i_in.value = float(data["i_p_ref"])
        elif kind == "error" and self.server is not None:
            for client in self.server.get_clients().values():
                client.add_notification(
                    "Bench", data.get("message", ""), auto_close_seconds=6.0, color="red"
                )

    def _plot_loop(self) -> None:
        """Push the live window to both plots at gui_rate_hz, and at once after a setpoint
        change: as soon as the drive streams the new reference back (at most WAKE_TIMEOUT_S)."""
        period = 1.0 / self.config.gui_rate_hz
        next_t = time.monotonic()
        while not self._stop.is_set():
            if self._wake.wait(max(0.0, next_t - time.monotonic())):
                self._wake.clear()
                self._push_after_setpoint()
                next_t = time.monotonic() + period
                continue
            self._push_plots()
            next_t += period
            if time.monotonic() - next_t > 1.0:
                next_t = time.monotonic()

    def _push_after_setpoint(self) -> None:
        """Push as soon as the plotted window ends with the commanded reference (the drive
        streams it back within a few ms), at most WAKE_TIMEOUT_S after the setpoint change."""
        target = self._wake_target
        deadline = time.monotonic() + WAKE_TIMEOUT_S
        while target is not None and time.monotonic() < deadline and not self._stop.is_set():
            if self._push_plots(require=target):
                return
            time.sleep(0.001)
        self._push_plots()

    def _push_plots(self, require: tuple[str, float] | None = None) -> bool:
        """Send the live window to both plots; with ``require`` = (signal, value) only if the
        window's last sample of that signal equals value. Returns whether it sent."""
        if self.server is None or not self.server.get_clients():
            return True  # nobody watches: no work
        names = list(LIVE_SIGNALS)
        try:
            w = self.bench.drive.live.window(self.config.live_window_s, names)
        except Exception:
            return True
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
        x = t - t[-1]
        n = len(x)
        speed_env = min_span_envelope(n, cols[0], cols[1], min_span=MIN_SPAN_SPEED_RPM)
        current_env = min_span_envelope(n, cols[2], cols[3], min_span=MIN_SPAN_I_P_A)
        self.speed_plot.data = (x, cols[0], cols[1], speed_env)
        self.current_plot.data = (x, cols[2], cols[3], current_env)
        self.frames_sent += 1
        self.last_live = w
        if self.scene is not None:
            self.scene.update(float(cols[0][-1]), w)
        return True

    def _status_loop(self) -> None:
        loaded = False
        while not self._stop.wait(0.25):
            if not loaded:  # the gains read back once at start (retried until it works)
                try:
                    self._load_gains()
                    loaded = True
                except Exception:
                    pass
            self._refresh_status()

    def _refresh_status(self) -> None:
        if self.server is None:
            return
        try:
            s = self.bench.state()
        except Exception as exc:
            self.status_md.content = f"**state unavailable:** {exc}"
            return
        live = s.get("live") or {}
        load = live.get("bus_load")
        latest = {}
        with contextlib.suppress(Exception):
            latest = self.bench.drive.live.latest()
        emcy = s.get("emcy") or []
        emcy_txt = (
            ", ".join(
                f"0x{int(e.get('code', 0)):04X} {e.get('text', '')}".strip() for e in emcy[-3:]
            )
            or "none"
        )
        hb = s.get("heartbeat_age_s")
        self.status_md.content = (
            f"**Bus** {s['bus']} · **node** {s['node_id']}  \n"
            f"**NMT** {s.get('nmt_state')} · **402** {s.get('state')} · "
            f"**mode** {s.get('mode')}  \n"
            f"**speed** {_fmt(latest.get('measurements.speed'), '.1f')} rpm "
            f"(set {_fmt(s['speed_setpoint'], '.0f')}) · "
            f"**i_p** {_fmt(latest.get('measurements.i_p'), '.2f')} A  \n"
            f"**heartbeat age** {_fmt(hb * 1e3 if hb is not None else None, '.0f')} ms · "
            f"**bus load** {_fmt(load * 100 if load is not None else None, '.1f')} % · "
            f"**dropped** {live.get('dropped', '–')} · **faults/EMCY** {emcy_txt}"
        )
        if self.scene is not None:
            self.scene.show_status(
                f"{_fmt(latest.get('measurements.speed'), '.0f')} rpm · {s.get('state')} · "
                f"i_p {_fmt(latest.get('measurements.i_p'), '.1f')} A"
            )
        ctl = s.get("controller")
        self.controller_md.content = (
            f"**In control:** {ctl['client']} since "
            f"{time.strftime('%H:%M:%S', time.localtime(ctl['since']))}"
            if ctl
            else "**In control:** nobody (the first action takes control)"
        )
