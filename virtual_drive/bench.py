"""Benchmark of the simulation core: ``python -m virtual_drive.bench``.

Prints the time per simulated second at fs = 50 kHz (best of several 1-s chunks) for the
PWM-exact model and the averaged model, with every signal recorded, in a speed-loop operating
point at 1500 rpm with the default DC-generator load (~97 A, commutations, open-phase diode
conduction).

In the same run it builds (cffi, from ``csrc/reference.c``, into a temporary directory) and
times a lean reference kernel: one C function doing the least per-sample work of a PWM-exact
drive simulation (Hall sector, deadbeat + IP, five exact PWM sub-intervals with ``exp``, Euler
mechanics, 14 float32 signals logged), no Python in the loop. Chunks of the product and of the
reference alternate, so both see the same machine load. The last line is
``ratio=<product / reference>`` for the PWM-exact model (thread CPU time, best chunk of each;
issue 11's goal: <= 2.0).
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # BLAS threads would compete for the core

__all__ = ["N_SAMPLES", "Timing", "build_reference", "main", "measure"]

N_SAMPLES = 50_000  #: one simulated second at fs = 50 kHz
_CSRC = Path(__file__).resolve().parent / "csrc"

_REF_CDEF = """
typedef struct {
    double R, L, k_e, J, B, T_load, V_dc, Ts;
    int pole_pairs;
    float kp_w, ki_w, i_lim, Phi_c, Gamma_c, w_ref;
    double i[3], omega, theta_e;
    float q, e1, u1, u2;
} ref_t;
void ref_run(ref_t *s, int n, float *log);
"""


class Timing:
    """Best wall and thread-CPU time (ms) per simulated second of a series of 1-s chunks."""

    def __init__(self) -> None:
        self.wall = math.inf
        self.cpu = math.inf

    def add(self, wall_s: float, cpu_s: float) -> None:
        self.wall = min(self.wall, wall_s * 1e3)
        self.cpu = min(self.cpu, cpu_s * 1e3)


def build_reference(tmpdir: str) -> Any:
    """Compile ``csrc/reference.c`` with cffi into ``tmpdir`` and import it (ffi, lib)."""
    from cffi import FFI

    ffi = FFI()
    ffi.cdef(_REF_CDEF)
    ffi.set_source(
        "_vd_reference",
        '#include "reference.h"\n',
        sources=[str(_CSRC / "reference.c")],
        include_dirs=[str(_CSRC)],
        extra_compile_args=["-std=c99", "-O3", "-fno-math-errno"],
        libraries=["m"],
    )
    path = ffi.compile(tmpdir=tmpdir, verbose=False)
    spec = importlib.util.spec_from_file_location("_vd_reference", path)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _reference_state(mod: Any, rpm: float) -> tuple[Any, Any]:
    """A ref_t at the product's operating point (Table 2 motor, default load and gains)."""
    import numpy as np

    from virtual_drive.sim.params import (
        RPM_PER_RAD_S,
        LoadParams,
        MotorParams,
        SpeedControllerParams,
        Ts,
    )

    m, ld, sp = MotorParams(), LoadParams(), SpeedControllerParams()
    s = mod.ffi.new("ref_t *")
    s.R, s.L, s.k_e, s.pole_pairs = m.R, m.L, m.k_e, m.pole_pairs
    s.J, s.B, s.T_load, s.V_dc, s.Ts = ld.J, ld.B_tot, ld.T_load, 48.0, Ts
    s.kp_w, s.ki_w, s.i_lim = sp.k_p, sp.k_i, sp.current_limit
    x = -m.R * Ts / m.L
    s.Phi_c = math.exp(x)
    s.Gamma_c = (1.0 - math.exp(x)) / (2.0 * m.R)
    s.w_ref = rpm
    s.omega = rpm / RPM_PER_RAD_S
    s.theta_e = math.pi / 3.0
    # integral part at the load's steady-state current so the run starts near equilibrium
    s.q = ld.B_tot * s.omega / m.K_t + sp.k_p * rpm
    log = np.empty(14 * N_SAMPLES, dtype=np.float32)
    return s, log


def measure(repeats: int = 5, rpm: float = 1500.0) -> dict[str, Timing]:
    """Timings of the product ("pwm", "averaged") and of the reference ("reference")."""
    from virtual_drive.sim import Simulator

    sims = {}
    for model in ("pwm", "averaged"):
        sim = Simulator(model=model)
        sim.set_speed(rpm)
        sim.set_mode("speed")
        sim.set_speed_ref(rpm)
        sim.run(N_SAMPLES, record=False)
        sims[model] = sim
    out = {name: Timing() for name in ("pwm", "averaged", "reference")}
    with tempfile.TemporaryDirectory(prefix="vd-bench-") as tmp:
        mod = build_reference(tmp)
        ref, log = _reference_state(mod, rpm)
        log_ptr = mod.ffi.cast("float *", log.ctypes.data)
        mod.lib.ref_run(ref, N_SAMPLES, log_ptr)  # warm-up
        for _ in range(repeats):
            for model, sim in sims.items():
                t0, c0 = time.perf_counter(), time.thread_time()
                rec = sim.run(N_SAMPLES)
                out[model].add(time.perf_counter() - t0, time.thread_time() - c0)
                assert len(rec["i_p"]) == N_SAMPLES
            t0, c0 = time.perf_counter(), time.thread_time()
            mod.lib.ref_run(ref, N_SAMPLES, log_ptr)
            out["reference"].add(time.perf_counter() - t0, time.thread_time() - c0)
        if not abs(float(log[4 * N_SAMPLES + N_SAMPLES - 1]) - rpm) < 0.2 * rpm:
            raise RuntimeError("reference kernel left its operating point")  # guards the build
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7, help="1-s chunks per kernel (best is kept)")
    args = ap.parse_args(argv)
    if args.repeats < 1:
        ap.error("--repeats must be >= 1")
    res = measure(args.repeats)
    for name, t in res.items():
        print(
            f"{name:9s}: {t.wall:7.2f} ms wall, {t.cpu:7.2f} ms CPU per simulated second "
            f"({1000.0 / t.wall:6.1f}x real time)"
        )
    print(f"load average: {' '.join(f'{x:.2f}' for x in os.getloadavg())} on {os.cpu_count()} CPUs")
    print(f"ms_per_sim_s={res['pwm'].wall:.2f}")
    print(f"ratio={res['pwm'].cpu / res['reference'].cpu:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
