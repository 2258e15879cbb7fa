"""PNG plots of a sweep (matplotlib, Agg): pass/fail and overshoot maps, metric histograms.

- ``map_pass.png``: over two swept parameters (``[sweep] map`` / ``--map X Y``; default the
  first two), the fraction of runs passing at each point (green all, red none; a black x
  where a run was not stable). With ``L_c/L`` on an axis the stability limit of eq. (17),
  L_c = 2 L, is drawn: Table 1 extended over the parameter plane.
- ``map_overshoot.png``: the largest overshoot (%) at each point (unstable points as x).
- ``histograms.png``: one histogram per numeric metric (finite values), its limit as a line.
- ``run_<N>.png`` (``--run N --plot``): one run's response against its reference.
"""

from __future__ import annotations

import math
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np

from virtual_drive.sweep.spec import Spec

__all__ = ["plot_run", "write_plots"]

_HIST = ("overshoot", "settling", "peak_phase_current", "ss_error", "speed_dip",
         "tracking_error")  # fmt: skip
_UNIT = {"overshoot": "%", "settling": "ms", "peak_phase_current": "A", "ss_error": "A or rpm",
         "speed_dip": "rpm", "tracking_error": "rpm"}  # fmt: skip


def _plt() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _axes(rows: list[dict[str, Any]], spec: Spec, want: tuple[str, str] | None) -> tuple | None:
    if want is not None:
        return want
    numeric = [p.name for p in spec.params if p.name != "controller"]
    if len(numeric) >= 2:
        return numeric[0], numeric[1]
    if len(numeric) == 1:
        return numeric[0], "R_c/R" if numeric[0] != "R_c/R" else "L_c/L"
    return None


def _grouped(rows: list[dict[str, Any]], x: str, y: str) -> dict[tuple[float, float], list]:
    g: dict[tuple[float, float], list] = defaultdict(list)
    for r in rows:
        g[(round(r[x], 12), round(r[y], 12))].append(r)
    return g


def _label(name: str) -> str:
    from virtual_drive.sweep.inputs import INPUTS

    unit = INPUTS.get(name, ("", ""))[0]
    return f"{name} ({unit})" if unit and unit != "dimensionless" else name


def _eq17(ax: Any, x: str, y: str) -> None:
    if x == "L_c/L":
        ax.axvline(2.0, color="k", ls="--", lw=1, label="eq. (17): L_c = 2 L")
        ax.legend(loc="upper left", fontsize=8)
    elif y == "L_c/L":
        ax.axhline(2.0, color="k", ls="--", lw=1, label="eq. (17): L_c = 2 L")
        ax.legend(loc="upper left", fontsize=8)


def write_plots(
    rows: list[dict[str, Any]], spec: Spec, out: Path, want: tuple[str, str] | None = None
) -> list[Path]:
    """Write the maps and histograms into ``out``; returns the files."""
    plt = _plt()
    files: list[Path] = []
    axes = _axes(rows, spec, want)
    if axes is not None and all(a in rows[0] for a in axes):
        x, y = axes
        g = _grouped(rows, x, y)
        pts = np.array(list(g.keys()))
        frac = np.array([np.mean([r["passed"] for r in v]) for v in g.values()])
        unstable = np.array([any(not r["stable"] for r in v) for v in g.values()])
        ov = np.array([max((r["overshoot"] for r in v if math.isfinite(r["overshoot"])),
                           default=np.nan) for v in g.values()])  # fmt: skip
        size = max(12.0, 9000.0 / max(len(pts), 1))
        for name, vals, cmap, label in (
            ("map_pass.png", frac, "RdYlGn", "fraction passing"),
            ("map_overshoot.png", ov, "viridis", "overshoot (%)"),
        ):
            fig, ax = plt.subplots(figsize=(7, 5), dpi=100)
            ok = np.isfinite(vals) & ~unstable if name == "map_overshoot.png" else np.isfinite(vals)
            sc = ax.scatter(pts[ok, 0], pts[ok, 1], c=vals[ok], cmap=cmap, s=size, marker="s",
                            vmin=0.0 if name == "map_pass.png" else None,
                            vmax=1.0 if name == "map_pass.png" else None)  # fmt: skip
            if unstable.any():
                ax.scatter(pts[unstable, 0], pts[unstable, 1], c="k", marker="x", s=size / 3,
                           label="not stable")  # fmt: skip
            fig.colorbar(sc, ax=ax, label=label)
            ax.set_xlabel(_label(x))
            ax.set_ylabel(_label(y))
            ax.set_title(f"{spec.name}: {label} over {x} x {y} ({len(rows)} runs)")
            _eq17(ax, x, y)
            if unstable.any() and x != "L_c/L" and y != "L_c/L":
                ax.legend(loc="upper left", fontsize=8)
            fig.tight_layout()
            fig.savefig(out / name)
            plt.close(fig)
            files.append(out / name)
    fig, axs = plt.subplots(2, 3, figsize=(12, 6.5), dpi=100)
    for ax, m in zip(axs.flat, _HIST, strict=True):
        vals = np.array([r[m] for r in rows], dtype=np.float64)
        vals = vals[np.isfinite(vals)]
        scale = 1e3 if m == "settling" else 1.0
        if vals.size:
            ax.hist(vals * scale, bins=min(40, max(5, int(math.sqrt(vals.size)))), color="C0")
        lims = {lim[m] for lim in spec.limits if m in lim}
        for lim in lims:
            ax.axvline(lim * scale, color="r", ls="--", lw=1)
        ax.set_title(f"{m} ({_UNIT[m]}), {vals.size} finite", fontsize=9)
    fig.suptitle(f"{spec.name}: metrics of {len(rows)} runs (red: limit)")
    fig.tight_layout()
    fig.savefig(out / "histograms.png")
    plt.close(fig)
    files.append(out / "histograms.png")
    return files


def plot_run(trace: Any, title: str, path: str | Path, unit: str) -> Path:
    """One run's response ``y`` and reference ``r`` (top) and peak phase current (bottom)."""
    from virtual_drive.sim.params import Ts

    plt = _plt()
    t = np.arange(trace.n) * Ts * 1e3
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(8, 5.5), dpi=100, sharex=True)
    a1.plot(t, trace.r, "k--", lw=1, label="reference")
    a1.plot(t, trace.y, "C0", lw=1, label="response")
    a1.set_ylabel(unit)
    a1.legend(fontsize=8)
    a1.set_title(title, fontsize=9)
    a2.plot(t, trace.i_peak, "C3", lw=0.8)
    a2.set_ylabel("max |i_phase| (A)")
    a2.set_xlabel("t (ms)")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return Path(path)
