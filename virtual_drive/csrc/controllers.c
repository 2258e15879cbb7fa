/* controllers.c -- see controllers.h for the laws, units, anti-windup and float32 notes. */
#include <math.h>

#include "controllers.h"

static int cc_finite(float x) { return (x == x) && (x - x == 0.0f); }

static float cc_sat(float x, float lo, float hi)
{
    if (x > hi) {
        return hi;
    }
    if (x < lo) {
        return lo;
    }
    return x;
}

static float cc_sign(float x) { return (x > 0.0f) ? 1.0f : ((x < 0.0f) ? -1.0f : 0.0f); }

int cc_current_configure(cc_current_t *c, int type, float Ts, float L_c, float R_c, float k_p,
                         float k_i, float T_BT, float T_DD, float T_SD, float V_G, int emf_ff)
{
    float x;
    if (!(cc_finite(Ts) && cc_finite(L_c) && cc_finite(R_c) && cc_finite(k_p) && cc_finite(k_i)
          && cc_finite(T_BT) && cc_finite(T_DD) && cc_finite(T_SD) && cc_finite(V_G))) {
        return -1;
    }
    if (Ts <= 0.0f || L_c <= 0.0f || R_c < 0.0f || type < CC_DEADBEAT || type > CC_PREDICTIVE) {
        return -1;
    }
    c->type = type;
    c->Ts = Ts;
    c->L_c = L_c;
    c->R_c = R_c;
    c->k_p = k_p;
    c->k_i = k_i;
    c->T_BT = T_BT;
    c->T_DD = T_DD;
    c->T_SD = T_SD;
    c->V_G = V_G;
    c->emf_ff = emf_ff ? 1 : 0;
    /* eq. (4), (5) with the estimates: Gamma_c = (1 - Phi_c) / (2 R_c)
     *   = Ts / (2 L_c) * g(x),  g(x) = expm1(x) / x,  x = -R_c Ts / L_c,
     * which tends to Ts / (2 L_c) as R_c -> 0.  Dividing by R_c directly fails for tiny R_c:
     * x underflows to 0 (or a subnormal) in float32 and (1 - Phi_c) / (2 R_c) becomes 0 or
     * wrong (R_c = 1.4e-45 gave Gamma_c = 0 -> 1/Gamma_c = inf -> overcurrent trip).  For
     * |x| < 1e-3, g(x) = 1 + x/2 + x^2/6 to float32 precision (next term x^3/24 < 5e-11). */
    x = -R_c * Ts / L_c;
    c->Phi_c = expf(x);
    if (x > -1.0e-3f) {
        c->Gamma_c = Ts / (2.0f * L_c) * (1.0f + x * (0.5f + x * (1.0f / 6.0f)));
    } else {
        c->Gamma_c = Ts / (2.0f * L_c) * (expm1f(x) / x);
    }
    return 0;
}

void cc_current_reset(cc_current_t *c, float v0)
{
    c->e1 = 0.0f;
    c->u1 = v0;
    c->u2 = v0;
    c->s = v0;
    c->v_L = v0;
    c->saturated = 0;
}

float cc_current_step(cc_current_t *c, float i_ref, float i_p, float e_L, float V_dc)
{
    float e = i_ref - i_p;
    float ff = c->emf_ff ? e_L : 0.0f;
    float u = 0.0f;      /* controller voltage without feed-forward, V */
    float d_u_d_e = 1.0f; /* sensitivity of u to e[k], V/A */
    float v, v_sat, u_sat, V_max, e_r;

    if (!(V_dc > 0.0f)) {
        V_dc = 1.0e-3f; /* no DC link: any nonzero command saturates */
    }
    V_max = V_dc;
    if (c->type == CC_DEADBEAT) {
        /* eq. (15): (1 - z^-2) u = (1 - Phi_c z^-1) e / Gamma_c */
        d_u_d_e = 1.0f / c->Gamma_c;
        u = c->u2 + (e - c->Phi_c * c->e1) / c->Gamma_c;
    } else if (c->type == CC_PI) {
        /* eq. (22): u = k_p e + s[k], s[k] = s[k-1] + k_i e[k] */
        d_u_d_e = c->k_p + c->k_i;
        u = c->k_p * e + c->s + c->k_i * e;
    } else {
        /* eq. (23): v(k+1) = 2 L f_s (i* - i_p(k)) - v(k) [+ 2 e_L(k)]; eq. (25) adds
         * 4 T_BT V_dc / Ts + E_L (T_DD + T_SD) f_s + 4 V_G (signs follow the current). */
        float fs = 1.0f / c->Ts;
        float dir = cc_sign(i_ref);
        d_u_d_e = 2.0f * c->L_c * fs;
        u = d_u_d_e * e - c->u1;
        u += dir * (4.0f * c->T_BT * V_dc * fs + 4.0f * c->V_G);
        u += e_L * (c->T_DD + c->T_SD) * fs;
        ff = c->emf_ff ? 2.0f * e_L : 0.0f;
    }
    v = u + ff;
    v_sat = cc_sat(v, -V_max, V_max);
    c->saturated = (v_sat != v) ? 1 : 0;
    u_sat = v_sat - ff;
    /* realizable reference: the error that would have produced u_sat */
    e_r = e;
    if (c->saturated && d_u_d_e != 0.0f) {
        e_r = e - (u - u_sat) / d_u_d_e;
    }
    if (c->type == CC_PI) {
        c->s = c->s + c->k_i * e_r;
    }
    if (c->type == CC_PREDICTIVE) {
        /* eq. (23) uses the total past line voltage v_L(k) */
        c->u2 = c->u1;
        c->u1 = v_sat;
    } else {
        c->u2 = c->u1;
        c->u1 = u_sat;
    }
    c->e1 = e_r;
    c->v_L = v_sat;
    return v_sat / V_dc;
}

int cc_speed_configure(cc_speed_t *s, float k_p, float k_i, float limit)
{
    if (!(cc_finite(k_p) && cc_finite(k_i) && cc_finite(limit)) || limit < 0.0f) {
        return -1;
    }
    s->k_p = k_p;
    s->k_i = k_i;
    s->limit = limit;
    return 0;
}

void cc_speed_reset(cc_speed_t *s, float i0, float w)
{
    s->q = i0 + s->k_p * w;
    s->q_c = 0.0f;
    s->saturated = 0;
}

float cc_speed_step(cc_speed_t *s, float w_ref, float w)
{
    /* IP (Fig. 17): i* = k_p (k_i x - w), x[k] = x[k-1] + e[k]; here q = k_p k_i x in A. */
    float e = w_ref - w;
    float inc = s->k_p * s->k_i * e;
    /* Kahan compensated sum q + inc */
    float y = inc - s->q_c;
    float t = s->q + y;
    float q_c = (t - s->q) - y;
    float out = t - s->k_p * w;
    float out_sat = cc_sat(out, -s->limit, s->limit);
    if (out_sat != out) {
        /* realizable reference: integral set so that the output is exactly the limit */
        s->q = out_sat + s->k_p * w;
        s->q_c = 0.0f;
        s->saturated = 1;
    } else {
        s->q = t;
        s->q_c = q_c;
        s->saturated = 0;
    }
    return out_sat;
}
