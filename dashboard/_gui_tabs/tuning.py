"""Tuning tab: the gain set typed per browser (controller, L_c or L_c/L, R_c, PI and IP gains),
its preview before anything is applied (stability, margins, ‖S‖∞ in text; Bode plot and
closed-loop poles in the main area's Loop tab, redrawn on every valid edit), Apply as one set,
Read back, Store, and the IP design from ξ, ω_n (eqs. 28–31).

Units: L_c µH, R_c mΩ, PI k_p/k_i V/A, IP k_p A/rpm, IP k_i 1/sample, ω_n rad/s,
b rpm/(A·sample).
"""

from __future__ import annotations

import threading
from typing import Any

from dashboard import _tuning as tuning
from dashboard._fields import FieldError, NumberSpec
from dashboard._gui_field import Field
from dashboard._gui_page import Page
from dashboard._models import CONTROLLER_TYPES, GainsIn, field_bounds
from firmware_protocol import paper

__all__ = ["TuningTab"]


class TuningTab:
    """The Tuning tab of one page: the typed gain set, its preview, Apply, Read back, Store."""

    def __init__(self, page: Page) -> None:
        self.page = page
        self._lock = threading.RLock()  # one preview at a time (see preview())
        gui = page.gui
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
        self.gain_btns.on_click(page.action(self._gain_button, self.tuning_md, needs_control=False))
        self.readback_md = gui.add_markdown("")
        self.type_in = gui.add_dropdown(
            "Current controller", tuple(CONTROLLER_TYPES), initial_value="deadbeat"
        )
        self.Lc_uH = Field(
            page, NumberSpec("L_c (µH)", *field_bounds(GainsIn, "L_c", 1e6), unit="µH"), 14.8
        )
        self.Lc_ratio = Field(page, NumberSpec("L_c / L", 0.0, 3.0, lo_open=True), 1.0)
        self.Rc_mOhm = Field(
            page, NumberSpec("R_c (mΩ)", *field_bounds(GainsIn, "R_c", 1e3), unit="mΩ"), 6.2
        )
        self.kp_i = Field(
            page, NumberSpec("PI k_p (V/A)", *field_bounds(GainsIn, "k_p"), unit="V/A"), 0.4647
        )
        self.ki_i = Field(
            page, NumberSpec("PI k_i (V/A)", *field_bounds(GainsIn, "k_i"), unit="V/A"), 0.0492
        )
        self.kp_w = Field(
            page,
            NumberSpec(
                "IP k_p (A/rpm)", *field_bounds(GainsIn, "speed_k_p"), unit="A/rpm"
            ),
            0.2113,
        )
        self.ki_w = Field(
            page,
            NumberSpec(
                "IP k_i (1/sample)", *field_bounds(GainsIn, "speed_k_i"), unit="1/sample"
            ),
            2.9994e-5,
        )
        with gui.add_folder("IP design from ξ, ω_n (eqs. 28–31)", expand_by_default=False):
            self.xi_in = Field(page, NumberSpec("ξ", 0.0, 10.0, lo_open=True), 1.0)
            self.wn_in = Field(
                page, NumberSpec("ω_n (rad/s)", 0.0, 1000.0, lo_open=True, unit="rad/s"), 2.3
            )
            self.a_in = Field(page, NumberSpec("a", 0.0, 1.0, lo_open=True), paper.A_IDENTIFIED)
            self.b_in = Field(
                page,
                NumberSpec(
                    "b (rpm/A per sample)", 0.0, 1.0, lo_open=True, unit="rpm/A/sample"
                ),
                paper.B_IDENTIFIED,
            )
            self.design_md = gui.add_markdown("", visible=False)
            gui.add_button("Compute IP gains").on_click(
                self.page.action(self._design_ip, self.design_md, needs_control=False)
            )
        self.diff_md = gui.add_markdown("")
        for f in (self.Rc_mOhm, self.kp_i, self.ki_i, self.kp_w, self.ki_w):
            f.input.on_update(lambda e: self.preview())
        self.type_in.on_update(lambda e: self.preview())
        self.Lc_uH.input.on_update(lambda e: self._on_Lc_uH())
        self.Lc_ratio.input.on_update(lambda e: self._on_Lc_ratio())

    @property
    def gains(self) -> dict[str, Any] | None:
        """The drive's applied set as this page's node holds it (:func:`dashboard._tuning.held`)."""
        return self.page.bench.gains

    def motor_L(self) -> float:
        return float(self.gains.get("motor_L", paper.L_TABLE2)) if self.gains else paper.L_TABLE2

    def speed_model(self) -> tuple[float, float]:
        """(a, b) of G(z) = b/(z − a): the identified model, else the paper's."""
        ident = self.page.bench.identified
        if ident:
            return float(ident["a"]), float(ident["b"])
        return tuning.A_PAPER, tuning.B_PAPER

    def _on_Lc_uH(self) -> None:
        with self._lock:
            if self.page.muted or not self.Lc_uH.validate():
                return
            with self.page.mute():
                self.Lc_ratio.set(round(self.Lc_uH.value() * 1e-6 / self.motor_L(), 6))
            self.preview()

    def _on_Lc_ratio(self) -> None:
        with self._lock:
            if self.page.muted or not self.Lc_ratio.validate():
                return
            with self.page.mute():
                self.Lc_uH.set(round(self.Lc_ratio.value() * self.motor_L() * 1e6, 6))
            self.preview()

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

    def typed_set(self, changes: dict[str, float | int]) -> dict[str, Any] | None:
        """The typed set as a full gain set (motor R, L from the last read-back), or None."""
        if not self.gains:
            return None
        return {**self.gains, **changes, "type": self.type_in.value}

    def preview(self) -> None:
        """The typed set's verdict and Loop plots, from what this page holds (no bus).

        One at a time per page, each from the fields as they are when it runs: viser runs the
        callbacks of quick keystrokes side by side, and the last preview drawn must be the
        last value typed (not an earlier keystroke's, drawn after it)."""
        with self._lock:
            if self.page.muted:
                return
            try:
                changes = self.changes()
                p = tuning.preview(self.page.bench, changes)
            except FieldError:
                self.preview_md.content = "**Preview:** fix the marked fields"
                return
            except Exception as exc:
                self.preview_md.content = f"**Not applicable:** {exc}"
                return
            self.preview_md.content = tuning.preview_markdown(p)
            self.show_loop_preview(changes)

    def show_loop_preview(self, changes: dict[str, float | int] | None = None) -> None:
        """Redraw the Loop tab: the typed set (``changes``) against the applied one."""
        a, b = self.speed_model()
        typed = self.typed_set(changes) if changes is not None else self.gains
        plots = self.page.plots
        plots.show_loop(typed, self.gains, a, b)
        name = typed["type"] if typed else "–"
        plots.loop_md.content = (
            f"Typed set ({name}, not yet applied) in colour, the drive's applied set in grey · "
            f"speed model a = {a:.7f}, b = {b:.4g} rpm/(A·sample) · drag to zoom, "
            "double-click to zoom out"
        )

    def _gain_button(self, event: Any) -> str | None:
        which = event.target.value
        if which == "Read back":
            self.load_gains(tuning.read_gains(self.page.bench))
            return "fields show the drive's read-back"
        if not self.page.control(self.tuning_md):
            return None
        if which == "Store":
            tuning.store(self.page.bench)
            self.show_diff()
            return "stored in the drive"
        return self.apply()

    def apply(self) -> str:
        """"Apply gains": this page's typed set, as one set (:func:`dashboard._tuning.apply`);
        the fields then show the set the drive holds (its GainResult: nothing is read again).
        FieldError (nothing sent) if a typed value is invalid."""
        changes = self.changes()
        applied = tuning.apply(self.page.bench, changes, force=bool(self.force_in.value))
        with self.page.mute():
            self.force_in.value = False  # an override is for one apply only
        self.load_gains(applied)
        return "applied; the fields show the drive's read-back"

    def use_ab(self, a: float, b: float) -> str:
        """Design the IP gains on the speed model ``a``, ``b`` (an identification's result)."""
        self.a_in.set(a)
        self.b_in.set(b)
        return self._design_ip(None)

    def _design_ip(self, event: Any) -> str:
        d = tuning.design_ip(
            self.page.bench, self.xi_in.value(), self.wn_in.value(), self.a_in.value(),
            self.b_in.value(),
        )
        self.kp_w.set(float(d["speed_k_p"]))
        self.ki_w.set(float(d["speed_k_i"]))
        self.preview()
        return "IP gains computed (not applied yet)"

    def load_gains(self, g: dict[str, Any] | None = None) -> None:
        """Put the drive's gains (``g``: as applied or read back; None: read them now) into
        this browser's fields."""
        g = g or tuning.read_gains(self.page.bench)
        with self.page.mute():
            self.type_in.value = g["type"]
        self.Lc_uH.set(round(g["L_c"] * 1e6, 6))
        self.Lc_ratio.set(round(g["L_c"] / g["motor_L"], 6))
        self.Rc_mOhm.set(round(g["R_c"] * 1e3, 6))
        self.kp_i.set(g["k_p"])
        self.ki_i.set(g["k_i"])
        self.kp_w.set(g["speed_k_p"])
        self.ki_w.set(g["speed_k_i"])
        self.show_readback(g)
        self.preview()
        self.show_diff()

    def on_gains(self, g: dict[str, Any]) -> None:
        """The node's gains changed (applied from any page): show them, redraw the preview
        against them (the Loop tab's grey curves follow the drive); no bus."""
        self.show_readback(g)
        self.preview()

    def show_readback(self, g: dict[str, Any]) -> None:
        self.readback_md.content = tuning.readback_markdown(g)

    def show_diff(self) -> None:
        try:
            self.diff_md.content = tuning.diff_markdown(tuning.stored_diff(self.page.bench))
        except Exception as exc:
            self.diff_md.content = f"stored values: {exc}"
