"""Captures as files: CSV (one column per signal, "t" in s first) and PNG (matplotlib, Agg)."""

from __future__ import annotations

import io

import numpy as np

from dashboard._bench import Capture

__all__ = ["capture_csv", "capture_png"]


def capture_csv(cap: Capture) -> bytes:
    """CSV of a capture: one header row of column names ("t" in s first), then one row per
    sample. The capture's metadata is in ``GET /api/trace/{id}`` (not in the CSV)."""
    names = list(cap.columns)
    data = np.column_stack([np.asarray(cap.columns[n], dtype=np.float64) for n in names])
    buf = io.StringIO()
    np.savetxt(buf, data, delimiter=",", header=",".join(names), comments="", fmt="%.9g")
    return buf.getvalue().encode()


def capture_png(cap: Capture, *, width_in: float = 9.0, height_in: float = 4.5) -> bytes:
    """A PNG plot of every column against "t" (ms); decimated to ≤ 4000 points per line."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width_in, height_in), dpi=100)
    ax = fig.add_subplot(1, 1, 1)
    t = np.asarray(cap.columns.get("t", np.arange(len(next(iter(cap.columns.values()))))))
    step = max(1, len(t) // 4000)
    for name, col in cap.columns.items():
        if name == "t":
            continue
        ax.plot(t[::step] * 1e3, np.asarray(col)[::step], label=name, linewidth=1.0)
    ax.set_xlabel("t (ms)")
    ax.set_title(f"{cap.kind} capture {cap.id}")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    return buf.getvalue()
