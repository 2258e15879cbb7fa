"""Benchmark of the simulation core: ``python -m virtual_drive.bench``.

Prints the wall time per simulated second at fs = 50 kHz (best of several 1-s chunks) for the
PWM-exact model and the averaged model, with every signal recorded, in a speed-loop operating
point at 1500 rpm with the default DC-generator load (~97 A, commutations, open-phase diode
conduction).  The last line is ``ms_per_sim_s=<value>`` for the PWM-exact model.
"""

from __future__ import annotations

import argparse
import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # BLAS threads would compete for the core


def measure(model: str, repeats: int = 5, rpm: float = 1500.0) -> tuple[float, float, float]:
    """(best wall ms, best CPU ms, segments per sample) per simulated second."""
    from virtual_drive.sim import Simulator

    sim = Simulator(model=model)
    sim.set_speed(rpm)
    sim.set_mode("speed")
    sim.set_speed_ref(rpm)
    sim.run(50_000, record=False)
    best_wall = best_cpu = float("inf")
    seg = 0.0
    for _ in range(repeats):
        s0 = sim.segments
        t0, c0 = time.perf_counter(), time.process_time()
        rec = sim.run(50_000)
        best_wall = min(best_wall, time.perf_counter() - t0)
        best_cpu = min(best_cpu, time.process_time() - c0)
        seg = (sim.segments - s0) / 50_000
        assert len(rec["i_p"]) == 50_000
    return best_wall * 1e3, best_cpu * 1e3, seg


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5, help="1-s chunks per model (best is kept)")
    args = ap.parse_args(argv)
    if args.repeats < 1:
        ap.error("--repeats must be >= 1")
    res = {m: measure(m, args.repeats) for m in ("averaged", "pwm")}
    for m, (wall, cpu, seg) in res.items():
        print(
            f"{m:9s}: {wall:7.2f} ms wall, {cpu:7.2f} ms CPU per simulated second "
            f"({1000.0 / wall:6.1f}x real time, {seg:.2f} circuit segments per sample)"
        )
    print(f"ms_per_sim_s={res['pwm'][0]:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
