/* reference.h -- lean reference kernel of the simulation benchmark (see reference.c). */
#ifndef BLDC_REFERENCE_H
#define BLDC_REFERENCE_H

typedef struct {
    /* parameters (SI; speeds of the IP loop in rpm) */
    double R, L, k_e, J, B, T_load, V_dc, Ts;
    int pole_pairs;
    float kp_w, ki_w, i_lim, Phi_c, Gamma_c, w_ref;
    /* state */
    double i[3], omega, theta_e;
    float q, e1, u1, u2;
} ref_t;

/* Run n samples; log holds 14 * n floats (signal j of sample k at log[j * n + k]). */
void ref_run(ref_t *s, int n, float *log);

#endif
