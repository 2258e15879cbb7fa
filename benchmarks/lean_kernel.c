/*
 * lean_kernel.c -- lean whole-loop reference kernel of the sweep benchmark (issue 28): the product's
 * closed loop in the sweep's case (PWM-exact unipolar bridge without non-idealities, deadbeat
 * current law eq. (15), IP speed loop eq. (27), speed mode, no fault) written as ONE C function
 * with the whole state in locals: no per-sample function calls, no struct loads or stores, no
 * mode / protection / record-selection tests.  Not used by the product; compiled by the
 * benchmark at run time (cffi, into a temporary directory; see benchmarks/_lean_kernel.py).
 *
 * Same equations as the product (plant.h, loop.h, controllers.h), so it gives the product's
 * records to float rounding from the same state (the benchmark checks it):
 *   - Hall sector s from theta_e, rounded-trapezoid back-EMF F(theta_e) of the phases;
 *   - pseudo current i_p of the conducting pair (open phase signed as in the previous sector);
 *   - IP speed loop (float32, Kahan-summed integral, realizable-reference anti-windup) and the
 *     deadbeat law (float32) u = u2 + (e - Phi_c e1) / Gamma_c, saturated at +-V_dc;
 *   - one sample of computational delay: m[k] and the sector are applied in the next period;
 *   - the unipolar PWM period as up to five sub-intervals, each solved in closed form
 *     i(t) = Phi i0 + (1 - Phi) u / R, Phi = exp(-R t / L); the open leg's freewheel diode
 *     clamps it to a rail while it conducts, its current-zero instant solved in closed form
 *     t* = (L/R) log1p(-i0 R / u); back-EMF held at its mid-sample value;
 *   - the exact shaft update for the sample-mean torque;
 *   - six float32 signals recorded per sample (the sweep's: i_p, i_a, i_b, i_c, speed, i_p*).
 * What it leaves out (the product does it): protection and trips, NaN guards, the other
 * controllers and modes, the back-EMF estimate e_L at the sample (only the feed-forward uses
 * it), blanking / switch drop / gate delays, the oversampled record, the torque and the other
 * eight signals, segment counting.
 */
#include <math.h>

#include "lean_kernel.h"

#define PI_L 3.14159265358979323846
#define TWO_PI_L (2.0 * PI_L)
#define I_EPS 1e-9

static const int l_plus[7] = {0, 0, 0, 1, 1, 2, 2};
static const int l_minus[7] = {0, 1, 2, 2, 0, 0, 1};
static const int l_open[7] = {0, 2, 1, 0, 2, 1, 0};
static const double l_open_sign[2][7] = {{0.0, 1.0, -1.0, 1.0, -1.0, 1.0, -1.0},
                                         {0.0, -1.0, 1.0, -1.0, 1.0, -1.0, 1.0}};

static inline double wrap(double x)
{
    if (x >= TWO_PI_L) {
        return (x >= 2.0 * TWO_PI_L) ? fmod(x, TWO_PI_L) : x - TWO_PI_L;
    }
    if (x < 0.0) {
        x = (x >= -TWO_PI_L) ? x + TWO_PI_L : fmod(x, TWO_PI_L) + TWO_PI_L;
    }
    return x;
}

/* trapezoid of phase a for theta in [0, 2 pi), corners rounded over w = 2 hw */
static inline double shape(double th, double hw, double inv2w)
{
    const double c = PI_L / 6.0, slope = 6.0 / PI_L;
    double T, x;
    int neg = 0;
    if (th >= PI_L) {
        th -= PI_L;
        neg = 1;
    }
    if (th > 0.5 * PI_L) {
        th = PI_L - th;
    }
    T = (th < c) ? th * slope : 1.0;
    x = th - c;
    if (x > -hw && x < hw) {
        double y = x + hw;
        T -= slope * (y * y * inv2w - (x > 0.0 ? x : 0.0));
    }
    return neg ? -T : T;
}

static inline void shapes(double th, double hw, double inv2w, double F[3])
{
    double tb = th - 2.0 * PI_L / 3.0, tc = th - 4.0 * PI_L / 3.0;
    if (tb < 0.0) {
        tb += TWO_PI_L;
        tb = (tb >= TWO_PI_L) ? tb - TWO_PI_L : tb;
    }
    if (tc < 0.0) {
        tc += TWO_PI_L;
        tc = (tc >= TWO_PI_L) ? tc - TWO_PI_L : tc;
    }
    F[0] = shape(th, hw, inv2w);
    F[1] = shape(tb, hw, inv2w);
    F[2] = shape(tc, hw, inv2w);
}

/* 1 - exp(-x) */
static inline double one_minus_phi(double x)
{
    if (x < 0.01) {
        return x * (1.0 + x * (-0.5 + x * (1.0 / 6.0 + x * (-1.0 / 24.0 + x * (1.0 / 120.0)))));
    }
    if (x < 0.02) {
        return x * (1.0 + x * (-0.5 + x * (1.0 / 6.0 + x * (-1.0 / 24.0 + x * (1.0 / 120.0
               + x * (-1.0 / 720.0 + x * (1.0 / 5040.0)))))));
    }
    return -expm1(-x);
}

static inline double log1p_s(double x)
{
    if (x < 0.005 && x > -0.005) {
        return x * (1.0 + x * (-0.5 + x * (1.0 / 3.0 + x * (-0.25 + x * (0.2 + x * (-1.0 / 6.0
               + x * (1.0 / 7.0)))))));
    }
    return log1p(x);
}

void lean_run(lean_t *s, int n, float *r_ip, float *r_ia, float *r_ib, float *r_ic,
              float *r_speed, float *r_iref)
{
    /* parameters */
    const double R = s->R, Lh = s->L, r_over_l = R / Lh, inv_r = 1.0 / R, l_over_r = Lh / R;
    const double k_e = s->k_e, Vd = s->V_dc, Ts = s->Ts, a_m = s->a_m, mech_gain = s->mech_gain;
    const double T_load = s->T_load, hw = 0.5 * s->emf_rounding, inv2w = 0.5 / s->emf_rounding;
    const double pp_half = s->pole_pairs * 0.5, mid_gain = 0.5 * Ts * s->pole_pairs;
    const double inv_Ts = 1.0 / Ts, kh = 0.5 * k_e, rpm = 60.0 / (2.0 * PI_L);
    const float Phi_c = s->Phi_c, Gamma_c = s->Gamma_c, inv_Gamma = 1.0f / Gamma_c;
    const float kp_w = s->kp_w, ki_w = s->ki_w, i_lim = s->i_lim, w_ref = s->w_ref;
    const float V_dc_f = (float)Vd;
    /* state */
    double i[3] = {s->i[0], s->i[1], s->i[2]}, omega = s->omega, theta = s->theta_e;
    float q = s->q, q_c = s->q_c, e1 = s->e1, u1 = s->u1, u2 = s->u2, m_prev = s->m_prev;
    int sec_prev = s->sec_prev, k;
    for (k = 0; k < n; ++k) {
        double Fs[3], i_p, speed, Te_int = 0.0, w0;
        float i_ref, m;
        int sec;
        {
            double u = wrap(theta - PI_L / 6.0);
            int x = (int)(u * (3.0 / PI_L));
            sec = (x > 5) ? 6 : x + 1;
        }
        i_p = 0.5 * (i[l_plus[sec]] - i[l_minus[sec]]
                     + l_open_sign[!(omega >= 0.0)][sec] * i[l_open[sec]]);
        speed = omega * rpm;
        {
            /* IP speed loop eq. (27), float32: i* = k_p (k_i sum(w* - w) - w), |i*| <= limit */
            const float w = (float)speed, inc = kp_w * ki_w * (w_ref - w);
            const float y = inc - q_c, t = q + y, out = t - kp_w * w;
            if (out > i_lim || out < -i_lim) {
                i_ref = (out > i_lim) ? i_lim : -i_lim;
                q = i_ref + kp_w * w;
                q_c = 0.0f;
            } else {
                i_ref = out;
                q_c = (t - q) - y;
                q = t;
            }
        }
        {
            /* deadbeat eq. (15), float32: (1 - z^-2) u = (1 - Phi_c z^-1) e / Gamma_c */
            const float e = i_ref - (float)i_p;
            const float u = u2 + (e - Phi_c * e1) / Gamma_c;
            float v = u, e_r = e;
            if (v > V_dc_f || v < -V_dc_f) {
                v = (v > V_dc_f) ? V_dc_f : -V_dc_f;
                e_r = e - (u - v) / inv_Gamma;
            }
            u2 = u1;
            u1 = v;
            e1 = e_r;
            m = v / V_dc_f;
        }
        r_ip[k] = (float)i_p;
        r_ia[k] = (float)i[0];
        r_ib[k] = (float)i[1];
        r_ic[k] = (float)i[2];
        r_speed[k] = (float)speed;
        r_iref[k] = i_ref;
        /* the PWM period of m[k-1]: back-EMF at the mid-sample angle */
        {
            double th = theta + mid_gain * omega;
            th = (th >= TWO_PI_L || th < 0.0) ? wrap(th) : th;
            shapes(th, hw, inv2w, Fs);
        }
        {
            const int z = l_open[sec_prev], a = (z == 0) ? 1 : 0, b = (z == 2) ? 1 : 2;
            const double kw = k_e * omega;
            const double e0 = kw * Fs[0], e1d = kw * Fs[1], e2 = kw * Fs[2];
            const double ea = kw * Fs[a], eb = kw * Fs[b], ez = kw * Fs[z];
            const double Fa = Fs[a], Fb = Fs[b], Fz = Fs[z];
            const double dp = 0.5 * (1.0 + (double)m_prev), dm = 0.5 * (1.0 - (double)m_prev);
            const int p_hi = (dp >= dm);
            const double d_hi = p_hi ? dp : dm, d_lo = p_hi ? dm : dp;
            const int a_hi = (a == (p_hi ? l_plus[sec_prev] : l_minus[sec_prev]));
            double edge[6], ia = i[a], ib = i[b], iz = i[z];
            int j;
            edge[0] = 0.0;
            edge[1] = (d_hi >= 1.0) ? 0.0 : 0.5 * (1.0 - d_hi) * Ts;
            edge[2] = (d_lo <= 0.0) ? 0.5 * Ts : 0.5 * (1.0 - d_lo) * Ts;
            edge[3] = (d_lo <= 0.0) ? 0.5 * Ts : 0.5 * (1.0 + d_lo) * Ts;
            edge[4] = (d_hi >= 1.0) ? Ts : 0.5 * (1.0 + d_hi) * Ts;
            edge[5] = Ts;
            for (j = 0; j < 5; ++j) {
                /* 0, 4 both legs low; 1, 3 the larger duty's leg high; 2 both high */
                const double va = (j == 2) ? Vd : ((j & 1) ? (a_hi ? Vd : 0.0) : 0.0);
                const double vb = (j == 2) ? Vd : ((j & 1) ? (a_hi ? 0.0 : Vd) : 0.0);
                double rem = edge[j + 1] - edge[j];
                if (rem < 1e-15) {
                    continue;
                }
                while (rem > 1e-15) {
                    double t_seg = rem, G, Phi, ia1, ib1, iz1;
                    int dz = (iz > I_EPS) ? 1 : ((iz < -I_EPS) ? -1 : 0);
                    if (dz == 0) {
                        const double v_open = 0.5 * (va + vb - ea - eb) + ez;
                        dz = (v_open > Vd) ? -1 : ((v_open < 0.0) ? 1 : 0);
                        iz = 0.0;
                    }
                    if (dz == 0) { /* open leg off: one loop current through a and b */
                        G = one_minus_phi(r_over_l * t_seg);
                        ia1 = (1.0 - G) * ia + G * inv_r * (0.5 * (va - vb - ea + eb));
                        ib1 = -ia1;
                        Te_int += kh * t_seg * (Fa * (0.5 * (ia - ib) + ia1) + Fb * (ib + ib1));
                        iz1 = 0.0;
                    } else { /* open leg clamped to a rail by its diode */
                        const double vz = (dz > 0) ? 0.0 : Vd;
                        const double vn = (va + vb + vz - e0 - e1d - e2) * (1.0 / 3.0);
                        const double ua = va - vn - ea, ub = vb - vn - eb, uz = vz - vn - ez;
                        double r;
                        if (iz != 0.0 && ((dz > 0) ? (uz < 0.0) : (uz > 0.0))
                            && fabs(iz) * Lh < t_seg * (fabs(uz) + R * fabs(iz))) {
                            const double t_star = log1p_s(-iz * R / uz) * l_over_r;
                            t_seg = (t_star < t_seg) ? t_star : t_seg;
                        }
                        G = one_minus_phi(r_over_l * t_seg);
                        Phi = 1.0 - G;
                        G *= inv_r;
                        iz1 = (t_seg < rem) ? 0.0 : Phi * iz + G * uz;
                        ia1 = Phi * ia + G * ua;
                        ib1 = Phi * ib + G * ub;
                        r = 0.5 * (ia1 + ib1 + iz1);
                        ia1 -= r;
                        ib1 -= r;
                        Te_int += kh * t_seg * (Fa * (ia + ia1) + Fb * (ib + ib1) + Fz * (iz + iz1));
                    }
                    ia = ia1;
                    ib = ib1;
                    iz = iz1;
                    rem -= t_seg;
                }
            }
            i[a] = ia;
            i[b] = ib;
            i[z] = iz;
        }
        m_prev = m;
        sec_prev = sec;
        /* shaft: exact solution of J dw/dt = T_e - B_tot w - T_load over Ts */
        w0 = omega;
        omega = a_m * w0 + mech_gain * (Te_int * inv_Ts - T_load);
        theta = wrap(theta + pp_half * (omega + w0) * Ts);
    }
    s->i[0] = i[0];
    s->i[1] = i[1];
    s->i[2] = i[2];
    s->omega = omega;
    s->theta_e = theta;
    s->q = q;
    s->q_c = q_c;
    s->e1 = e1;
    s->u1 = u1;
    s->u2 = u2;
    s->m_prev = m_prev;
    s->sec_prev = sec_prev;
}
