"""Speed tab: setpoint, ± steps, a timed setpoint sequence and (virtual drive) a load step.

Units: rpm, s, N·m.
"""

from __future__ import annotations

from typing import Any

from dashboard._fields import FieldError, NumberSpec
from dashboard._gui_field import Field
from dashboard._gui_page import Page
from dashboard._models import LoadIn, SequenceStep, SpeedIn, SpeedStepIn, field_bounds

__all__ = ["SpeedTab", "parse_sequence"]


class SpeedTab:
    """The Speed tab of one page: its fields and buttons."""

    def __init__(self, page: Page) -> None:
        self.page = page
        gui = page.gui
        self.speed_in = Field(
            page, NumberSpec("Speed setpoint (rpm)", *field_bounds(SpeedIn, "rpm"), unit="rpm"), 0.0
        )
        btn = gui.add_button("Set speed")
        self.speed_md = page.md()
        btn.on_click(page.action(self._set_speed, self.speed_md))
        self.step_size = Field(
            page,
            NumberSpec(
                "Step size (rpm)", 1, field_bounds(SpeedStepIn, "delta_rpm")[1], unit="rpm"
            ),
            500.0,
        )
        self.step_btns = gui.add_button_group("Step", ("+ step", "− step"))
        self.stepbtn_md = page.md()
        self.step_btns.on_click(page.action(self._step, self.stepbtn_md))
        self.sequence_in = gui.add_text(
            "Sequence (s:rpm, …)",
            "0:1000, 3:1500, 6:1000, 9:0",
            hint="time after start in s : setpoint in rpm",
        )
        seq = gui.add_button_group("Sequence", ("Run sequence", "Stop sequence"))
        self.seq_md = page.md()
        seq.on_click(page.action(self._sequence_button, self.seq_md))
        self.load_in = Field(
            page, NumberSpec("Load torque (N·m)", *field_bounds(LoadIn, "T_load"), unit="N·m"), 0.0
        )
        b = gui.add_button(
            "Apply load step",
            disabled=not page.bench.virtual,
            hint="virtual drive only: sim_load.T_load",
        )
        self.load_md = page.md()
        b.on_click(page.action(self._load, self.load_md))

    def _set_speed(self, event: Any) -> None:
        self.page.bench.set_speed(self.speed_in.value())

    def _step(self, event: Any) -> None:
        sign = 1.0 if event.target.value == "+ step" else -1.0
        rpm = self.page.bench.step_speed(sign * self.step_size.value())
        self.speed_in.set(rpm)

    def _sequence_button(self, event: Any) -> str:
        if event.target.value == "Stop sequence":
            self.page.bench.stop_sequence()
            return "sequence stopped (last setpoint kept)"
        steps = parse_sequence(self.sequence_in.value)
        self.page.bench.start_sequence(steps)
        return f"sequence of {len(steps)} steps started"

    def _load(self, event: Any) -> None:
        self.page.bench.set_load(self.load_in.value())


def parse_sequence(text: str) -> list[tuple[float, float]]:
    """``"0:1000, 3:1500"`` → [(0.0, 1000.0), (3.0, 1500.0)] (s, rpm); FieldError otherwise."""
    t_spec = NumberSpec("sequence time (s)", *field_bounds(SequenceStep, "at_s"), unit="s")
    rpm_spec = NumberSpec("sequence setpoint (rpm)", *field_bounds(SequenceStep, "rpm"), unit="rpm")
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
