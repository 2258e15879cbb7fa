"""The paper's experiments in one run: a commissioning report of the connected drive.

:func:`run_report` runs the experiments of :data:`EXPERIMENTS` (or ``only`` those) in order,
each leaving the drive as found (state, mode, setpoints, gains and the settings it changes; also
on error and cancel), and returns a :class:`Report`; :meth:`Report.write` saves ``report.json``
(the schema ``{"drive": {...}, "experiments": [{"id", "title", "paper_ref", "verdict",
"metrics": {NAME: {"measured", "model", "paper", "unit", "tolerance", "verdict"}}}]}`` plus the
paper's inconsistencies) and one self-contained offline ``report.html`` (figures as base64 PNG).
``drive-link report`` is the command (:mod:`.cli`).
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ...errors import DriveError, InvalidValue
from ..report_ids import EXPERIMENT_IDS
from ..steps import Hooks
from . import current, electrical, ripple, speed
from ._base import Context, ExperimentResult, is_virtual
from .paper_checks import inconsistencies

if TYPE_CHECKING:
    from ...link.drive import Drive

__all__ = ["EXPERIMENTS", "Report", "run_report"]

#: id → the experiment (in the order they run; the speed model is identified before the speed
#: step uses it).
EXPERIMENTS: dict[str, Callable[[Context], ExperimentResult]] = {
    "current_step_deadbeat": current.current_step_deadbeat,
    "lc_sweep": current.lc_sweep,
    "current_step_pi": current.current_step_pi,
    "current_step_predictive": current.current_step_predictive,
    "pwm_ripple": ripple.pwm_ripple,
    "identify_electrical": electrical.identify_electrical,
    "identify_speed_model": speed.identify_speed_model,
    "speed_step": speed.speed_step,
    "load_step": speed.load_step,
}
if tuple(EXPERIMENTS) != EXPERIMENT_IDS:  # (the light list the parser and the GUI name)
    raise ImportError("drive_link.workflows.report_ids.EXPERIMENT_IDS differs from EXPERIMENTS")


@dataclass
class Report:
    """The run: ``drive`` (identity, real or virtual, time, load), the ``results`` and the
    paper's ``inconsistencies``."""

    drive: dict[str, Any]
    results: list[ExperimentResult] = field(default_factory=list)
    inconsistencies: list[dict[str, Any]] = field(default_factory=list)

    def as_dict(self) -> dict[str, Any]:
        return {
            "drive": self.drive,
            "experiments": [r.as_dict() for r in self.results],
            "paper_inconsistencies": self.inconsistencies,
        }

    def write(self, out_dir: str | Path) -> tuple[Path, Path]:
        """``report.json`` and ``report.html`` in ``out_dir`` (created); returns both paths."""
        from .html import render

        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        js = out / "report.json"
        js.write_text(json.dumps(self.as_dict(), indent=1, allow_nan=False))
        html = out / "report.html"
        html.write_text(render(self), encoding="utf-8")
        return js, html


def _identity(drive: Drive) -> dict[str, Any]:
    info: dict[str, Any] = {"node_id": drive.node_id}
    for name in ("manufacturer_device_name", "hardware_version", "software_version",
                 "identity.vendor_id", "identity.product_code", "identity.revision_number",
                 "identity.serial_number", "motor.R", "motor.L", "current_controller.L_c"):
        try:
            info[name] = drive.read(name)
        except (DriveError, KeyError):
            info[name] = None
    return info


def select(only: list[str] | None) -> list[str]:
    """The experiment ids to run (all by default); :class:`InvalidValue` names unknown ones."""
    if not only:
        return list(EXPERIMENTS)
    bad = [k for k in only if k not in EXPERIMENTS]
    if bad:
        raise InvalidValue(f"unknown experiment(s) {', '.join(bad)}; known: "
                           f"{', '.join(EXPERIMENTS)}")
    return [k for k in EXPERIMENTS if k in only]


def run_report(
    drive: Drive,
    only: list[str] | None = None,
    hooks: Hooks | None = None,
    on_result: Callable[[ExperimentResult], None] | None = None,
) -> Report:
    """Run the experiments on ``drive``; ``hooks.progress`` gets the fraction of the whole run
    (0..1) and a text, ``hooks.sleep`` may raise to cancel (the drive is put back as found
    first), ``hooks.say`` gets each experiment's 'what I change' line. An experiment that fails
    is recorded as failed with its error and the run goes on (KeyboardInterrupt stops it)."""
    ids = select(only)
    h = hooks or Hooks()
    t0 = time.monotonic()
    load0 = os.getloadavg()[0]
    virtual = is_virtual(drive)
    info = {**_identity(drive), "virtual": virtual,
            "kind": "virtual drive (answers the 0x5000-0x50FF objects)" if virtual
            else "real drive (no virtual-only objects)"}
    rep = Report(info, inconsistencies=inconsistencies())
    for j, key in enumerate(ids):
        lo, hi = j / len(ids), (j + 1) / len(ids)

        def progress(f: float, text: str, key: str = key, lo: float = lo, hi: float = hi) -> None:
            h.report(lo + (hi - lo) * min(max(f, 0.0), 1.0), f"{key}: {text}")

        ctx_hooks = Hooks(progress=progress, sleep=h.sleep, say=h.say)
        ctx = Context(drive, ctx_hooks, virtual, speed_model=_model(rep))
        t1 = time.monotonic()
        h.report(lo, f"{key}: starting")
        try:
            res = EXPERIMENTS[key](ctx)
        except DriveError as exc:
            res = ExperimentResult(key, key, "", reason=f"failed: {exc}",
                                   verdict_override="fail")
        res.seconds = time.monotonic() - t1
        if res.reason.startswith("not applicable"):
            res.verdict_override = "not applicable"
        rep.results.append(res)
        if on_result is not None:
            on_result(res)
    h.report(1.0, "done")
    rep.drive["seconds"] = round(time.monotonic() - t0, 1)
    rep.drive["load_1min"] = [round(load0, 2), round(os.getloadavg()[0], 2)]
    rep.drive["cpus"] = os.cpu_count()
    return rep


def _model(rep: Report) -> tuple[float, float] | None:
    for r in rep.results:
        if r.id == "identify_speed_model" and "a" in r.metrics:
            a, b = r.metrics["a"].measured, r.metrics["b"].measured
            if a is not None and b is not None:
                return a, b
    return None
