/* lean_kernel.h -- lean whole-loop reference kernel of the sweep benchmark (see lean_kernel.c). */
#ifndef BENCH_LEAN_KERNEL_H
#define BENCH_LEAN_KERNEL_H

typedef struct {
    /* parameters (SI; speeds of the IP loop in rpm) */
    double R, L, k_e, emf_rounding, a_m, mech_gain, T_load, V_dc, Ts;
    int pole_pairs;
    float Phi_c, Gamma_c, kp_w, ki_w, i_lim, w_ref;
    /* state */
    double i[3], omega, theta_e;
    float q, q_c, e1, u1, u2, m_prev;
    int sec_prev;
} lean_t;

/* Run n samples of the speed loop; each r_* holds n floats: i_p, i_a, i_b, i_c (A), speed (rpm),
 * i_p* (A). */
void lean_run(lean_t *s, int n, float *r_ip, float *r_ia, float *r_ib, float *r_ic,
              float *r_speed, float *r_iref);

#endif
