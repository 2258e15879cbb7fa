/*
 * controllers.h -- the paper's current and speed controllers, portable C99 for the
 * TMS320F28335 (float32 FPU).  Valle et al., IEEE Access 2020, eqs. (15), (22), (23), (25), (27).
 *
 * Rules: C99, float32 only (no double), no malloc, no fixed-width 8-bit types, only <math.h>.
 * All voltages in V, currents in A, speeds in rpm, times in s.
 *
 * Sign convention: i_p >= 0 is motoring, equal to eq. (1) (|i_a|+|i_b|+|i_c|)/2; v_L is the
 * line voltage the bridge applies between the sector's "+" and "-" phases; m = v_L / V_dc.
 *
 * Anti-windup (all controllers): "realizable reference" conditioning (Hanus et al. 1987).
 * When m saturates at +-1, the error stored in the controller state is replaced by the error
 * that would have produced exactly the applied (saturated) output, and the applied voltage
 * is stored as the past output.  The controller state is then exactly that of the linear loop
 * driven by a realizable reference, so the closed loop stays the designed linear loop: for the
 * deadbeat law the plant pole that (15) cancels (z = Phi, tau ~ 2.4 ms) is never excited and a
 * saturated step ends in a time-optimal ramp plus two samples, without overshoot.  Storing the
 * clamped output alone (observer form with A_o = z^2) splits the two memories of the
 * 1/(z^2-1) integrator and leaves an error that decays with the plant's own 2.4 ms time
 * constant (hundreds of samples); storing the unclamped output winds up (overshoot).
 *
 * float32 speed integrator: the IP integrator of Fig. 17 sums the speed error x = sum(e)
 * (rpm * samples); at 50 kHz with k_i ~ 3e-5 it reaches ~1e7 where a float32 ulp is ~1 rpm,
 * so small errors are lost.  Here the integral is kept in amperes, q = k_p * k_i * sum(e), and
 * accumulated with Kahan compensated summation (q plus a float32 compensation term q_c), which
 * carries increments of 1e-6 A onto 200 A without loss.
 */
#ifndef BLDC_CONTROLLERS_H
#define BLDC_CONTROLLERS_H

#define CC_DEADBEAT 0
#define CC_PI 1
#define CC_PREDICTIVE 2

/* Current controller: configuration (set by cc_current_configure) and state. */
typedef struct {
    int type;          /* CC_DEADBEAT eq.(15), CC_PI eq.(22), CC_PREDICTIVE eq.(23)/(25) */
    float Ts;          /* s, sampling period */
    float L_c;         /* H, inductance estimate (deadbeat, predictive) */
    float R_c;         /* Ohm, resistance estimate (deadbeat) */
    float k_p;         /* V/A, PI proportional gain k_p,i */
    float k_i;         /* V/A, PI integral gain k_i,i (per sample) */
    float T_BT;        /* s, blanking-time estimate (eq. 25) */
    float T_DD;        /* s, driver-delay estimate (eq. 25) */
    float T_SD;        /* s, sampling-delay estimate (eq. 25) */
    float V_G;         /* V, switch-drop estimate (eq. 25) */
    int emf_ff;        /* 1: back-EMF feed-forward on */
    /* derived */
    float Phi_c;       /* 1, exp(-R_c Ts / L_c), eq. (4) with the estimates */
    float Gamma_c;     /* A/V, (1 - Phi_c) / (2 R_c), eq. (5) with the estimates */
    /* state */
    float e1;          /* A, previous (realizable) error e[k-1] */
    float u1;          /* V, applied controller voltage at k-1 (without feed-forward) */
    float u2;          /* V, applied controller voltage at k-2 (without feed-forward) */
    float s;           /* V, PI integrator */
    float v_L;         /* V, last total commanded line voltage (after saturation) */
    int saturated;     /* 1 if the last output was clipped */
} cc_current_t;

/* Speed controller (IP, Fig. 17 / eq. 27) with a current limit on its output. */
typedef struct {
    float k_p;         /* A/rpm */
    float k_i;         /* 1/sample */
    float limit;       /* A, |i_p*| <= limit */
    float q;           /* A, integral part k_p*k_i*sum(e), Kahan sum */
    float q_c;         /* A, Kahan compensation of q */
    int saturated;
} cc_speed_t;

/* Set configuration and derived constants; keeps the state.  Returns 0, or -1 if a value is
 * not usable (Ts <= 0, L_c <= 0, R_c < 0, non-finite); then nothing is changed. */
int cc_current_configure(cc_current_t *c, int type, float Ts, float L_c, float R_c, float k_p,
                         float k_i, float T_BT, float T_DD, float T_SD, float V_G, int emf_ff);

/* Reset the state as if the loop had been in steady state applying v0 volts (bumpless start). */
void cc_current_reset(cc_current_t *c, float v0);

/* One sample: reference i_ref (A), measured i_p (A), back-EMF estimate e_L (V), measured V_dc (V).
 * Returns the modulation index m in [-1, 1] for the next PWM period. */
float cc_current_step(cc_current_t *c, float i_ref, float i_p, float e_L, float V_dc);

int cc_speed_configure(cc_speed_t *s, float k_p, float k_i, float limit);

/* Bumpless start: output equals i0 (A) at speed w (rpm). */
void cc_speed_reset(cc_speed_t *s, float i0, float w);

/* One sample: reference w_ref and measured speed w (rpm). Returns i_p* (A), |.| <= limit. */
float cc_speed_step(cc_speed_t *s, float w_ref, float w);

#endif
