/*
 * controller.h -- current controller exported by current-control-toolbox
 * title:       Paper 000 (Le Pioufle 1992): total compensation with integrators matched to the PI (eq 18-24)
 * method:      tci
 * version:     0.1.0
 * spec sha256: 9e6cb4b92141432f59e1d7413c810901151cf0d51431f1522b402acd653e204e
 * law sha256:  90c4e7796dd79efda679655c0965ba833435312321211368983ea39f1a158566
 * created:     2026-11-28T00:23:18+00:00
 * equations:   000 eq (18) (sign corrected): de/dt = -K11 e - K12 int e; 000 eq (19)-(20): total compensation with integrators; 000 eq (21): s^2 + K11 s + K12 = 0; 000 eq (22)-(24): K21 = E k_i Kp/Lq, K22 = E k_i KI/Lq, K11 = K21, K12 = K22
 *
 * C99, header-only, no dynamic memory; libm: sqrtf, sinf, cosf (float path).
 * Call cct_init() once, then cct_set_vdc() with the measured bus voltage and
 * cct_step() once per controller period (example at the end of this file). The
 * voltage returned is applied by the inverter DELAY_SAMPLES periods later (the
 * next period for DELAY_SAMPLES = 1, this one for 0): the computation delay is
 * part of the plant the design assumed, not of this code.
 * Law per axis: x' = A x + B [i_ref; i_meas], v = C x + D [i_ref; i_meas]
 *   (1-DOF laws as second-order sections of K(z) = v / (i_ref - i_meas)),
 * then decoupling  v_d += -cross w_e Lq_c i_q,
 *                  v_q +=  cross w_e Ld_c i_d + emf w_e flux_c,  w_e = p Omega_m,
 * then the circle limit |v| <= limit in use (radial scaling; the inscribed
 * circle of the SVM hexagon), and
 * back-calculation anti-windup x += aw (v_sat - v_unsat).
 * The limit in use is V_MAX_PER_VDC x the bus voltage last given to set_vdc
 * (V_MAX, the nominal bus, after init).
 * Voltage placement (toolbox/ARCHITECTURE.md "The digital loop"; every analysis,
 * the simulation and the certificates model exactly this): v_d_comp, v_q_comp
 * are v_dq rotated by DELAY_COMP_TIME w_e (the middle of the application
 * period); apply them with the inverse Park transform at the SAMPLED angle
 * theta_e, the angle of this period's currents, during the period DELAY_SAMPLES
 * later. v_d, v_q are the law's own (unrotated) output.
 * Faults: out->status is
 *   CCT_STATUS_OK (0)          the law ran;
 *   CCT_STATUS_BAD_INPUT (1)   an input is inf or nan;
 *   CCT_STATUS_BAD_STATE (2)   the result overflowed (inf/nan in v or the state);
 *   CCT_STATUS_IMPLAUSIBLE (4) a measured current beyond I_PLAUSIBLE or the
 *                                  speed beyond W_PLAUSIBLE (a sensor fault).
 * On 1 and 2 the last good output is repeated (0 V before the first good
 * period) with saturated = 0; on 4 implausible currents are replaced by the
 * law's prediction of them (one period of the PRED_* dq model from the last good
 * sample), an implausible speed by the last plausible one, and the output computed
 * from the state, the references and this period's angle and bus (the voltage
 * limit where the voltage is placed now). In all three cases the state is left
 * exactly as it was (no integrator update): the next valid period continues as
 * if the bad one had not happened. Finiteness is
 * tested on the IEEE-754 bits, so -ffast-math cannot remove the test.
 * cct_set_vdc refuses a bus reading that is not finite and > 0 (1) or lies
 * outside [VDC_MIN, VDC_PLAUSIBLE] (4), keeping the limit in use.
 * Handover and restart: cct_reset() zeroes the states and the held output
 * (the limit in use kept); cct_preset_at(&s, &in, v_d, v_q) puts the states
 * where the next step with the inputs in outputs (v_d, v_q) (bumpless transfer
 * from an open-loop voltage); cct_preset(&s, v_d, v_q) the linear laws' part
 * alone. out->sat_d, out->sat_q say which axis the voltage limit reduced.
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
#define CCT_V_MAX 1.060660172e+02f /* voltage limit (circle radius) at the nominal bus voltage, V; cct_init's default */
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
/* dq model (motor data) that predicts an implausible current sample's replacement */
#define CCT_PRED_R 6.000000238e-01f /* ohm */
#define CCT_PRED_LD 1.399999950e-03f /* H */
#define CCT_PRED_LQ 2.799999900e-03f /* H */
#define CCT_PRED_FLUX 1.199999973e-01f /* Wb */
#define CCT_DELAY_COMP_TIME 1.500000071e-04f /* s (1.5 Ts, drive.angle_compensation = "mid_period"): v_dq is placed at theta_e + CCT_DELAY_COMP_TIME * w_e (rad); applied inside cct_step, outputs v_d_comp, v_q_comp */


/* inputs: currents in A, measured MECHANICAL speed in rad/s.
 * dq frame (power-invariant Park transform: |i_dq|^2 = i_a^2 + i_b^2 + i_c^2, power = v_d i_d + v_q i_q):
 * d along the rotor's permanent-magnet flux, q 90 electrical degrees ahead of
 * it in the direction of positive rotation (phase order a, b, c);
 * i_d = sqrt(2/3) (i_a cos th + i_b cos(th - 2pi/3) + i_c cos(th + 2pi/3)),
 * i_q = -sqrt(2/3) (i_a sin th + i_b sin(th - 2pi/3) + i_c sin(th + 2pi/3)),
 * th = theta_e the electrical angle of the d axis from phase a's axis. */
typedef struct {
    float i_d_ref; /* A */
    float i_q_ref; /* A */
    float i_d;     /* measured, A; |i_d| <= CCT_I_PLAUSIBLE else refused */
    float i_q;     /* measured, A; |i_q| <= CCT_I_PLAUSIBLE else refused */
    float omega_m; /* measured mechanical speed, rad/s (w_e = POLE_PAIRS omega_m); |omega_m| <= CCT_W_PLAUSIBLE */
} cct_input_t;

#define CCT_STATUS_OK 0         /* the law ran */
#define CCT_STATUS_BAD_INPUT 1  /* a non-finite input: output held, state kept */
#define CCT_STATUS_BAD_STATE 2  /* non-finite result (overflow): output held, state kept */
#define CCT_STATUS_CLAMPED 3     /* integer variants: an input beyond its range was clamped (the law ran) */
#define CCT_STATUS_IMPLAUSIBLE 4 /* a measurement beyond its plausible range: replaced by the last
                                     * plausible one for this period's output, state kept */

/* plausible ranges (a sample beyond them is a sensor or ADC fault, not a
 * current or speed the drive can have): cct_step refuses measured currents
 * or speed beyond them, cct_set_vdc bus readings outside [VDC_MIN, VDC_PLAUSIBLE] */
#define CCT_I_PLAUSIBLE 6.000000000e+01f /* A, 2 x motor.max_current (else 2 x max(2 x rated, V_MAX/R, flux/L)) */
#define CCT_W_PLAUSIBLE 4.600000000e+02f /* rad/s mechanical, 2 x drive.max_speed (else see the docs) */
#define CCT_VDC_MIN 1.500000060e-01f /* V, 1e-3 x DRIVE_VDC */
#define CCT_VDC_PLAUSIBLE 3.000000000e+02f /* V, 2 x DRIVE_VDC */

typedef struct {
    float v_d;     /* V, the law's output (limited), applied DELAY_SAMPLES periods later */
    float v_q;     /* V */
    float v_d_comp; /* V, v_dq rotated by CCT_DELAY_COMP_TIME w_e (voltage placement): */
    float v_q_comp; /* V, feed these to the inverse Park transform at the SAMPLED theta_e */
    int saturated; /* 1 when the voltage limit acted */
    int sat_d;     /* 1 when the limit reduced |v_d| (e.g. stop an outer d loop's integrator) */
    int sat_q;     /* 1 when the limit reduced |v_q| (e.g. stop the speed loop's integrator) */
    int status;    /* CCT_STATUS_* */
} cct_output_t;

/* controller states (ss d axis: 1, ss q axis: 1; arrays have at least one element)
 * and the last good output, held when a period fails */
typedef struct {
    float d[1];
    float q[1];
    float v_d_hold; /* V */
    float v_q_hold; /* V */
    float v_d_comp_hold; /* V */
    float v_q_comp_hold; /* V */
    float v_max;    /* V, voltage limit in use (cct_set_vdc); CCT_V_MAX after init */
    float i_d_pred; /* A, the currents predicted for the next sampling instant (0 after */
    float i_q_pred; /* reset), used in place of an implausible current sample */
    float omega_m_good; /* rad/s, last plausible speed, used in place of an implausible one */
} cct_state_t;

/* zero states and held outputs (0 V), keeping the voltage limit in use:
 * e.g. after a trip, before the PWM is enabled again */
static inline void cct_reset(cct_state_t *s)
{
    unsigned i;
    for (i = 0u; i < 1u; ++i) { s->d[i] = 0.0f; }
    for (i = 0u; i < 1u; ++i) { s->q[i] = 0.0f; }
    s->v_d_hold = 0.0f;
    s->v_q_hold = 0.0f;
    s->v_d_comp_hold = 0.0f;
    s->v_q_comp_hold = 0.0f;
    s->i_d_pred = 0.0f;
    s->i_q_pred = 0.0f;
    s->omega_m_good = 0.0f;
}

/* cct_reset and the voltage limit CCT_V_MAX (nominal bus CCT_DRIVE_VDC) */
static inline void cct_init(cct_state_t *s)
{
    cct_reset(s);
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

/* 1 when v is a NaN (IEEE-754 bits, immune to -ffast-math) */
static inline int cct_isnan(float v)
{
    union { float f; uint32_t u; } b;
    b.f = v;
    return (b.u & 0x7f800000u) == 0x7f800000u && (b.u & 0x007fffffu) != 0u;
}

/* measured DC-link voltage (V) -> voltage limit CCT_V_MAX_PER_VDC * vdc (the
 * circle's radius); call whenever a new bus measurement arrives (e.g. once per
 * period, before cct_step). Returns CCT_STATUS_OK; CCT_STATUS_BAD_INPUT
 * (vdc not finite or not > 0) or CCT_STATUS_IMPLAUSIBLE (vdc outside
 * [CCT_VDC_MIN, CCT_VDC_PLAUSIBLE]) leave the limit in use unchanged. */
static inline int cct_set_vdc(cct_state_t *s, float vdc)
{
    if (!(cct_finite(vdc) && vdc > 0.0f)) {
        return CCT_STATUS_BAD_INPUT;
    }
    if (!(vdc >= CCT_VDC_MIN && vdc <= CCT_VDC_PLAUSIBLE)) {
        return CCT_STATUS_IMPLAUSIBLE;
    }
    s->v_max = CCT_V_MAX_PER_VDC * vdc;
    return CCT_STATUS_OK;
}

/* 1 when both measured currents lie within their plausible range
 * (finite inputs: cct_step tests finiteness first) */
static inline int cct_currents_plausible(const cct_input_t *in)
{
    return in->i_d <= CCT_I_PLAUSIBLE && in->i_d >= -CCT_I_PLAUSIBLE
        && in->i_q <= CCT_I_PLAUSIBLE && in->i_q >= -CCT_I_PLAUSIBLE;
}

/* 1 when the measured currents and speed lie within their plausible ranges */
static inline int cct_plausible(const cct_input_t *in)
{
    return cct_currents_plausible(in)
        && in->omega_m <= CCT_W_PLAUSIBLE && in->omega_m >= -CCT_W_PLAUSIBLE;
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
    out->sat_d = 0;
    out->sat_q = 0;
    out->status = status;
}

/* d axis linear law: returns v (V); updates the state to A x + B u */
static inline float cct_d_linear(float *x, float r, float y)
{
    static const float a[1] = { 1.000000000e+00f };
    static const float b[2] = { 9.999999747e-05f, -9.999999747e-05f };
    static const float c[1] = { 9.900000000e+02f };
    float xn[1];
    float v = 5.299499989e+00f * r + -4.699500084e+00f * y;
    unsigned i, j;
    for (i = 0u; i < 1u; ++i) {
        float acc = b[2u * i] * r + b[2u * i + 1u] * y;
        for (j = 0u; j < 1u; ++j) {
            acc += a[1u * i + j] * x[j];
        }
        v += c[i] * x[i];
        xn[i] = acc;
    }
    for (i = 0u; i < 1u; ++i) {
        x[i] = xn[i];
    }
    return v;
}

/* q axis linear law: returns v (V); updates the state to A x + B u */
static inline float cct_q_linear(float *x, float r, float y)
{
    static const float a[1] = { 1.000000000e+00f };
    static const float b[2] = { 9.999999747e-05f, -9.999999747e-05f };
    static const float c[1] = { 1.980000000e+03f };
    float xn[1];
    float v = 1.059899998e+01f * r + -9.998999596e+00f * y;
    unsigned i, j;
    for (i = 0u; i < 1u; ++i) {
        float acc = b[2u * i] * r + b[2u * i + 1u] * y;
        for (j = 0u; j < 1u; ++j) {
            acc += a[1u * i + j] * x[j];
        }
        v += c[i] * x[i];
        xn[i] = acc;
    }
    for (i = 0u; i < 1u; ++i) {
        x[i] = xn[i];
    }
    return v;
}

/* d axis: the state for which the linear law outputs v with the inputs
 * (r, y) (exactly: C x = v - D [r; y]), on the steady-state manifold
 * (I - A) x = B [r; y] when the law has an integrator (else the closest
 * state to it in least squares) */
static inline void cct_d_preset(float *x, float v, float r, float y)
{
    static const float g[1] = { 1.010101056e-03f };
    static const float h[2] = { 0.0f, 0.0f };
    const float c = v - (5.299499989e+00f * r + -4.699500084e+00f * y);
    unsigned i;
    for (i = 0u; i < 1u; ++i) {
        x[i] = g[i] * c + h[2u * i] * r + h[2u * i + 1u] * y;
    }
}

/* q axis: the state for which the linear law outputs v with the inputs
 * (r, y) (exactly: C x = v - D [r; y]), on the steady-state manifold
 * (I - A) x = B [r; y] when the law has an integrator (else the closest
 * state to it in least squares) */
static inline void cct_q_preset(float *x, float v, float r, float y)
{
    static const float g[1] = { 5.050505279e-04f };
    static const float h[2] = { 0.0f, 0.0f };
    const float c = v - (1.059899998e+01f * r + -9.998999596e+00f * y);
    unsigned i;
    for (i = 0u; i < 1u; ++i) {
        x[i] = g[i] * c + h[2u * i] * r + h[2u * i + 1u] * y;
    }
}

/* bumpless transfer (e.g. open-loop voltage -> closed loop): puts the states
 * where the next cct_step with the inputs *in outputs v_d, v_q (V, the
 * law's output: decoupling included, before the limit, so keep |v| within
 * it), and holds that voltage as the last good output. Call it in the period
 * of the handover, with the inputs of the step that follows (references
 * typically set to the measured currents). A static law (no state) cannot be
 * preset: its output follows from the inputs alone; only the held output is
 * set. Returns CCT_STATUS_OK, or _BAD_INPUT / _IMPLAUSIBLE (nothing changed). */
static inline int cct_preset_at(cct_state_t *s, const cct_input_t *in, float v_d, float v_q)
{
    if (!(cct_finite(v_d) && cct_finite(v_q)
          && cct_finite(in->i_d_ref) && cct_finite(in->i_q_ref)
          && cct_finite(in->i_d) && cct_finite(in->i_q)
          && cct_finite(in->omega_m))) {
        return CCT_STATUS_BAD_INPUT;
    }
    if (!cct_plausible(in)) {
        return CCT_STATUS_IMPLAUSIBLE;
    }
    const float w = (float)CCT_POLE_PAIRS * in->omega_m; /* electrical speed, rad/s */
    const float vd_lin = v_d + (float)CCT_DEC_CROSS * w * CCT_DEC_LQ * in->i_q;
    const float vq_lin = v_q - (float)CCT_DEC_CROSS * w * CCT_DEC_LD * in->i_d
                       - (float)CCT_DEC_EMF * w * CCT_DEC_FLUX;
    cct_d_preset(s->d, vd_lin, in->i_d_ref, in->i_d);
    cct_q_preset(s->q, vq_lin, in->i_q_ref, in->i_q);
    s->i_d_pred = in->i_d;
    s->i_q_pred = in->i_q;
    s->omega_m_good = in->omega_m;
    s->v_d_hold = v_d;
    s->v_q_hold = v_q;
    {
        const float thc = CCT_DELAY_COMP_TIME * w;
        const float cc = cosf(thc);
        const float sc = sinf(thc);
        s->v_d_comp_hold = v_d * cc - v_q * sc;
        s->v_q_comp_hold = v_d * sc + v_q * cc;
    }
    return CCT_STATUS_OK;
}

/* the linear laws' part only: the states where each axis law outputs v_d, v_q
 * (V) at zero error, i.e. with i_ref = i_meas for a one-degree-of-freedom law
 * (v = K (i_ref - i_meas)) and with zero currents otherwise;
 * decoupling terms come on top at speed. Held output set to (v_d, v_q).
 * Use cct_preset_at for an exact handover at speed or with currents. */
static inline void cct_preset(cct_state_t *s, float v_d, float v_q)
{
    cct_d_preset(s->d, v_d, 0.0f, 0.0f);
    cct_q_preset(s->q, v_q, 0.0f, 0.0f);
    s->v_d_hold = v_d;
    s->v_q_hold = v_q;
    s->v_d_comp_hold = v_d;
    s->v_q_comp_hold = v_q;
}

/* one controller period: the whole law (linear laws, decoupling, limit, anti-windup).
 * out->status: CCT_STATUS_OK; _BAD_INPUT / _BAD_STATE with the last good
 * output repeated and the state left as it was; _IMPLAUSIBLE: implausible
 * currents replaced by the prediction the last good period made of them
 * (forward Euler of the PRED_* dq model, DELAY_SAMPLES <= 1 exactly; beyond, the
 * previous output stands for the voltage applied), an implausible speed by
 * the last plausible one, the output computed from the state, the references and the angle of
 * this period (so the voltage limit is the one at this angle), the state left
 * as it was (no integrator update; see the top of this file). */
static inline void cct_step(cct_state_t *s, const cct_input_t *in, cct_output_t *out)
{
    cct_state_t nx;
    if (!(cct_finite(in->i_d_ref) && cct_finite(in->i_q_ref)
          && cct_finite(in->i_d) && cct_finite(in->i_q)
          && cct_finite(in->omega_m))) {
        cct_hold(s, out, CCT_STATUS_BAD_INPUT);
        return;
    }
    float i_d = in->i_d;
    float i_q = in->i_q;
    float omega_m = in->omega_m;
    int status = CCT_STATUS_OK;
    if (!cct_plausible(in)) {
        status = CCT_STATUS_IMPLAUSIBLE;
        if (!cct_currents_plausible(in)) {
            i_d = s->i_d_pred;
            i_q = s->i_q_pred;
        }
        if (!(omega_m <= CCT_W_PLAUSIBLE && omega_m >= -CCT_W_PLAUSIBLE)) {
            omega_m = s->omega_m_good;
        }
    }
    nx = *s;
    const float w = (float)CCT_POLE_PAIRS * omega_m; /* electrical speed, rad/s */
    const float vd_lin = cct_d_linear(nx.d, in->i_d_ref, i_d);
    const float vq_lin = cct_q_linear(nx.q, in->i_q_ref, i_q);
    const float vd = vd_lin - (float)CCT_DEC_CROSS * w * CCT_DEC_LQ * i_q;
    const float vq = vq_lin + (float)CCT_DEC_CROSS * w * CCT_DEC_LD * i_d
                   + (float)CCT_DEC_EMF * w * CCT_DEC_FLUX;
    float vds = vd;
    float vqs = vq;
    int saturated = 0;
    const float mag2 = vd * vd + vq * vq;
    if (mag2 > s->v_max * s->v_max) {
        const float k = s->v_max / sqrtf(mag2);
        vds = vd * k;
        vqs = vq * k;
        saturated = 1;
    }
    /* back-calculation anti-windup */
    nx.d[0] += 1.886970495e-05f * (vds - vd);
    nx.q[0] += 9.434852473e-06f * (vqs - vq);
    if (!(cct_finite(vds) && cct_finite(vqs) && cct_state_finite(&nx))) {
        cct_hold(s, out, CCT_STATUS_BAD_STATE);
        return;
    }
    /* voltage placement (toolbox/ARCHITECTURE.md "The digital loop"): v_dq rotated
     * by DELAY_COMP_TIME w_e, i.e. placed at theta_e + DELAY_COMP_TIME w_e */
    const float thc = CCT_DELAY_COMP_TIME * w;
    const float cc = cosf(thc);
    const float sc = sinf(thc);
    const float vdr = vds * cc - vqs * sc;
    const float vqr = vds * sc + vqs * cc;
    if (status == CCT_STATUS_OK) { /* an implausible period leaves the state as it was */
        nx.v_d_hold = vds;
        nx.v_q_hold = vqs;
        nx.v_d_comp_hold = vdr;
        nx.v_q_comp_hold = vqr;
        {
            /* the currents at the next sampling instant: one forward-Euler period of
             * the controller's dq model under the voltage applied meanwhile (this
             * output without computation delay, else the previous one; the placement
             * makes its rotor-frame mean v_dq) */
#if CCT_DELAY_SAMPLES == 0
            const float ud = vds;
            const float uq = vqs;
#else
            const float ud = s->v_d_hold;
            const float uq = s->v_q_hold;
#endif
            nx.i_d_pred = i_d + CCT_SAMPLE_TIME / CCT_PRED_LD
                        * (ud - CCT_PRED_R * i_d + w * CCT_PRED_LQ * i_q);
            nx.i_q_pred = i_q + CCT_SAMPLE_TIME / CCT_PRED_LQ
                        * (uq - CCT_PRED_R * i_q - w * CCT_PRED_LD * i_d - w * CCT_PRED_FLUX);
        }
        nx.omega_m_good = omega_m;
        *s = nx;
    }
    out->v_d = vds;
    out->v_q = vqs;
    out->v_d_comp = vdr;
    out->v_q_comp = vqr;
    out->saturated = saturated;
    out->sat_d = vds != vd;
    out->sat_q = vqs != vq;
    out->status = status;
}
#if defined(CCT_FIXED_POINT) || defined(CCT_MCSDK) || defined(CCT_IQMATH)
#include <stdint.h>
/* integer voltage placement: (pd, pq) = v_dq rotated by x (Q30 rad, |x| <= 1.5) */
static inline void cct_place_q30(int64_t vd, int64_t vq, int64_t x, int64_t *pd, int64_t *pq)
{
    const int64_t one = (int64_t)1 << 30;
    const int64_t x2 = (x * x) >> 30;
    const int64_t c3 = one - x2 / 30;
    const int64_t c2 = one - ((x2 * c3) >> 30) / 12;
    const int64_t cs = one - ((x2 * c2) >> 30) / 2;
    const int64_t s3 = one - x2 / 42;
    const int64_t s2 = one - ((x2 * s3) >> 30) / 20;
    const int64_t s1 = one - ((x2 * s2) >> 30) / 6;
    const int64_t sn = (x * s1) >> 30;
    *pd = (vd * cs - vq * sn) >> 30;
    *pq = (vd * sn + vq * cs) >> 30;
}
#endif

#ifdef CCT_FIXED_POINT
/*
 * Fixed point: Q31 words (value / 2^31), int64 accumulators, arithmetic
 * right shifts (as gcc and arm-none-eabi implement >> on negative values).
 * Each coefficient set is an int32 mantissa vector m with one shift F:
 * c = m / 2^F (integer gains with power-of-two divisors, as STM32 MCSDK).
 * Inputs up to I_MAX = 30 A and W_MAX = 230 rad/s (mechanical),
 * voltage limit 106.066 V: bases below are powers of two above rigorous
 * bounds of every signal and state, so no accumulator or word overflows. The
 * input words reach twice these ranges (the plausible ranges): cct_step_q31
 * clamps references and measurements beyond I_MAX / W_MAX (status CLAMPED)
 * and refuses measurements at or beyond the plausible ranges (status
 * IMPLAUSIBLE: the last plausible sample used, the state not updated).
 * Quantisation error bound, d axis: |v_q31 - v_exact| <= 7.16e-05 V over 20 ms from equal states.
 * Quantisation error bound, q axis: |v_q31 - v_exact| <= 0.000141 V over 20 ms from equal states.
 */
#include <stdint.h>
#define CCT_Q31_I_BASE 6.400000000e+01f /* A at full scale */
#define CCT_Q31_V_BASE 2.048000000e+03f /* V at full scale */
#define CCT_Q31_W_BASE 5.120000000e+02f /* mechanical rad/s at full scale */
#define CCT_Q31_I_MAX 3.000000000e+01f /* A, current range (cct_step_q31 clamps beyond) */
#define CCT_Q31_W_MAX 2.300000000e+02f /* rad/s, speed range (cct_step_q31 clamps beyond) */
#define CCT_Q31_I_PLAUSIBLE 6.000000000e+01f /* A, 2 x Q31_I_MAX: measured currents at or beyond are refused */
#define CCT_Q31_W_PLAUSIBLE 4.600000000e+02f /* rad/s, 2 x Q31_W_MAX: a measured speed at or beyond is refused */
/* the same as Q31 words */
#define CCT_Q31_I_MAX_W 1006632960L
#define CCT_Q31_W_MAX_W 964689920L
#define CCT_Q31_I_PLAUSIBLE_W 2013265920L
#define CCT_Q31_W_PLAUSIBLE_W 1929379840L
#define CCT_Q31_V_MAX 111218280L /* V_MAX / V_BASE in Q31: the largest limit */
#define CCT_Q31_VDC_BASE 2.896309326e+03f /* V of bus at full scale (cct_set_vdc_q31) */
#define CCT_Q31_D_X0_BASE 2.500000000e-01f /* state 0 full scale */
#define CCT_Q31_Q_X0_BASE 2.500000000e-01f /* state 0 full scale */
#define CCT_Q31_DEC_DD -769658139L /* decoupling coefficient -0.1792 p.u. = m / 2^shift */
#define CCT_Q31_DEC_DD_SHIFT 32u
#define CCT_Q31_DEC_DQ 769658139L /* decoupling coefficient 0.0896 p.u. = m / 2^shift */
#define CCT_Q31_DEC_DQ_SHIFT 33u
#define CCT_Q31_DEC_DE 1030792151L /* decoupling coefficient 0.12 p.u. = m / 2^shift */
#define CCT_Q31_DEC_DE_SHIFT 33u

typedef struct {
    int32_t i_d_ref; /* Q31 of Q31_I_BASE */
    int32_t i_q_ref;
    int32_t i_d;
    int32_t i_q;
    int32_t omega_m; /* Q31 of Q31_W_BASE (mechanical) */
} cct_input_q31_t;

/* voltage placement: rotation angle at full-scale speed, Q30 rad
 * (0.3072 rad = DELAY_COMP_TIME x POLE_PAIRS x Q31_W_BASE) */
#define CCT_Q31_COMP_K 329853488

typedef struct {
    int32_t v_d; /* Q31 of Q31_V_BASE, the law's output (limited) */
    int32_t v_q;
    int32_t v_d_comp; /* Q31 of Q31_V_BASE, v_dq placed as the float path does: feed */
    int32_t v_q_comp; /* these to the inverse Park transform at the SAMPLED theta_e */
    int saturated;
    int status;    /* CCT_STATUS_OK, _CLAMPED (an input beyond its range was clamped)
                    * or _IMPLAUSIBLE (a measurement replaced by the last plausible one) */
} cct_output_q31_t;

typedef struct {
    int32_t d[1];
    int32_t q[1];
    int32_t v_max; /* voltage limit in use, Q31 of Q31_V_BASE (cct_set_vdc_q31) */
    int32_t i_d_good; /* last plausible measurements (0 after init), used in place */
    int32_t i_q_good; /* of an implausible one */
    int32_t omega_m_good;
} cct_state_q31_t;

static inline void cct_init_q31(cct_state_q31_t *s)
{
    unsigned i;
    for (i = 0u; i < 1u; ++i) { s->d[i] = 0; }
    for (i = 0u; i < 1u; ++i) { s->q[i] = 0; }
    s->v_max = CCT_Q31_V_MAX;
    s->i_d_good = 0;
    s->i_q_good = 0;
    s->omega_m_good = 0;
}

/* measured DC-link voltage as Q31 of CCT_Q31_VDC_BASE (chosen so that the
 * word IS the voltage limit in Q31 of Q31_V_BASE). The scaling and the state
 * bounds were derived for the nominal bus: above it the limit is clamped to
 * CCT_Q31_V_MAX and 1 is returned; a negative word is refused (-1, limit
 * unchanged, as for a word at or below 1e-3 of the nominal limit, e.g. the 0 of
 * a non-finite reading converted by cct_to_q31); 0 otherwise. */
static inline int cct_set_vdc_q31(cct_state_q31_t *s, int32_t vdc)
{
    if (vdc <= CCT_Q31_V_MAX / 1000) { return -1; } /* below 1e-3 x nominal (0: a lost reading) */
    if (vdc > CCT_Q31_V_MAX) {
        s->v_max = CCT_Q31_V_MAX;
        return 1;
    }
    s->v_max = vdc;
    return 0;
}

/* physical value -> Q31 word of base, clamped to +-range with *clamped = 1
 * beyond it; a NaN gives 0 with *clamped = 1. Pass the plausible ranges
 * (CCT_Q31_I_PLAUSIBLE, base CCT_Q31_I_BASE; CCT_Q31_W_PLAUSIBLE,
 * CCT_Q31_W_BASE) so that cct_step_q31 sees an implausible sample (a
 * value clamped here lands on the plausible limit, which it refuses) and
 * clamps to the ranges itself. */
static inline int32_t cct_to_q31(float value, float range, float base, int *clamped)
{
    float v = value;
    if (cct_isnan(v)) { *clamped = 1; return 0; } /* bits: -ffast-math proof */
    if (v > range) { v = range; *clamped = 1; }
    if (v < -range) { v = -range; *clamped = 1; }
    {
        const float q = v / base * 2147483648.0f; /* truncated towards zero below */
        if (q >= 2147483648.0f) { return INT32_MAX; }
        if (q <= -2147483648.0f) { return -INT32_MAX; }
        return (int32_t)q;
    }
}

/* v clamped to [-lim, lim]; *flag = 1 when it acts */
static inline int32_t cct_clamp_q31(int32_t v, int32_t lim, int *flag)
{
    if (v > lim) { *flag = 1; return lim; }
    if (v < -lim) { *flag = 1; return -lim; }
    return v;
}

/* 1 when |v| < lim (the plausible side of a plausible limit) */
static inline int cct_below_q31(int32_t v, int32_t lim)
{
    return (int64_t)v < (int64_t)lim && (int64_t)v > -(int64_t)lim;
}

static inline int32_t cct_sat32(int64_t v)
{
    if (v > (int64_t)INT32_MAX) { return INT32_MAX; }
    if (v < -(int64_t)INT32_MAX) { return -INT32_MAX; }
    return (int32_t)v;
}

static inline int64_t cct_shr(int64_t acc, unsigned f)
{
    return f ? (acc + ((int64_t)1 << (f - 1u))) >> f : acc;
}

static inline uint32_t cct_isqrt64(uint64_t v)
{
    uint64_t r = 0u, bit = (uint64_t)1 << 62;
    while (bit > v) { bit >>= 2; }
    while (bit != 0u) {
        if (v >= r + bit) { v -= r + bit; r = (r >> 1) + bit; } else { r >>= 1; }
        bit >>= 2;
    }
    return (uint32_t)r;
}

/* d axis: v_lin (Q31, int64 before limiting) and x <- A x + B u */
static inline int64_t cct_d_linear_q31(int32_t *x, int32_t r, int32_t y)
{
    static const int32_t co[3] = { 259522560L, 355643425L, -315378106L };
    static const int32_t ca[4] = {
        268435456L, 6871948L, -6871948L, 41494919L,
    };
    static const unsigned fa[1] = { 28u };
    int32_t xn[1];
    unsigned i, j;
    int64_t acc = (int64_t)co[1] * r + (int64_t)co[2] * y;
    for (j = 0u; j < 1u; ++j) { acc += (int64_t)co[j] * x[j]; }
    acc = cct_shr(acc, 31u);
    for (i = 0u; i < 1u; ++i) {
        const int32_t *m = &ca[4u * i];
        int64_t a = (int64_t)m[1] * r + (int64_t)m[2] * y;
        for (j = 0u; j < 1u; ++j) { a += (int64_t)m[j] * x[j]; }
        xn[i] = cct_sat32(cct_shr(a, fa[i]));
    }
    for (i = 0u; i < 1u; ++i) { x[i] = xn[i]; }
    return acc;
}

static inline void cct_d_antiwindup_q31(int32_t *x, int64_t dv)
{
    static const int32_t aw[1] = { 41494919L };
    static const unsigned fa[1] = { 28u };
    unsigned i;
    for (i = 0u; i < 1u; ++i) {
        x[i] = cct_sat32((int64_t)x[i] + cct_shr((int64_t)aw[i] * dv, fa[i]));
    }
}

/* q axis: v_lin (Q31, int64 before limiting) and x <- A x + B u */
static inline int64_t cct_q_linear_q31(int32_t *x, int32_t r, int32_t y)
{
    static const int32_t co[3] = { 259522560L, 355643425L, -335510766L };
    static const int32_t ca[4] = {
        268435456L, 6871948L, -6871948L, 20747460L,
    };
    static const unsigned fa[1] = { 28u };
    int32_t xn[1];
    unsigned i, j;
    int64_t acc = (int64_t)co[1] * r + (int64_t)co[2] * y;
    for (j = 0u; j < 1u; ++j) { acc += (int64_t)co[j] * x[j]; }
    acc = cct_shr(acc, 30u);
    for (i = 0u; i < 1u; ++i) {
        const int32_t *m = &ca[4u * i];
        int64_t a = (int64_t)m[1] * r + (int64_t)m[2] * y;
        for (j = 0u; j < 1u; ++j) { a += (int64_t)m[j] * x[j]; }
        xn[i] = cct_sat32(cct_shr(a, fa[i]));
    }
    for (i = 0u; i < 1u; ++i) { x[i] = xn[i]; }
    return acc;
}

static inline void cct_q_antiwindup_q31(int32_t *x, int64_t dv)
{
    static const int32_t aw[1] = { 20747460L };
    static const unsigned fa[1] = { 28u };
    unsigned i;
    for (i = 0u; i < 1u; ++i) {
        x[i] = cct_sat32((int64_t)x[i] + cct_shr((int64_t)aw[i] * dv, fa[i]));
    }
}

/* one controller period. Measured currents at or beyond Q31_I_PLAUSIBLE_W
 * (both replaced) or a speed at or beyond Q31_W_PLAUSIBLE_W: the last plausible
 * sample is used, the state is not updated, status IMPLAUSIBLE; references and
 * measurements beyond the ranges Q31_I_MAX_W / Q31_W_MAX_W are clamped to
 * them, status CLAMPED (the law ran); else status OK. */
static inline void cct_step_q31(cct_state_q31_t *s, const cct_input_q31_t *in, cct_output_q31_t *out)
{
    cct_state_q31_t nx = *s;
    int status = CCT_STATUS_OK;
    int clamped = 0;
    int32_t i_d = in->i_d;
    int32_t i_q = in->i_q;
    int32_t w_m = in->omega_m;
    if (!(cct_below_q31(i_d, CCT_Q31_I_PLAUSIBLE_W) && cct_below_q31(i_q, CCT_Q31_I_PLAUSIBLE_W))) {
        i_d = s->i_d_good;
        i_q = s->i_q_good;
        status = CCT_STATUS_IMPLAUSIBLE;
    }
    if (!cct_below_q31(w_m, CCT_Q31_W_PLAUSIBLE_W)) {
        w_m = s->omega_m_good;
        status = CCT_STATUS_IMPLAUSIBLE;
    }
    i_d = cct_clamp_q31(i_d, CCT_Q31_I_MAX_W, &clamped);
    i_q = cct_clamp_q31(i_q, CCT_Q31_I_MAX_W, &clamped);
    w_m = cct_clamp_q31(w_m, CCT_Q31_W_MAX_W, &clamped);
    const int32_t r_d = cct_clamp_q31(in->i_d_ref, CCT_Q31_I_MAX_W, &clamped);
    const int32_t r_q = cct_clamp_q31(in->i_q_ref, CCT_Q31_I_MAX_W, &clamped);
    if (clamped && status == CCT_STATUS_OK) { status = CCT_STATUS_CLAMPED; }
    const int64_t vd_lin = cct_d_linear_q31(nx.d, r_d, i_d);
    const int64_t vq_lin = cct_q_linear_q31(nx.q, r_q, i_q);
    const int64_t wiq = cct_shr((int64_t)w_m * i_q, 31u);
    const int64_t wid = cct_shr((int64_t)w_m * i_d, 31u);
    const int64_t vd = vd_lin + cct_shr((int64_t)CCT_Q31_DEC_DD * wiq, CCT_Q31_DEC_DD_SHIFT);
    const int64_t vq = vq_lin + cct_shr((int64_t)CCT_Q31_DEC_DQ * wid, CCT_Q31_DEC_DQ_SHIFT)
                     + cct_shr((int64_t)CCT_Q31_DEC_DE * w_m, CCT_Q31_DEC_DE_SHIFT);
    const int64_t vdc = cct_sat32(vd);
    const int64_t vqc = cct_sat32(vq);
    const uint64_t mag2 = (uint64_t)(vdc * vdc) + (uint64_t)(vqc * vqc);
    int64_t vds = vdc;
    int64_t vqs = vqc;
    out->saturated = 0;
    if (mag2 > (uint64_t)s->v_max * (uint64_t)s->v_max) {
        const int64_t mag = (int64_t)cct_isqrt64(mag2);
        vds = (vdc * s->v_max) / mag;
        vqs = (vqc * s->v_max) / mag;
        out->saturated = 1;
    }
    cct_d_antiwindup_q31(nx.d, vds - vd);
    cct_q_antiwindup_q31(nx.q, vqs - vq);
    if (status != CCT_STATUS_IMPLAUSIBLE) {
        nx.i_d_good = i_d;
        nx.i_q_good = i_q;
        nx.omega_m_good = w_m;
        *s = nx;
    }
    out->status = status;
    out->v_d = (int32_t)vds;
    out->v_q = (int32_t)vqs;
    {
        /* voltage placement: v_dq rotated by DELAY_COMP_TIME w_e */
        int64_t pd, pq;
        cct_place_q30(vds, vqs, ((int64_t)w_m * CCT_Q31_COMP_K) >> 31, &pd, &pq);
        out->v_d_comp = (int32_t)cct_sat32(pd);
        out->v_q_comp = (int32_t)cct_sat32(pq);
    }
}
#endif /* CCT_FIXED_POINT */

#if defined(CCT_MCSDK) || defined(CCT_IQMATH)
#error "MCSDK/IQmath variants not available: d axis: the MCSDK/IQmath variants run a one-degree-of-freedom PI (v from i_ref - i_meas); this law weights them differently"
#endif

/* Operating envelope (toolbox.plant.OperatingEnvelope, constant Ld, Lq, flux):
 * current references for a torque at a speed: MTPA below base speed, field
 * weakening above, the torque limit where the request exceeds it; voltage
 * limit 100.763 V (the drive's circle less 5 % for the loop), current
 * limit 30 A. Table of 17 speeds (0 .. 230 rad/s
 * mechanical) x 11 torques (0 .. the limit at that speed), interpolated linearly
 * in |speed| and in the torque's fraction of the limit; a negative torque mirrors
 * i_q. Memory: (N_SPEED + 2 N_SPEED N_TORQUE) x 4 = 1564 bytes of constants. */
#define CCT_ENV_N_SPEED 17
#define CCT_ENV_N_TORQUE 11
#define CCT_ENV_SPEED_STEP 1.437500000e+01f /* rad/s between rows */
static const float cct_env_t_max[17] = {1.517998028e+01f, 1.517998028e+01f, 1.517998028e+01f, 1.517998028e+01f, 1.517998028e+01f, 1.517998028e+01f, 1.517998028e+01f, 1.517998028e+01f, 1.517998028e+01f, 1.517998028e+01f, 1.517998028e+01f, 1.515088177e+01f, 1.437792301e+01f, 1.317889500e+01f, 1.185832691e+01f, 1.051155949e+01f, 9.169061661e+00f};
static const float cct_env_i_d[17][11] = {
    {0.0f, -1.162094697e-01f, -4.593077302e-01f, -1.013748884e+00f, -1.756687403e+00f, -2.661387920e+00f, -3.700351954e+00f, -4.847593307e+00f, -6.079951286e+00f, -7.377611160e+00f, -8.724101067e+00f},
    {0.0f, -1.162094697e-01f, -4.593077302e-01f, -1.013748884e+00f, -1.756687403e+00f, -2.661387920e+00f, -3.700351954e+00f, -4.847593307e+00f, -6.079951286e+00f, -7.377611160e+00f, -8.724101067e+00f},
    {0.0f, -1.162094697e-01f, -4.593077302e-01f, -1.013748884e+00f, -1.756687403e+00f, -2.661387920e+00f, -3.700351954e+00f, -4.847593307e+00f, -6.079951286e+00f, -7.377611160e+00f, -8.724101067e+00f},
    {0.0f, -1.162094697e-01f, -4.593077302e-01f, -1.013748884e+00f, -1.756687403e+00f, -2.661387920e+00f, -3.700351954e+00f, -4.847593307e+00f, -6.079951286e+00f, -7.377611160e+00f, -8.724101067e+00f},
    {0.0f, -1.162094697e-01f, -4.593077302e-01f, -1.013748884e+00f, -1.756687403e+00f, -2.661387920e+00f, -3.700351954e+00f, -4.847593307e+00f, -6.079951286e+00f, -7.377611160e+00f, -8.724101067e+00f},
    {0.0f, -1.162094697e-01f, -4.593077302e-01f, -1.013748884e+00f, -1.756687403e+00f, -2.661387920e+00f, -3.700351954e+00f, -4.847593307e+00f, -6.079951286e+00f, -7.377611160e+00f, -8.724101067e+00f},
    {0.0f, -1.162094697e-01f, -4.593077302e-01f, -1.013748884e+00f, -1.756687403e+00f, -2.661387920e+00f, -3.700351954e+00f, -4.847593307e+00f, -6.079951286e+00f, -7.377611160e+00f, -8.724101067e+00f},
    {0.0f, -1.162094697e-01f, -4.593077302e-01f, -1.013748884e+00f, -1.756687403e+00f, -2.661387920e+00f, -3.700351954e+00f, -4.847593307e+00f, -6.079951286e+00f, -7.377611160e+00f, -8.724101067e+00f},
    {0.0f, -1.162094697e-01f, -4.593077302e-01f, -1.013748884e+00f, -1.756687403e+00f, -2.661387920e+00f, -3.700351954e+00f, -4.847593307e+00f, -6.079951286e+00f, -7.377611160e+00f, -8.724101067e+00f},
    {0.0f, -1.162094697e-01f, -4.593077302e-01f, -1.013748884e+00f, -1.756687403e+00f, -2.661387920e+00f, -3.700351954e+00f, -4.847593307e+00f, -6.079951286e+00f, -7.377611160e+00f, -8.724101067e+00f},
    {0.0f, -1.162094697e-01f, -4.593077302e-01f, -1.013748884e+00f, -1.756687403e+00f, -2.661387920e+00f, -3.700351954e+00f, -4.847593307e+00f, -6.079951286e+00f, -7.377611160e+00f, -8.724101067e+00f},
    {0.0f, -1.157661676e-01f, -4.575760961e-01f, -1.009997129e+00f, -1.750339985e+00f, -2.652036190e+00f, -3.687739134e+00f, -4.831587791e+00f, -6.060513496e+00f, -7.354766846e+00f, -1.027422714e+01f},
    {0.0f, -1.042970940e-01f, -4.127224982e-01f, -9.126411080e-01f, -1.585259199e+00f, -2.408217669e+00f, -3.358071089e+00f, -4.412198067e+00f, -7.194410324e+00f, -1.164074898e+01f, -1.634380913e+01f},
    {0.0f, -8.767792583e-02f, -3.475443125e-01f, -7.705564499e-01f, -1.343031168e+00f, -2.048300743e+00f, -4.560843468e+00f, -8.091043472e+00f, -1.186135101e+01f, -1.587382317e+01f, -2.014353752e+01f},
    {0.0f, -7.102838159e-02f, -2.820273638e-01f, -1.514985085e+00f, -3.833406687e+00f, -6.411139011e+00f, -9.230657578e+00f, -1.227960491e+01f, -1.555205631e+01f, -1.904970169e+01f, -2.278340340e+01f},
    {-2.274555683e+00f, -3.525066853e+00f, -5.020668030e+00f, -6.751771450e+00f, -8.707500458e+00f, -1.087714005e+01f, -1.325143337e+01f, -1.582368565e+01f, -1.859074593e+01f, -2.155398178e+01f, -2.472044563e+01f},
    {-7.561707497e+00f, -8.650993347e+00f, -9.922908783e+00f, -1.137330437e+01f, -1.299734688e+01f, -1.479015923e+01f, -1.674745178e+01f, -1.886612511e+01f, -2.114487076e+01f, -2.358477402e+01f, -2.619003868e+01f},
};
static const float cct_env_i_q[17][11] = {
    {0.0f, 3.158214092e+00f, 6.291279793e+00f, 9.376590729e+00f, 1.239593315e+01f, 1.533629513e+01f, 1.818971252e+01f, 2.095249748e+01f, 2.362423515e+01f, 2.620678902e+01f, 2.870348549e+01f},
    {0.0f, 3.158214092e+00f, 6.291279793e+00f, 9.376590729e+00f, 1.239593315e+01f, 1.533629513e+01f, 1.818971252e+01f, 2.095249748e+01f, 2.362423515e+01f, 2.620678902e+01f, 2.870348549e+01f},
    {0.0f, 3.158214092e+00f, 6.291279793e+00f, 9.376590729e+00f, 1.239593315e+01f, 1.533629513e+01f, 1.818971252e+01f, 2.095249748e+01f, 2.362423515e+01f, 2.620678902e+01f, 2.870348549e+01f},
    {0.0f, 3.158214092e+00f, 6.291279793e+00f, 9.376590729e+00f, 1.239593315e+01f, 1.533629513e+01f, 1.818971252e+01f, 2.095249748e+01f, 2.362423515e+01f, 2.620678902e+01f, 2.870348549e+01f},
    {0.0f, 3.158214092e+00f, 6.291279793e+00f, 9.376590729e+00f, 1.239593315e+01f, 1.533629513e+01f, 1.818971252e+01f, 2.095249748e+01f, 2.362423515e+01f, 2.620678902e+01f, 2.870348549e+01f},
    {0.0f, 3.158214092e+00f, 6.291279793e+00f, 9.376590729e+00f, 1.239593315e+01f, 1.533629513e+01f, 1.818971252e+01f, 2.095249748e+01f, 2.362423515e+01f, 2.620678902e+01f, 2.870348549e+01f},
    {0.0f, 3.158214092e+00f, 6.291279793e+00f, 9.376590729e+00f, 1.239593315e+01f, 1.533629513e+01f, 1.818971252e+01f, 2.095249748e+01f, 2.362423515e+01f, 2.620678902e+01f, 2.870348549e+01f},
    {0.0f, 3.158214092e+00f, 6.291279793e+00f, 9.376590729e+00f, 1.239593315e+01f, 1.533629513e+01f, 1.818971252e+01f, 2.095249748e+01f, 2.362423515e+01f, 2.620678902e+01f, 2.870348549e+01f},
    {0.0f, 3.158214092e+00f, 6.291279793e+00f, 9.376590729e+00f, 1.239593315e+01f, 1.533629513e+01f, 1.818971252e+01f, 2.095249748e+01f, 2.362423515e+01f, 2.620678902e+01f, 2.870348549e+01f},
    {0.0f, 3.158214092e+00f, 6.291279793e+00f, 9.376590729e+00f, 1.239593315e+01f, 1.533629513e+01f, 1.818971252e+01f, 2.095249748e+01f, 2.362423515e+01f, 2.620678902e+01f, 2.870348549e+01f},
    {0.0f, 3.158214092e+00f, 6.291279793e+00f, 9.376590729e+00f, 1.239593315e+01f, 1.533629513e+01f, 1.818971252e+01f, 2.095249748e+01f, 2.362423515e+01f, 2.620678902e+01f, 2.870348549e+01f},
    {0.0f, 3.152176380e+00f, 6.279345989e+00f, 9.359021187e+00f, 1.237306881e+01f, 1.530851650e+01f, 1.815740585e+01f, 2.091603088e+01f, 2.358394432e+01f, 2.616297340e+01f, 2.818581581e+01f},
    {0.0f, 2.991760254e+00f, 5.962092876e+00f, 8.891529083e+00f, 1.176403046e+01f, 1.456770992e+01f, 1.729483414e+01f, 1.994131279e+01f, 2.210760689e+01f, 2.373516273e+01f, 2.515710449e+01f},
    {0.0f, 2.742797375e+00f, 5.469030857e+00f, 8.163421631e+00f, 1.081298733e+01f, 1.340761566e+01f, 1.564134502e+01f, 1.756149483e+01f, 1.929476738e+01f, 2.084925842e+01f, 2.223146057e+01f},
    {0.0f, 2.468439341e+00f, 4.924765587e+00f, 7.282733440e+00f, 9.458907127e+00f, 1.149280071e+01f, 1.338180828e+01f, 1.512635994e+01f, 1.672862434e+01f, 1.819138908e+01f, 1.951708221e+01f},
    {0.0f, 2.103404045e+00f, 4.137466431e+00f, 6.090010643e+00f, 7.951826572e+00f, 9.716515541e+00f, 1.138008690e+01f, 1.294042969e+01f, 1.439672947e+01f, 1.574890518e+01f, 1.699704552e+01f},
    {0.0f, 1.735100508e+00f, 3.424049377e+00f, 5.059346199e+00f, 6.634810448e+00f, 8.145571709e+00f, 9.587964058e+00f, 1.095934391e+01f, 1.225787258e+01f, 1.348226738e+01f, 1.463153839e+01f},
};
/* torque (N m), omega_m (mechanical rad/s) -> *i_d_ref, *i_q_ref (A); returns 0,
 * 1 (torque clamped to the limit at that speed) or 2 (|omega_m| beyond the
 * table: its last row used). The Python mirror is
 * toolbox.export._envelope_table.EnvelopeTable.reference. */
static inline int cct_envelope_ref(float torque, float omega_m, float *i_d_ref, float *i_q_ref)
{
    int status = 0;
    float s = (omega_m < 0.0f ? -omega_m : omega_m) / CCT_ENV_SPEED_STEP;
    if (!(s <= (float)(CCT_ENV_N_SPEED - 1))) { s = (float)(CCT_ENV_N_SPEED - 1); status = 2; }
    int k = (int)s;
    if (k > CCT_ENV_N_SPEED - 2) { k = CCT_ENV_N_SPEED - 2; }
    const float fs = s - (float)k;
    const float t_lim = cct_env_t_max[k] + fs * (cct_env_t_max[k + 1] - cct_env_t_max[k]);
    const float ta = torque < 0.0f ? -torque : torque;
    float f = t_lim > 0.0f ? ta / t_lim : 0.0f;
    if (f > 1.0f) { f = 1.0f; if (status == 0) { status = 1; } }
    const float c = f * (float)(CCT_ENV_N_TORQUE - 1);
    int j = (int)c;
    if (j > CCT_ENV_N_TORQUE - 2) { j = CCT_ENV_N_TORQUE - 2; }
    const float fc = c - (float)j;
    const float d_lo = cct_env_i_d[k][j] + fc * (cct_env_i_d[k][j + 1] - cct_env_i_d[k][j]);
    const float d_hi = cct_env_i_d[k + 1][j] + fc * (cct_env_i_d[k + 1][j + 1] - cct_env_i_d[k + 1][j]);
    const float q_lo = cct_env_i_q[k][j] + fc * (cct_env_i_q[k][j + 1] - cct_env_i_q[k][j]);
    const float q_hi = cct_env_i_q[k + 1][j] + fc * (cct_env_i_q[k + 1][j + 1] - cct_env_i_q[k + 1][j]);
    const float iq = q_lo + fs * (q_hi - q_lo);
    *i_d_ref = d_lo + fs * (d_hi - d_lo);
    *i_q_ref = torque < 0.0f ? -iq : iq;
    return status;
}

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
    const int bus = cct_set_vdc(&ctl, adc_vdc());
    if (bus != CCT_STATUS_OK) {
        fault_report(bus); /* bus reading lost or implausible: previous limit kept */
    }
    in.i_d_ref = i_d_ref;
    in.i_q_ref = i_q_ref;
    in.i_d = adc_i_d();
    in.i_q = adc_i_q();
    in.omega_m = encoder_speed();

    cct_step(&ctl, &in, &out);
    if (out.status != CCT_STATUS_OK) {
        fault_report(out.status); /* state kept (output held, or from the last plausible
                                   * measurement: 4): decide to trip or ride through */
    }
    /* inverse Park at the SAMPLED theta_e (wrapped to [-pi, pi)); the PWM applies
     * it DELAY_SAMPLES periods later (the next period for DELAY_SAMPLES = 1) */
    pwm_apply(out.v_d_comp, out.v_q_comp, theta_e);
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
