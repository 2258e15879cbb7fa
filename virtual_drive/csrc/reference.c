/*
 * reference.c -- lean reference kernel for `python -m virtual_drive.bench` (issue 11): the
 * least per-sample work a PWM-exact BLDC drive simulation needs, written as one C function with
 * no Python in the loop, so the product's speed can be stated as a ratio to it on the same
 * machine in the same run.  Not used by the product; built by the benchmark at run time.
 *
 * Per 20 us sample: Hall sector from theta_e, trapezoidal back-EMF of the three phases, the
 * pseudo current of the conducting pair, IP speed loop and deadbeat current law (float32, as
 * the DSP), the unipolar PWM period as five sub-intervals each solved exactly with exp()
 * (i(t) = Phi i0 + (1 - Phi) u / R of the conducting pair; the open phase is taken as carrying
 * no current), Euler mechanics, and 14 float32 signals written to the log.  What it leaves out
 * (the product does it): diode conduction of the open phase, commutation decay, rounded EMF
 * corners, the computational delay pipeline, protection, non-idealities.
 */
#include <math.h>

#include "reference.h"

#define PI_R 3.14159265358979323846

static double tri(double th)
{
    /* trapezoid, phase a: flat +1 on [30, 150] deg, -1 on [210, 330] deg, ramps between */
    double x = fmod(th, 2.0 * PI_R);
    if (x < 0.0) {
        x += 2.0 * PI_R;
    }
    if (x < PI_R / 6.0) {
        return x * (6.0 / PI_R);
    }
    if (x < 5.0 * PI_R / 6.0) {
        return 1.0;
    }
    if (x < 7.0 * PI_R / 6.0) {
        return 1.0 - (x - 5.0 * PI_R / 6.0) * (6.0 / PI_R);
    }
    if (x < 11.0 * PI_R / 6.0) {
        return -1.0;
    }
    return -1.0 + (x - 11.0 * PI_R / 6.0) * (6.0 / PI_R);
}

static const int ref_plus[7] = {0, 0, 0, 1, 1, 2, 2};
static const int ref_minus[7] = {0, 1, 2, 2, 0, 0, 1};

void ref_run(ref_t *s, int n, float *log)
{
    int k, x;
    const double Ts = s->Ts;
    for (k = 0; k < n; ++k) {
        double F[3], e[3], u_sec, ip, e_L, speed, Te, edge[6];
        float w_err, i_ref, err, v, m;
        int sec, p, q, j;
        double th = fmod(s->theta_e - PI_R / 6.0, 2.0 * PI_R);
        if (th < 0.0) {
            th += 2.0 * PI_R;
        }
        sec = (int)(th * (3.0 / PI_R)) + 1;
        if (sec > 6) {
            sec = 6;
        }
        p = ref_plus[sec];
        q = ref_minus[sec];
        for (x = 0; x < 3; ++x) {
            F[x] = tri(s->theta_e - x * (2.0 * PI_R / 3.0));
            e[x] = s->k_e * s->omega * F[x];
        }
        e_L = e[p] - e[q];
        ip = 0.5 * (s->i[p] - s->i[q]);
        speed = s->omega * (30.0 / PI_R);
        /* IP speed loop (float32): i* = k_p (k_i sum(w* - w) - w), clamped */
        w_err = s->w_ref - (float)speed;
        s->q += s->kp_w * s->ki_w * w_err;
        i_ref = s->q - s->kp_w * (float)speed;
        if (i_ref > s->i_lim) {
            i_ref = s->i_lim;
            s->q = i_ref + s->kp_w * (float)speed;
        } else if (i_ref < -s->i_lim) {
            i_ref = -s->i_lim;
            s->q = i_ref + s->kp_w * (float)speed;
        }
        /* deadbeat eq. (15) (float32): u = u2 + (e - Phi e1) / Gamma, plus the e_L
         * feed-forward, saturated at +-V_dc; anti-windup: the state keeps the applied voltage
         * and the error that would have produced it */
        err = i_ref - (float)ip;
        v = s->u2 + (err - s->Phi_c * s->e1) / s->Gamma_c;
        m = (v + (float)e_L) / (float)s->V_dc;
        if (m > 1.0f || m < -1.0f) {
            float u_sat;
            m = (m > 1.0f) ? 1.0f : -1.0f;
            u_sat = m * (float)s->V_dc - (float)e_L;
            err -= (v - u_sat) * s->Gamma_c;
            v = u_sat;
        }
        s->e1 = err;
        s->u2 = s->u1;
        s->u1 = v;
        /* five exact sub-intervals of the unipolar PWM period */
        {
            double dp = 0.5 * (1.0 + m), dm = 0.5 * (1.0 - m);
            double dh = dp > dm ? dp : dm, dl = dp > dm ? dm : dp;
            double sgn = dp >= dm ? 1.0 : -1.0;
            edge[0] = 0.0;
            edge[1] = 0.5 * (1.0 - dh) * Ts;
            edge[2] = 0.5 * (1.0 - dl) * Ts;
            edge[3] = 0.5 * (1.0 + dl) * Ts;
            edge[4] = 0.5 * (1.0 + dh) * Ts;
            edge[5] = Ts;
            Te = 0.0;
            for (j = 0; j < 5; ++j) {
                double dt = edge[j + 1] - edge[j];
                double vl = (j == 1 || j == 3) ? sgn * s->V_dc : 0.0;
                double Phi = exp(-s->R * dt / s->L);
                double i0 = ip;
                u_sec = (vl - e_L) / (2.0 * s->R);
                ip = Phi * ip + (1.0 - Phi) * u_sec;
                Te += 0.5 * (i0 + ip) * dt;
            }
            s->i[p] = ip;
            s->i[q] = -ip;
            s->i[3 - p - q] = 0.0;
            Te = s->k_e * (F[p] - F[q]) * Te / Ts;
        }
        /* Euler mechanics */
        s->omega += Ts * (Te - s->B * s->omega - s->T_load) / s->J;
        s->theta_e = fmod(s->theta_e + s->pole_pairs * s->omega * Ts, 2.0 * PI_R);
        /* 14 float32 signals */
        log[0 * n + k] = (float)ip;
        log[1 * n + k] = (float)s->i[0];
        log[2 * n + k] = (float)s->i[1];
        log[3 * n + k] = (float)s->i[2];
        log[4 * n + k] = (float)speed;
        log[5 * n + k] = m * (float)s->V_dc;
        log[6 * n + k] = (float)e_L;
        log[7 * n + k] = m;
        log[8 * n + k] = (float)sec;
        log[9 * n + k] = i_ref;
        log[10 * n + k] = s->w_ref;
        log[11 * n + k] = (float)s->V_dc;
        log[12 * n + k] = (float)Te;
        log[13 * n + k] = (float)s->theta_e;
    }
}
