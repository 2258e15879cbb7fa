"""One browser's panel: its own inputs (viser ``client.gui``), plots, notices and lease token.

Every browser gets its own handles, so what one browser types never appears in another, and an
action applies exactly the values of the browser that pressed the button (and only if that
browser holds the control lease). Typed numbers are text fields parsed strictly
(:mod:`dashboard.fields`): an invalid entry shows a message right under the field and nothing is
sent. After Apply or Read back the fields show the drive's read-back. Notices appear under the
control that caused them. Units: rpm, A, µH, mΩ, V/A, A/rpm, 1/sample, N·m, s.
"""

from __future__ import annotations

import contextlib
import html
import secrets
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
import viser
import viser.uplot as uplot

from dashboard import experiments, tuning
from dashboard.fields import FieldError, NumberSpec, show
from dashboard.models import CONTROLLER_TYPES, CurrentStepIn, IdentifyIn, TraceIn
from dashboard.security import token_ok

if TYPE_CHECKING:
    from dashboard.gui import BenchGui

SPEED_COLORS = ("#1f77b4", "#ff7f0e")
CURRENT_COLORS = ("#2ca02c", "#d62728")

#: hides the legend row of the invisible min-span helper series (4th row, last, of a live plot)
LEGEND_CSS = "<style>.uplot .u-legend tr.u-series:nth-child(4):last-child{display:none}</style>"


def _fmt(x: Any, spec: str = ".4g") -> str:
    try:
        f = float(x)
    except (TypeError, ValueError):
        return "–"
    return format(f, spec) if np.isfinite(f) else "–"


def _series(labels: tuple[str, ...], colors: tuple[str, ...], x_label: str) -> list[Any]:
    out: list[Any] = [uplot.Series(label=x_label)]
    for lab, col in zip(labels, colors, strict=False):
        out.append(uplot.Series(label=lab, stroke=col, width=1.5))
    return out


class Field:
    """A typed number: a text input plus a message line under it (hidden while valid)."""

    def __init__(self, panel: Panel, spec: NumberSpec, initial: float, hint: str = "") -> None:
        self.panel = panel
        self.spec = spec
        self.input = panel.gui.add_text(spec.label, show(initial), hint=hint or None)
        self.error = panel.gui.add_markdown("", visible=False)
        self.input.on_update(lambda e: self.validate())

    def validate(self) -> bool:
        try:
            self.spec.parse(self.input.value)
        except FieldError as exc:
            self._show_error(str(exc))
            return False
        self._show_error("")
        return True

    def _show_error(self, text: str) -> None:
        if text:
            self.error.content = f"⚠ {text} — nothing sent"
            self.error.visible = True
        elif self.error.visible:
            self.error.visible = False
            self.error.content = ""

    def value(self) -> float:
        """The typed value, exactly; FieldError (shown at the field) otherwise."""
        try:
            v = self.spec.parse(self.input.value)
        except FieldError as exc:
            self._show_error(str(exc))
            raise
        self._show_error("")
        return v

    def set(self, x: float) -> None:
        """Show ``x`` (a read-back) in the field without firing its callbacks' echo."""
        with self.panel.mute():
            self.input.value = show(x)
        self._show_error("")


class Panel:
    """The GUI of one connected browser."""

    def __init__(self, owner: BenchGui, client: viser.ClientHandle) -> None:
        self.owner = owner
        self.bench = owner.bench
        self.config = owner.config
        self.client = client
        self.cid = client.client_id
        self.gui = client.gui
        self.token: str | None = None  # this browser's lease token once it took control
        self.authenticated = self.config.token is None
        self._muted = 0
        self.gains: dict[str, Any] | None = None
        self.last_status = ""
        self.last_legends: tuple[str, str] = ("", "")
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
            except Exception as exc:
                self.notice(md, str(exc) or type(exc).__name__)
            else:
                self.notice(md, done if isinstance(done, str) else "")
            self.owner.refresh_status()

        return cb

    # ------------------------------------------------------------------ layout
    def _build(self) -> None:
        gui = self.gui
        gui.add_html(LEGEND_CSS)
        self.status_html = gui.add_html("connecting …")
        self.controller_md = gui.add_markdown("")
        if self.config.token is not None:
            self.token_in = gui.add_text(
                "Access token", "", hint="the bench's --token; needed to change anything"
            )
            gui.add_button("Sign in").on_click(lambda e: self._sign_in())
        self.take_btn = gui.add_button("Take control", color="orange")
        self.drive_btns = gui.add_button_group(
            "Drive", ("Enable", "Disable", "Quick stop", "Fault reset")
        )
        self.control_md = gui.add_markdown("", visible=False)
        self.take_btn.on_click(
            self.action(self._take_control, self.control_md, needs_control=False)
        )
        self.drive_btns.on_click(self.action(self._drive_button, self.control_md))
        self.action_html = gui.add_html("")
        self.cancel_btn = gui.add_button("Cancel action", color="red", visible=False)
        self.cancel_btn.on_click(self.action(self._cancel, self.control_md))
        self.speed_legend = gui.add_html("")
        self.speed_plot = self._live_plot("speed (rpm)", "rpm", SPEED_COLORS)
        self.current_legend = gui.add_html("")
        self.current_plot = self._live_plot("i_p (A)", "A", CURRENT_COLORS)
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

    def _live_plot(self, y_label: str, unit: str, colors: tuple[str, str]) -> Any:
        window = self.config.live_window_s
        x0 = np.linspace(-window, 0.0, 2)
        zero = np.zeros(2)
        name = y_label.split(" ")[0]  # the axis carries the unit, the legend the names
        return self.gui.add_uplot(
            (x0, zero, zero, zero),
            (
                *_series((f"{name} ({unit})", f"{name}* ({unit})"), colors, "t (s)"),
                uplot.Series(label="", stroke="rgba(0,0,0,0)", width=0, points={"show": False}),
            ),
            scales={"x": uplot.Scale(time=False, range=(-window, 0.0))},
            axes=(uplot.Axis(label="t (s)"), uplot.Axis(label=unit, size=60)),
            aspect=3.0,
        )

    def _build_speed_tab(self) -> None:
        gui = self.gui
        self.speed_in = Field(self, NumberSpec("Speed setpoint (rpm)", -4000, 4000), 0.0)
        btn = gui.add_button("Set speed")
        self.speed_md = self.md()
        btn.on_click(self.action(self._set_speed, self.speed_md))
        self.step_size = Field(self, NumberSpec("Step size (rpm)", 1, 4000), 500.0)
        self.step_btns = gui.add_button_group("Step", ("+ step", "− step"))
        self.stepbtn_md = self.md()
        self.step_btns.on_click(self.action(self._step, self.stepbtn_md))
        self.sequence_in = gui.add_text(
            "Sequence (s:rpm, …)",
            "0:1000, 3:1500, 6:1000, 9:0",
            hint="time after start in s : setpoint in rpm",
        )
        seq = gui.add_button_group("Sequence", ("Run sequence", "Stop sequence"))
        self.seq_md = self.md()
        seq.on_click(self.action(self._sequence_button, self.seq_md))
        self.load_in = Field(self, NumberSpec("Load torque (N·m)", -20, 20), 0.0)
        b = gui.add_button(
            "Apply load step",
            disabled=not self.bench.virtual,
            hint="virtual drive only: sim_load.T_load",
        )
        self.load_md = self.md()
        b.on_click(self.action(self._load, self.load_md))

    def md(self) -> Any:
        """A hidden notice line (shown by :meth:`notice`) right under the last control."""
        return self.gui.add_markdown("", visible=False)

    def _build_current_tab(self) -> None:
        gui = self.gui
        self.i_in = Field(self, NumberSpec("i_p* (A)", -200, 200), 0.0)
        btn = gui.add_button("Set current")
        self.current_md = self.md()
        btn.on_click(self.action(self._set_current, self.current_md))
        with gui.add_folder("Current step test (Fig. 13)"):
            self.step_from = Field(self, NumberSpec("From (A)", -200, 200), 15.0)
            self.step_to = Field(self, NumberSpec("To (A)", -200, 200), 20.0)
            self.avg_n = Field(
                self, NumberSpec("Moving average (samples)", 1, 1000, integer=True), 1
            )
            run = gui.add_button("Run current step")
            self.step_md = self.md()
            run.on_click(self.action(self._current_step, self.step_md))
            self.step_plot = gui.add_uplot(
                (np.zeros(2),) * 5,
                tuple(
                    _series(
                        ("i_p (A)", "ī_p (A)", "i_p* (A)", "model (A)"),
                        ("#2ca02c", "#9467bd", "#d62728", "#7f7f7f"),
                        "t (ms)",
                    )
                ),
                scales={"x": uplot.Scale(time=False, auto=True)},
                axes=(uplot.Axis(label="t (ms)"), uplot.Axis(label="i_p (A)", size=60)),
                title="Current step at 50 kHz",
                aspect=2.0,
            )

    def _build_tuning_tab(self) -> None:
        gui = self.gui
        # preview, Apply and its notice first: visible without scrolling
        self.preview_md = gui.add_markdown("")
        self.force_in = gui.add_checkbox(
            "Override margin check",
            False,
            hint="apply a stable set with poor margins (L_c > 1.5 L, GM < 2 dB or ‖S‖∞ > 5) "
            "once; an unstable set is refused regardless",
        )
        self.gain_btns = gui.add_button_group("Gains", ("Apply gains", "Read back", "Store"))
        self.tuning_md = gui.add_markdown("", visible=False)
        self.gain_btns.on_click(self.action(self._gain_button, self.tuning_md, needs_control=False))
        self.readback_md = gui.add_markdown("")
        self.type_in = gui.add_dropdown(
            "Current controller", tuple(CONTROLLER_TYPES), initial_value="deadbeat"
        )
        self.Lc_uH = Field(self, NumberSpec("L_c (µH)", 0.0, 2000.0, lo_open=True), 14.8)
        self.Lc_ratio = Field(self, NumberSpec("L_c / L", 0.0, 3.0, lo_open=True), 1.0)
        self.Rc_mOhm = Field(self, NumberSpec("R_c (mΩ)", 0.0, 1000.0), 6.2)
        self.kp_i = Field(self, NumberSpec("PI k_p (V/A)", 0.0, 100.0), 0.4647)
        self.ki_i = Field(self, NumberSpec("PI k_i (V/A)", 0.0, 100.0), 0.0492)
        self.kp_w = Field(self, NumberSpec("IP k_p (A/rpm)", 0.0, 100.0), 0.2113)
        self.ki_w = Field(self, NumberSpec("IP k_i (1/sample)", 0.0, 1.0), 2.9994e-5)
        with gui.add_folder("IP design from ξ, ω_n (eqs. 28–31)", expand_by_default=False):
            self.xi_in = Field(self, NumberSpec("ξ", 0.0, 10.0, lo_open=True), 1.0)
            self.wn_in = Field(self, NumberSpec("ω_n (rad/s)", 0.0, 1000.0, lo_open=True), 2.3)
            self.a_in = Field(self, NumberSpec("a", 0.0, 1.0, lo_open=True), 0.9999785)
            self.b_in = Field(
                self, NumberSpec("b (rpm/A per sample)", 0.0, 1.0, lo_open=True), 3.33715e-4
            )
            self.design_md = gui.add_markdown("", visible=False)
            gui.add_button("Compute IP gains").on_click(
                self.action(self._design_ip, self.design_md, needs_control=False)
            )
        self.diff_md = gui.add_markdown("")
        for f in (self.Rc_mOhm, self.kp_i, self.ki_i, self.kp_w, self.ki_w):
            f.input.on_update(lambda e: self._preview())
        self.type_in.on_update(lambda e: self._preview())
        self.Lc_uH.input.on_update(lambda e: self._on_Lc_uH())
        self.Lc_ratio.input.on_update(lambda e: self._on_Lc_ratio())

    def _build_identify_tab(self) -> None:
        gui = self.gui
        gui.add_markdown(
            "Current step in current mode; fit G(z) = b/(z − a) to the speed (Fig. 16). "
            "The drive is put back as found afterwards."
        )
        self.id_from = Field(self, NumberSpec("Identify from (A)", -200, 200), 15.0)
        self.id_to = Field(self, NumberSpec("Identify to (A)", -200, 200), 30.0)
        self.id_dur = Field(self, NumberSpec("Duration (s)", 0.0, 20.0, lo_open=True), 1.0)
        self.id_btns = gui.add_button_group("Identification", ("Run", "Use a, b in IP design"))
        self.id_md = gui.add_markdown("", visible=False)
        self.id_btns.on_click(self.action(self._identify_button, self.id_md, needs_control=False))
        self.id_plot = gui.add_uplot(
            (np.zeros(2), np.zeros(2), np.zeros(2)),
            tuple(_series(("speed (rpm)", "model (rpm)"), ("#1f77b4", "#7f7f7f"), "t (s)")),
            scales={"x": uplot.Scale(time=False, auto=True)},
            axes=(uplot.Axis(label="t (s)"), uplot.Axis(label="speed (rpm)", size=60)),
            title="Identification: data and fit",
            aspect=2.0,
        )

    def _build_captures_tab(self) -> None:
        gui = self.gui
        self.cap_dd = gui.add_dropdown("Capture", ("none",), initial_value="none")
        dl = gui.add_button_group("Download", ("CSV", "PNG"))
        self.cap_md = gui.add_markdown("", visible=False)
        dl.on_click(self.action(self._download, self.cap_md, needs_control=False))
        with gui.add_folder("Trace (i_p at 50 kHz)"):
            self.tr_len = Field(self, NumberSpec("Length (samples)", 2, 8192, integer=True), 1000)
            self.tr_div = Field(self, NumberSpec("Divider", 1, 5000, integer=True), 1)
            gui.add_button("Capture now").on_click(self.action(self._capture_now, self.cap_md))
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

    def _cancel(self, event: Any) -> str:
        return "cancelling …" if self.bench.cancel_action() else "no action under way"

    # ------------------------------------------------------------------ speed / current
    def _set_speed(self, event: Any) -> None:
        self.bench.set_speed(self.speed_in.value())

    def _step(self, event: Any) -> None:
        sign = 1.0 if event.target.value == "+ step" else -1.0
        rpm = self.bench.step_speed(sign * self.step_size.value())
        self.speed_in.set(rpm)

    def _sequence_button(self, event: Any) -> str:
        if event.target.value == "Stop sequence":
            self.bench.stop_sequence()
            return "sequence stopped (last setpoint kept)"
        steps = parse_sequence(self.sequence_in.value)
        self.bench.start_sequence(steps)
        return f"sequence of {len(steps)} steps started"

    def _load(self, event: Any) -> None:
        self.bench.set_load(self.load_in.value())

    def _set_current(self, event: Any) -> None:
        self.bench.set_current(self.i_in.value())

    def _current_step(self, event: Any) -> str:
        body = CurrentStepIn(
            from_A=self.step_from.value(), to_A=self.step_to.value(), duration_ms=2.0
        )
        avg = int(self.avg_n.value())
        res = experiments.current_step(self.bench, body, average_samples=avg)
        cap = self.bench.captures[res["capture"]["id"]]
        c = cap.columns
        self.step_plot.data = (c["t"] * 1e3, c["i_p"], c["i_p_avg"], c["i_p_ref"], c["model"])
        m = res["metrics"]
        return (
            f"**{res['controller']}**: rise {_fmt(m.get('rise_time_s', np.nan) * 1e6, '.0f')} µs · "
            f"settling {_fmt(m.get('settling_time_s', np.nan) * 1e6, '.0f')} µs · "
            f"overshoot {_fmt(m.get('overshoot_pct'), '.1f')} % · "
            f"steady-state error {_fmt(m.get('steady_state_error_A'), '.3f')} A · "
            f"model RMS error {_fmt(res.get('model_rms_error_A'), '.3f')} A"
        )

    # ------------------------------------------------------------------ tuning
    def motor_L(self) -> float:
        return float(self.gains.get("motor_L", 14.8e-6)) if self.gains else 14.8e-6

    def _on_Lc_uH(self) -> None:
        if self._muted or not self.Lc_uH.validate():
            return
        with self.mute():
            self.Lc_ratio.set(round(self.Lc_uH.value() * 1e-6 / self.motor_L(), 6))
        self._preview()

    def _on_Lc_ratio(self) -> None:
        if self._muted or not self.Lc_ratio.validate():
            return
        with self.mute():
            self.Lc_uH.set(round(self.Lc_ratio.value() * self.motor_L() * 1e6, 6))
        self._preview()

    def changes(self) -> dict[str, float | int]:
        """This browser's gain set in drive units; FieldError (shown at the fields) if any typed
        value is invalid: then nothing is sent."""
        fields = {
            "L_c": (self.Lc_uH, 1e-6),
            "R_c": (self.Rc_mOhm, 1e-3),
            "k_p": (self.kp_i, 1.0),
            "k_i": (self.ki_i, 1.0),
            "speed_k_p": (self.kp_w, 1.0),
            "speed_k_i": (self.ki_w, 1.0),
        }
        out: dict[str, float | int] = {"type": CONTROLLER_TYPES[self.type_in.value]}
        errors = []
        for key, (f, scale) in fields.items():
            try:
                out[key] = f.value() * scale
            except FieldError as exc:
                errors.append(str(exc))
        if not self.Lc_ratio.validate():
            errors.append("L_c / L is invalid")
        if errors:
            raise FieldError("; ".join(errors))
        return out

    def _preview(self) -> None:
        if self._muted:
            return
        try:
            p = tuning.preview(self.bench, self.changes())
        except FieldError:
            self.preview_md.content = "**Preview:** fix the marked fields"
            return
        except Exception as exc:
            self.preview_md.content = f"**Not applicable:** {exc}"
            return
        self.preview_md.content = tuning.preview_markdown(p)

    def _gain_button(self, event: Any) -> str | None:
        which = event.target.value
        if which == "Read back":
            self.load_gains()
            return "fields show the drive's read-back"
        if not self._control(self.tuning_md):
            return None
        if which == "Store":
            tuning.store(self.bench)
            self.show_diff()
            return "stored in the drive"
        changes = self.changes()  # FieldError → shown, nothing sent
        tuning.apply(self.bench, changes, force=bool(self.force_in.value))
        with self.mute():
            self.force_in.value = False  # an override is for one apply only
        self.load_gains()
        return "applied; the fields show the drive's read-back"

    def _design_ip(self, event: Any) -> str:
        d = tuning.design_ip(
            self.bench, self.xi_in.value(), self.wn_in.value(), self.a_in.value(), self.b_in.value()
        )
        self.kp_w.set(float(d["speed_k_p"]))
        self.ki_w.set(float(d["speed_k_i"]))
        self._preview()
        return "IP gains computed (not applied yet)"

    def load_gains(self, g: dict[str, Any] | None = None) -> None:
        """Put the drive's read-back gains into this browser's fields."""
        g = g or tuning.read_gains(self.bench)
        self.gains = g
        with self.mute():
            self.type_in.value = g["type"]
        self.Lc_uH.set(round(g["L_c"] * 1e6, 6))
        self.Lc_ratio.set(round(g["L_c"] / g["motor_L"], 6))
        self.Rc_mOhm.set(round(g["R_c"] * 1e3, 6))
        self.kp_i.set(g["k_p"])
        self.ki_i.set(g["k_i"])
        self.kp_w.set(g["speed_k_p"])
        self.ki_w.set(g["speed_k_i"])
        self.show_readback(g)
        self._preview()
        self.show_diff()

    def show_readback(self, g: dict[str, Any]) -> None:
        self.readback_md.content = tuning.readback_markdown(g)

    def show_diff(self) -> None:
        try:
            self.diff_md.content = tuning.diff_markdown(tuning.stored_diff(self.bench))
        except Exception as exc:
            self.diff_md.content = f"stored values: {exc}"

    # ------------------------------------------------------------------ identify / captures
    def _identify_button(self, event: Any) -> str | None:
        if event.target.value != "Run":
            ident = self.bench.identified
            if not ident:
                raise ValueError("run an identification first")
            self.a_in.set(float(ident["a"]))
            self.b_in.set(float(ident["b"]))
            return self._design_ip(event)
        if not self._control(self.id_md):
            return None
        body = IdentifyIn(
            from_A=self.id_from.value(), to_A=self.id_to.value(), duration_s=self.id_dur.value()
        )
        res = experiments.identify(self.bench, body)
        c = self.bench.captures[res["capture"]["id"]].columns
        self.id_plot.data = (c["t"], c["speed"], c["model"])
        return (
            f"a = **{res['a']:.8f}**, b = **{res['b']:.6g}** rpm/(A·sample) at Ts = 20 µs · "
            f"fit RMS error {_fmt(res['rms_error_rpm'], '.3g')} rpm"
        )

    def _capture_now(self, event: Any) -> str:
        cfg = TraceIn(
            length=int(self.tr_len.value()), divider=int(self.tr_div.value()), pre_trigger=0
        )
        cap = experiments.capture(self.bench, cfg)
        return f"capture #{cap.id} recorded"

    def show_captures(self) -> None:
        opts = tuple(f"#{c.id} {c.kind}" for c in self.bench.captures.values()) or ("none",)
        self.cap_dd.options = opts
        with self.mute():
            self.cap_dd.value = opts[-1]

    def _download(self, event: Any) -> None:
        from dashboard.export import capture_csv, capture_png

        if self.cap_dd.value == "none":
            raise ValueError("no capture yet")
        cap = self.bench.captures[int(self.cap_dd.value.split(" ")[0].lstrip("#"))]
        fmt = event.target.value.lower()
        data = capture_csv(cap) if fmt == "csv" else capture_png(cap)
        self.client.send_file_download(
            f"capture_{cap.id}_{cap.kind}.{fmt}", data, save_immediately=True
        )

    # ------------------------------------------------------------------ live updates
    def show_status(self, text: str) -> None:
        if text != self.last_status:
            self.last_status = text
            self.status_html.content = text

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


def parse_sequence(text: str) -> list[tuple[float, float]]:
    """``"0:1000, 3:1500"`` → [(0.0, 1000.0), (3.0, 1500.0)] (s, rpm); FieldError otherwise."""
    t_spec = NumberSpec("sequence time (s)", 0, 600)
    rpm_spec = NumberSpec("sequence setpoint (rpm)", -4000, 4000)
    steps = []
    for part in str(text).split(","):
        if not part.strip():
            continue
        at, sep, rpm = part.partition(":")
        if not sep:
            raise FieldError(f"sequence: {part.strip()!r} is not 'time:rpm'")
        steps.append((t_spec.parse(at), rpm_spec.parse(rpm)))
    if not steps:
        raise FieldError("sequence: give 'time:rpm' pairs")
    if [s[0] for s in steps] != sorted(s[0] for s in steps):
        raise FieldError("sequence: times must ascend")
    return steps
