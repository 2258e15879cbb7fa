/* plant.c -- see plant.h for the model, its assumptions and units. */
#include <math.h>

#include "plant.h"

#define PI_D 3.14159265358979323846
#define TWO_PI_D (2.0 * PI_D)
#define I_EPS 1e-9 /* A: a current below this with an open leg counts as zero */

static const double phase_shift[3] = {0.0, 2.0 * PI_D / 3.0, 4.0 * PI_D / 3.0};

void plant_update(plant_t *p)
{
    p->r_over_l = p->R / p->L;
    p->inv_r = 1.0 / p->R;
}

double plant_emf_shape(double theta, double w)
{
    double hw = (w > 0.0) ? 0.5 * w : 0.0;
    if (theta >= TWO_PI_D || theta < 0.0) {
        theta = plant_wrap_2pi(theta);
    }
    return plant_emf_shape_in(theta, hw, 0.5 / w);
}

int plant_hall_sector(double theta_e)
{
    return plant_hall_sector_in(theta_e);
}

void plant_emf(const plant_t *p, double theta_e, double e[3])
{
    int x;
    for (x = 0; x < 3; ++x) {
        e[x] = p->k_e * p->omega * plant_emf_shape(theta_e - phase_shift[x], p->emf_rounding);
    }
}

void plant_emf_shapes(const plant_t *p, double theta_e, double F[3])
{
    double w = p->emf_rounding;
    plant_emf_shapes_in(theta_e, (w > 0.0) ? 0.5 * w : 0.0, 0.5 / w, F);
}

void plant_set_segment_emf(plant_t *p, double theta_e)
{
    double w = p->emf_rounding, kw = p->k_e * p->omega, F[3];
    plant_emf_shapes_in(theta_e, (w > 0.0) ? 0.5 * w : 0.0, 0.5 / w, F);
    p->F_seg[0] = F[0];
    p->F_seg[1] = F[1];
    p->F_seg[2] = F[2];
    p->e_seg[0] = kw * F[0];
    p->e_seg[1] = kw * F[1];
    p->e_seg[2] = kw * F[2];
}

static double sgn_d(double x) { return (x > 0.0) ? 1.0 : ((x < 0.0) ? -1.0 : 0.0); }

/* Phi(t) = exp(-R t / L) and G(t) = (1 - Phi)/R, accurate for small R t / L.
 * r_over_l = R / L, inv_r = 1 / R. */
static void phi_g(double r_over_l, double inv_r, double t, double *Phi, double *G)
{
    double x = r_over_l * t, em1;
    if (x < 0.01) {
        /* 1 - exp(-x) by its series to x^5: relative error < 2e-13 for x < 0.01 */
        em1 = x * (1.0 + x * (-0.5 + x * (1.0 / 6.0 + x * (-1.0 / 24.0 + x * (1.0 / 120.0)))));
    } else if (x < 0.02) {
        /* series to x^7: relative error < 1e-16 for x < 0.02 */
        em1 = x * (1.0 + x * (-0.5 + x * (1.0 / 6.0 + x * (-1.0 / 24.0 + x * (1.0 / 120.0
              + x * (-1.0 / 720.0 + x * (1.0 / 5040.0)))))));
    } else {
        em1 = -expm1(-x);
    }
    *Phi = 1.0 - em1;
    *G = em1 * inv_r;
}

/* log1p(x), by its series to x^7 for |x| < 0.005 (relative error < 1e-17, below one ulp): the
 * argument of a diode's current-zero event is that small except near commutation. */
static double log1p_small(double x)
{
    if (x < 0.005 && x > -0.005) {
        return x * (1.0 + x * (-0.5 + x * (1.0 / 3.0 + x * (-0.25 + x * (0.2 + x * (-1.0 / 6.0
               + x * (1.0 / 7.0)))))));
    }
    return log1p(x);
}

int plant_advance(plant_t *p, const int mode[3], const double v_drv[3], double dt)
{
    double remaining = dt;
    int iter = 0;
    int nseg = 0;
    const double Vd = p->V_dc, VG = p->V_G;
    const double r_over_l = p->r_over_l, inv_r = p->inv_r;
    /* The six-step case (legs a < b driven, leg z open, no switch drop) is solved by
     * plant_advance_six_step, the one home of its per-interval update. */
    if (VG == 0.0) {
        int z = (mode[0] == PLANT_OPEN) ? 0 : ((mode[1] == PLANT_OPEN) ? 1 : 2);
        int a = (z == 0) ? 1 : 0, b = (z == 2) ? 1 : 2;
        if (mode[z] == PLANT_OPEN && mode[a] == PLANT_DRIVEN && mode[b] == PLANT_DRIVEN) {
            return plant_advance_six_step(p, z, &v_drv[a], &v_drv[b], &dt, 1);
        }
    }
    while (remaining > 1e-15 && iter < 24) {
        const double *e = p->e_seg;
        double v[3], u[3], Phi, G, t_seg, t_ev = remaining;
        int known[3], diode[3], nk = 0, x, ev_leg = -1;
        ++iter;
        for (x = 0; x < 3; ++x) {
            diode[x] = 0;
            known[x] = 1;
            if (mode[x] == PLANT_DRIVEN) {
                v[x] = v_drv[x] - VG * sgn_d(p->i[x]);
            } else if (p->i[x] > I_EPS) {
                v[x] = -VG;
                diode[x] = 1;
            } else if (p->i[x] < -I_EPS) {
                v[x] = Vd + VG;
                diode[x] = -1;
            } else {
                known[x] = 0;
                p->i[x] = 0.0;
            }
            nk += known[x];
        }
        if (nk <= 1) {
            /* all currents zero: does some pair of legs start conducting? */
            double best = 0.0;
            int bp = -1, bq = -1, q;
            for (x = 0; x < 3; ++x) {
                for (q = 0; q < 3; ++q) {
                    double vp, vq, drive;
                    if (q == x) {
                        continue;
                    }
                    /* current into the motor at x (lower diode if open), out at q */
                    vp = known[x] ? v[x] : -VG;
                    vq = known[q] ? v[q] : Vd + VG;
                    drive = (vp - vq) - (e[x] - e[q]);
                    if (drive > best) {
                        best = drive;
                        bp = x;
                        bq = q;
                    }
                }
            }
            if (bp < 0) {
                p->i[0] = p->i[1] = p->i[2] = 0.0;
                remaining = 0.0;
                ++nseg;
                break;
            }
            for (x = 0; x < 3; ++x) {
                known[x] = 0;
            }
            nk = 2;
            if (mode[bp] != PLANT_DRIVEN) {
                v[bp] = -VG;
                diode[bp] = 1;
            }
            if (mode[bq] != PLANT_DRIVEN) {
                v[bq] = Vd + VG;
                diode[bq] = -1;
            }
            known[bp] = known[bq] = 1;
        }
        if (nk == 2) {
            int z = !known[0] ? 0 : (!known[1] ? 1 : 2);
            int a = (z + 1) % 3, b = (z + 2) % 3;
            double v_open = 0.5 * (v[a] + v[b] - e[a] - e[b]) + e[z];
            if (v_open > Vd + VG) {
                v[z] = Vd + VG;
                diode[z] = -1;
                nk = 3;
            } else if (v_open < -VG) {
                v[z] = -VG;
                diode[z] = 1;
                nk = 3;
            }
        }
        if (nk == 3) {
            double vn = (v[0] + v[1] + v[2] - e[0] - e[1] - e[2]) * (1.0 / 3.0);
            for (x = 0; x < 3; ++x) {
                u[x] = v[x] - vn - e[x];
            }
        } else {
            int z = !known[0] ? 0 : (!known[1] ? 1 : 2);
            int a = (z + 1) % 3, b = (z + 2) % 3;
            double ul = 0.5 * (v[a] - v[b] - e[a] + e[b]);
            u[a] = ul;
            u[b] = -ul;
            u[z] = 0.0;
            p->i[z] = 0.0;
            p->i[b] = -p->i[a];
        }
        /* diode current-zero events */
        for (x = 0; x < 3; ++x) {
            if (diode[x] != 0 && u[x] * diode[x] < 0.0 && p->i[x] * diode[x] > 0.0
                && fabs(p->i[x]) * p->L < t_ev * (fabs(u[x]) + p->R * fabs(p->i[x]))) {
                /* (the pre-check: the current cannot reach zero sooner than at its initial
                 * slope, so no event within t_ev unless i0 L / (|u| + R |i0|) < t_ev) */
                double t_star = log1p(-p->i[x] * p->R / u[x]) / r_over_l;
                if (t_star < t_ev) {
                    t_ev = t_star;
                    ev_leg = x;
                }
            }
        }
        t_seg = t_ev;
        phi_g(r_over_l, inv_r, t_seg, &Phi, &G);
        {
            double i_new[3], Tm = 0.0;
            for (x = 0; x < 3; ++x) {
                i_new[x] = Phi * p->i[x] + G * u[x];
            }
            if (ev_leg >= 0) {
                i_new[ev_leg] = 0.0;
            }
            if (nk == 3) { /* enforce the star constraint against rounding */
                double r = (i_new[0] + i_new[1] + i_new[2]) * (1.0 / 3.0);
                for (x = 0; x < 3; ++x) {
                    if (x != ev_leg) {
                        i_new[x] -= (ev_leg >= 0) ? 1.5 * r : r;
                    }
                }
            }
            for (x = 0; x < 3; ++x) {
                Tm += p->F_seg[x] * 0.5 * (p->i[x] + i_new[x]);
                p->i[x] = i_new[x];
                if (fabs(i_new[x]) > p->i_abs_max) {
                    p->i_abs_max = fabs(i_new[x]);
                }
                if (!(i_new[x] == i_new[x]) || fabs(i_new[x]) > 1e12) {
                    p->nonfinite = 1;
                }
            }
            p->Te_int += p->k_e * Tm * t_seg;
            plant_track_ip(p, p->w_ip[0] * i_new[0] + p->w_ip[1] * i_new[1]
                                  + p->w_ip[2] * i_new[2]);
        }
        remaining -= t_seg;
        ++nseg;
        if (p->nonfinite) {
            break;
        }
    }
    return nseg;
}

/* plant_advance_six_step for the open leg z.  The fast path of plant_advance (legs a < b driven,
 * z open, V_G = 0) over n consecutive segments, with the state in locals: the same floating-
 * point operations in the same order, so the result is bit-identical to n calls of
 * plant_advance.  Two bookkeeping simplifications, exact by construction: (1) at most two
 * sub-segments per segment (a diode current-zero event leaves the open leg at zero current,
 * after which no event can occur), so plant_advance's cap of 24 is never reached and not
 * counted; (2) with the open leg not conducting (iz0 = iz1 = 0) its torque term Fz (0 + 0) is
 * a signed zero, which leaves Te_int unchanged (Te_int starts at +0, so it is never -0), and
 * |ib1| = |ia1|, |iz1| = 0 leave the current maximum at |ia1|. */
static int six_step_z(plant_t *p, const int z, const double *va_seg, const double *vb_seg,
                      const double *dt_seg, int n)
{
    const int a = (z == 0) ? 1 : 0, b = (z == 2) ? 1 : 2;
    const double Vd = p->V_dc, R = p->R, Lh = p->L;
    const double r_over_l = p->r_over_l, inv_r = p->inv_r, kh = p->k_e * 0.5, l_over_r = Lh / R;
    const double ea = p->e_seg[a], eb = p->e_seg[b], ez = p->e_seg[z];
    /* e_seg[0], e_seg[1], e_seg[2] (the order of the sum in vn) */
    const double e0 = (z == 0) ? ez : ea;
    const double e1 = (z == 1) ? ez : ((z == 0) ? ea : eb);
    const double e2 = (z == 2) ? ez : eb;
    const double Fa = p->F_seg[a], Fb = p->F_seg[b], Fz = p->F_seg[z];
    const double wa = p->w_ip[a], wb = p->w_ip[b], wz = p->w_ip[z];
    double ip_lo = p->ip_min, ip_hi = p->ip_max, ip_last = p->ip_last;
    int ip_dir = p->ip_dir, ip_peaks = p->ip_peaks;
    double ia = p->i[a], ib = p->i[b], iz = p->i[z];
    double Te_int = p->Te_int, i_abs_max = p->i_abs_max;
    int nonfinite = 0, nseg = 0, s;
    for (s = 0; s < n; ++s) {
        const double va = va_seg[s], vb = vb_seg[s];
        double remaining = dt_seg[s];
        while (remaining > 1e-15) {
            double Phi, G, t_seg = remaining, ia0 = ia, ib0 = ib, ia1, ib1, iz1, ai;
            int dz = 0;
            if (iz > I_EPS) {
                dz = 1;
            } else if (iz < -I_EPS) {
                dz = -1;
            } else {
                double v_open = 0.5 * (va + vb - ea - eb) + ez;
                if (v_open > Vd) {
                    dz = -1;
                } else if (v_open < 0.0) {
                    dz = 1;
                }
                iz = 0.0;
            }
            if (dz == 0) { /* case B: one loop current through a and b */
                double ul = 0.5 * (va - vb - ea + eb);
                phi_g(r_over_l, inv_r, t_seg, &Phi, &G);
                ia1 = Phi * ia0 + G * ul;
                ib1 = -ia1;
                Te_int += kh * t_seg * (Fa * (0.5 * (ia0 - ib0) + ia1) + Fb * (ib0 + ib1));
                ai = fabs(ia1);
                iz1 = 0.0;
            } else { /* case A: leg z clamped by its diode */
                const double iz0 = iz, vz = (dz > 0) ? 0.0 : Vd;
                const double vn = (va + vb + vz - e0 - e1 - e2) * (1.0 / 3.0);
                const double ua = va - vn - ea, ub = vb - vn - eb, uz = vz - vn - ez;
                double r;
                if (iz0 != 0.0 && ((dz > 0) ? (uz < 0.0) : (uz > 0.0))
                    && fabs(iz0) * Lh < t_seg * (fabs(uz) + R * fabs(iz0))) {
                    /* (the pre-check: the current cannot reach zero sooner than at its initial
                     * slope, so no event within t_seg unless i0 L / (|u| + R |i0|) < t_seg) */
                    double t_star = log1p_small(-iz0 * R / uz) * l_over_r;
                    if (t_star < t_seg) {
                        t_seg = t_star;
                    }
                }
                phi_g(r_over_l, inv_r, t_seg, &Phi, &G);
                iz1 = (t_seg < remaining) ? 0.0 : Phi * iz0 + G * uz;
                ia1 = Phi * ia0 + G * ua;
                ib1 = Phi * ib0 + G * ub;
                r = 0.5 * (ia1 + ib1 + iz1); /* star constraint against rounding */
                ia1 -= r;
                ib1 -= r;
                Te_int += kh * t_seg * (Fa * (ia0 + ia1) + Fb * (ib0 + ib1) + Fz * (iz0 + iz1));
                ai = fabs(ia1) > fabs(ib1) ? fabs(ia1) : fabs(ib1);
                if (fabs(iz1) > ai) {
                    ai = fabs(iz1);
                }
            }
            ia = ia1;
            ib = ib1;
            iz = iz1;
            plant_track_ip_in(wa * ia1 + wb * ib1 + wz * iz1, &ip_lo, &ip_hi, &ip_last, &ip_dir,
                              &ip_peaks);
            if (ai > i_abs_max) {
                i_abs_max = ai;
            }
            if (!(ai <= 1e12)) { /* (NaN or beyond 1e12 A) */
                nonfinite = 1;
                break;
            }
            remaining -= t_seg;
            ++nseg;
        }
    }
    p->i[a] = ia;
    p->i[b] = ib;
    p->i[z] = iz;
    p->Te_int = Te_int;
    p->i_abs_max = i_abs_max;
    p->ip_min = ip_lo;
    p->ip_max = ip_hi;
    p->ip_last = ip_last;
    p->ip_dir = ip_dir;
    p->ip_peaks = ip_peaks;
    if (nonfinite) {
        p->nonfinite = 1;
    }
    return nseg;
}

int plant_advance_six_step(plant_t *p, int z, const double *va_seg, const double *vb_seg,
                           const double *dt_seg, int n)
{
    switch (z) {
    case 0:
        return six_step_z(p, 0, va_seg, vb_seg, dt_seg, n);
    case 1:
        return six_step_z(p, 1, va_seg, vb_seg, dt_seg, n);
    default:
        return six_step_z(p, 2, va_seg, vb_seg, dt_seg, n);
    }
}

void plant_mech_step(plant_t *p, double Ts, double a_m)
{
    plant_mech_step_in(p, Ts, a_m);
}
