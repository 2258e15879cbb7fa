"""The main area of one browser's page: a wide panel docked left with the plots, tabs
Live · Capture · Loop.

- Live: speed and i_p with their references (speed*, i_p*), large, one cursor synced across
  both (click locks it), drag to zoom (x and y), double-click to zoom out.
- Capture: the selected 50 kHz capture (trace, current step with the model, identification
  with its fit), the newest one shown when it arrives.
- Loop: Bode plot of the open current and speed loops and the closed-loop poles in the z-plane
  for the values typed in the Tuning tab (before anything is applied), the drive's applied set
  beside them as the reference (paper Figs. 4, 5, 12).

Units: t s (live, identification) or ms (50 kHz captures); speed rpm; currents A; frequency Hz;
magnitude dB; phase degrees; z-plane dimensionless.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, cast

import numpy as np
import viser.uplot as uplot

from dashboard import _loop_view as loop_view
from dashboard._gui_field import (
    CURRENT_COLORS,
    PLOT_HEIGHT_PX,
    SPEED_COLORS,
    live_series,
    series,
)
from dashboard._plot_style import SignalStyle, capture_styles

if TYPE_CHECKING:
    from dashboard._bench import Capture

__all__ = ["PLOT_AREA_WIDTH_PX", "PlotArea", "axis_key", "capture_view", "unit_axes"]

#: requested width of the plot area (px); with the control panel's 800 px wider than any
#: screen: viser scales both docked regions to the window, keeping its minimum 120 px canvas
#: strip (:data:`STRIP_PX`): at 1280 px the plots get 789 px (62 %).
PLOT_AREA_WIDTH_PX = 1700
STRIP_PX = 120  #: viser's minimum canvas width: the readout column between plots and controls
READOUT_HEIGHT_PX = 300  #: height of the readout in the strip over a shown 3D rotor (px)
#: its height when no rotor is drawn there (px): the strip is the readout, viser's notices
#: (software WebGL, uploads) go below it
READOUT_FULL_PX = 560

#: hides the legend row of the invisible min-span helper series (4th row, last, of a live plot)
LEGEND_CSS = "<style>.uplot .u-legend tr.u-series:nth-child(4):last-child{display:none}</style>"

CAPTURE_COLORS = ("#2ca02c", "#9467bd", "#d62728", "#7f7f7f", "#1f77b4", "#ff7f0e", "#8c564b")
TYPED, APPLIED = "#1f618d", "#aab7b8"  #: typed set (bold), applied set (grey reference)
SPEED_TYPED, SPEED_APPLIED = "#d35400", "#f5cba7"


def _cursor(key: str) -> Any:
    """A crosshair synced across the plots of one group, locked by a click; drag zooms x and y."""
    return uplot.Cursor(
        sync=uplot.Cursor_Sync(key=key), lock=True, drag=uplot.Cursor_Drag(x=True, y=True)
    )


def capture_view(
    cap: Capture,
) -> tuple[str, str, list[SignalStyle], tuple[np.ndarray, ...]]:
    """(title, x label, series styles in drawing order, data) of a capture for the capture
    plot: each signal on the axis of its own unit (:mod:`dashboard._plot_style`)."""
    c = cap.columns
    styles = capture_styles(cap.kind, list(c))[: len(CAPTURE_COLORS)]
    if cap.kind == "identification":
        x, x_label = np.asarray(c["t"], dtype=np.float64), "t (s)"
        title = f"#{cap.id} identification: speed and the fitted G(z) = b/(z − a)"
    else:
        x, x_label = np.asarray(c["t"], dtype=np.float64) * 1e3, "t (ms)"
        title = f"#{cap.id} {cap.kind.replace('_', ' ')} at 50 kHz"
    data = (x, *(np.asarray(c[s.key], dtype=np.float64) for s in styles))
    return title, x_label, styles, data


def _styled(s: SignalStyle) -> Any:
    """A uPlot series of a styled signal, on the scale of its unit."""
    return uplot.Series(
        label=s.label, stroke=s.color, width=s.width,
        dash=cast(Any, list(s.dash) or None),  # None: solid (uPlot takes null; viser's type not)
        scale=axis_key(s.unit),
    )


def axis_key(unit: str) -> str:
    """The uPlot scale key of a unit ("1" for a dimensionless signal)."""
    return unit or "1"


def unit_axes(units: list[str], x_label: str) -> tuple[Any, ...]:
    """The x axis, then one y axis per unit: the first on the left, the others on the right
    (grid lines only for the first)."""
    axes = [uplot.Axis(label=x_label)]
    for k, u in enumerate(units):
        axes.append(
            uplot.Axis(
                scale=axis_key(u), label=u or "1", size=60, side=3 if k == 0 else 1,
                grid={"show": k == 0},
            )
        )
    return tuple(axes)


def _capture_series(styles: list[SignalStyle], x_label: str) -> tuple[Any, ...]:
    """The capture plot's series: one per styled signal, the remaining slots hidden (on the
    first unit's scale)."""
    out: list[Any] = [uplot.Series(label=x_label)]
    out += [_styled(s) for s in styles]
    key = axis_key(styles[0].unit) if styles else "A"
    for col in CAPTURE_COLORS[len(styles) :]:
        out.append(uplot.Series(label="", stroke=col, show=False, scale=key))
    return tuple(out)


class PlotArea:
    """The main plot area of one browser's page (docked left) and the readout strip; owns its
    plots and what they last showed."""

    def __init__(self, gui: Any, live_window_s: float) -> None:
        self.gui = gui
        self.live_window_s = live_window_s
        self.last_legends: tuple[str, str] = ("", "")
        self.plot_panel = gui.add_panel()
        with self.plot_panel.add_tab("Live"):
            gui.add_html(LEGEND_CSS)
            self.speed_legend = gui.add_html("")
            self.speed_plot = self._live_plot("speed", "rpm", SPEED_COLORS)
            self.current_legend = gui.add_html("")
            self.current_plot = self._live_plot("i_p", "A", CURRENT_COLORS)
        with self.plot_panel.add_tab("Capture"):
            self.capture_md = gui.add_markdown("No capture yet: run one from the Current, "
                                               "Identify or Captures tab.")
            self._build_capture_plot()
        with self.plot_panel.add_tab("Loop"):
            self.loop_md = gui.add_markdown("")
            self._build_loop_plots()
        self.plot_panel.dock_left()
        self.plot_panel.set_width(PLOT_AREA_WIDTH_PX)
        # the canvas strip between plots and controls: the live readout, not an empty gap
        self.readout_panel = gui.add_panel()
        with self.readout_panel.add_tab("Now"):
            self.readout_html = gui.add_html("")
        self.readout_panel.float(x=0, y=0, width=STRIP_PX, height=READOUT_FULL_PX)

    def fit_readout(self, rotor_shown: bool) -> None:
        """The readout over the top of a shown 3D rotor, or the whole strip without one."""
        self.readout_panel.set_height(READOUT_HEIGHT_PX if rotor_shown else READOUT_FULL_PX)

    def show_readout(self, text: str) -> None:
        """The live readout (sent only when it changed)."""
        if text != self.readout_html.content:
            self.readout_html.content = text

    def show_legends(self, speed: str, current: str) -> None:
        """The live plots' legend lines (sent only when they changed)."""
        if (speed, current) != self.last_legends:
            self.last_legends = (speed, current)
            self.speed_legend.content = speed
            self.current_legend.content = current

    def show_live(self, speed: tuple[Any, ...], current: tuple[Any, ...]) -> None:
        """The live window: (t, reference, measurement, envelope) of each plot."""
        self.speed_plot.data = speed
        self.current_plot.data = current

    def _live_plot(self, name: str, unit: str, colors: tuple[str, str]) -> Any:
        window = self.live_window_s
        x0 = np.linspace(-window, 0.0, 2)
        zero = np.zeros(2)
        return self.gui.add_uplot(
            (x0, zero, zero, zero),
            (
                *live_series(name, unit, colors, "t (s)"),
                uplot.Series(label="", stroke="rgba(0,0,0,0)", width=0, points={"show": False}),
            ),
            scales={"x": uplot.Scale(time=False, range=(-window, 0.0))},
            axes=(uplot.Axis(label="t (s)"), uplot.Axis(label=unit, size=60)),
            cursor=_cursor("live"),
            height=PLOT_HEIGHT_PX,
        )

    # ------------------------------------------------------------------ capture
    def _build_capture_plot(self) -> None:
        nan = np.full(2, np.nan)
        n = len(CAPTURE_COLORS)
        self._capture_axes: tuple[str, ...] = ()
        self.capture_plot = self.gui.add_uplot(
            (np.zeros(2), *(nan,) * n),
            _capture_series([], "t (ms)"),
            scales={"x": uplot.Scale(time=False, auto=True)},
            axes=(uplot.Axis(label="t (ms)"), uplot.Axis(label="A", size=60)),
            cursor=_cursor("capture"),
            height=int(PLOT_HEIGHT_PX * 1.6),
        )

    def show_capture_plot(self, cap: Capture) -> None:
        """Show ``cap`` in the Capture tab, each signal on the axis of its unit, measurements
        on top; unused series slots stay empty (NaN) and unlabelled."""
        title, x_label, styles, data = capture_view(cap)
        n = len(CAPTURE_COLORS)
        filler = np.full(data[0].size, np.nan)
        units = list(dict.fromkeys(s.unit for s in styles))
        sig = (x_label, *(f"{s.key}|{s.label}|{s.unit}" for s in styles))
        if sig != self._capture_axes:  # labels and axes change with the capture's columns
            self.capture_plot.series = _capture_series(styles, x_label)
            self.capture_plot.axes = unit_axes(units, x_label)
            self._capture_axes = sig
        self.capture_plot.data = (*data, *(filler,) * (n - len(styles)))
        self.capture_md.content = f"**{title}**"

    # ------------------------------------------------------------------ loop
    def _build_loop_plots(self) -> None:
        gui = self.gui
        f = loop_view.frequency_grid()
        nan = np.full(f.size, np.nan)
        log_x = {
            "x": uplot.Scale(
                time=False, distr=3, log=10, range=(float(f[0]), float(f[-1]))
            )
        }
        labels = ("current, typed", "current, applied", "speed, typed", "speed, applied")
        colors = (TYPED, APPLIED, SPEED_TYPED, SPEED_APPLIED)

        def bode(y_label: str, title: str) -> Any:
            return gui.add_uplot(
                (f, nan, nan, nan, nan),
                tuple(series(labels, colors, "f (Hz)")),
                scales=log_x,
                axes=(uplot.Axis(label="f (Hz)"), uplot.Axis(label=y_label, size=60)),
                cursor=_cursor("bode"),
                title=title,
                height=int(PLOT_HEIGHT_PX * 0.85),
            )

        self.bode_mag = bode("|L| (dB)", "Open loops: magnitude")
        self.bode_phase = bode("∠L (°)", "Open loops: phase")
        z0 = loop_view.z_plane_data(np.zeros(0), np.zeros(0), np.zeros(0))

        def dot(fill: str) -> uplot.Series_Points:
            return uplot.Series_Points(show=True, size=9, width=2, fill=fill)

        self.z_plane = gui.add_uplot(
            z0,
            (
                uplot.Series(label="Re z"),
                uplot.Series(label="|z| = 1", stroke="#7f8c8d", width=1),
                uplot.Series(label="", stroke="#7f8c8d", width=1),
                uplot.Series(label="current poles, typed", stroke=TYPED, width=0,
                             points=dot(TYPED)),
                uplot.Series(label="current poles, applied", stroke=APPLIED, width=0,
                             points=dot("#ffffff")),
                uplot.Series(label="speed poles, typed", stroke=SPEED_TYPED, width=0,
                             points=dot(SPEED_TYPED)),
            ),
            scales={
                "x": uplot.Scale(time=False, range=(-1.3, 1.3)),
                "y": uplot.Scale(range=(-1.15, 1.15)),
            },
            axes=(uplot.Axis(label="Re z"), uplot.Axis(label="Im z", size=60)),
            cursor=uplot.Cursor(drag=uplot.Cursor_Drag(x=True, y=True)),
            title="Closed-loop poles (z-plane)",
            height=int(PLOT_HEIGHT_PX * 1.2),
        )
        self.loop_updates = 0

    def show_loop(
        self, typed: dict[str, Any] | None, applied: dict[str, Any] | None, a: float, b: float
    ) -> None:
        """Draw the Bode curves and poles of the ``typed`` set against the ``applied`` one
        (either may be None: its curves are left empty). Speed model G(z) = b/(z − a)."""
        f = loop_view.frequency_grid()
        nan = np.full(f.size, np.nan)
        views = []
        for g in (typed, applied):
            try:
                views.append(loop_view.loop_view(g, a, b) if g else None)
            except (ValueError, KeyError, ZeroDivisionError):
                views.append(None)
        t, r = views
        self.bode_mag.data = (
            f,
            t.current_db if t else nan,
            r.current_db if r else nan,
            t.speed_db if t else nan,
            r.speed_db if r else nan,
        )
        self.bode_phase.data = (
            f,
            t.current_deg if t else nan,
            r.current_deg if r else nan,
            t.speed_deg if t else nan,
            r.speed_deg if r else nan,
        )
        empty = np.zeros(0, dtype=complex)
        self.z_plane.data = loop_view.z_plane_data(
            t.current_poles if t else empty,
            r.current_poles if r else empty,
            t.speed_poles if t else empty,
        )
        self.loop_updates += 1
