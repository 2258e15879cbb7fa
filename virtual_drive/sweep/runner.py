"""One sweep run in a worker: build the simulator from a :class:`~.spec.RunJob`, run its
scenario, compute the metrics and the verdict, return the row (plain Python values).

:func:`run_batch` is the task the engines send (a local process or a Dask worker): it reads and
writes no file, so a task lost with its worker is simply run again elsewhere.
"""

from __future__ import annotations

import math
from typing import Any

from virtual_drive.sim import (
    CurrentControllerParams,
    InverterParams,
    LoadParams,
    MotorParams,
    ProtectionParams,
    Simulator,
    SpeedControllerParams,
)
from virtual_drive.sweep.limits import severity, verdict
from virtual_drive.sweep.metrics import METRICS, compute_metrics
from virtual_drive.sweep.scenarios import Trace, simulate
from virtual_drive.sweep.spec import RunJob

__all__ = ["INPUT_COLUMNS", "build_simulator", "run_batch", "run_one", "run_trace"]

#: the resolved inputs written in every row, in this order
INPUT_COLUMNS: tuple[str, ...] = (
    "R", "L", "K_rpm", "k_e", "pole_pairs", "J", "B", "k_gen", "T_load", "V_dc", "controller",
    "L_c", "R_c", "L_c/L", "R_c/R", "k_p", "k_i", "emf_feedforward", "speed_k_p", "speed_k_i",
    "current_limit", "overcurrent_trip", "overvoltage_trip", "undervoltage_trip",
)  # fmt: skip


def build_simulator(inputs: dict[str, Any], model: str = "pwm") -> Simulator:
    """A fresh :class:`Simulator` with the run's motor, supply, load, gains and protection
    (``ValueError`` naming the field for a value the drive would refuse)."""
    g = inputs
    return Simulator(
        motor=MotorParams(R=g["R"], L=g["L"], K_rpm=g["K_rpm"], pole_pairs=g["pole_pairs"]),
        inverter=InverterParams(V_dc=g["V_dc"]),
        load=LoadParams(T_load=g["T_load"], k_gen=g["k_gen"], J=g["J"], B=g["B"]),
        current=CurrentControllerParams(
            type=g["controller"], L_c=g["L_c"], R_c=g["R_c"], k_p=g["k_p"], k_i=g["k_i"],
            emf_feedforward=bool(g["emf_feedforward"]),
        ),
        speed=SpeedControllerParams(
            k_p=g["speed_k_p"], k_i=g["speed_k_i"], current_limit=g["current_limit"]
        ),
        model=model,
        protection=ProtectionParams(
            overcurrent_trip=g["overcurrent_trip"],
            overvoltage_trip=g["overvoltage_trip"],
            undervoltage_trip=g["undervoltage_trip"],
        ),
    )


def run_trace(job: RunJob) -> Trace:
    """The recorded response of ``job`` (for a plot of one run)."""
    return simulate(build_simulator(job.inputs, job.model), job.scenario, job.inputs)


def run_one(job: RunJob) -> dict[str, Any]:
    """The row of ``job``: run, point, scenario, seed, inputs, metrics, pass, fails, error."""
    row: dict[str, Any] = {
        "run": job.run,
        "point": job.point,
        "scenario": job.scenario.name,
        "seed": job.seed,
    }
    for k in INPUT_COLUMNS:
        v = job.inputs[k]
        row[k] = v if isinstance(v, str) else float(v)
    error = ""
    try:
        sim = build_simulator(job.inputs, job.model)
        trace = simulate(sim, job.scenario, job.inputs, reuse=True)
    except ValueError as exc:  # a value the drive refuses: the row says which
        error = str(exc).splitlines()[0]
        metrics: dict[str, Any] = {m: math.nan for m in METRICS}
        metrics["stable"] = False
        metrics["emcy"] = 0
        fails = [f"error: {error}"]
    else:
        metrics = compute_metrics(trace, job.scenario, job.band, job.inputs["current_limit"])
        fails = verdict(metrics, job.limits)
    row.update(metrics)
    row["passed"] = not fails
    row["fails"] = ";".join(fails)
    row["severity"] = severity(metrics, job.limits, fails)
    row["error"] = error
    return row


def run_batch(jobs: list[RunJob]) -> list[dict[str, Any]]:
    """Rows of ``jobs`` in order: the engines' task."""
    return [run_one(j) for j in jobs]
