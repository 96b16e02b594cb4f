/*
 * controller.h -- current controller exported by current-control-toolbox
 * title:       Paper 002 (Cormerais 2002): Boolean predictive control at 10 kHz with switching penalty (sect. 4, simulation 3)
 * method:      fcs_mpc
 * version:     0.1.0
 * spec sha256: 600c2c7e54f2d6f6e865680421b0620963b931525a29cc6dcbde689c5dbfef36
 * law sha256:  7eb7eb09cc055079980ece9e31d17b2583a9e3efb2cee518b12af18fc369f046
 * created:     2026-11-28T00:23:30+00:00
 *
 * C99, header-only, no dynamic memory; libm: sinf, cosf. Float only (no
 * fixed-point variant: CCT_FIXED_POINT, CCT_MCSDK and CCT_IQMATH are errors).
 * Boolean predictive control (Cormerais 2002, paper 002): every period
 * cct_step() predicts the currents one period ahead (forward Euler of the dq
 * model with the controller's R, Ld, Lq, flux) for each of the 8 inverter
 * states and returns the state of least
 *   J = ALPHA (i_q - i_q_ref)^2 + BETA (i_d - i_d_ref)^2 + GAMMA commutations
 * (criterion (23), GAMMA the switching penalty); ties go to the fewest
 * commutations, then the lower state index.
 * No computation delay: the state returned is applied at once, for this period.
 * Call cct_init() once, then cct_set_vdc() with the measured bus voltage and
 * cct_step() once per period (example at the end of this file).
 * Faults: out->status CCT_STATUS_BAD_INPUT (an input is inf/nan) or
 * CCT_STATUS_BAD_STATE (the cost overflowed): the previous state is held;
 * CCT_STATUS_IMPLAUSIBLE (a measured current or the speed beyond
 * CCT_I_PLAUSIBLE / CCT_W_PLAUSIBLE): the currents are replaced by the
 * law's own prediction of them, the speed by the last plausible one, and the
 * state is chosen as usual.
 */
#ifndef CCT_CONTROLLER_H
#define CCT_CONTROLLER_H

#include <math.h> /* sinf, cosf */
#include <stdint.h> /* uint32_t */

#ifdef CCT_FIXED_POINT
#error "fixed-point variant not available: the fcs_mpc law is exported in float only"
#endif /* CCT_FIXED_POINT */
#if defined(CCT_MCSDK) || defined(CCT_IQMATH)
#error "MCSDK/IQmath variants not available: the fcs_mpc law is exported in float only"
#endif

#define CCT_SAMPLE_TIME 9.999999747e-05f /* controller period, s */
#define CCT_DELAY_SAMPLES 0 /* computation delay, periods */
#define CCT_DRIVE_VDC 1.200000000e+01f /* nominal DC-link voltage, V */
#define CCT_R_HEX_PER_VDC 8.164966106e-01f /* active vector length per volt of bus (power-invariant dq) */
#define CCT_R_HEX 9.797959328e+00f /* active vector length at the nominal bus, V */
/* controller-side model of the predictor */
#define CCT_DEC_R 1.999999955e-02f /* ohm */
#define CCT_DEC_LD 1.125999988e-04f /* H */
#define CCT_DEC_LQ 1.125999988e-04f /* H */
#define CCT_DEC_FLUX 6.038999930e-02f /* Wb */
#define CCT_POLE_PAIRS 6 /* w_e = POLE_PAIRS * Omega_m */
/* criterion (23) weights: alpha (q error, A^-2), beta (d error, A^-2), gamma (per commutation) */
#define CCT_FCS_ALPHA 1.000000000e+00f
#define CCT_FCS_BETA 1.000000000e+00f
#define CCT_FCS_GAMMA 3.500000000e+01f

/* inputs: currents in A, measured MECHANICAL speed in rad/s, ELECTRICAL angle in rad */
typedef struct {
    float i_d_ref; /* A */
    float i_q_ref; /* A */
    float i_d;     /* measured, A */
    float i_q;     /* measured, A */
    float omega_m; /* measured mechanical speed, rad/s */
    float theta_e; /* measured electrical rotor angle at the sampling instant, rad */
} cct_input_t;

#define CCT_STATUS_OK 0         /* the law ran */
#define CCT_STATUS_BAD_INPUT 1  /* a non-finite input: switch state held */
#define CCT_STATUS_BAD_STATE 2  /* non-finite cost (overflow): switch state held */
#define CCT_STATUS_IMPLAUSIBLE 4 /* a measurement beyond its plausible range: replaced by the
                                     * law's prediction (currents) or the last plausible speed */

/* plausible ranges (a sample beyond them is a sensor or ADC fault): cct_step
 * refuses measured currents or speed beyond them, cct_set_vdc bus readings
 * outside [VDC_MIN, VDC_PLAUSIBLE] */
#define CCT_I_PLAUSIBLE 3.000000000e+02f /* A, 2 x motor.max_current (else 2 x max(2 x rated, V_MAX/R, flux/L)) */
#define CCT_W_PLAUSIBLE 9.367203522e+01f /* rad/s mechanical, 2 x drive.max_speed (else see the docs) */
#define CCT_VDC_MIN 1.200000010e-02f /* V, 1e-3 x DRIVE_VDC */
#define CCT_VDC_PLAUSIBLE 2.400000000e+01f /* V, 2 x DRIVE_VDC */

typedef struct {
    int state;     /* inverter state 0..7 = 4 m1 + 2 m2 + m3 (paper 002 numbering) */
    int s_a;       /* cell C1 (phase a): 1 = upper switch on */
    int s_b;       /* cell C2 (phase b) */
    int s_c;       /* cell C3 (phase c) */
    int commutations; /* cells that change with respect to the previous state */
    int status;    /* CCT_STATUS_* */
} cct_output_t;

typedef struct {
    int conf;      /* last chosen inverter state (applied now) */
    float r_hex;   /* V, length of an active vector (cct_set_vdc) */
    float i_d_pred; /* A, the law's prediction of the currents at the next sampling */
    float i_q_pred; /* instant (used in place of an implausible current sample) */
    float omega_m_good; /* rad/s, last plausible speed */
} cct_state_t;

static inline void cct_init(cct_state_t *s)
{
    s->conf = 0;
    s->r_hex = CCT_R_HEX;
    s->i_d_pred = 0.0f;
    s->i_q_pred = 0.0f;
    s->omega_m_good = 0.0f;
}

/* 1 when v is neither inf nor nan (IEEE-754 bits, immune to -ffast-math) */
static inline int cct_finite(float v)
{
    union { float f; uint32_t u; } b;
    b.f = v;
    return (b.u & 0x7f800000u) != 0x7f800000u;
}

/* measured DC-link voltage (V) -> active vector length CCT_R_HEX_PER_VDC * vdc.
 * Returns CCT_STATUS_OK; CCT_STATUS_BAD_INPUT (not finite or not > 0) or
 * CCT_STATUS_IMPLAUSIBLE (outside [CCT_VDC_MIN, CCT_VDC_PLAUSIBLE]) leave
 * the length in use unchanged. */
static inline int cct_set_vdc(cct_state_t *s, float vdc)
{
    if (!(cct_finite(vdc) && vdc > 0.0f)) {
        return CCT_STATUS_BAD_INPUT;
    }
    if (!(vdc >= CCT_VDC_MIN && vdc <= CCT_VDC_PLAUSIBLE)) {
        return CCT_STATUS_IMPLAUSIBLE;
    }
    s->r_hex = CCT_R_HEX_PER_VDC * vdc;
    return CCT_STATUS_OK;
}

/* number of cells that differ between two inverter states */
static inline int cct_changes(int a, int b)
{
    const int x = a ^ b;
    return (x & 1) + ((x >> 1) & 1) + ((x >> 2) & 1);
}

/* dq voltage of inverter state st at the angle whose cos, sin are c, sn */
static inline void cct_vector(int st, float r_hex, float c, float sn, float *vd, float *vq)
{
    const float m1 = (float)((st >> 2) & 1);
    const float m2 = (float)((st >> 1) & 1);
    const float m3 = (float)(st & 1);
    const float va = r_hex * (m1 - 0.5f * m2 - 0.5f * m3);
    const float vb = r_hex * 0.866025404f * (m2 - m3);
    *vd = va * c + vb * sn;
    *vq = -va * sn + vb * c;
}

/* one forward-Euler period of the controller's dq model (paper 002 predictor) */
static inline void cct_predict(float *i_d, float *i_q, float vd, float vq, float w)
{
    const float d = *i_d;
    const float q = *i_q;
    *i_d = d + CCT_SAMPLE_TIME / CCT_DEC_LD * (vd - CCT_DEC_R * d + w * CCT_DEC_LQ * q);
    *i_q = q + CCT_SAMPLE_TIME / CCT_DEC_LQ * (vq - CCT_DEC_R * q - w * CCT_DEC_LD * d
                                               - w * CCT_DEC_FLUX);
}

static inline void cct_emit(cct_output_t *out, int st, int nch, int status)
{
    out->state = st;
    out->s_a = (st >> 2) & 1;
    out->s_b = (st >> 1) & 1;
    out->s_c = st & 1;
    out->commutations = nch;
    out->status = status;
}

/* one controller period: the inverter state of least
 *   J = ALPHA (i_q - i_q_ref)^2 + BETA (i_d - i_d_ref)^2 + GAMMA commutations
 * over the 8 states (ties: fewest commutations, then the lower index).
 * A current sample beyond I_PLAUSIBLE is replaced by the law's own prediction
 * of it (made last period with the state applied since), a speed beyond
 * W_PLAUSIBLE by the last plausible speed; the choice is made with them and
 * status is CCT_STATUS_IMPLAUSIBLE. A non-finite input holds the state. */
static inline void cct_step(cct_state_t *s, const cct_input_t *in, cct_output_t *out)
{
    float omega_m = in->omega_m;
    float idp = in->i_d;
    float iqp = in->i_q;
    float thp = in->theta_e;
    int status = CCT_STATUS_OK;
    float best_j = 0.0f;
    int best = -1;
    int best_c = 99;
    int cand;
    float c, sn;
    float best_id = 0.0f, best_iq = 0.0f;
    if (!(cct_finite(in->i_d_ref) && cct_finite(in->i_q_ref) && cct_finite(in->i_d)
          && cct_finite(in->i_q) && cct_finite(in->omega_m) && cct_finite(in->theta_e))) {
        cct_emit(out, s->conf, 0, CCT_STATUS_BAD_INPUT); /* state held */
        return;
    }
    if (!(in->i_d <= CCT_I_PLAUSIBLE && in->i_d >= -CCT_I_PLAUSIBLE
          && in->i_q <= CCT_I_PLAUSIBLE && in->i_q >= -CCT_I_PLAUSIBLE)) {
        idp = s->i_d_pred;
        iqp = s->i_q_pred;
        status = CCT_STATUS_IMPLAUSIBLE;
    }
    if (!(omega_m <= CCT_W_PLAUSIBLE && omega_m >= -CCT_W_PLAUSIBLE)) {
        omega_m = s->omega_m_good;
        status = CCT_STATUS_IMPLAUSIBLE;
    }
    const float w = (float)CCT_POLE_PAIRS * omega_m; /* electrical speed, rad/s */
    c = cosf(thp);
    sn = sinf(thp);
    for (cand = 0; cand < 8; ++cand) {
        float vd, vq, idn = idp, iqn = iqp, j;
        const int nch = cct_changes(cand, s->conf);
        cct_vector(cand, s->r_hex, c, sn, &vd, &vq);
        cct_predict(&idn, &iqn, vd, vq, w);
        j = CCT_FCS_ALPHA * (iqn - in->i_q_ref) * (iqn - in->i_q_ref)
          + CCT_FCS_BETA * (idn - in->i_d_ref) * (idn - in->i_d_ref)
          + CCT_FCS_GAMMA * (float)nch;
        if (best < 0 || j < best_j || (j == best_j && nch < best_c)) {
            best_j = j;
            best = cand;
            best_c = nch;
            best_id = idn; /* the chosen state's currents at the next instant */
            best_iq = iqn;
        }
    }
    if (!cct_finite(best_j)) {
        cct_emit(out, s->conf, 0, CCT_STATUS_BAD_STATE); /* state held */
        return;
    }
    s->conf = best;
    s->i_d_pred = best_id; /* the currents at the next sampling instant */
    s->i_q_pred = best_iq;
    s->omega_m_good = omega_m;
    cct_emit(out, best, best_c, status);
}

#if 0 /* usage example: copy the lines between BEGIN and END into main.c */
// EXAMPLE main.c BEGIN
#include <stdio.h>
#include "controller.h"

/* stand-ins for the board's drivers: ADC, encoder, gate drivers, fault output */
static float adc_i_d(void) { return 0.0f; }
static float adc_i_q(void) { return 0.0f; }
static float adc_vdc(void) { return CCT_DRIVE_VDC; }
static float encoder_speed(void) { return 0.0f; }
static float encoder_theta_e(void) { return 0.0f; }
static void gates_apply(int s_a, int s_b, int s_c) { (void)s_a; (void)s_b; (void)s_c; }
static void fault_report(int status) { printf("controller status %d\n", status); }

static cct_state_t ctl;

/* once per controller period (CCT_SAMPLE_TIME s) */
static void control_isr(float i_d_ref, float i_q_ref)
{
    cct_input_t in;
    cct_output_t out;
    const int bus = cct_set_vdc(&ctl, adc_vdc());
    if (bus != CCT_STATUS_OK) {
        fault_report(bus); /* bus reading lost or implausible: previous vectors kept */
    }
    in.i_d_ref = i_d_ref;
    in.i_q_ref = i_q_ref;
    in.i_d = adc_i_d();
    in.i_q = adc_i_q();
    in.omega_m = encoder_speed();
    in.theta_e = encoder_theta_e();
    cct_step(&ctl, &in, &out);
    if (out.status != CCT_STATUS_OK) {
        fault_report(out.status); /* previous state held: decide to trip or ride through */
    }
    gates_apply(out.s_a, out.s_b, out.s_c); /* applied next period when DELAY_SAMPLES >= 1 */
}

int main(void)
{
    int k;
    cct_init(&ctl);
    for (k = 0; k < 10; ++k) {
        control_isr(0.0f, 1.0f);
    }
    return 0;
}
// EXAMPLE main.c END
#endif /* usage example */

#endif /* CCT_CONTROLLER_H */
