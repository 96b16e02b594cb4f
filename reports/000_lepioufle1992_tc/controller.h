/*
 * controller.h -- current controller exported by current-control-toolbox
 * title:       Paper 000 (Le Pioufle 1992): total compensation, K1 = K2 = 800 (eq 8-11)
 * method:      tc
 * version:     0.1.0
 * spec sha256: bfbd2612ef9951308507a3387cd59aa74050331f6eaa224654826036fce3a2dc
 * law sha256:  dab511f4adfe54cbe9ad2f71164538c8a88b06f065552f0626310cb505472d91
 * created:     2026-11-25T17:26:09+00:00
 * equations:   000 eq (8): de/dt = -K e; 000 eq (9)-(11): total compensation law; 000 eq (12): controller-side parameters R_c, L_dc, L_qc, psi_fc
 *
 * C99, header-only, no dynamic memory; libm: sqrtf, sinf, cosf (float path).
 * Call cct_init() once, then cct_set_vdc() with the measured bus voltage and
 * cct_step() once per controller period (example at the end of this file). The
 * voltage returned is applied by the inverter in the NEXT period: the
 * computation delay is part of the plant the design assumed, not of this code.
 * Law per axis: x' = A x + B [i_ref; i_meas], v = C x + D [i_ref; i_meas]
 *   (1-DOF laws as second-order sections of K(z) = v / (i_ref - i_meas)),
 * then decoupling  v_d += -cross w_e Lq_c i_q,
 *                  v_q +=  cross w_e Ld_c i_d + emf w_e flux_c,  w_e = p Omega_m,
 * then the SVM hexagon limit (voltage_limit = "hexagon", as the toolbox
 * simulator): the voltage is rotated to the stationary frame at the angle
 * theta_e + w_e Ts (DELAY_SAMPLES + 1/2) (input theta_e: electrical angle at the
 * sampling instant) and scaled radially onto the hexagon whose apothem is the
 * limit in use, and
 * back-calculation anti-windup x += aw (v_sat - v_unsat).
 * The limit in use is V_MAX_PER_VDC x the bus voltage last given to set_vdc
 * (V_MAX, the nominal bus, after init).
 * Faults: out->status is
 *   CCT_STATUS_OK (0)        the law ran;
 *   CCT_STATUS_BAD_INPUT (1) an input is inf or nan;
 *   CCT_STATUS_BAD_STATE (2) the result overflowed (inf/nan in v or the state).
 * On 1 and 2 the last good output is repeated (0 V before the first good
 * period), saturated = 0, and the state is left exactly as it was: the next
 * valid period continues as if the bad one had not happened. Finiteness is
 * tested on the IEEE-754 bits, so -ffast-math cannot remove the test.
 * SOS coefficient layout = CMSIS-DSP arm_biquad_cascade_df2T_f32:
 *   {b0, b1, b2, a1, a2} per stage with a1, a2 NEGATED with respect to the
 *   denominator 1 + a1 z^-1 + a2 z^-2 (scipy / MATLAB convention), i.e.
 *   y = b0 x + s1; s1 = b1 x + a1 y + s2; s2 = b2 x + a2 y.
 */
#ifndef CCT_CONTROLLER_H
#define CCT_CONTROLLER_H

#include <math.h> /* sqrtf, sinf, cosf */
#include <stdint.h> /* uint32_t */

#define CCT_SAMPLE_TIME 9.999999747e-05f /* controller period, s */
#define CCT_DELAY_SAMPLES 1 /* computation delay the design assumed, periods */
#define CCT_V_MAX 1.060660172e+02f /* voltage limit (hexagon apothem) at the nominal bus voltage, V; cct_init's default */
#define CCT_V_MAX_PER_VDC 7.071067691e-01f /* voltage limit per volt of measured bus (cct_set_vdc) */
/* motor (power-invariant dq convention) */
#define CCT_MOTOR_R 6.000000238e-01f /* stator resistance, ohm */
#define CCT_MOTOR_LD 1.399999950e-03f /* d-axis inductance, H */
#define CCT_MOTOR_LQ 2.799999900e-03f /* q-axis inductance, H */
#define CCT_MOTOR_FLUX 1.199999973e-01f /* PM flux linkage, Wb */
#define CCT_MOTOR_POLE_PAIRS 4 /* pole pairs */
#define CCT_MOTOR_J 1.109999954e-03f /* inertia, kg m^2 */
#define CCT_MOTOR_FRICTION 1.399999950e-03f /* viscous friction, N m s/rad */
#define CCT_MOTOR_MAX_CURRENT 3.000000000e+01f /* dq current amplitude limit, A */
#define CCT_MOTOR_RATED_CURRENT 2.000000000e+01f /* A */
#define CCT_MOTOR_RATED_SPEED 2.300000000e+02f /* mechanical, rad/s */
/* drive */
#define CCT_DRIVE_VDC 1.500000000e+02f /* DC-link voltage, V */
/* decoupling: controller-side model parameters */
#define CCT_DEC_CROSS 1 /* 1: cross-coupling terms on */
#define CCT_DEC_EMF 1 /* 1: back-EMF term on */
#define CCT_DEC_LD 1.399999950e-03f /* H */
#define CCT_DEC_LQ 2.799999900e-03f /* H */
#define CCT_DEC_FLUX 1.199999973e-01f /* Wb */
#define CCT_POLE_PAIRS 4 /* w_e = POLE_PAIRS * Omega_m */


/* inputs: currents in A, measured MECHANICAL speed in rad/s */
typedef struct {
    float i_d_ref; /* A */
    float i_q_ref; /* A */
    float i_d;     /* measured, A */
    float i_q;     /* measured, A */
    float omega_m; /* measured mechanical speed, rad/s */
    float theta_e; /* measured ELECTRICAL rotor angle at the sampling instant, rad */
} cct_input_t;

#define CCT_STATUS_OK 0         /* the law ran */
#define CCT_STATUS_BAD_INPUT 1  /* a non-finite input: output held, state kept */
#define CCT_STATUS_BAD_STATE 2  /* non-finite result (overflow): output held, state kept */

typedef struct {
    float v_d;     /* V, the law's output (limited), to apply next period */
    float v_q;     /* V */
    float v_d_comp; /* V, = v_d (this design has no delay compensation): */
    float v_q_comp; /* V, feed these to the inverse Park transform at theta_e */
    int saturated; /* 1 when the voltage limit acted */
    int status;    /* CCT_STATUS_* */
} cct_output_t;

/* controller states (ss d axis: 0, ss q axis: 0; arrays have at least one element)
 * and the last good output, held when a period fails */
typedef struct {
    float d[1];
    float q[1];
    float v_d_hold; /* V */
    float v_q_hold; /* V */
    float v_d_comp_hold; /* V */
    float v_q_comp_hold; /* V */
    float v_max;    /* V, voltage limit in use (cct_set_vdc); CCT_V_MAX after init */
} cct_state_t;

/* zero states and held outputs; voltage limit CCT_V_MAX (nominal bus CCT_DRIVE_VDC) */
static inline void cct_init(cct_state_t *s)
{
    unsigned i;
    for (i = 0u; i < 1u; ++i) { s->d[i] = 0.0f; }
    for (i = 0u; i < 1u; ++i) { s->q[i] = 0.0f; }
    s->v_d_hold = 0.0f;
    s->v_q_hold = 0.0f;
    s->v_d_comp_hold = 0.0f;
    s->v_q_comp_hold = 0.0f;
    s->v_max = CCT_V_MAX;
}

/* 1 when v is neither inf nor nan. Tested on the IEEE-754 bits, so that
 * -ffast-math / -ffinite-math-only cannot remove the test (isfinite() may be). */
static inline int cct_finite(float v)
{
    union { float f; uint32_t u; } b;
    b.f = v;
    return (b.u & 0x7f800000u) != 0x7f800000u;
}

/* measured DC-link voltage (V) -> voltage limit CCT_V_MAX_PER_VDC * vdc (the
 * hexagon's apothem); call whenever a new bus measurement arrives (e.g. once per
 * period, before cct_step). Returns CCT_STATUS_OK, or CCT_STATUS_BAD_INPUT
 * (vdc not finite or not > 0) leaving the limit in use unchanged. */
static inline int cct_set_vdc(cct_state_t *s, float vdc)
{
    if (!(cct_finite(vdc) && vdc > 0.0f)) {
        return CCT_STATUS_BAD_INPUT;
    }
    s->v_max = CCT_V_MAX_PER_VDC * vdc;
    return CCT_STATUS_OK;
}

static inline int cct_state_finite(const cct_state_t *s)
{
    unsigned i;
    int ok = 1;
    for (i = 0u; i < 1u; ++i) { ok &= cct_finite(s->d[i]); }
    for (i = 0u; i < 1u; ++i) { ok &= cct_finite(s->q[i]); }
    return ok;
}

static inline void cct_hold(const cct_state_t *s, cct_output_t *out, int status)
{
    out->v_d = s->v_d_hold;
    out->v_q = s->v_q_hold;
    out->v_d_comp = s->v_d_comp_hold;
    out->v_q_comp = s->v_q_comp_hold;
    out->saturated = 0;
    out->status = status;
}

/* d axis linear law: returns v (V); updates the state to A x + B u */
static inline float cct_d_linear(float *x, float r, float y)
{
    (void)x;
    return 1.120000005e+00f * r + -5.199999809e-01f * y;
}

/* q axis linear law: returns v (V); updates the state to A x + B u */
static inline float cct_q_linear(float *x, float r, float y)
{
    (void)x;
    return 2.240000010e+00f * r + -1.639999986e+00f * y;
}

/* one controller period: the whole law (linear laws, decoupling, limit, anti-windup).
 * out->status: CCT_STATUS_OK, or _BAD_INPUT / _BAD_STATE with the last good
 * output repeated and the state left as it was (see the top of this file). */
static inline void cct_step(cct_state_t *s, const cct_input_t *in, cct_output_t *out)
{
    cct_state_t nx;
    if (!(cct_finite(in->i_d_ref) && cct_finite(in->i_q_ref)
          && cct_finite(in->i_d) && cct_finite(in->i_q)
          && cct_finite(in->omega_m) && cct_finite(in->theta_e))) {
        cct_hold(s, out, CCT_STATUS_BAD_INPUT);
        return;
    }
    nx = *s;
    const float w = (float)CCT_POLE_PAIRS * in->omega_m; /* electrical speed, rad/s */
    const float vd_lin = cct_d_linear(nx.d, in->i_d_ref, in->i_d);
    const float vq_lin = cct_q_linear(nx.q, in->i_q_ref, in->i_q);
    const float vd = vd_lin - (float)CCT_DEC_CROSS * w * CCT_DEC_LQ * in->i_q;
    const float vq = vq_lin + (float)CCT_DEC_CROSS * w * CCT_DEC_LD * in->i_d
                   + (float)CCT_DEC_EMF * w * CCT_DEC_FLUX;
    float vds = vd;
    float vqs = vq;
    int saturated = 0;
    /* SVM hexagon in the stationary frame at the angle of the middle of the
     * application period (as the toolbox simulator): theta_e + w_e Ts (DELAY + 1/2) */
    const float th = in->theta_e + w * CCT_SAMPLE_TIME * ((float)CCT_DELAY_SAMPLES + 0.5f);
    const float c = cosf(th);
    const float sn = sinf(th);
    const float va = vd * c - vq * sn;
    const float vb = vd * sn + vq * c;
    /* largest projection on the edge normals (30, 90, 150 deg); the edges lie
     * at the apothem r_hex sqrt(3)/2 = V_MAX from the centre */
    const float p1 = 0.866025404f * va + 0.5f * vb;
    const float p3 = -0.866025404f * va + 0.5f * vb;
    float pm = vb < 0.0f ? -vb : vb;
    if (p1 > pm) { pm = p1; }
    if (-p1 > pm) { pm = -p1; }
    if (p3 > pm) { pm = p3; }
    if (-p3 > pm) { pm = -p3; }
    if (pm > s->v_max) {
        const float k = s->v_max / pm;
        vds = vd * k;
        vqs = vq * k;
        saturated = 1;
    }
    if (!(cct_finite(vds) && cct_finite(vqs) && cct_state_finite(&nx))) {
        cct_hold(s, out, CCT_STATUS_BAD_STATE);
        return;
    }
    const float vdr = vds; /* no delay compensation in this design */
    const float vqr = vqs;
    nx.v_d_hold = vds;
    nx.v_q_hold = vqs;
    nx.v_d_comp_hold = vdr;
    nx.v_q_comp_hold = vqr;
    *s = nx;
    out->v_d = vds;
    out->v_q = vqs;
    out->v_d_comp = vdr;
    out->v_q_comp = vqr;
    out->saturated = saturated;
    out->status = CCT_STATUS_OK;
}

#ifdef CCT_FIXED_POINT
#error "fixed-point variant not available: voltage_limit = 'hexagon' is implemented in the float path only; the Q31 variant needs voltage_limit = 'circle'"
#endif /* CCT_FIXED_POINT */

#if defined(CCT_MCSDK) || defined(CCT_IQMATH)
#error "MCSDK/IQmath variants not available: voltage_limit = 'hexagon' is implemented in the float path only; the MCSDK/IQmath variants need voltage_limit = 'circle'"
#endif

#if 0 /* usage example: copy the lines between BEGIN and END into main.c */
// EXAMPLE main.c BEGIN
#include <stdio.h>
#include "controller.h"

/* stand-ins for the board's drivers: ADC, encoder, PWM, fault output */
static float adc_i_d(void) { return 0.0f; }
static float adc_i_q(void) { return 0.0f; }
static float adc_vdc(void) { return CCT_DRIVE_VDC; }
static float encoder_speed(void) { return 0.0f; }
static float encoder_theta_e(void) { return 0.0f; }
static void pwm_apply(float v_d, float v_q, float theta_e)
{
    (void)v_d; (void)v_q; (void)theta_e; /* inverse Park at theta_e, then SVM */
}
static void fault_report(int status) { printf("controller status %d\n", status); }

static cct_state_t ctl;

/* once per controller period (CCT_SAMPLE_TIME s), e.g. in the ADC interrupt */
static void control_isr(float i_d_ref, float i_q_ref)
{
    cct_input_t in;
    cct_output_t out;
    const float theta_e = encoder_theta_e();
    if (cct_set_vdc(&ctl, adc_vdc()) != CCT_STATUS_OK) {
        fault_report(CCT_STATUS_BAD_INPUT); /* bus reading lost: previous limit kept */
    }
    in.i_d_ref = i_d_ref;
    in.i_q_ref = i_q_ref;
    in.i_d = adc_i_d();
    in.i_q = adc_i_q();
    in.omega_m = encoder_speed();
    in.theta_e = theta_e;
    cct_step(&ctl, &in, &out);
    if (out.status != CCT_STATUS_OK) {
        fault_report(out.status); /* output held, state kept: decide to trip or ride through */
    }
    pwm_apply(out.v_d_comp, out.v_q_comp, theta_e); /* applied during the next period */
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
