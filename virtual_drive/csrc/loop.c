/* loop.c -- see loop.h. */
#include <math.h>
#include <stddef.h>

#include "bldc_drive_od.h" /* OD_EMCY_*, OD_TRIP_* (generated from the EDS) */
#include "loop.h"

#define PI_D 3.14159265358979323846
#define RPM_PER_RAD_S (60.0 / (2.0 * PI_D))

/* six-step table: "+" and "-" phase per Hall sector 1..6 (index 0 unused) */
static const int sec_plus[7] = {0, 0, 0, 1, 1, 2, 2};
static const int sec_minus[7] = {0, 1, 2, 2, 0, 0, 1};
static const int sec_open[7] = {0, 2, 1, 0, 2, 1, 0};

static double sgn_d(double x) { return (x > 0.0) ? 1.0 : ((x < 0.0) ? -1.0 : 0.0); }

/* sign of the open phase of sector s in the previous sector along the direction of rotation:
 * [0][s] for omega >= 0 (previous = s - 1), [1][s] otherwise (previous = s + 1) */
static const double open_sign[2][7] = {{0.0, 1.0, -1.0, 1.0, -1.0, 1.0, -1.0},
                                       {0.0, -1.0, 1.0, -1.0, 1.0, -1.0, 1.0}};

/* Signed pseudo current: (s+ i+ + s- i- + s_o i_o)/2 with the open phase signed as in the
 * previous sector along the direction of rotation; equals eq. (1) when motoring. */
static double pseudo_current(const double i[3], int sec, double omega)
{
    int o = sec_open[sec];
    return 0.5 * (i[sec_plus[sec]] - i[sec_minus[sec]] + open_sign[!(omega >= 0.0)][sec] * i[o]);
}

void loop_update_mech(sample_loop_t *loop)
{
    if (loop->p.B_tot > 0.0) {
        loop->a_m = exp(-loop->p.B_tot * loop->Ts / loop->p.J);
        loop->p.mech_gain = -expm1(-loop->p.B_tot * loop->Ts / loop->p.J) / loop->p.B_tot;
    } else {
        loop->a_m = 1.0;
        loop->p.mech_gain = 0.0;
    }
}

static double ctrl_v0(const sample_loop_t *loop, double e_L)
{
    if (loop->cc.type == CC_PREDICTIVE) {
        return e_L;
    }
    return loop->cc.emf_ff ? 0.0 : e_L;
}

void loop_init(sample_loop_t *loop)
{
    loop->p.i[0] = loop->p.i[1] = loop->p.i[2] = 0.0;
    loop->p.Te_int = 0.0;
    loop->p.i_abs_max = 0.0;
    loop->p.nonfinite = 0;
    loop->m_prev = loop->m_prev2 = 0.0f;
    loop->sec_prev = loop->sec_prev2 = plant_hall_sector(loop->p.theta_e);
    loop->on_prev = loop->on_prev2 = 0;
    loop->active = 0;
    loop->fault_code = 0;
    loop->fault_reason = 0;
    loop->fault_time = 0.0;
    loop->inject = 0;
    loop->segments = 0;
    loop->os_len = 0;
    loop->p.ip_min = loop->p.ip_max = loop->p.ip_last = 0.0;
    loop->p.ip_dir = loop->p.ip_peaks = 0;
    cc_current_reset(&loop->cc, 0.0f);
    cc_speed_reset(&loop->sc, 0.0f, 0.0f);
    loop_update_mech(loop);
}

void loop_reset_fault(sample_loop_t *loop)
{
    loop->fault_code = 0;
    loop->fault_reason = 0;
    loop->inject = 0;
    loop->p.nonfinite = 0;
    loop->p.i_abs_max = 0.0;
    loop->active = 0;
}

static void os_record(sample_loop_t *loop, double t)
{
    double *b;
    int sec;
    if (loop->os_buf == NULL || loop->os_len >= loop->os_cap) {
        return;
    }
    b = loop->os_buf + 5 * loop->os_len;
    sec = plant_hall_sector(loop->p.theta_e);
    b[0] = t;
    b[1] = loop->p.i[0];
    b[2] = loop->p.i[1];
    b[3] = loop->p.i[2];
    b[4] = pseudo_current(loop->p.i, sec, loop->p.omega);
    loop->os_len++;
}

static int leg_mode_pwm(double d, double u, double Ts, double T_BT)
{
    /* returns 1 high, 0 low, 2 open */
    double r, f;
    if (d >= 1.0) {
        return 1;
    }
    if (d <= 0.0) {
        return 0;
    }
    r = 0.5 * (1.0 - d) * Ts;
    f = 0.5 * (1.0 + d) * Ts;
    if (u < r) {
        return 0;
    }
    if (u < r + T_BT) {
        return 2;
    }
    if (u < f) {
        return 1;
    }
    if (u < f + T_BT) {
        return 2;
    }
    return 0;
}

/* Edges of a unipolar PWM period in pattern time: the leg with the larger duty d_hi rises at
 * edge[1] and falls at edge[4], the other at edge[2] / edge[3] (centred windows; a duty of 1 is
 * on for the whole period, 0 never); edge[0] = 0, edge[5] = Ts. */
static inline void pwm_edges(double d_hi, double d_lo, double Ts, double edge[6])
{
    edge[0] = 0.0;
    edge[1] = (d_hi >= 1.0) ? 0.0 : 0.5 * (1.0 - d_hi) * Ts;
    edge[2] = (d_lo <= 0.0) ? 0.5 * Ts : 0.5 * (1.0 - d_lo) * Ts;
    edge[3] = (d_lo <= 0.0) ? 0.5 * Ts : 0.5 * (1.0 + d_lo) * Ts;
    edge[4] = (d_hi >= 1.0) ? Ts : 0.5 * (1.0 + d_hi) * Ts;
    edge[5] = Ts;
}

static void sort_d(double *a, int n)
{
    int i, j;
    for (i = 1; i < n; ++i) {
        double x = a[i];
        for (j = i - 1; j >= 0 && a[j] > x; --j) {
            a[j + 1] = a[j];
        }
        a[j + 1] = x;
    }
}

/* Advance the plant over pattern time [u0, u1) of one PWM period; t_start is the absolute time
 * at u0 (for the oversampled record). */
static void apply_pattern(sample_loop_t *loop, float m, int sec, int on, double u0, double u1,
                          double t_start)
{
    double bp[16 + LOOP_OS_MAX];
    int nb = 0, j;
    int mode[3];
    double vdrv[3] = {0.0, 0.0, 0.0};
    const double Ts = loop->Ts, Vd = loop->p.V_dc;
    double dp = 0.5 * (1.0 + (double)m), dm = 0.5 * (1.0 - (double)m);
    int xp = sec_plus[sec], xm = sec_minus[sec];
    double os_dt = (loop->os_n > 0) ? Ts / loop->os_n : 0.0;
    if (u1 <= u0) {
        return;
    }
    if (on && loop->model == LOOP_MODEL_PWM && loop->T_BT == 0.0 && os_dt == 0.0) {
        /* Fast path without blanking time: the edges are already ordered,
         * r_hi <= r_lo <= f_lo <= f_hi for the legs with the larger / smaller duty. */
        int x_hi = (dp >= dm) ? xp : xm, x_lo = (dp >= dm) ? xm : xp;
        double d_hi = (dp >= dm) ? dp : dm, d_lo = (dp >= dm) ? dm : dp;
        double edge[6];
        int open = 3 - xp - xm, k;
        pwm_edges(d_hi, d_lo, Ts, edge);
        mode[x_hi] = PLANT_DRIVEN;
        mode[x_lo] = PLANT_DRIVEN;
        mode[open] = PLANT_OPEN;
        vdrv[open] = 0.0;
        if (loop->p.V_G == 0.0) {
            /* all sub-intervals in one call (legs a < b driven, see plant_advance_six_step) */
            double va[5], vb[5], dt[5];
            int ns = 0, xa = (open == 0) ? 1 : 0;
            for (k = 0; k < 5; ++k) {
                double a = (edge[k] > u0) ? edge[k] : u0;
                double b = (edge[k + 1] < u1) ? edge[k + 1] : u1;
                double v_hi, v_lo;
                if (b - a < 1e-15) {
                    continue;
                }
                v_hi = (k >= 1 && k <= 3) ? Vd : 0.0;
                v_lo = (k == 2) ? Vd : 0.0;
                va[ns] = (xa == x_hi) ? v_hi : v_lo;
                vb[ns] = (xa == x_hi) ? v_lo : v_hi;
                dt[ns] = b - a;
                ++ns;
            }
            loop->segments += plant_advance_six_step(&loop->p, open, va, vb, dt, ns);
            return;
        }
        for (k = 0; k < 5; ++k) {
            double a = (edge[k] > u0) ? edge[k] : u0;
            double b = (edge[k + 1] < u1) ? edge[k + 1] : u1;
            if (b - a < 1e-15) {
                continue;
            }
            vdrv[x_hi] = (k >= 1 && k <= 3) ? Vd : 0.0;
            vdrv[x_lo] = (k == 2) ? Vd : 0.0;
            loop->segments += plant_advance(&loop->p, mode, vdrv, b - a);
        }
        return;
    }
    bp[nb++] = u0;
    bp[nb++] = u1;
    if (on && loop->model == LOOP_MODEL_PWM) {
        double cand[8];
        int c;
        cand[0] = 0.5 * (1.0 - dp) * Ts;
        cand[1] = cand[0] + loop->T_BT;
        cand[2] = 0.5 * (1.0 + dp) * Ts;
        cand[3] = cand[2] + loop->T_BT;
        cand[4] = 0.5 * (1.0 - dm) * Ts;
        cand[5] = cand[4] + loop->T_BT;
        cand[6] = 0.5 * (1.0 + dm) * Ts;
        cand[7] = cand[6] + loop->T_BT;
        for (c = 0; c < 8; ++c) {
            if (cand[c] > u0 && cand[c] < u1) {
                bp[nb++] = cand[c];
            }
        }
    }
    if (os_dt > 0.0) {
        /* grid points t_k + j Ts/os_n, in pattern time u = t - t_start + u0 */
        double g = ceil((t_start - loop->t) / os_dt - 1e-9) * os_dt + loop->t; /* absolute */
        for (; g < t_start + (u1 - u0) - 1e-12 && nb < 16 + LOOP_OS_MAX; g += os_dt) {
            double ug = g - t_start + u0;
            if (ug > u0 + 1e-12) {
                bp[nb++] = ug;
            }
        }
    }
    sort_d(bp, nb);
    for (j = 0; j + 1 < nb; ++j) {
        double a = bp[j], b = bp[j + 1], um = 0.5 * (a + b);
        int x;
        if (b - a < 1e-15) {
            continue;
        }
        if (!on) {
            mode[0] = mode[1] = mode[2] = PLANT_OPEN;
        } else {
            for (x = 0; x < 3; ++x) {
                mode[x] = PLANT_OPEN;
            }
            if (loop->model == LOOP_MODEL_PWM) {
                int mp = leg_mode_pwm(dp, um, Ts, loop->T_BT);
                int mm = leg_mode_pwm(dm, um, Ts, loop->T_BT);
                if (mp != 2) {
                    mode[xp] = PLANT_DRIVEN;
                    vdrv[xp] = mp ? Vd : 0.0;
                }
                if (mm != 2) {
                    mode[xm] = PLANT_DRIVEN;
                    vdrv[xm] = mm ? Vd : 0.0;
                }
            } else {
                double bt = Vd * loop->T_BT / Ts;
                mode[xp] = PLANT_DRIVEN;
                mode[xm] = PLANT_DRIVEN;
                vdrv[xp] = dp * Vd - sgn_d(loop->p.i[xp]) * bt;
                vdrv[xm] = dm * Vd - sgn_d(loop->p.i[xm]) * bt;
            }
        }
        loop->segments += plant_advance(&loop->p, mode, vdrv, b - a);
        if (os_dt > 0.0) {
            double tb = t_start + (b - u0);
            double rel = (tb - loop->t) / os_dt;
            double rr = floor(rel + 0.5);
            if (fabs(rel - rr) < 1e-6 && rr >= 1.0 && rr < (double)loop->os_n - 0.5) {
                os_record(loop, tb);
            }
        }
    }
}

static void trip(sample_loop_t *loop, int code, int reason)
{
    loop->fault_code = code;
    loop->fault_reason = reason;
    loop->fault_time = loop->t;
    loop->on_prev = loop->on_prev2 = 0;
    loop->active = 0;
}

/* apply_pattern over a whole period for the common case -- PWM model, bridge on, no blanking
 * time, no switch drop, no oversampled record -- with the set-up of its fast path: the same
 * sub-intervals [a, b) and leg voltages, handed to plant_advance_six_step in one call. */
static void pattern_six_step(sample_loop_t *loop, float m, int sec, double u0, double u1)
{
    const double Ts = loop->Ts, Vd = loop->p.V_dc;
    const double dp = 0.5 * (1.0 + (double)m), dm = 0.5 * (1.0 - (double)m);
    const int xp = sec_plus[sec], xm = sec_minus[sec], open = sec_open[sec];
    const int p_hi = (dp >= dm);
    const double d_hi = p_hi ? dp : dm, d_lo = p_hi ? dm : dp;
    /* leg a (the lower-numbered driven leg) is the one with the larger duty? */
    const int a_hi = (((open == 0) ? 1 : 0) == (p_hi ? xp : xm));
    const double v1a = a_hi ? Vd : 0.0, v1b = a_hi ? 0.0 : Vd; /* sub-intervals 1 and 3 */
    double edge[6], va[5], vb[5], dt[5];
    int ns = 0, k;
    if (u1 <= u0) {
        return;
    }
    pwm_edges(d_hi, d_lo, Ts, edge);
    for (k = 0; k < 5; ++k) {
        double a = (edge[k] > u0) ? edge[k] : u0;
        double b = (edge[k + 1] < u1) ? edge[k + 1] : u1;
        if (b - a < 1e-15) {
            continue;
        }
        /* sub-intervals: 0 and 4 both legs low, 1 and 3 only the larger duty high, 2 both high */
        va[ns] = (k == 2) ? Vd : ((k & 1) ? v1a : 0.0);
        vb[ns] = (k == 2) ? Vd : ((k & 1) ? v1b : 0.0);
        dt[ns] = b - a;
        ++ns;
    }
    loop->segments += plant_advance_six_step(&loop->p, open, va, vb, dt, ns);
}

int loop_run(sample_loop_t *loop, int n, float **sig, double *t_out)
{
    int k;
    plant_t *const p = &loop->p;
    const double Ts = loop->Ts;
    float *rec_ptr[LOOP_NSIG]; /* the recorded signals' buffers, */
    int rec_sig[LOOP_NSIG];    /* their SIG_* indices */
    int n_rec = 0, all_sig;
    double hw, inv2w, mid_gain;
    int six; /* the period's pattern is pattern_six_step's case whenever the bridge is on */
    int emf_always; /* e_L and T_e at the sample are needed at every sample of this chunk */
    plant_update(p); /* R, L may have been changed between chunks */
    for (k = 0; sig != NULL && k < LOOP_NSIG; ++k) {
        if (sig[k] != NULL) { /* (checked once per chunk, not per sample) */
            rec_ptr[n_rec] = sig[k];
            rec_sig[n_rec++] = k;
        }
    }
    all_sig = (n_rec == LOOP_NSIG);
    {
        /* constants of this chunk (the parameters change only between calls) */
        const double w = p->emf_rounding;
        hw = (w > 0.0) ? 0.5 * w : 0.0;
        inv2w = 0.5 / w;
        mid_gain = 0.5 * Ts * p->pole_pairs;
        six = (loop->model == LOOP_MODEL_PWM && loop->T_BT == 0.0 && loop->os_n <= 0
               && p->V_G == 0.0);
        /* e_L feeds the current law only with the EMF feed-forward or the predictive law;
         * otherwise e_L and T_e at the sample are only recorded (or start the controllers) */
        emf_always = loop->cc.emf_ff || loop->cc.type == CC_PREDICTIVE
                     || (sig != NULL && (sig[SIG_E_L] != NULL || sig[SIG_T_E] != NULL));
    }
    for (k = 0; k < n; ++k) {
        const double theta = p->theta_e, omega = p->omega;
        const int sec = plant_hall_sector_in(theta);
        const int last = (k == n - 1);
        double e_L = 0.0, i_p, speed, Te = 0.0, i_ref = 0.0, w_ref = loop->w_ref_set;
        float m = 0.0f;
        int on = 0;
        if (emf_always || last
            || (loop->mode != LOOP_OFF && loop->fault_code == 0 && !loop->active)) {
            /* back-EMF e_x = k_e w F_x and torque T_e = k_e sum(F_x i_x) at the sample; not
             * computed when nothing uses them (the values are the same either way) */
            double e[3], F[3], kw = p->k_e * omega;
            plant_emf_shapes_in(theta, hw, inv2w, F);
            e[0] = kw * F[0];
            e[1] = kw * F[1];
            e[2] = kw * F[2];
            Te = 0.0;
            Te += F[0] * p->i[0];
            Te += F[1] * p->i[1];
            Te += F[2] * p->i[2];
            Te *= p->k_e;
            e_L = e[sec_plus[sec]] - e[sec_minus[sec]];
        }
        i_p = pseudo_current(p->i, sec, omega);
        speed = omega * RPM_PER_RAD_S;
        /* protection */
        if (loop->fault_code == 0) {
            if (p->nonfinite || !(i_p == i_p)) {
                trip(loop, OD_TRIP_NONFINITE_EMCY, OD_TRIP_NONFINITE);
            } else if (p->i_abs_max > loop->oc_trip) {
                trip(loop, OD_TRIP_OVERCURRENT_EMCY, OD_TRIP_OVERCURRENT);
            } else if (loop->inject != 0) {
                trip(loop, loop->inject, OD_TRIP_INJECTED);
                loop->inject = 0;
            } else if (p->V_dc > loop->ov_trip) {
                trip(loop, OD_TRIP_DC_OVERVOLTAGE_EMCY, OD_TRIP_DC_OVERVOLTAGE);
            } else if (p->V_dc < loop->uv_trip) {
                trip(loop, OD_TRIP_DC_UNDERVOLTAGE_EMCY, OD_TRIP_DC_UNDERVOLTAGE);
            }
        }
        {
            /* (a NaN current has set p->nonfinite, which zeroes the state below: no fmax) */
            double a0 = fabs(p->i[0]), a1 = fabs(p->i[1]), a2 = fabs(p->i[2]);
            double a12 = (a1 > a2) ? a1 : a2;
            p->i_abs_max = (a0 > a12) ? a0 : a12;
        }
        if (p->nonfinite) {
            /* keep the record finite: a tripped, diverged plant is frozen at zero */
            p->i[0] = p->i[1] = p->i[2] = 0.0;
            if (!(p->omega == p->omega)) {
                p->omega = 0.0;
            }
            if (!(p->theta_e == p->theta_e)) {
                p->theta_e = 0.0;
            }
            p->Te_int = 0.0;
            p->i_abs_max = 0.0;
            p->nonfinite = 0;
            p->ip_min = p->ip_max = 0.0;
            i_p = e_L = Te = 0.0;
            speed = p->omega * RPM_PER_RAD_S;
        }
        /* controllers */
        if (loop->mode != LOOP_OFF && loop->fault_code == 0) {
            if (!loop->active) {
                cc_current_reset(&loop->cc, (float)ctrl_v0(loop, e_L));
                cc_speed_reset(&loop->sc, (float)i_p, (float)speed);
            }
            if (loop->mode == LOOP_SPEED) {
                i_ref = cc_speed_step(&loop->sc, (float)w_ref, (float)speed);
            } else {
                i_ref = loop->i_ref_set;
            }
            m = cc_current_step(&loop->cc, (float)i_ref, (float)i_p, (float)e_L, (float)p->V_dc);
            on = 1;
            loop->active = 1;
        } else {
            loop->active = 0;
            i_ref = (loop->mode == LOOP_CURRENT) ? loop->i_ref_set : 0.0;
        }
        if (loop->mode != LOOP_SPEED) {
            w_ref = (loop->mode == LOOP_OFF) ? 0.0 : w_ref;
        }
        /* record sample k (loop->last: only the chunk's last sample is kept, the one seen after
         * the call) */
        if (sig != NULL || last) {
            float r[LOOP_NSIG];
            int j;
            r[SIG_I_P] = (float)i_p;
            r[SIG_I_A] = (float)p->i[0];
            r[SIG_I_B] = (float)p->i[1];
            r[SIG_I_C] = (float)p->i[2];
            r[SIG_SPEED] = (float)speed;
            r[SIG_V_L] = m * (float)p->V_dc;
            r[SIG_E_L] = (float)e_L;
            r[SIG_M] = m;
            r[SIG_HALL] = (float)sec;
            r[SIG_I_P_REF] = (float)i_ref;
            r[SIG_SPEED_REF] = (float)((loop->mode == LOOP_SPEED) ? w_ref : 0.0);
            r[SIG_V_DC] = (float)p->V_dc;
            r[SIG_T_E] = (float)Te;
            r[SIG_THETA_E] = (float)p->theta_e;
            r[SIG_I_P_MIN] = (float)((p->ip_min < i_p) ? p->ip_min : i_p);
            r[SIG_I_P_MAX] = (float)((p->ip_max > i_p) ? p->ip_max : i_p);
            r[SIG_I_P_PEAKS] = (float)p->ip_peaks;
            if (all_sig) { /* every signal recorded: no index per signal */
                for (j = 0; j < LOOP_NSIG; ++j) {
                    rec_ptr[j][k] = r[j];
                }
            } else {
                for (j = 0; j < n_rec; ++j) {
                    rec_ptr[j][k] = r[rec_sig[j]];
                }
            }
            if (last) {
                for (j = 0; j < LOOP_NSIG; ++j) {
                    loop->last[j] = r[j];
                }
            }
        }
        if (t_out != NULL) {
            t_out[k] = loop->t;
        }
        if (loop->os_n > 0) {
            os_record(loop, loop->t);
        }
        { /* i_p over the coming PWM period, tracked by the plant at every switching edge */
            p->w_ip[sec_plus[sec]] = 0.5;
            p->w_ip[sec_minus[sec]] = -0.5;
            p->w_ip[sec_open[sec]] = 0.5 * open_sign[!(omega >= 0.0)][sec];
            p->ip_min = p->ip_max = p->ip_last = i_p;
            p->ip_peaks = 0;
        }
        /* advance the circuit over [t_k, t_k + Ts), back-EMF at the sample's mid-angle (as
         * plant_set_segment_emf) */
        {
            const double kw = p->k_e * p->omega;
            plant_emf_shapes_in(p->theta_e + mid_gain * p->omega, hw, inv2w, p->F_seg);
            p->e_seg[0] = kw * p->F_seg[0];
            p->e_seg[1] = kw * p->F_seg[1];
            p->e_seg[2] = kw * p->F_seg[2];
        }
        if (loop->T_delay > 0.0) {
            if (six && loop->on_prev2) {
                pattern_six_step(loop, loop->m_prev2, loop->sec_prev2, Ts - loop->T_delay, Ts);
            } else {
                apply_pattern(loop, loop->m_prev2, loop->sec_prev2, loop->on_prev2,
                              Ts - loop->T_delay, Ts, loop->t);
            }
            if (six && loop->on_prev) {
                pattern_six_step(loop, loop->m_prev, loop->sec_prev, 0.0, Ts - loop->T_delay);
            } else {
                apply_pattern(loop, loop->m_prev, loop->sec_prev, loop->on_prev, 0.0,
                              Ts - loop->T_delay, loop->t + loop->T_delay);
            }
        } else if (six && loop->on_prev) {
            pattern_six_step(loop, loop->m_prev, loop->sec_prev, 0.0, Ts);
        } else {
            apply_pattern(loop, loop->m_prev, loop->sec_prev, loop->on_prev, 0.0, Ts, loop->t);
        }
        if (loop->fault_code != 0) {
            on = 0;
        }
        loop->m_prev2 = loop->m_prev;
        loop->sec_prev2 = loop->sec_prev;
        loop->on_prev2 = loop->on_prev;
        loop->m_prev = m;
        loop->sec_prev = sec;
        loop->on_prev = on;
        plant_mech_step_in(p, Ts, loop->a_m);
        loop->k += 1;
        loop->t = loop->k * Ts;
    }
    return n;
}

int loop_run_points(sample_loop_t *loop, int n, const int *at, int n_at, float *snap)
{
    int done = 0, j, x;
    for (j = 0; j < n_at; ++j) {
        int a = (at[j] < n) ? at[j] : n;
        if (a > done) {
            loop_run(loop, a - done, NULL, NULL);
            done = a;
        }
        for (x = 0; x < LOOP_NSIG; ++x) {
            snap[j * LOOP_NSIG + x] = loop->last[x];
        }
    }
    if (n > done) {
        loop_run(loop, n - done, NULL, NULL);
    }
    return n;
}
