"""cffi (out-of-line, API mode) build script for ``virtual_drive._core``.

The extension compiles the portable controllers (``csrc/controllers.c``, the code the F28335
would run) together with the host-side plant (``csrc/plant.c``) and sample loop
(``csrc/loop.c``).  Built by ``setup.py`` (``cffi_modules``) during ``pip install -e .`` /
``pip wheel``; can also be run directly: ``python virtual_drive/_build_core.py``.
"""

from __future__ import annotations

from pathlib import Path

from cffi import FFI

__all__ = ["CDEF", "ffibuilder"]

_CSRC = Path(__file__).resolve().parent / "csrc"
_SOURCES = ["controllers.c", "plant.c", "loop.c"]

CDEF = """
#define CC_DEADBEAT 0
#define CC_PI 1
#define CC_PREDICTIVE 2
#define LOOP_NSIG 17
#define LOOP_OS_MAX 64

typedef struct {
    int type; float Ts; float L_c; float R_c; float k_p; float k_i;
    float T_BT; float T_DD; float T_SD; float V_G; int emf_ff;
    float Phi_c; float Gamma_c; float e1; float u1; float u2; float s; float v_L;
    int saturated;
} cc_current_t;

typedef struct {
    float k_p; float k_i; float limit; float q; float q_c; int saturated;
} cc_speed_t;

typedef struct {
    double R; double L; double r_over_l; double inv_r; double k_e; int pole_pairs;
    double emf_rounding;
    double J; double B_tot; double mech_gain; double T_load; double V_dc; double V_G;
    double i[3]; double omega; double theta_e;
    double e_seg[3]; double F_seg[3];
    double Te_int; double i_abs_max; int nonfinite;
    double w_ip[3]; double ip_min; double ip_max; double ip_last; int ip_dir; int ip_peaks;
} plant_t;

typedef struct {
    plant_t p; cc_current_t cc; cc_speed_t sc;
    double Ts; double a_m; int model; int mode; int active;
    double T_BT; double T_delay; double i_ref_set; double w_ref_set;
    float m_prev; float m_prev2; int sec_prev; int sec_prev2; int on_prev; int on_prev2;
    double oc_trip; double ov_trip; double uv_trip;
    int fault_code; int fault_reason; double fault_time; int inject;
    double t; long long k;
    float last[17];
    long long segments;
    int os_n; double *os_buf; long long os_cap; long long os_len;
    ...;
} sample_loop_t;

int cc_current_configure(cc_current_t *c, int type, float Ts, float L_c, float R_c, float k_p,
                         float k_i, float T_BT, float T_DD, float T_SD, float V_G, int emf_ff);
void cc_current_reset(cc_current_t *c, float v0);
float cc_current_step(cc_current_t *c, float i_ref, float i_p, float e_L, float V_dc);
int cc_speed_configure(cc_speed_t *s, float k_p, float k_i, float limit);
void cc_speed_reset(cc_speed_t *s, float i0, float w);
float cc_speed_step(cc_speed_t *s, float w_ref, float w);

double plant_emf_shape(double theta, double w);
int plant_hall_sector(double theta_e);

void loop_init(sample_loop_t *loop);
void loop_update_mech(sample_loop_t *loop);
int loop_run(sample_loop_t *loop, int n, float **sig, double *t_out);
int loop_run_points(sample_loop_t *loop, int n, const int *at, int n_at, float *snap);
void loop_reset_fault(sample_loop_t *loop);
"""

ffibuilder = FFI()
ffibuilder.cdef(CDEF)
ffibuilder.set_source(
    "virtual_drive._core",
    '#include "controllers.h"\n#include "plant.h"\n#include "loop.h"\n',
    sources=[str(Path("virtual_drive") / "csrc" / s) for s in _SOURCES],
    # firmware_protocol: the generated header bldc_drive_od.h (OD_EMCY_*, OD_TRIP_*)
    include_dirs=[str(Path("virtual_drive") / "csrc"), "firmware_protocol"],
    extra_compile_args=["-std=c99", "-O3", "-fno-math-errno", "-fno-semantic-interposition"],
    libraries=["m"],
)

if __name__ == "__main__":
    import os

    os.chdir(_CSRC.parent.parent)
    ffibuilder.compile(verbose=True)
