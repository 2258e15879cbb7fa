"""The ids of the commissioning report's experiments, in the order they run
(:data:`drive_link.workflows.report.EXPERIMENTS` is built in this order and checks it).

A module of its own, without the experiments: ``drive-link``'s parser (``--only``'s help) and
the dashboard's Report tab name them without importing :mod:`drive_link.workflows.report`,
whose scipy imports cost about 1 s of CPU per command line (``drive-link --help`` took 1.0 s,
0.97 s of it in that import) and 2-6 s on a loaded host.
"""

from __future__ import annotations

__all__ = ["EXPERIMENT_IDS"]

EXPERIMENT_IDS: tuple[str, ...] = (
    "current_step_deadbeat",
    "lc_sweep",
    "current_step_pi",
    "current_step_predictive",
    "pwm_ripple",
    "identify_electrical",
    "identify_speed_model",  # (before the speed step, which uses the identified model)
    "speed_step",
    "load_step",
)
