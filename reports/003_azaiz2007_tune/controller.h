/*
 * controller.h -- current controller exported by current-control-toolbox
 * title:       Paper 003 motor: structured robust tuning of the PI, disk margin 0.5 over R, Ld, Lq x0.5..x2, speed-sensor errors, 0..230 rad/s, with the design delay and one period more
 * method:      tune
 * version:     0.1.0
 * spec sha256: 02480abeeda782370b097f3b15bb037166aab2d66a90454d9bcecda075fe11b2
 * law sha256:  33f23fd436f4fd5a387f4548e5143536c9f15b6b30fe38f478bc916f50ae21be
 * created:     2026-11-28T00:24:57+00:00
 * equations:   structured tuning of Kp_d, Ki_d, Kp_q, Ki_q and the cross-coupling feedforward scale: min max(t5_d, t5_q) s.t. multiloop disk margin >= alpha on every model (delay d and d + 1), worst-case search over the box
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
#define CCT_V_MAX 8.660253906e+01f /* voltage limit (circle radius) at the nominal bus voltage, V; cct_init's default */
#define CCT_V_MAX_PER_VDC 5.773502588e-01f /* voltage limit per volt of measured bus (cct_set_vdc) */
/* motor (amplitude-invariant dq convention) */
#define CCT_MOTOR_R 6.000000238e-01f /* stator resistance, ohm */
#define CCT_MOTOR_LD 1.399999950e-03f /* d-axis inductance, H */
#define CCT_MOTOR_LQ 2.799999900e-03f /* q-axis inductance, H */
#define CCT_MOTOR_FLUX 1.199999973e-01f /* PM flux linkage, Wb */
#define CCT_MOTOR_POLE_PAIRS 4 /* pole pairs */
#define CCT_MOTOR_J 1.109999954e-03f /* inertia, kg m^2 */
#define CCT_MOTOR_FRICTION 1.399999950e-03f /* viscous friction, N m s/rad */
#define CCT_MOTOR_MAX_CURRENT 2.000000000e+01f /* dq current amplitude limit, A */
#define CCT_MOTOR_RATED_CURRENT 2.000000000e+01f /* A */
#define CCT_MOTOR_RATED_SPEED 2.300000000e+02f /* mechanical, rad/s */
/* drive */
#define CCT_DRIVE_VDC 1.500000000e+02f /* DC-link voltage, V */
/* decoupling: controller-side model parameters */
#define CCT_DEC_CROSS 1 /* 1: cross-coupling terms on */
#define CCT_DEC_EMF 1 /* 1: back-EMF term on */
#define CCT_DEC_LD 4.931088770e-04f /* H */
#define CCT_DEC_LQ 9.862177540e-04f /* H */
#define CCT_DEC_FLUX 1.199999973e-01f /* Wb */
#define CCT_POLE_PAIRS 4 /* w_e = POLE_PAIRS * Omega_m */
/* dq model (motor data) that predicts an implausible current sample's replacement */
#define CCT_PRED_R 6.000000238e-01f /* ohm */
#define CCT_PRED_LD 1.399999950e-03f /* H */
#define CCT_PRED_LQ 2.799999900e-03f /* H */
#define CCT_PRED_FLUX 1.199999973e-01f /* Wb */
#define CCT_DELAY_COMP_TIME 1.500000071e-04f /* s (1.5 Ts, drive.angle_compensation = "mid_period"): v_dq is placed at theta_e + CCT_DELAY_COMP_TIME * w_e (rad); applied inside cct_step, outputs v_d_comp, v_q_comp */
/* d axis PI gains (method tune), FOR INFORMATION ONLY: the code
 *   runs the coefficients of the law below, derived from these gains at export;
 *   to retune, change the spec and re-export (editing these numbers does nothing).
 *   Kp = 1.72386531 V/A (parallel proportional gain)
 *   Ki = 1079.76897 V/(A s) (parallel integral gain)
 *   Ki Ts = 0.107976897 V/A (integral gain per sample)
 *   Ti = 0.0015965131 s (series form Kp (1 + 1/(Ti s)), Ti = Kp/Ki)
 */
/* q axis PI gains (method tune), FOR INFORMATION ONLY: the code
 *   runs the coefficients of the law below, derived from these gains at export;
 *   to retune, change the spec and re-export (editing these numbers does nothing).
 *   Kp = 4.6366345 V/A (parallel proportional gain)
 *   Ki = 963.974821 V/(A s) (parallel integral gain)
 *   Ki Ts = 0.0963974821 V/A (integral gain per sample)
 *   Ti = 0.00480991246 s (series form Kp (1 + 1/(Ti s)), Ti = Kp/Ki)
 */

#define CCT_D_GAIN 1.777853727e+00f /* d axis SOS output gain, V/A */
#define CCT_D_NUM_STAGES 1
#define CCT_Q_GAIN 4.684833050e+00f /* q axis SOS output gain, V/A */
#define CCT_Q_NUM_STAGES 1

/* inputs: currents in A, measured MECHANICAL speed in rad/s.
 * dq frame (amplitude-invariant Park transform: |i_dq| = peak phase current, |v_dq| = peak phase voltage):
 * d along the rotor's permanent-magnet flux, q 90 electrical degrees ahead of
 * it in the direction of positive rotation (phase order a, b, c);
 * i_d = 2/3 (i_a cos th + i_b cos(th - 2pi/3) + i_c cos(th + 2pi/3)),
 * i_q = -2/3 (i_a sin th + i_b sin(th - 2pi/3) + i_c sin(th + 2pi/3)),
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
#define CCT_I_PLAUSIBLE 4.000000000e+01f /* A, 2 x motor.max_current (else 2 x max(2 x rated, V_MAX/R, flux/L)) */
#define CCT_W_PLAUSIBLE 7.216878662e+02f /* rad/s mechanical, 2 x drive.max_speed (else see the docs) */
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

/* controller states (sos d axis: 2, sos q axis: 2; arrays have at least one element)
 * and the last good output, held when a period fails */
typedef struct {
    float d[2];
    float q[2];
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
    for (i = 0u; i < 2u; ++i) { s->d[i] = 0.0f; }
    for (i = 0u; i < 2u; ++i) { s->q[i] = 0.0f; }
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
    for (i = 0u; i < 2u; ++i) { ok &= cct_finite(s->d[i]); }
    for (i = 0u; i < 2u; ++i) { ok &= cct_finite(s->q[i]); }
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
    /* 1 stage(s) {b0, b1, b2, a1, a2} (a1, a2 negated, CMSIS df2T), gain CCT_D_GAIN */
    static const float c[5] = {
        1.000000000e+00f, -9.392656088e-01f, 0.0f, 1.000000000e+00f, 0.0f,
    };
    float in = r - y;
    unsigned k;
    for (k = 0u; k < 1u; ++k) {
        const float *s = &c[5u * k];
        const float out = s[0] * in + x[2u * k];
        x[2u * k] = s[1] * in + s[3] * out + x[2u * k + 1u];
        x[2u * k + 1u] = s[2] * in + s[4] * out;
        in = out;
    }
    return CCT_D_GAIN * in;
}

/* q axis linear law: returns v (V); updates the state to A x + B u */
static inline float cct_q_linear(float *x, float r, float y)
{
    /* 1 stage(s) {b0, b1, b2, a1, a2} (a1, a2 negated, CMSIS df2T), gain CCT_Q_GAIN */
    static const float c[5] = {
        1.000000000e+00f, -9.794235229e-01f, 0.0f, 1.000000000e+00f, 0.0f,
    };
    float in = r - y;
    unsigned k;
    for (k = 0u; k < 1u; ++k) {
        const float *s = &c[5u * k];
        const float out = s[0] * in + x[2u * k];
        x[2u * k] = s[1] * in + s[3] * out + x[2u * k + 1u];
        x[2u * k + 1u] = s[2] * in + s[4] * out;
        in = out;
    }
    return CCT_Q_GAIN * in;
}

/* d axis: the state for which the linear law outputs v with the inputs
 * (r, y) (exactly: C x = v - D [r; y]), on the steady-state manifold
 * (I - A) x = B [r; y] when the law has an integrator (else the closest
 * state to it in least squares) */
static inline void cct_d_preset(float *x, float v, float r, float y)
{
    static const float g[2] = { 5.624759793e-01f, 0.0f };
    static const float h[4] = { 0.0f, 0.0f, -3.036720492e-02f, 3.036720492e-02f };
    const float c = v - (1.777853727e+00f * r + -1.777853727e+00f * y);
    unsigned i;
    for (i = 0u; i < 2u; ++i) {
        x[i] = g[i] * c + h[2u * i] * r + h[2u * i + 1u] * y;
    }
}

/* q axis: the state for which the linear law outputs v with the inputs
 * (r, y) (exactly: C x = v - D [r; y]), on the steady-state manifold
 * (I - A) x = B [r; y] when the law has an integrator (else the closest
 * state to it in least squares) */
static inline void cct_q_preset(float *x, float v, float r, float y)
{
    static const float g[2] = { 2.134547681e-01f, 0.0f };
    static const float h[4] = { 0.0f, 0.0f, -1.028825156e-02f, 1.028825156e-02f };
    const float c = v - (4.684833050e+00f * r + -4.684833050e+00f * y);
    unsigned i;
    for (i = 0u; i < 2u; ++i) {
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
 * (v = K (i_ref - i_meas): every axis of this header) and with zero currents otherwise;
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
    nx.d[0] += 3.416164592e-02f * (vds - vd);
    nx.q[0] += 4.392152652e-03f * (vqs - vq);
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
 * Inputs up to I_MAX = 20 A and W_MAX = 360.844 rad/s (mechanical),
 * voltage limit 86.6025 V: bases below are powers of two above rigorous
 * bounds of every signal and state, so no accumulator or word overflows. The
 * input words reach twice these ranges (the plausible ranges): cct_step_q31
 * clamps references and measurements beyond I_MAX / W_MAX (status CLAMPED)
 * and refuses measurements at or beyond the plausible ranges (status
 * IMPLAUSIBLE: the last plausible sample used, the state not updated).
 * Quantisation error bound, d axis: |v_q31 - v_exact| <= 5.32e-05 V over 20 ms from equal states.
 * Quantisation error bound, q axis: |v_q31 - v_exact| <= 0.000127 V over 20 ms from equal states.
 */
#include <stdint.h>
#define CCT_Q31_I_BASE 6.400000000e+01f /* A at full scale */
#define CCT_Q31_V_BASE 1.024000000e+03f /* V at full scale */
#define CCT_Q31_W_BASE 1.024000000e+03f /* mechanical rad/s at full scale */
#define CCT_Q31_I_MAX 2.000000000e+01f /* A, current range (cct_step_q31 clamps beyond) */
#define CCT_Q31_W_MAX 3.608439331e+02f /* rad/s, speed range (cct_step_q31 clamps beyond) */
#define CCT_Q31_I_PLAUSIBLE 4.000000000e+01f /* A, 2 x Q31_I_MAX: measured currents at or beyond are refused */
#define CCT_Q31_W_PLAUSIBLE 7.216878662e+02f /* rad/s, 2 x Q31_W_MAX: a measured speed at or beyond is refused */
/* the same as Q31 words */
#define CCT_Q31_I_MAX_W 671088640L
#define CCT_Q31_W_MAX_W 756744544L
#define CCT_Q31_I_PLAUSIBLE_W 1342177280L
#define CCT_Q31_W_PLAUSIBLE_W 1513489089L
#define CCT_Q31_V_MAX 181618690L /* V_MAX / V_BASE in Q31: the largest limit */
#define CCT_Q31_VDC_BASE 1.773619995e+03f /* V of bus at full scale (cct_set_vdc_q31) */
#define CCT_Q31_D_X0_BASE 1.280000000e+02f /* state 0 full scale */
#define CCT_Q31_D_X1_BASE 1.000000000e+00f /* state 1 full scale */
#define CCT_Q31_Q_X0_BASE 6.400000000e+01f /* state 0 full scale */
#define CCT_Q31_Q_X1_BASE 1.000000000e+00f /* state 1 full scale */
#define CCT_Q31_DEC_DD -542178960L /* decoupling coefficient -0.252472 p.u. = m / 2^shift */
#define CCT_Q31_DEC_DD_SHIFT 31u
#define CCT_Q31_DEC_DQ 542178960L /* decoupling coefficient 0.126236 p.u. = m / 2^shift */
#define CCT_Q31_DEC_DQ_SHIFT 32u
#define CCT_Q31_DEC_DE 1030792151L /* decoupling coefficient 0.48 p.u. = m / 2^shift */
#define CCT_Q31_DEC_DE_SHIFT 31u
/* d axis per-unit PI gains as integer / 2^shift, FOR INFORMATION ONLY
 * (the Q31 law below runs its own quantised coefficients):
 *   Kp = 925493141L / 2^33 (0.107742 p.u.)
 *   Ki Ts = 927514484L / 2^37 (0.00674856 p.u.)
 */
/* q axis per-unit PI gains as integer / 2^shift, FOR INFORMATION ONLY
 * (the Q31 law below runs its own quantised coefficients):
 *   Kp = 622318548L / 2^31 (0.28979 p.u.)
 *   Ki Ts = 828048066L / 2^37 (0.00602484 p.u.)
 */

typedef struct {
    int32_t i_d_ref; /* Q31 of Q31_I_BASE */
    int32_t i_q_ref;
    int32_t i_d;
    int32_t i_q;
    int32_t omega_m; /* Q31 of Q31_W_BASE (mechanical) */
} cct_input_q31_t;

/* voltage placement: rotation angle at full-scale speed, Q30 rad
 * (0.6144 rad = DELAY_COMP_TIME x POLE_PAIRS x Q31_W_BASE) */
#define CCT_Q31_COMP_K 659706977

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
    int32_t d[2];
    int32_t q[2];
    int32_t v_max; /* voltage limit in use, Q31 of Q31_V_BASE (cct_set_vdc_q31) */
    int32_t i_d_good; /* last plausible measurements (0 after init), used in place */
    int32_t i_q_good; /* of an implausible one */
    int32_t omega_m_good;
} cct_state_q31_t;

static inline void cct_init_q31(cct_state_q31_t *s)
{
    unsigned i;
    for (i = 0u; i < 2u; ++i) { s->d[i] = 0; }
    for (i = 0u; i < 2u; ++i) { s->q[i] = 0; }
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
    static const int32_t co[4] = { 238619492L, 0L, 119309746L, -119309746L };
    static const int32_t ca[10] = {
        134217728L, 1048576L, 4075817L, -4075817L, 36680787L,
        0L, 0L, 0L, 0L, 0L,
    };
    static const unsigned fa[2] = { 27u, 31u };
    int32_t xn[2];
    unsigned i, j;
    int64_t acc = (int64_t)co[2] * r + (int64_t)co[3] * y;
    for (j = 0u; j < 2u; ++j) { acc += (int64_t)co[j] * x[j]; }
    acc = cct_shr(acc, 30u);
    for (i = 0u; i < 2u; ++i) {
        const int32_t *m = &ca[5u * i];
        int64_t a = (int64_t)m[2] * r + (int64_t)m[3] * y;
        for (j = 0u; j < 2u; ++j) { a += (int64_t)m[j] * x[j]; }
        xn[i] = cct_sat32(cct_shr(a, fa[i]));
    }
    for (i = 0u; i < 2u; ++i) { x[i] = xn[i]; }
    return acc;
}

static inline void cct_d_antiwindup_q31(int32_t *x, int64_t dv)
{
    static const int32_t aw[2] = { 36680787L, 0L };
    static const unsigned fa[2] = { 27u, 31u };
    unsigned i;
    for (i = 0u; i < 2u; ++i) {
        x[i] = cct_sat32((int64_t)x[i] + cct_shr((int64_t)aw[i] * dv, fa[i]));
    }
}

/* q axis: v_lin (Q31, int64 before limiting) and x <- A x + B u */
static inline int64_t cct_q_linear_q31(int32_t *x, int32_t r, int32_t y)
{
    static const int32_t co[4] = { 157196918L, 0L, 157196918L, -157196918L };
    static const int32_t ca[10] = {
        134217728L, 2097152L, 2761731L, -2761731L, 9432076L,
        0L, 0L, 0L, 0L, 0L,
    };
    static const unsigned fa[2] = { 27u, 31u };
    int32_t xn[2];
    unsigned i, j;
    int64_t acc = (int64_t)co[2] * r + (int64_t)co[3] * y;
    for (j = 0u; j < 2u; ++j) { acc += (int64_t)co[j] * x[j]; }
    acc = cct_shr(acc, 29u);
    for (i = 0u; i < 2u; ++i) {
        const int32_t *m = &ca[5u * i];
        int64_t a = (int64_t)m[2] * r + (int64_t)m[3] * y;
        for (j = 0u; j < 2u; ++j) { a += (int64_t)m[j] * x[j]; }
        xn[i] = cct_sat32(cct_shr(a, fa[i]));
    }
    for (i = 0u; i < 2u; ++i) { x[i] = xn[i]; }
    return acc;
}

static inline void cct_q_antiwindup_q31(int32_t *x, int64_t dv)
{
    static const int32_t aw[2] = { 9432076L, 0L };
    static const unsigned fa[2] = { 27u, 31u };
    unsigned i;
    for (i = 0u; i < 2u; ++i) {
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
/* integer variants: PI law v = Kp e + I, I += Ki e + Kaw (v_sat - v) per axis;
 *   d: Kp = 1.77785376 V/A, Ki = 0.107976897 V/A per sample, Kaw = 0.060734409
 *   q: Kp = 4.68483324 V/A, Ki = 0.0963974821 V/A per sample, Kaw = 0.0205765023
 * ranges: references and measurements beyond the current range and a speed
 * beyond the speed range are clamped (status CLAMPED); measurements beyond
 * twice the ranges (the plausible ranges; for the MCSDK the int16 rail) are
 * refused (status IMPLAUSIBLE: the last plausible sample used, no integral update) */
#define CCT_MCSDK_I_FS 4.000000000e+01f /* A = 32768 digits (s16A): twice the current range */
#define CCT_MCSDK_V_FS 1.732050781e+02f /* V = 32768 digits (s16V) */
#define CCT_MCSDK_W_FS 7.216878662e+02f /* mechanical rad/s = 32768 digits: twice the speed range */
#define CCT_MCSDK_RANGE 16384 /* digits of the current and speed ranges (half the full scale) */
#define CCT_MCSDK_V_MAX 16384 /* nominal voltage limit, s16V */
#define CCT_IQ_I_BASE 2.000000000e+01f /* A = 1.0 p.u. */
#define CCT_IQ_V_BASE 8.660253906e+01f /* V = 1.0 p.u. (nominal limit) */
#define CCT_IQ_W_BASE 3.608439331e+02f /* mechanical rad/s = 1.0 p.u. */
#endif
#if defined(CCT_MCSDK) || defined(CCT_IQMATH)
#include <stdint.h>

static inline uint64_t cct_isqrt_u64(uint64_t v)
{
    uint64_t r = 0u, bit = (uint64_t)1 << 62;
    while (bit > v) { bit >>= 2; }
    while (bit != 0u) {
        if (v >= r + bit) { v -= r + bit; r = (r >> 1) + bit; } else { r >>= 1; }
        bit >>= 2;
    }
    return r;
}

/* clamp v to [-lim, lim]; sets *flag when it acts */
static inline int64_t cct_clamp64(int64_t v, int64_t lim, int *flag)
{
    if (v > lim) { *flag = 1; return lim; }
    if (v < -lim) { *flag = 1; return -lim; }
    return v;
}

/* radial limit of (vd, vq) to vmax; returns 1 when it acted */
static inline int cct_limit64(int64_t *vd, int64_t *vq, int64_t vmax)
{
    const uint64_t mag2 = (uint64_t)(*vd * *vd) + (uint64_t)(*vq * *vq);
    if (mag2 > (uint64_t)vmax * (uint64_t)vmax) {
        const int64_t mag = (int64_t)cct_isqrt_u64(mag2);
        *vd = (*vd * vmax) / mag;
        *vq = (*vq * vmax) / mag;
        return 1;
    }
    return 0;
}
#endif

#ifdef CCT_MCSDK
/*
 * STM32 MCSDK-style PI (PI_Controller): signals in int16 digits,
 *   current  s16A: CCT_MCSDK_I_FS A = 32768 digits
 *   voltage  s16V: CCT_MCSDK_V_FS V = 32768 digits (twice the nominal limit)
 *   speed:         CCT_MCSDK_W_FS rad/s (mechanical) = 32768 digits
 * gains int16 with power-of-two divisors, v = (KP e >> KP_DIV) + (integral >> KI_DIV),
 * integral += KI e (int32, clamped to +-V_FS), back-calculation anti-windup.
 */
#define CCT_MCSDK_D_KP_GAIN (13454) /* d_kp: gain / 2^DIV */
#define CCT_MCSDK_D_KP_DIV 15
#define CCT_MCSDK_D_KI_GAIN (817) /* d_ki: gain / 2^DIV */
#define CCT_MCSDK_D_KI_DIV 15
#define CCT_MCSDK_D_KAW_GAIN (1990) /* d_kaw: gain / 2^DIV */
#define CCT_MCSDK_D_KAW_DIV 15
#define CCT_MCSDK_Q_KP_GAIN (17726) /* q_kp: gain / 2^DIV */
#define CCT_MCSDK_Q_KP_DIV 14
#define CCT_MCSDK_Q_KI_GAIN (729) /* q_ki: gain / 2^DIV */
#define CCT_MCSDK_Q_KI_DIV 15
#define CCT_MCSDK_Q_KAW_GAIN (674) /* q_kaw: gain / 2^DIV */
#define CCT_MCSDK_Q_KAW_DIV 15
#define CCT_MCSDK_DD_GAIN (-21544) /* dd: gain / 2^DIV */
#define CCT_MCSDK_DD_DIV 15
#define CCT_MCSDK_DQ_GAIN (10772) /* dq: gain / 2^DIV */
#define CCT_MCSDK_DQ_DIV 15
#define CCT_MCSDK_DE_GAIN (16384) /* de: gain / 2^DIV */
#define CCT_MCSDK_DE_DIV 13

/* voltage placement: rotation angle at MCSDK_W_FS, Q30 rad
 * (0.433013 rad = DELAY_COMP_TIME x POLE_PAIRS x MCSDK_W_FS) */
#define CCT_MCSDK_COMP_K 464943848

typedef struct {
    int16_t i_d_ref; /* s16A */
    int16_t i_q_ref;
    int16_t i_d;
    int16_t i_q;
    int16_t omega_m; /* digits of MCSDK_W_FS */
} cct_input_s16_t;


typedef struct {
    int16_t v_d;   /* s16V, the law's output (limited) */
    int16_t v_q;
    int16_t v_d_comp; /* s16V, v_dq placed as the float path does: feed these to */
    int16_t v_q_comp; /* the inverse Park transform at the SAMPLED theta_e */
    int saturated;
    int status;    /* CCT_STATUS_OK, _CLAMPED (an input beyond its range was clamped)
                    * or _IMPLAUSIBLE (a measurement at the rail: the last plausible one used) */
} cct_output_s16_t;

/* run-time gains of one axis (as the SDK's PI handle): the step reads these,
 * so retuning in the field is writing them. Change KI_DIV only with the
 * integral at 0 (it holds integral x 2^KI_DIV). */
typedef struct {
    int16_t kp_gain;
    uint16_t kp_div;  /* log2 of the divisor, 0..15 */
    int16_t ki_gain;
    uint16_t ki_div;
    int16_t kaw_gain;
    uint16_t kaw_div;
} cct_gains_s16_t;

typedef struct {
    int32_t int_d; /* integral term x 2^KI_DIV, s16V */
    int32_t int_q;
    int32_t v_max; /* voltage limit in use, s16V (cct_set_vdc_s16) */
    cct_gains_s16_t gd; /* d-axis gains, CCT_MCSDK_D_* after init */
    cct_gains_s16_t gq; /* q-axis gains */
    int16_t i_d_good; /* last plausible measurements (0 after init) */
    int16_t i_q_good;
    int16_t omega_m_good;
} cct_state_s16_t;

static inline void cct_init_s16(cct_state_s16_t *s)
{
    s->int_d = 0;
    s->int_q = 0;
    s->v_max = CCT_MCSDK_V_MAX;
    s->gd.kp_gain = CCT_MCSDK_D_KP_GAIN; s->gd.kp_div = CCT_MCSDK_D_KP_DIV;
    s->gd.ki_gain = CCT_MCSDK_D_KI_GAIN; s->gd.ki_div = CCT_MCSDK_D_KI_DIV;
    s->gd.kaw_gain = CCT_MCSDK_D_KAW_GAIN; s->gd.kaw_div = CCT_MCSDK_D_KAW_DIV;
    s->gq.kp_gain = CCT_MCSDK_Q_KP_GAIN; s->gq.kp_div = CCT_MCSDK_Q_KP_DIV;
    s->gq.ki_gain = CCT_MCSDK_Q_KI_GAIN; s->gq.ki_div = CCT_MCSDK_Q_KI_DIV;
    s->gq.kaw_gain = CCT_MCSDK_Q_KAW_GAIN; s->gq.kaw_div = CCT_MCSDK_Q_KAW_DIV;
    s->i_d_good = 0;
    s->i_q_good = 0;
    s->omega_m_good = 0;
}

/* amps -> s16A digits, rounded; clamped to the rail +-32767 (which
 * cct_step_s16 refuses as implausible) with *clamped = 1 beyond it; a NaN
 * gives 0 with *clamped = 1 */
static inline int16_t cct_to_s16a(float amps, int *clamped)
{
    const float d = amps * (32768.0f / CCT_MCSDK_I_FS);
    if (cct_isnan(amps)) { *clamped = 1; return (int16_t)0; } /* bits: -ffast-math proof */
    if (!(d < 32767.0f)) { *clamped = 1; return (int16_t)32767; }
    if (!(d > -32767.0f)) { *clamped = 1; return (int16_t)-32767; }
    return (int16_t)(d >= 0.0f ? d + 0.5f : d - 0.5f);
}

/* bus voltage as s16V digits of MCSDK_V_FS / V_MAX_PER_VDC; clamped to the full
 * scale (1); a reading at or below 1e-3 of the nominal limit is refused (-1, limit kept) */
static inline int cct_set_vdc_s16(cct_state_s16_t *s, int32_t vmax_digits)
{
    if (vmax_digits <= CCT_MCSDK_V_MAX / 1000) { return -1; }
    s->v_max = vmax_digits > 32767 ? 32767 : vmax_digits;
    return vmax_digits > 32767 ? 1 : 0;
}

static inline int64_t cct_pi_s16(int32_t *integ, int32_t e, const cct_gains_s16_t *g)
{
    const int64_t v = (((int64_t)g->kp_gain * e) >> g->kp_div) + ((int64_t)*integ >> g->ki_div);
    int flag = 0;
    *integ = (int32_t)cct_clamp64((int64_t)*integ + (int64_t)g->ki_gain * e,
                                    (int64_t)32767 << g->ki_div, &flag);
    return v;
}

/* back-calculation: integral += KAW (v_sat - v), in integral units */
static inline void cct_aw_s16(int32_t *integ, int64_t dv, const cct_gains_s16_t *g)
{
    int flag = 0;
    *integ = (int32_t)cct_clamp64((int64_t)*integ
        + (((int64_t)g->kaw_gain * dv * ((int64_t)1 << g->ki_div)) >> g->kaw_div),
        (int64_t)32767 << g->ki_div, &flag);
}

/* 1 when an int16 measurement is off the rail (|v| < 32767: within twice its range) */
static inline int cct_off_rail(int16_t v)
{
    return v < 32767 && v > -32767;
}

/* one period. Measured currents (both replaced) or speed on the int16 rail
 * (+-32767 or -32768: twice the range, what cct_to_s16a returns beyond
 * it): the last plausible sample used, integrals not updated, status
 * IMPLAUSIBLE; inputs beyond MCSDK_RANGE clamped to it, status CLAMPED. */
static inline void cct_step_s16(cct_state_s16_t *s, const cct_input_s16_t *in, cct_output_s16_t *out)
{
    int clamped = 0;
    int status = CCT_STATUS_OK;
    int16_t i_d = in->i_d;
    int16_t i_q = in->i_q;
    int16_t w_m = in->omega_m;
    int32_t int_d = s->int_d;
    int32_t int_q = s->int_q;
    if (!(cct_off_rail(i_d) && cct_off_rail(i_q))) {
        i_d = s->i_d_good;
        i_q = s->i_q_good;
        status = CCT_STATUS_IMPLAUSIBLE;
    }
    if (!cct_off_rail(w_m)) {
        w_m = s->omega_m_good;
        status = CCT_STATUS_IMPLAUSIBLE;
    }
    const int64_t idr = cct_clamp64(in->i_d_ref, CCT_MCSDK_RANGE, &clamped);
    const int64_t iqr = cct_clamp64(in->i_q_ref, CCT_MCSDK_RANGE, &clamped);
    const int64_t idm = cct_clamp64(i_d, CCT_MCSDK_RANGE, &clamped);
    const int64_t iqm = cct_clamp64(i_q, CCT_MCSDK_RANGE, &clamped);
    const int64_t w = cct_clamp64(w_m, CCT_MCSDK_RANGE, &clamped);
    if (clamped && status == CCT_STATUS_OK) { status = CCT_STATUS_CLAMPED; }
    int64_t vd = cct_pi_s16(&int_d, (int32_t)(idr - idm), &s->gd);
    int64_t vq = cct_pi_s16(&int_q, (int32_t)(iqr - iqm), &s->gq);
    vd += (CCT_MCSDK_DD_GAIN * ((w * iqm) >> 15)) >> CCT_MCSDK_DD_DIV;
    vq += (CCT_MCSDK_DQ_GAIN * ((w * idm) >> 15)) >> CCT_MCSDK_DQ_DIV;
    vq += (CCT_MCSDK_DE_GAIN * w) >> CCT_MCSDK_DE_DIV;
    {
        const int64_t ud = vd;
        const int64_t uq = vq;
        int flag = 0;
        vd = cct_clamp64(vd, (int64_t)1 << 40, &flag);
        vq = cct_clamp64(vq, (int64_t)1 << 40, &flag);
        out->saturated = cct_limit64(&vd, &vq, s->v_max) | flag;
        cct_aw_s16(&int_d, vd - ud, &s->gd);
        cct_aw_s16(&int_q, vq - uq, &s->gq);
    }
    if (status != CCT_STATUS_IMPLAUSIBLE) {
        s->int_d = int_d;
        s->int_q = int_q;
        s->i_d_good = (int16_t)idm;
        s->i_q_good = (int16_t)iqm;
        s->omega_m_good = (int16_t)w;
    }
    out->v_d = (int16_t)vd;
    out->v_q = (int16_t)vq;
    {
        int64_t pd, pq;
        int flag = 0;
        cct_place_q30(vd, vq, (w * CCT_MCSDK_COMP_K) >> 15, &pd, &pq);
        out->v_d_comp = (int16_t)cct_clamp64(pd, 32767, &flag);
        out->v_q_comp = (int16_t)cct_clamp64(pq, 32767, &flag);
    }
    out->status = status;
}
#endif /* CCT_MCSDK */

#ifdef CCT_IQMATH
/*
 * TI IQmath-style: _IQ24 per-unit int32 words (value x 2^24, +-128 p.u.),
 * bases CCT_IQ_I_BASE A, CCT_IQ_V_BASE V (the nominal limit),
 * CCT_IQ_W_BASE rad/s (mechanical); _IQmpy(a, b) = (a b) >> 24 in int64.
 * Inputs beyond +-1 p.u. are clamped (status CLAMPED); measurements beyond
 * +-2 p.u. are refused (status IMPLAUSIBLE: the last plausible sample used,
 * no integral update).
 */
#define CCT_IQ_ONE ((int32_t)1 << 24)
#define CCT_IQ_D_KP ((int32_t)6888351L)
#define CCT_IQ_D_KI ((int32_t)418360L)
#define CCT_IQ_D_KAW ((int32_t)1018954L)
#define CCT_IQ_Q_KP ((int32_t)18151537L)
#define CCT_IQ_Q_KI ((int32_t)373495L)
#define CCT_IQ_Q_KAW ((int32_t)345216L)
#define CCT_IQ_DD ((int32_t)-5515330L)
#define CCT_IQ_DQ ((int32_t)2757665L)
#define CCT_IQ_DE ((int32_t)33554432L)

static inline int32_t cct_iqmpy(int64_t a, int64_t b) { return (int32_t)((a * b) >> 24); }

/* voltage placement: rotation angle at IQ_W_BASE, Q30 rad
 * (0.216506 rad = DELAY_COMP_TIME x POLE_PAIRS x IQ_W_BASE) */
#define CCT_IQ_COMP_K 232471924

typedef struct {
    int32_t i_d_ref; /* _IQ24 p.u. of IQ_I_BASE */
    int32_t i_q_ref;
    int32_t i_d;
    int32_t i_q;
    int32_t omega_m; /* _IQ24 p.u. of IQ_W_BASE */
} cct_input_iq_t;

typedef struct {
    int32_t v_d;   /* _IQ24 p.u. of IQ_V_BASE, the law's output (limited) */
    int32_t v_q;
    int32_t v_d_comp; /* _IQ24 p.u., v_dq placed as the float path does: feed these */
    int32_t v_q_comp; /* to the inverse Park transform at the SAMPLED theta_e */
    int saturated;
    int status;    /* CCT_STATUS_OK, _CLAMPED or _IMPLAUSIBLE */
} cct_output_iq_t;

/* run-time gains of one axis (_IQ24 per unit): the step reads these */
typedef struct {
    int32_t kp;
    int32_t ki;  /* per sample */
    int32_t kaw;
} cct_gains_iq_t;

typedef struct {
    int32_t int_d; /* integral term, _IQ24 p.u. V */
    int32_t int_q;
    int32_t v_max; /* voltage limit in use, _IQ24 p.u. (cct_set_vdc_iq) */
    cct_gains_iq_t gd; /* d-axis gains, CCT_IQ_D_* after init */
    cct_gains_iq_t gq;
    int32_t i_d_good; /* last plausible measurements (0 after init) */
    int32_t i_q_good;
    int32_t omega_m_good;
} cct_state_iq_t;

static inline void cct_init_iq(cct_state_iq_t *s)
{
    s->int_d = 0;
    s->int_q = 0;
    s->v_max = CCT_IQ_ONE;
    s->gd.kp = CCT_IQ_D_KP; s->gd.ki = CCT_IQ_D_KI; s->gd.kaw = CCT_IQ_D_KAW;
    s->gq.kp = CCT_IQ_Q_KP; s->gq.ki = CCT_IQ_Q_KI; s->gq.kaw = CCT_IQ_Q_KAW;
    s->i_d_good = 0;
    s->i_q_good = 0;
    s->omega_m_good = 0;
}

/* bus voltage relative to nominal (_IQ24, 1.0 = DRIVE_VDC): limit = V_MAX x ratio, up
 * to 2x (1 beyond); a ratio at or below 1e-3 is refused (-1, limit kept) */
static inline int cct_set_vdc_iq(cct_state_iq_t *s, int32_t ratio)
{
    if (ratio <= CCT_IQ_ONE / 1000) { return -1; }
    s->v_max = ratio > 2 * CCT_IQ_ONE ? 2 * CCT_IQ_ONE : ratio;
    return ratio > 2 * CCT_IQ_ONE ? 1 : 0;
}

/* 1 when |v| <= 2 p.u. (the plausible range) */
static inline int cct_plausible_iq(int32_t v)
{
    return v <= 2 * CCT_IQ_ONE && v >= -2 * CCT_IQ_ONE;
}

/* one period. Measured currents (both replaced) or speed beyond 2 p.u.: the
 * last plausible sample used, integrals not updated, status IMPLAUSIBLE;
 * inputs beyond 1 p.u. clamped, status CLAMPED. */
static inline void cct_step_iq(cct_state_iq_t *s, const cct_input_iq_t *in, cct_output_iq_t *out)
{
    int clamped = 0;
    int flag = 0;
    int status = CCT_STATUS_OK;
    int32_t i_d = in->i_d;
    int32_t i_q = in->i_q;
    int32_t w_m = in->omega_m;
    if (!(cct_plausible_iq(i_d) && cct_plausible_iq(i_q))) {
        i_d = s->i_d_good;
        i_q = s->i_q_good;
        status = CCT_STATUS_IMPLAUSIBLE;
    }
    if (!cct_plausible_iq(w_m)) {
        w_m = s->omega_m_good;
        status = CCT_STATUS_IMPLAUSIBLE;
    }
    const int64_t idr = cct_clamp64(in->i_d_ref, CCT_IQ_ONE, &clamped);
    const int64_t iqr = cct_clamp64(in->i_q_ref, CCT_IQ_ONE, &clamped);
    const int64_t idm = cct_clamp64(i_d, CCT_IQ_ONE, &clamped);
    const int64_t iqm = cct_clamp64(i_q, CCT_IQ_ONE, &clamped);
    const int64_t w = cct_clamp64(w_m, CCT_IQ_ONE, &clamped);
    if (clamped && status == CCT_STATUS_OK) { status = CCT_STATUS_CLAMPED; }
    const int64_t ed = idr - idm;
    const int64_t eq = iqr - iqm;
    int64_t vd = (int64_t)cct_iqmpy(s->gd.kp, ed) + s->int_d;
    int64_t vq = (int64_t)cct_iqmpy(s->gq.kp, eq) + s->int_q;
    int64_t ud, uq;
    vd += cct_iqmpy(CCT_IQ_DD, cct_iqmpy(w, iqm));
    vq += (int64_t)cct_iqmpy(CCT_IQ_DQ, cct_iqmpy(w, idm)) + cct_iqmpy(CCT_IQ_DE, w);
    ud = vd;
    uq = vq;
    out->saturated = cct_limit64(&vd, &vq, s->v_max);
    if (status != CCT_STATUS_IMPLAUSIBLE) {
        s->int_d = (int32_t)cct_clamp64((int64_t)s->int_d + cct_iqmpy(s->gd.ki, ed)
                                          + cct_iqmpy(s->gd.kaw, vd - ud), 64 * (int64_t)CCT_IQ_ONE, &flag);
        s->int_q = (int32_t)cct_clamp64((int64_t)s->int_q + cct_iqmpy(s->gq.ki, eq)
                                          + cct_iqmpy(s->gq.kaw, vq - uq), 64 * (int64_t)CCT_IQ_ONE, &flag);
        s->i_d_good = (int32_t)idm;
        s->i_q_good = (int32_t)iqm;
        s->omega_m_good = (int32_t)w;
    }
    out->v_d = (int32_t)vd;
    out->v_q = (int32_t)vq;
    {
        int64_t pd, pq;
        cct_place_q30(vd, vq, (w * CCT_IQ_COMP_K) >> 24, &pd, &pq);
        out->v_d_comp = (int32_t)pd;
        out->v_q_comp = (int32_t)pq;
    }
    out->status = status;
}
#endif /* CCT_IQMATH */

/* Operating envelope (toolbox.plant.OperatingEnvelope, constant Ld, Lq, flux):
 * current references for a torque at a speed: MTPA below base speed, field
 * weakening above, the torque limit where the request exceeds it; voltage
 * limit 82.2724 V (the drive's circle less 5 % for the loop), current
 * limit 20 A. Table of 17 speeds (0 .. 221.169 rad/s
 * mechanical) x 11 torques (0 .. the limit at that speed), interpolated linearly
 * in |speed| and in the torque's fraction of the limit; a negative torque mirrors
 * i_q. Memory: (N_SPEED + 2 N_SPEED N_TORQUE) x 4 = 1564 bytes of constants. */
#define CCT_ENV_N_SPEED 17
#define CCT_ENV_N_TORQUE 11
#define CCT_ENV_SPEED_STEP 1.382306671e+01f /* rad/s between rows */
static const float cct_env_t_max[17] = {1.476881313e+01f, 1.476881313e+01f, 1.476881313e+01f, 1.476881313e+01f, 1.476881313e+01f, 1.476881313e+01f, 1.476881313e+01f, 1.476881313e+01f, 1.476881313e+01f, 1.476881313e+01f, 1.476881313e+01f, 1.377247047e+01f, 1.172482395e+01f, 9.330856323e+00f, 6.708024502e+00f, 3.760003090e+00f, 2.162053715e-03f};
static const float cct_env_i_d[17][11] = {
    {0.0f, -4.900363460e-02f, -1.950167865e-01f, -4.351290762e-01f, -7.647510171e-01f, -1.177957416e+00f, -1.667886853e+00f, -2.227143049e+00f, -2.848156214e+00f, -3.523478031e+00f, -4.246001244e+00f},
    {0.0f, -4.900363460e-02f, -1.950167865e-01f, -4.351290762e-01f, -7.647510171e-01f, -1.177957416e+00f, -1.667886853e+00f, -2.227143049e+00f, -2.848156214e+00f, -3.523478031e+00f, -4.246001244e+00f},
    {0.0f, -4.900363460e-02f, -1.950167865e-01f, -4.351290762e-01f, -7.647510171e-01f, -1.177957416e+00f, -1.667886853e+00f, -2.227143049e+00f, -2.848156214e+00f, -3.523478031e+00f, -4.246001244e+00f},
    {0.0f, -4.900363460e-02f, -1.950167865e-01f, -4.351290762e-01f, -7.647510171e-01f, -1.177957416e+00f, -1.667886853e+00f, -2.227143049e+00f, -2.848156214e+00f, -3.523478031e+00f, -4.246001244e+00f},
    {0.0f, -4.900363460e-02f, -1.950167865e-01f, -4.351290762e-01f, -7.647510171e-01f, -1.177957416e+00f, -1.667886853e+00f, -2.227143049e+00f, -2.848156214e+00f, -3.523478031e+00f, -4.246001244e+00f},
    {0.0f, -4.900363460e-02f, -1.950167865e-01f, -4.351290762e-01f, -7.647510171e-01f, -1.177957416e+00f, -1.667886853e+00f, -2.227143049e+00f, -2.848156214e+00f, -3.523478031e+00f, -4.246001244e+00f},
    {0.0f, -4.900363460e-02f, -1.950167865e-01f, -4.351290762e-01f, -7.647510171e-01f, -1.177957416e+00f, -1.667886853e+00f, -2.227143049e+00f, -2.848156214e+00f, -3.523478031e+00f, -4.246001244e+00f},
    {0.0f, -4.900363460e-02f, -1.950167865e-01f, -4.351290762e-01f, -7.647510171e-01f, -1.177957416e+00f, -1.667886853e+00f, -2.227143049e+00f, -2.848156214e+00f, -3.523478031e+00f, -4.246001244e+00f},
    {0.0f, -4.900363460e-02f, -1.950167865e-01f, -4.351290762e-01f, -7.647510171e-01f, -1.177957416e+00f, -1.667886853e+00f, -2.227143049e+00f, -2.848156214e+00f, -3.523478031e+00f, -4.246001244e+00f},
    {0.0f, -4.900363460e-02f, -1.950167865e-01f, -4.351290762e-01f, -7.647510171e-01f, -1.177957416e+00f, -1.667886853e+00f, -2.227143049e+00f, -2.848156214e+00f, -3.523478031e+00f, -4.246001244e+00f},
    {0.0f, -4.900363460e-02f, -1.950167865e-01f, -4.351290762e-01f, -7.647510171e-01f, -1.177957416e+00f, -1.667886853e+00f, -2.227143049e+00f, -2.848156214e+00f, -3.523478031e+00f, -4.246001244e+00f},
    {0.0f, -4.262435064e-02f, -1.697414517e-01f, -3.791383505e-01f, -6.673007011e-01f, -1.029645801e+00f, -1.460799098e+00f, -2.338956118e+00f, -4.888846874e+00f, -7.594146252e+00f, -1.045689869e+01f},
    {0.0f, -3.090471588e-02f, -1.232204512e-01f, -8.624585271e-01f, -2.387325048e+00f, -4.050416470e+00f, -5.847460270e+00f, -7.775096893e+00f, -9.831268311e+00f, -1.201559353e+01f, -1.432977104e+01f},
    {-3.993182898e+00f, -4.865157604e+00f, -5.830950260e+00f, -6.889496803e+00f, -8.039589882e+00f, -9.280014992e+00f, -1.060967922e+01f, -1.202775478e+01f, -1.353381634e+01f, -1.512798500e+01f, -1.681108284e+01f},
    {-1.000037289e+01f, -1.063291454e+01f, -1.131334782e+01f, -1.204160023e+01f, -1.281757355e+01f, -1.364116859e+01f, -1.451230717e+01f, -1.543096066e+01f, -1.639717102e+01f, -1.741108322e+01f, -1.847297668e+01f},
    {-1.530184746e+01f, -1.565806007e+01f, -1.602926445e+01f, -1.641549301e+01f, -1.681677818e+01f, -1.723315239e+01f, -1.766464806e+01f, -1.811130524e+01f, -1.857315826e+01f, -1.905025673e+01f, -1.954264832e+01f},
    {-1.999795723e+01f, -1.999816132e+01f, -1.999836540e+01f, -1.999856949e+01f, -1.999877357e+01f, -1.999897766e+01f, -1.999918175e+01f, -1.999938583e+01f, -1.999959183e+01f, -1.999979591e+01f, -2.000000000e+01f},
};
static const float cct_env_i_q[17][11] = {
    {0.0f, 2.050051928e+00f, 4.093135357e+00f, 6.122590542e+00f, 8.132338524e+00f, 1.011708260e+01f, 1.207243061e+01f, 1.399493313e+01f, 1.588205528e+01f, 1.773209763e+01f, 1.954409027e+01f},
    {0.0f, 2.050051928e+00f, 4.093135357e+00f, 6.122590542e+00f, 8.132338524e+00f, 1.011708260e+01f, 1.207243061e+01f, 1.399493313e+01f, 1.588205528e+01f, 1.773209763e+01f, 1.954409027e+01f},
    {0.0f, 2.050051928e+00f, 4.093135357e+00f, 6.122590542e+00f, 8.132338524e+00f, 1.011708260e+01f, 1.207243061e+01f, 1.399493313e+01f, 1.588205528e+01f, 1.773209763e+01f, 1.954409027e+01f},
    {0.0f, 2.050051928e+00f, 4.093135357e+00f, 6.122590542e+00f, 8.132338524e+00f, 1.011708260e+01f, 1.207243061e+01f, 1.399493313e+01f, 1.588205528e+01f, 1.773209763e+01f, 1.954409027e+01f},
    {0.0f, 2.050051928e+00f, 4.093135357e+00f, 6.122590542e+00f, 8.132338524e+00f, 1.011708260e+01f, 1.207243061e+01f, 1.399493313e+01f, 1.588205528e+01f, 1.773209763e+01f, 1.954409027e+01f},
    {0.0f, 2.050051928e+00f, 4.093135357e+00f, 6.122590542e+00f, 8.132338524e+00f, 1.011708260e+01f, 1.207243061e+01f, 1.399493313e+01f, 1.588205528e+01f, 1.773209763e+01f, 1.954409027e+01f},
    {0.0f, 2.050051928e+00f, 4.093135357e+00f, 6.122590542e+00f, 8.132338524e+00f, 1.011708260e+01f, 1.207243061e+01f, 1.399493313e+01f, 1.588205528e+01f, 1.773209763e+01f, 1.954409027e+01f},
    {0.0f, 2.050051928e+00f, 4.093135357e+00f, 6.122590542e+00f, 8.132338524e+00f, 1.011708260e+01f, 1.207243061e+01f, 1.399493313e+01f, 1.588205528e+01f, 1.773209763e+01f, 1.954409027e+01f},
    {0.0f, 2.050051928e+00f, 4.093135357e+00f, 6.122590542e+00f, 8.132338524e+00f, 1.011708260e+01f, 1.207243061e+01f, 1.399493313e+01f, 1.588205528e+01f, 1.773209763e+01f, 1.954409027e+01f},
    {0.0f, 2.050051928e+00f, 4.093135357e+00f, 6.122590542e+00f, 8.132338524e+00f, 1.011708260e+01f, 1.207243061e+01f, 1.399493313e+01f, 1.588205528e+01f, 1.773209763e+01f, 1.954409027e+01f},
    {0.0f, 2.050051928e+00f, 4.093135357e+00f, 6.122590542e+00f, 8.132338524e+00f, 1.011708260e+01f, 1.207243061e+01f, 1.399493313e+01f, 1.588205528e+01f, 1.773209763e+01f, 1.954409027e+01f},
    {0.0f, 1.911892414e+00f, 3.818125248e+00f, 5.713258266e+00f, 7.592265606e+00f, 9.450689316e+00f, 1.128473663e+01f, 1.303422642e+01f, 1.447702599e+01f, 1.581445312e+01f, 1.704855537e+01f},
    {0.0f, 1.627860785e+00f, 3.252220154e+00f, 4.836676598e+00f, 6.337284088e+00f, 7.774839878e+00f, 9.146695137e+00f, 1.045111847e+01f, 1.168709373e+01f, 1.285411549e+01f, 1.395197678e+01f},
    {0.0f, 1.226344705e+00f, 2.426813841e+00f, 3.598609686e+00f, 4.739286423e+00f, 5.846751690e+00f, 6.919251442e+00f, 7.955341816e+00f, 8.953853607e+00f, 9.913844109e+00f, 1.083454990e+01f},
    {0.0f, 8.288505673e-01f, 1.646076083e+00f, 2.450720072e+00f, 3.241892815e+00f, 4.018774509e+00f, 4.780613422e+00f, 5.526725769e+00f, 6.256491661e+00f, 6.969351292e+00f, 7.664798260e+00f},
    {0.0f, 4.415596724e-01f, 8.798973560e-01f, 1.314854741e+00f, 1.746278286e+00f, 2.174019098e+00f, 2.597934008e+00f, 3.017884016e+00f, 3.433735847e+00f, 3.845360994e+00f, 4.252635956e+00f},
    {0.0f, 2.434787457e-04f, 4.869565309e-04f, 7.304333849e-04f, 9.739093366e-04f, 1.217384241e-03f, 1.460858388e-03f, 1.704331371e-03f, 1.947803539e-03f, 2.191274893e-03f, 2.434744965e-03f},
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
