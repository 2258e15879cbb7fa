"""Captures as files: CSV (one column per signal, "t" in s first) and PNG (matplotlib, Agg;
one axis per unit, measurements on top, as in the GUI)."""

from __future__ import annotations

from typing import Any

import numpy as np

from dashboard._bench import Capture
from dashboard._plot_style import capture_styles
from drive_link.link.writers import csv_text, png_bytes

__all__ = ["capture_csv", "capture_figure", "capture_png"]


def capture_csv(cap: Capture) -> bytes:
    """CSV of a capture: one header row of column names ("t" in s first), then one row per
    sample. The capture's metadata is in ``GET /api/trace/{id}`` (not in the CSV)."""
    names = list(cap.columns)
    cols = [np.asarray(cap.columns[n], dtype=np.float64) for n in names]
    return csv_text(names, cols, lineterminator="\n").encode()


def capture_png(cap: Capture, *, width_in: float = 9.0, height_in: float = 4.5) -> bytes:
    """A PNG of :func:`capture_figure`."""
    fig = capture_figure(cap, width_in=width_in, height_in=height_in)
    return png_bytes(fig, tight=False)


def capture_figure(cap: Capture, *, width_in: float = 9.0, height_in: float = 4.5) -> Any:
    """A matplotlib Figure of a capture as the GUI draws it (:mod:`dashboard._plot_style`): one axis
    per unit (A, V, rpm, sector ...) stacked over a shared time axis (ms; s for an
    identification), measurements on top in the strongest colour, references and models
    thinner and dashed, legends with units; decimated to ≤ 4000 points per line."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    styles = capture_styles(cap.kind, list(cap.columns))
    units = list(dict.fromkeys(s.unit for s in styles)) or [""]
    fig = Figure(figsize=(width_in, max(height_in, 2.4 * len(units))), dpi=100)
    axes = fig.subplots(len(units), 1, sharex=True, squeeze=False)[:, 0]
    first = next(iter(cap.columns.values()))
    t = np.asarray(cap.columns.get("t", np.arange(len(first))), dtype=np.float64)
    ident = cap.kind == "identification"
    x, x_label = (t, "t (s)") if ident else (t * 1e3, "t (ms)")
    step = max(1, len(t) // 4000)
    for ax, unit in zip(axes, units, strict=True):
        for s in styles:
            if s.unit != unit:
                continue
            ax.plot(
                x[::step],
                np.asarray(cap.columns[s.key], dtype=np.float64)[::step],
                label=s.label,
                color=s.color,
                linewidth=s.width * 0.8,
                dashes=s.dash or (None, None),
                zorder=2 + s.z,  # measurements last: on top
            )
        ax.set_ylabel(unit or "1")
        ax.grid(True, alpha=0.3)
        ax.legend(loc="best", fontsize=8)
    axes[-1].set_xlabel(x_label)
    axes[0].set_title(f"{cap.kind.replace('_', ' ')} capture {cap.id}")
    fig.tight_layout()
    return fig
