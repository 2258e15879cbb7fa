/*
 * plant.h -- BLDC motor (star, per-phase R and L, trapezoidal back-EMF with rounded corners),
 * two-level three-phase bridge with freewheel diodes, and the shaft.  Host-side simulation code
 * (double precision); not DSP code.
 *
 * Electrical model.  Phase x in {a,b,c}: v_x - v_n = R i_x + L di_x/dt + e_x, i_a+i_b+i_c = 0.
 * A leg is either driven (switch on: v_x = 0 or V_dc, minus V_G sign(i_x)) or open (both
 * switches off: its diode clamps it to 0 - V_G if i_x > 0, to V_dc + V_G if i_x < 0; with
 * i_x = 0 it floats and conducts only if its open-circuit voltage leaves [-V_G, V_dc+V_G]).
 * While the leg states are constant the circuit is linear with constant inputs, so each
 * segment is solved in closed form: i(t) = Phi(t) i0 + (1 - Phi(t)) u / R, Phi = exp(-R t/L),
 * with u the (constant) voltage across the phase's R-L.  A diode current reaching zero is an
 * event found in closed form, t* = (L/R) log1p(-i0 R/u); the segment is split there and the leg
 * floats afterwards.  This is how the outgoing phase decays at commutation (and how all
 * currents decay with the bridge off): through the freewheel diodes, against the DC link.
 * Back-EMF is taken constant within each sample at its value at the sample's mid-angle
 * (midpoint rule; at 4000 rpm, 4 pole pairs the rotor turns 1.9 deg electrical in one 20 us
 * sample), so within every PWM sub-interval e is constant.  Speed is constant within a sample; the shaft is advanced once per sample with the
 * exact solution of J dw/dt = T_e - (B + k_gen') w - T_load for the sample-mean torque.
 *
 * Back-EMF shape: e_x = k_e w F(theta_e - phi_x), k_e = K_rpm (60/2pi) / 2 per phase, F an
 * odd trapezoid with 120 deg flat tops and 60 deg ramps whose four corners are rounded by a
 * moving average over emf_rounding rad electrical (0 = ideal trapezoid; fringing, Sec. IV-B).
 * Phase a: flat +1 on [30, 150] deg, flat -1 on [210, 330] deg.  Hall sector s = 1..6 spans
 * theta_e in [30 + 60 (s-1), 30 + 60 s) deg; six-step table (+,-): 1 (a,b) 2 (a,c) 3 (b,c)
 * 4 (b,a) 5 (c,a) 6 (c,b).  Torque T_e = k_e sum(F_x i_x) (N m).
 */
#ifndef BLDC_PLANT_H
#define BLDC_PLANT_H

#include <math.h>

#define PLANT_DRIVEN 0
#define PLANT_OPEN 1

typedef struct {
    /* parameters (SI) */
    double R;            /* Ohm per phase */
    double L;            /* H per phase */
    double r_over_l;     /* 1/s, R / L (derived, set by plant_update) */
    double inv_r;        /* 1/Ohm, 1 / R (derived) */
    double k_e;          /* V s/rad per phase (mechanical rad/s) */
    int pole_pairs;
    double emf_rounding; /* rad electrical, [0, pi/3] */
    double J;            /* kg m^2 */
    double B_tot;        /* N m s/rad: friction B plus DC-generator load k_gen */
    double mech_gain;    /* rad/s per N m: (1 - a_m) / B_tot, set by loop_update_mech */
    double T_load;       /* N m, constant load torque */
    double V_dc;         /* V */
    double V_G;          /* V, switch / diode drop */
    /* state */
    double i[3];         /* A, phase currents, positive into the motor */
    double omega;        /* rad/s mechanical */
    double theta_e;      /* rad electrical in [0, 2 pi) */
    double e_seg[3];     /* V, phase back-EMFs used for the segments of this sample */
    double F_seg[3];     /* 1, their shape values */
    /* accumulators over the current sample */
    double Te_int;       /* N m s */
    double i_abs_max;    /* A, largest |i_x| seen */
    int nonfinite;
    /* the pseudo current w_ip . i over the current PWM period, at every sub-segment end (every
     * switching edge, diode current zero and the period's end; plant_track_ip); the loop sets
     * w_ip and resets the rest at each sample */
    double w_ip[3];      /* 1, pseudo-current weight of each phase (+-1/2 or 0) */
    double ip_min;       /* A, least value seen */
    double ip_max;       /* A, largest value seen */
    double ip_last;      /* A, last value that moved by more than PLANT_IP_STEP */
    int ip_dir;          /* +1 rising, -1 falling, 0 not yet known (kept across periods) */
    int ip_peaks;        /* local maxima seen (rising then falling) */
} plant_t;

/* Recompute the derived constants (r_over_l, inv_r) after R or L changed. */
void plant_update(plant_t *p);

/* Trapezoid shape F(theta) in [-1, 1] for phase a, with rounding width w (rad). */
double plant_emf_shape(double theta, double w);

/* Hall sector 1..6 from the electrical angle. */
int plant_hall_sector(double theta_e);

/* Shape values F_x(theta_e) of the three phases. */
void plant_emf_shapes(const plant_t *p, double theta_e, double F[3]);

/* Set the back-EMF used by plant_advance (e_seg, F_seg) for the angle theta_e (rad). */
void plant_set_segment_emf(plant_t *p, double theta_e);

/* Advance the circuit by dt seconds with the given leg states (PLANT_DRIVEN / PLANT_OPEN) and
 * driven leg voltages v_drv (V, ideal, before the V_G drop), back-EMF e_seg constant.
 * Integrates torque into Te_int.  Returns the number of solved sub-segments. */
int plant_advance(plant_t *p, const int mode[3], const double v_drv[3], double dt);

/* The six-step case of plant_advance (two legs driven, leg z open, V_G = 0 required) over n
 * consecutive segments of dt_seg[s] seconds with the driven legs at va_seg[s], vb_seg[s] (legs
 * a < b, the two others than z): bit-identical to n plant_advance calls, without their
 * per-call set-up.  Returns the number of solved sub-segments. */
int plant_advance_six_step(plant_t *p, int z, const double *va_seg, const double *vb_seg,
                           const double *dt_seg, int n);

/* Phase back-EMFs (V) at the present angle and speed. */
void plant_emf(const plant_t *p, double theta_e, double e[3]);

/* Shaft update over Ts with mean torque Te_int / Ts; resets Te_int; advances theta_e with the
 * mean speed.  a_m = exp(-B_tot Ts / J). */
void plant_mech_step(plant_t *p, double Ts, double a_m);

/* ---- inline helpers (the one home of this arithmetic; inlined into the sample loop) ---- */
#define PLANT_PI 3.14159265358979323846
#define PLANT_TWO_PI (2.0 * PLANT_PI)

/* x (rad) wrapped into [0, 2 pi). */
static inline double plant_wrap_2pi(double x)
{
    if (x >= 0.0 && x < 2.0 * PLANT_TWO_PI) {
        return (x >= PLANT_TWO_PI) ? x - PLANT_TWO_PI : x;
    }
    if (x < 0.0 && x >= -PLANT_TWO_PI) {
        return x + PLANT_TWO_PI;
    }
    x = fmod(x, PLANT_TWO_PI);
    return (x < 0.0) ? x + PLANT_TWO_PI : x;
}

/* Trapezoid F(theta) of phase a for theta in [0, 2 pi), rounding half-width hw = w / 2 (rad;
 * 0: ideal trapezoid) and inv2w = 0.5 / w. */
static inline double plant_emf_shape_in(double theta, double hw, double inv2w)
{
    const double c = PLANT_PI / 6.0;    /* corner at 30 deg */
    const double slope = 6.0 / PLANT_PI; /* ramp slope, 1/rad */
    double T, x;
    int neg = 0;
    if (theta >= PLANT_PI) { /* F(theta + pi) = -F(theta) */
        theta -= PLANT_PI;
        neg = 1;
    }
    if (theta > 0.5 * PLANT_PI) { /* F(pi - theta) = F(theta) */
        theta = PLANT_PI - theta;
    }
    T = (theta < c) ? theta * slope : 1.0;
    x = theta - c;
    if (x > -hw && x < hw) {
        /* moving average of width w across a slope change of -slope */
        double y = x + hw;
        T -= slope * (y * y * inv2w - (x > 0.0 ? x : 0.0));
    }
    return neg ? -T : T;
}

/* F of the three phases at theta_e (rad, any value); hw, inv2w as plant_emf_shape_in. */
static inline void plant_emf_shapes_in(double theta_e, double hw, double inv2w, double F[3])
{
    double tb, tc;
    if (theta_e >= PLANT_TWO_PI || theta_e < 0.0) {
        theta_e = plant_wrap_2pi(theta_e);
    }
    tb = theta_e - 2.0 * PLANT_PI / 3.0;
    tc = theta_e - 4.0 * PLANT_PI / 3.0;
    if (tb < 0.0) {
        tb += PLANT_TWO_PI; /* (may round to 2 pi: wrapped to 0) */
        tb = (tb >= PLANT_TWO_PI) ? tb - PLANT_TWO_PI : tb;
    }
    if (tc < 0.0) {
        tc += PLANT_TWO_PI;
        tc = (tc >= PLANT_TWO_PI) ? tc - PLANT_TWO_PI : tc;
    }
    F[0] = plant_emf_shape_in(theta_e, hw, inv2w);
    F[1] = plant_emf_shape_in(tb, hw, inv2w);
    F[2] = plant_emf_shape_in(tc, hw, inv2w);
}

/* Hall sector 1..6 of theta_e (rad). */
static inline int plant_hall_sector_in(double theta_e)
{
    double u = plant_wrap_2pi(theta_e - PLANT_PI / 6.0);
    int s = (int)(u * (3.0 / PLANT_PI));
    return (s > 5) ? 6 : s + 1;
}

/* A change of the pseudo current smaller than this (A) does not count as a direction. */
#define PLANT_IP_STEP 1e-6

/* Track the pseudo current ip = w_ip . i (A) at a sub-segment end.  Within a sub-segment every
 * phase current is i_inf + (i0 - i_inf) exp(-R t / L) (one time constant, constant inputs), so
 * ip is monotonic there and the period's extremes are among these points. */
static inline void plant_track_ip_in(double ip, double *lo, double *hi, double *last, int *dir,
                                     int *peaks)
{
    /* (branch-free: the direction alternates every sub-segment) */
    const double d = ip - *last;
    const int up = (d > PLANT_IP_STEP), down = (d < -PLANT_IP_STEP);
    *lo = (ip < *lo) ? ip : *lo;
    *hi = (ip > *hi) ? ip : *hi;
    *peaks += down & (*dir > 0);
    *dir = up ? 1 : (down ? -1 : *dir);
    *last = (up | down) ? ip : *last;
}

/* plant_track_ip_in on the plant's own fields. */
static inline void plant_track_ip(plant_t *p, double ip)
{
    plant_track_ip_in(ip, &p->ip_min, &p->ip_max, &p->ip_last, &p->ip_dir, &p->ip_peaks);
}

/* plant_mech_step's body. */
static inline void plant_mech_step_in(plant_t *p, double Ts, double a_m)
{
    double Te = p->Te_int * (1.0 / Ts);
    double w0 = p->omega;
    if (p->B_tot > 0.0) {
        p->omega = a_m * w0 + p->mech_gain * (Te - p->T_load);
    } else {
        p->omega = w0 + Ts * (Te - p->T_load) / p->J;
    }
    p->theta_e = plant_wrap_2pi(p->theta_e + p->pole_pairs * 0.5 * (p->omega + w0) * Ts);
    p->Te_int = 0.0;
    if (!(p->omega == p->omega)) {
        p->nonfinite = 1;
    }
}

#endif
