/*
 * Software-in-the-loop plant for tests/export/test_sil.py: an exported
 * controller.h, driven the way its own usage example says, closing the loop
 * around a PMSM written here (independent of the simulator's numba kernel).
 *
 * Plant (rotor dq frame, salient, PM flux, imposed constant speed; the
 * equations of toolbox/ARCHITECTURE.md "Parameters and models"):
 *     Ld did/dt = vd - R id + w Lq iq
 *     Lq diq/dt = vq - R iq - w Ld id - w flux,    theta(t) = w t exactly,
 * integrated in double by classical RK4, N_SUB equal steps per period.
 *
 * The digital loop (DESIGN.md "The digital loop"): at t_k = k Ts the drivers
 * below return the sampled i_d, i_q, theta_e (wrapped to [-pi, pi), as an
 * encoder gives it) and the mechanical speed; the controller's period runs
 * (control_isr); pwm_apply() turns the (compensated) dq command into
 * v_alpha_beta = R(theta_e) v at the SAMPLED angle and puts it in a delay
 * line; the voltage in force over [t_k, t_k + Ts) is the one stored
 * DELAY periods earlier (0 V before). Average inverter, held over the period
 *     HOLD 0 "rotor":      v_dq = R(-theta_mid) v_alpha_beta constant,
 *                          theta_mid the true angle at t_k + Ts/2;
 *     HOLD 1 "stationary": v_alpha_beta constant, v_dq(t) = R(-theta(t)) v_ab;
 * gates_apply() (fcs_mpc headers) holds the inverter state's vector
 * r_hex (s_a + a s_b + a^2 s_c), a = exp(j 2 pi / 3), in the stationary frame.
 *
 * This file is completed by the test: it #includes "sil_isr.c", the
 * header's usage example with its driver stand-ins and its main() removed
 * (the float path), or a period routine of an integer variant written in
 * the example's image (SIL_VARIANT), and "sil_init.c" (the init call).
 *
 * stdin: R Ld Lq flux pole_pairs vdc r_hex Ts delay hold n_sub omega_m n
 *        then n lines "i_d_ref i_q_ref" (A), one per period;
 * stdout: n lines "i_d i_q" (A, sampled at t_k, %.17g), then
 *         "faults <count> last <status>" and "clamped <count>".
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#define SIL_MAX_DELAY 16

static const double SIL_PI = 3.14159265358979323846;

/* plant and drive parameters (stdin) */
static double R_, LD_, LQ_, FLUX_, VDC_, RHEX_, TS_, OMEGA_M_, W_;
static int POLES_, DELAY_, HOLD_, NSUB_;
/* plant state and time */
static double id_, iq_, t_;
static long k_;
/* delay line of v_alpha_beta: slot k % (DELAY + 1) */
static double line_a_[SIL_MAX_DELAY + 1], line_b_[SIL_MAX_DELAY + 1];
static int faults_ = 0, last_status_ = 0, clamped_ = 0;

static double theta_at(double t) { return W_ * t; }

/* ---- drivers: what the usage example's stand-ins stand for */
#ifndef SIL_GLITCH_K
static float adc_i_d(void) { return (float)id_; }
static float adc_i_q(void) { return (float)iq_; }
static float adc_vdc(void) { return (float)VDC_; }
#else
/* sensor glitches (tests/export/test_hardened.py): a 1e6 A current sample in
 * period SIL_GLITCH_K, a 1e30 V bus reading in period SIL_GLITCH_K + 1 */
static float adc_i_d(void) { return (float)id_; }
static float adc_i_q(void) { return k_ == SIL_GLITCH_K ? 1e6f : (float)iq_; }
static float adc_vdc(void) { return k_ == SIL_GLITCH_K + 1 ? 1e30f : (float)VDC_; }
#endif
static float encoder_speed(void) { return (float)OMEGA_M_; }
static float encoder_theta_e(void)
{
    double th = fmod(theta_at(t_), 2.0 * SIL_PI);
    if (th >= SIL_PI) { th -= 2.0 * SIL_PI; }
    if (th < -SIL_PI) { th += 2.0 * SIL_PI; }
    return (float)th;
}
static void sil_store(double va, double vb)
{
    const int slot = (int)(k_ % (DELAY_ + 1));
    line_a_[slot] = va;
    line_b_[slot] = vb;
}
#ifndef SIL_GATES
/* inverse Park at theta_e (the sampled angle the example passes), into the delay line */
static void pwm_apply(float v_d, float v_q, float theta_e)
{
    const double c = cos((double)theta_e), s = sin((double)theta_e);
    sil_store((double)v_d * c - (double)v_q * s, (double)v_d * s + (double)v_q * c);
}
#else
/* inverter state (fcs_mpc headers): its stationary-frame vector, into the delay line */
static void gates_apply(int s_a, int s_b, int s_c)
{
    sil_store(RHEX_ * ((double)s_a - 0.5 * (double)s_b - 0.5 * (double)s_c),
              RHEX_ * 0.5 * sqrt(3.0) * (double)(s_b - s_c));
}
#endif
static void fault_report(int status)
{
    ++faults_;
    last_status_ = status;
}

#include "sil_isr.c"
#include "sil_init.c"

/* ---- plant */
static void deriv(double t, double i_d, double i_q, double va, double vb, double *did,
                  double *diq)
{
    double vd, vq;
    if (HOLD_ == 1) { /* v_alpha_beta held: Park at the true angle */
        const double th = theta_at(t);
        vd = va * cos(th) + vb * sin(th);
        vq = -va * sin(th) + vb * cos(th);
    } else {          /* (va, vb) already the held dq voltage */
        vd = va;
        vq = vb;
    }
    *did = (vd - R_ * i_d + W_ * LQ_ * i_q) / LD_;
    *diq = (vq - R_ * i_q - W_ * LD_ * i_d - W_ * FLUX_) / LQ_;
}

static void period(double va, double vb)
{
    const double h = TS_ / (double)NSUB_;
    const double t0 = t_;
    int j;
    if (HOLD_ == 0) { /* rotor frame: the dq voltage at the mid-period angle, held */
        const double thm = theta_at(t0 + 0.5 * TS_);
        const double vd = va * cos(thm) + vb * sin(thm);
        const double vq = -va * sin(thm) + vb * cos(thm);
        va = vd;
        vb = vq;
    }
    for (j = 0; j < NSUB_; ++j) {
        const double t = t0 + (double)j * h;
        double a1, b1, a2, b2, a3, b3, a4, b4;
        deriv(t, id_, iq_, va, vb, &a1, &b1);
        deriv(t + 0.5 * h, id_ + 0.5 * h * a1, iq_ + 0.5 * h * b1, va, vb, &a2, &b2);
        deriv(t + 0.5 * h, id_ + 0.5 * h * a2, iq_ + 0.5 * h * b2, va, vb, &a3, &b3);
        deriv(t + h, id_ + h * a3, iq_ + h * b3, va, vb, &a4, &b4);
        id_ += h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
        iq_ += h / 6.0 * (b1 + 2.0 * b2 + 2.0 * b3 + b4);
    }
    t_ = t0 + TS_;
}

int main(void)
{
    long n, k;
    if (scanf("%lf %lf %lf %lf %d %lf %lf %lf %d %d %d %lf %ld", &R_, &LD_, &LQ_, &FLUX_,
              &POLES_, &VDC_, &RHEX_, &TS_, &DELAY_, &HOLD_, &NSUB_, &OMEGA_M_, &n) != 13
        || DELAY_ < 0 || DELAY_ > SIL_MAX_DELAY || NSUB_ < 1 || n < 1) {
        fprintf(stderr, "bad parameter line\n");
        return 2;
    }
    W_ = (double)POLES_ * OMEGA_M_;
    id_ = 0.0;
    iq_ = 0.0;
    t_ = 0.0;
    sil_init();
    for (k = 0; k < n; ++k) {
        double idr, iqr, va = 0.0, vb = 0.0;
        if (scanf("%lf %lf", &idr, &iqr) != 2) {
            fprintf(stderr, "missing reference line %ld\n", k);
            return 2;
        }
        k_ = k;
        t_ = (double)k * TS_;
        printf("%.17g %.17g\n", id_, iq_);
        control_isr((float)idr, (float)iqr);
        if (k >= DELAY_) {
            const int slot = (int)((k - DELAY_) % (DELAY_ + 1));
            va = line_a_[slot];
            vb = line_b_[slot];
        }
        period(va, vb);
    }
    printf("faults %d last %d\nclamped %d\n", faults_, last_status_, clamped_);
    return 0;
}
