"""The lean whole-loop C reference kernel of the sweep benchmark (issue 28).

``benchmarks/lean_kernel.c`` is the product's closed loop in the sweep's case (PWM-exact bridge,
deadbeat eq. (15), IP speed loop, speed mode) written as one tight C function with its state in
locals, built here with cffi into a temporary directory at benchmark time (nothing is committed or
installed). :func:`lean_from` starts it from a :class:`~virtual_drive.sim.Simulator`'s own state
and parameters, so both run the same loop from the same point and their records can be compared
(:func:`compare`) before their speed is. The product's model and the kernel must stay the
same: the benchmark refuses to print a ratio when their records differ.
"""

from __future__ import annotations

import importlib.util
import time
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["SIGNALS", "build_lean", "compare", "lean_from", "time_both"]

_HERE = Path(__file__).resolve().parent
SIGNALS = ("i_p", "i_a", "i_b", "i_c", "speed", "i_p_ref")  #: the sweep's recorded signals

_CDEF = """
typedef struct {
    double R, L, k_e, emf_rounding, a_m, mech_gain, T_load, V_dc, Ts;
    int pole_pairs;
    float Phi_c, Gamma_c, kp_w, ki_w, i_lim, w_ref;
    double i[3], omega, theta_e;
    float q, q_c, e1, u1, u2, m_prev;
    int sec_prev;
} lean_t;
void lean_run(lean_t *s, int n, float *r_ip, float *r_ia, float *r_ib, float *r_ic,
              float *r_speed, float *r_iref);
"""


def build_lean(tmpdir: str) -> Any:
    """Compile ``lean_kernel.c`` with the product core's flags into ``tmpdir``; the module."""
    from cffi import FFI

    ffi = FFI()
    ffi.cdef(_CDEF)
    ffi.set_source(
        "_vd_lean",
        '#include "lean_kernel.h"\n',
        sources=[str(_HERE / "lean_kernel.c")],
        include_dirs=[str(_HERE)],
        extra_compile_args=["-std=c99", "-O3", "-fno-math-errno", "-fno-semantic-interposition"],
        libraries=["m"],
    )
    path = ffi.compile(tmpdir=tmpdir, verbose=False)
    spec = importlib.util.spec_from_file_location("_vd_lean", path)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def lean_from(mod: Any, sim: Any) -> Any:
    """A ``lean_t`` holding ``sim``'s parameters and state (sim in speed mode, running, no
    fault, PWM model without non-idealities, deadbeat without feed-forward: the kernel's case)."""
    L = sim._L
    p, cc, sc = L.p, L.cc, L.sc
    if not (
        L.mode == 2 and L.active and L.fault_code == 0 and L.model == 0 and L.on_prev
        and L.T_BT == 0.0 and L.T_delay == 0.0 and p.V_G == 0.0 and L.os_n == 0
        and cc.type == 0 and not cc.emf_ff and p.B_tot > 0.0 and p.emf_rounding > 0.0
    ):  # fmt: skip
        raise ValueError("the lean kernel covers the running speed loop of the sweep's case only")
    s = mod.ffi.new("lean_t *")
    for k in ("R", "L", "k_e", "emf_rounding", "mech_gain", "T_load", "V_dc", "pole_pairs"):
        setattr(s, k, getattr(p, k))
    s.a_m, s.Ts = L.a_m, L.Ts
    s.Phi_c, s.Gamma_c = cc.Phi_c, cc.Gamma_c
    s.kp_w, s.ki_w, s.i_lim, s.w_ref = sc.k_p, sc.k_i, sc.limit, L.w_ref_set
    s.i = list(p.i)
    s.omega, s.theta_e = p.omega, p.theta_e
    s.q, s.q_c, s.e1, s.u1, s.u2 = sc.q, sc.q_c, cc.e1, cc.u1, cc.u2
    s.m_prev, s.sec_prev = L.m_prev, L.sec_prev
    return s


def _run_lean(mod: Any, s: Any, rec: dict[str, np.ndarray]) -> None:
    n = len(rec["i_p"])
    ptr = [mod.ffi.cast("float *", rec[k].ctypes.data) for k in SIGNALS]
    mod.lib.lean_run(s, n, *ptr)


def compare(mod: Any, sim: Any, n: int) -> dict[str, float]:
    """Run ``sim`` and the kernel started from its state for ``n`` samples each; the largest
    absolute difference of each recorded signal (0.0 everywhere: bit-identical records).
    Leaves ``sim`` advanced by n samples."""
    s = lean_from(mod, sim)
    a = {k: np.zeros(n, dtype=np.float32) for k in SIGNALS}
    b = {k: np.zeros(n, dtype=np.float32) for k in SIGNALS}
    sim.run_record(n, a)
    _run_lean(mod, s, b)
    return {k: float(np.max(np.abs(a[k].astype(np.float64) - b[k]))) for k in SIGNALS}


def time_both(mod: Any, sim: Any, n: int, repeats: int) -> tuple[float, float]:
    """Best thread-CPU seconds of ``n`` samples: the product's sweep path
    (``Simulator.run_record`` with the six signals) and the kernel, in alternating chunks from
    the same operating point (each continues its own run)."""
    s = lean_from(mod, sim)
    rec = {k: np.zeros(n, dtype=np.float32) for k in SIGNALS}
    rec2 = {k: np.zeros(n, dtype=np.float32) for k in SIGNALS}
    _run_lean(mod, s, rec2)  # warm-up
    best_sim = best_ref = float("inf")
    for _ in range(repeats):
        c0 = time.thread_time()
        sim.run_record(n, rec)
        best_sim = min(best_sim, time.thread_time() - c0)
        c0 = time.thread_time()
        _run_lean(mod, s, rec2)
        best_ref = min(best_ref, time.thread_time() - c0)
    return best_sim, best_ref
