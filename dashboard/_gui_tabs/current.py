"""Current tab: i_p* setpoint and the current step test (paper Fig. 13); the step's 50 kHz
record is drawn in the main area's Capture tab (the bench's "capture" event selects it).

Units: A, samples.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from dashboard import _experiments as experiments
from dashboard._fields import NumberSpec
from dashboard._gui_field import Field, fmt
from dashboard._gui_page import Page
from dashboard._models import CurrentIn, CurrentStepIn, field_bounds

__all__ = ["CurrentTab"]


class CurrentTab:
    """The Current tab of one page: i_p* and the current step test."""

    def __init__(self, page: Page) -> None:
        self.page = page
        gui = page.gui
        self.i_in = Field(
            page, NumberSpec("i_p* (A)", *field_bounds(CurrentIn, "i_p_ref"), unit="A"), 0.0
        )
        btn = gui.add_button("Set current")
        self.current_md = page.md()
        btn.on_click(page.action(self._set_current, self.current_md))
        with gui.add_folder("Current step test (Fig. 13)"):
            self.step_from = Field(
                page, NumberSpec("From (A)", *field_bounds(CurrentStepIn, "from_A"), unit="A"), 15.0
            )
            self.step_to = Field(
                page, NumberSpec("To (A)", *field_bounds(CurrentStepIn, "to_A"), unit="A"), 20.0
            )
            self.avg_n = Field(
                page,
                NumberSpec(
                    "Moving average (samples)", 1, 1000, integer=True, unit="samples"
                ),
                1,
            )
            run = gui.add_button("Run current step")
            self.step_md = page.md()
            run.on_click(page.action(self._current_step, self.step_md))

    def _set_current(self, event: Any) -> None:
        self.page.bench.set_current(self.i_in.value())

    def _current_step(self, event: Any) -> str:
        body = CurrentStepIn(
            from_A=self.step_from.value(), to_A=self.step_to.value(), duration_ms=2.0
        )
        avg = int(self.avg_n.value())
        res = experiments.current_step(self.page.bench, body, average_samples=avg)
        m = res["metrics"]
        return (
            f"**{res['controller']}**: rise {fmt(m.get('rise_time_s', np.nan) * 1e6, '.0f')} µs · "
            f"settling {fmt(m.get('settling_time_s', np.nan) * 1e6, '.0f')} µs · "
            f"overshoot {fmt(m.get('overshoot_pct'), '.1f')} % · "
            f"steady-state error {fmt(m.get('steady_state_error_A'), '.3f')} A · "
            f"model RMS error {fmt(res.get('model_rms_error_A'), '.3f')} A (plot: Capture tab)"
        )
