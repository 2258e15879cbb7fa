"""Plots that show the motor (issue 24): every signal on an axis of its own unit with a legend
that says it, the measurement drawn on top in the strongest line, references and models
thinner and dashed, in the GUI's capture plot (the uPlot series and axes it sends) and in the
PNG export (the matplotlib figure).

Truths: the physical units of the paper's signals (v_L and e_L are line voltages in V, i_p a
current in A, speed in rpm, the Hall sector a sector number 1..6), and what "on top" means
for each library (uPlot draws series in order; matplotlib by zorder).
"""

from __future__ import annotations

import numpy as np
import pytest

from dashboard._bench import Capture
from dashboard._export import capture_figure, capture_png
from dashboard._gui_plots import _capture_series, capture_view, unit_axes

pytestmark = pytest.mark.unit

TRUE_UNITS = {"i_p": "A", "i_p_avg": "A", "i_p_ref": "A", "model": "A", "v_L": "V",
              "e_L": "V", "hall_sector": "sector", "speed": "rpm"}


def _step_capture() -> Capture:
    t = np.arange(500) * 20e-6
    on = (t > 2e-3).astype(float)
    cols = {
        "t": t, "i_p": 15 + 5 * on, "i_p_avg": 15 + 5 * on, "i_p_ref": 15 + 5 * on,
        "model": 15 + 5 * on, "v_L": 12 * np.sin(t * 900), "e_L": np.full(500, 4.0),
        "hall_sector": (np.arange(500) // 80) % 6 + 1.0,
    }
    return Capture(7, "current_step", cols, {})


def _identification() -> Capture:
    t = np.linspace(0, 1, 300)
    return Capture(8, "identification",
                   {"t": t, "i_p": np.full(300, 20.0), "speed": 900 * t, "model": 900 * t}, {})


def test_gui_capture_series_sit_on_the_axis_of_their_own_unit():
    _title, x_label, styles, _data = capture_view(_step_capture())
    series = _capture_series(styles, x_label)[1 : 1 + len(styles)]
    for st, se in zip(styles, series, strict=True):
        unit = TRUE_UNITS[st.key]
        assert st.label.endswith(f"({unit})"), st.label  # e.g. "v_L (V)", never "v_L (A)"
        assert se["scale"] == unit, (st.key, se)
    axes = unit_axes(list(dict.fromkeys(s.unit for s in styles)), x_label)
    assert [a["label"] for a in axes[1:]] == ["A", "V", "sector"]
    assert [a["scale"] for a in axes[1:]] == ["A", "V", "sector"]
    assert axes[1]["side"] == 3 and all(a["side"] == 1 for a in axes[2:])  # left, then right


def test_gui_measurements_are_drawn_last_and_strongest():
    _, _, styles, _data = capture_view(_step_capture())
    keys = [s.key for s in styles]
    # uPlot draws in series order: i_p after i_p*, ī_p and the model
    assert keys.index("i_p") > max(keys.index(k) for k in ("model", "i_p_ref", "i_p_avg"))
    by = {s.key: s for s in styles}
    assert by["i_p"].width > by["model"].width and not by["i_p"].dash
    assert by["model"].dash and by["i_p_ref"].dash
    ident = capture_view(_identification())[2]
    assert [s.label for s in ident][-2:] == ["i_p (A)", "speed (rpm)"]
    assert next(s for s in ident if s.key == "model").label == "fit (rpm)"


def test_png_export_has_one_axis_per_unit_true_legends_and_the_measurement_on_top():
    fig = capture_figure(_step_capture())
    axes = fig.axes
    assert [ax.get_ylabel() for ax in axes] == ["A", "V", "sector"]
    for ax in axes:
        unit = ax.get_ylabel()
        labels = [ln.get_label() for ln in ax.get_lines()]
        assert labels and all(lab.endswith(f"({unit})") for lab in labels), labels
    current = {ln.get_label(): ln for ln in axes[0].get_lines()}
    top = max(current.values(), key=lambda ln: ln.get_zorder())
    assert top.get_label() == "i_p (A)"
    assert top.get_linewidth() > current["model (A)"].get_linewidth()
    assert current["model (A)"].get_linestyle() == "--"
    assert capture_png(_step_capture()).startswith(b"\x89PNG")
