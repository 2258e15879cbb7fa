/*
 * loop.h -- the virtual drive's sample loop: plant + unipolar PWM bridge + the portable
 * controllers, run for a whole chunk of samples per call (never a call per sample).
 *
 * Timing (fs = 50 kHz, Ts = 20 us).  At sample instant t_k (the PWM period boundary, i.e. the
 * middle of the zero vector where the sampled current equals its ripple average) the loop
 * measures i_p, speed, Hall sector and back-EMF, runs the controllers and stores m[k] and the
 * sector.  m[k] is applied in the PWM period that starts at t_{k+1}: one sample of
 * computational delay, as eq. (6).  Commutation (which two legs switch, which is open) is
 * latched with m from the Hall sector read at the same sample.
 *
 * Unipolar PWM on the two conducting legs (full bridge): the "+" leg is high for a centred
 * window of d+ = (1 + m)/2 of the period, the "-" leg for d- = (1 - m)/2, so v_L has two pulses
 * per period (100 kHz) and mean m V_dc.  Inverter non-idealities (eq. 25): each switching
 * edge is preceded by a blanking time T_BT in which the leg is open (its diode conducts);
 * switches and diodes drop V_G; T_DD + T_SD delays the whole pulse pattern relative to the
 * sampling instant (so the sample is no longer at the zero-vector centre).  The averaged model
 * replaces the pattern by the leg mean voltages (blanking as its mean effect -sign(i) V_dc
 * T_BT / Ts per leg) and keeps the delay, but has no ripple.
 *
 * Protection (checked at every sample; trip = bridge off at once, fault code kept until
 * loop_reset_fault): any |i_x| seen during the last sample > oc_trip or a non-finite state ->
 * OD_EMCY_OVERCURRENT; V_dc > ov_trip -> OD_EMCY_DC_OVERVOLTAGE; V_dc < uv_trip ->
 * OD_EMCY_DC_UNDERVOLTAGE; an injected fault -> its code.  The reason is one of OD_TRIP_*; both
 * sets of macros are generated into firmware_protocol/bldc_drive_od.h from
 * firmware_protocol/emcy_codes.py.
 */
#ifndef BLDC_LOOP_H
#define BLDC_LOOP_H

#include "controllers.h"
#include "plant.h"

#define LOOP_NSIG 17
#define LOOP_OS_MAX 64

enum {
    SIG_I_P = 0,
    SIG_I_A,
    SIG_I_B,
    SIG_I_C,
    SIG_SPEED,
    SIG_V_L,
    SIG_E_L,
    SIG_M,
    SIG_HALL,
    SIG_I_P_REF,
    SIG_SPEED_REF,
    SIG_V_DC,
    SIG_T_E,
    SIG_THETA_E,
    SIG_I_P_MIN,  /* least i_p over the PWM period before the sample (at its switching edges) */
    SIG_I_P_MAX,  /* largest i_p over that period */
    SIG_I_P_PEAKS /* ripple maxima of i_p in that period (2 for unipolar PWM) */
};

#define LOOP_OFF 0
#define LOOP_CURRENT 1
#define LOOP_SPEED 2

#define LOOP_MODEL_PWM 0
#define LOOP_MODEL_AVERAGED 1

/* The whole state of the 50 kHz sample loop (one per simulated drive): the plant, both
 * controllers, the PWM pattern memory of the delays, the protection and the records.  Owned by
 * virtual_drive.sim.Simulator (its _loop); every loop_* function takes it as `loop`. */
typedef struct {
    plant_t p;
    cc_current_t cc;
    cc_speed_t sc;
    double Ts;         /* s */
    double a_m;        /* exp(-B_tot Ts / J) */
    int model;         /* LOOP_MODEL_* */
    int mode;          /* LOOP_OFF / LOOP_CURRENT / LOOP_SPEED */
    int active;        /* controllers ran at the previous sample */
    double T_BT;       /* s, actual blanking time */
    double T_delay;    /* s, actual T_DD + T_SD */
    double i_ref_set;  /* A */
    double w_ref_set;  /* rpm */
    float m_prev, m_prev2;
    int sec_prev, sec_prev2;
    int on_prev, on_prev2;
    double oc_trip, ov_trip, uv_trip;
    int fault_code;    /* 0 none, else EMCY code (OD_EMCY_*) */
    int fault_reason;  /* 0 none, else OD_TRIP_* */
    double fault_time; /* s */
    int inject;        /* pending injected fault code, 0 none */
    double t;          /* s, time of the next sample */
    long long k;       /* index of the next sample */
    float last[LOOP_NSIG];
    long long segments; /* solved circuit segments (diagnostic) */
    /* oversampled record (optional): os_n points per sample of t, i_a, i_b, i_c, i_p */
    int os_n;
    double *os_buf;    /* 5 doubles per point */
    long long os_cap;  /* points */
    long long os_len;
} sample_loop_t;

/* Initialise state (currents, speed, pipeline, controllers reset) after the params are set. */
void loop_init(sample_loop_t *loop);

/* Recompute derived plant constants after changing p.J / p.B_tot. */
void loop_update_mech(sample_loop_t *loop);

/* Run n samples.  sig[j] (j < LOOP_NSIG) may be NULL or point to n floats; t_out may be NULL
 * or point to n doubles.  Returns the number of samples run (n). */
int loop_run(sample_loop_t *loop, int n, float **sig, double *t_out);

/* Run n samples in one call (no record) and copy the LOOP_NSIG latest values (loop->last) into
 * snap + LOOP_NSIG * j once at[j] samples have run, for j < n_at (0 <= at[0] <= at[1] <= ...;
 * an at[j] > n counts as n): the values of the instants a pacing tick's TPDOs are due at,
 * without a call per instant.  Returns n. */
int loop_run_points(sample_loop_t *loop, int n, const int *at, int n_at, float *snap);

void loop_reset_fault(sample_loop_t *loop);

#endif
