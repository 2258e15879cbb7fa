"""What every report experiment shares: the metric and experiment records with their verdicts,
the run context (drive, hooks, real or virtual), settled-step helpers and figures as base64 PNG.

A metric's verdict: "pass" when |measured − model| ≤ tolerance (same unit as the metric),
"fail" otherwise, "not applicable" when it was not measured. An experiment passes when all its
judged metrics pass. Units: A, V, rpm, s, Ω, H, % as each metric states.
"""

from __future__ import annotations

import base64
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ..steps import Hooks

if TYPE_CHECKING:
    from ...link.drive import Drive

__all__ = [
    "NOT_APPLICABLE",
    "Context",
    "ExperimentResult",
    "Metric",
    "figure_png",
    "is_virtual",
    "settling_samples",
]

NOT_APPLICABLE = "not applicable"


def _num(x: Any) -> float | None:
    if x is None:
        return None
    x = float(x)
    return x if math.isfinite(x) else None


@dataclass
class Metric:
    """One number: ``measured`` on the drive, ``model`` (the paper's equations for this drive's
    parameters), ``paper`` (printed in the paper, None if it prints none), ``unit``,
    ``tolerance`` (allowed |measured − model|, same unit; None: not judged)."""

    measured: float | None
    model: float | None
    paper: float | None
    unit: str
    tolerance: float | None
    verdict: str = ""

    def __post_init__(self) -> None:
        self.measured, self.model, self.paper = (
            _num(self.measured),
            _num(self.model),
            _num(self.paper),
        )
        if self.verdict:
            return
        if self.measured is None or self.model is None or self.tolerance is None:
            self.verdict = NOT_APPLICABLE if self.measured is None else "info"
        else:
            ok = abs(self.measured - self.model) <= self.tolerance
            self.verdict = "pass" if ok else "fail"

    def as_dict(self) -> dict[str, Any]:
        return {
            "measured": self.measured,
            "model": self.model,
            "paper": self.paper,
            "unit": self.unit,
            "tolerance": self.tolerance,
            "verdict": self.verdict,
        }


@dataclass
class ExperimentResult:
    """One experiment: ``id``, ``title``, ``paper_ref``, ``metrics`` by name, the conditions it
    set (``conditions``, text), ``notes`` (text), ``figures`` (base64 PNG), ``seconds`` taken,
    ``reason`` (why not applicable / why it failed)."""

    id: str
    title: str
    paper_ref: str
    metrics: dict[str, Metric] = field(default_factory=dict)
    conditions: str = ""
    notes: list[str] = field(default_factory=list)
    figures: list[str] = field(default_factory=list)
    seconds: float = 0.0
    reason: str = ""
    verdict_override: str = ""

    @property
    def verdict(self) -> str:
        if self.verdict_override:
            return self.verdict_override
        judged = [m.verdict for m in self.metrics.values() if m.verdict in ("pass", "fail")]
        if not judged:
            return NOT_APPLICABLE
        return "fail" if "fail" in judged else "pass"

    def as_dict(self) -> dict[str, Any]:
        """The JSON record of the issue's schema."""
        return {
            "id": self.id,
            "title": self.title,
            "paper_ref": self.paper_ref,
            "verdict": self.verdict,
            "metrics": {k: m.as_dict() for k, m in self.metrics.items()},
        }


@dataclass
class Context:
    """A report run: the ``drive``, ``hooks`` (progress, cancel, announcements), ``virtual``
    (the drive answers the virtual-only objects 0x5000-0x50FF) and ``speed_model`` (a, b)
    identified in this run (None until identify_speed_model ran)."""

    drive: Drive
    hooks: Hooks
    virtual: bool
    speed_model: tuple[float, float] | None = None
    progress: Callable[[float, str], None] | None = None

    def step_hooks(self, lo: float, hi: float) -> Hooks:
        """Hooks whose progress 0..1 maps onto ``lo..hi`` of this experiment's share."""
        outer = self.hooks

        def progress(f: float, text: str) -> None:
            outer.report(lo + (hi - lo) * f, text)

        return Hooks(progress=progress, sleep=outer.sleep, say=outer.say)


def is_virtual(drive: Drive) -> bool:
    """True when the drive answers sim_info.speed_factor (0x5030:2), an object only the
    virtual drive has (0x5000-0x50FF: the DSP firmware need not implement them). The identity
    0x1018 and the device name 0x1008 are reported but do not tell the two apart: the virtual
    drive carries the DSP's identity."""
    from ...errors import DriveError

    try:
        drive.read("sim_info.speed_factor")
        return True
    except (DriveError, KeyError):
        return False


def settling_samples(y: np.ndarray, y_from: float, y_to: float, band: float = 0.05) -> int | None:
    """Loop samples after the step (``y[0]`` is the step's sample) until ``y`` stays within
    ``band`` × |step| of ``y_to``; None if it never does within ``y``."""
    err = np.abs(np.asarray(y, dtype=float) - y_to) > band * abs(y_to - y_from)
    out = np.flatnonzero(err)
    if out.size == 0:
        return 0
    k = int(out[-1]) + 1
    return k if k < len(y) else None


def figure_png(fig: Any) -> str:
    """A matplotlib figure as base64 PNG (closed afterwards)."""
    from ...link.writers import png_bytes

    return base64.b64encode(png_bytes(fig, dpi=90)).decode("ascii")


def new_figure(rows: int = 1, height: float = 3.2) -> tuple[Any, Any]:
    """A figure (Agg backend, no display) with ``rows`` stacked axes sharing x."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(rows, 1, figsize=(7.5, height * rows), sharex=True, squeeze=False)
    return fig, [a[0] for a in axes]
