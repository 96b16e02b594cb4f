/*
 * controller.h -- current controller exported by current-control-toolbox
 * title:       Paper 002 (Cormerais 2002): decoupled PI with space-vector modulation at 1 kHz (sect. 3, simulation 1)
 * method:      pi
 * version:     0.1.0
 * spec sha256: 63448721dc1b996ad9673edd2f7d8f63d5f662add7890a1068308cfa4e6a5529
 * law sha256:  3ee178d01754d3d92d2158aed6c68c397e43237bcab357f65d6657f481221a9a
 * created:     2026-11-28T00:23:50+00:00
 * equations:   000 sect. 2, Fig. 2a and eq (3): v = E k_i (Kp e + KI int e); 002 eq (19)-(20): K = 10 R, Ti = L/R (pole-zero cancellation); Kp = E k_i Kp_n, Ki = E k_i Ki_n (000 appendix: E = 150 V, k_i = 256/50)
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
 * then the SVM hexagon limit (voltage_limit = "hexagon", as the toolbox
 * simulator): the voltage is rotated to the stationary frame at the angle
 * theta_e + DELAY_COMP_TIME w_e where it is placed (input theta_e: electrical
 * angle at the sampling instant, any range; wrap it to [-pi, pi) to keep float
 * precision) and scaled radially onto the hexagon whose apothem is the
 * limit in use, and
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

#define CCT_SAMPLE_TIME 1.000000047e-03f /* controller period, s */
#define CCT_DELAY_SAMPLES 0 /* computation delay the design assumed, periods */
#define CCT_V_MAX 8.485280991e+00f /* voltage limit (hexagon apothem) at the nominal bus voltage, V; cct_init's default */
#define CCT_V_MAX_PER_VDC 7.071067691e-01f /* voltage limit per volt of measured bus (cct_set_vdc) */
/* motor (power-invariant dq convention) */
#define CCT_MOTOR_R 1.999999955e-02f /* stator resistance, ohm */
#define CCT_MOTOR_LD 1.125999988e-04f /* d-axis inductance, H */
#define CCT_MOTOR_LQ 1.125999988e-04f /* q-axis inductance, H */
#define CCT_MOTOR_FLUX 6.038999930e-02f /* PM flux linkage, Wb */
#define CCT_MOTOR_POLE_PAIRS 6 /* pole pairs */
#define CCT_MOTOR_J 1.000000000e+00f /* inertia, kg m^2 */
#define CCT_MOTOR_FRICTION 0.0f /* viscous friction, N m s/rad */
#define CCT_MOTOR_MAX_CURRENT 1.500000000e+02f /* dq current amplitude limit, A */
#define CCT_MOTOR_RATED_CURRENT 1.000000000e+02f /* A */
/* drive */
#define CCT_DRIVE_VDC 1.200000000e+01f /* DC-link voltage, V */
/* decoupling: controller-side model parameters */
#define CCT_DEC_CROSS 1 /* 1: cross-coupling terms on */
#define CCT_DEC_EMF 1 /* 1: back-EMF term on */
#define CCT_DEC_LD 1.125999988e-04f /* H */
#define CCT_DEC_LQ 1.125999988e-04f /* H */
#define CCT_DEC_FLUX 6.038999930e-02f /* Wb */
#define CCT_POLE_PAIRS 6 /* w_e = POLE_PAIRS * Omega_m */
/* dq model (motor data) that predicts an implausible current sample's replacement */
#define CCT_PRED_R 1.999999955e-02f /* ohm */
#define CCT_PRED_LD 1.125999988e-04f /* H */
#define CCT_PRED_LQ 1.125999988e-04f /* H */
#define CCT_PRED_FLUX 6.038999930e-02f /* Wb */
#define CCT_DELAY_COMP_TIME 5.000000237e-04f /* s (0.5 Ts, drive.angle_compensation = "mid_period"): v_dq is placed at theta_e + CCT_DELAY_COMP_TIME * w_e (rad); applied inside cct_step, outputs v_d_comp, v_q_comp */
/* d axis PI gains (method pi), FOR INFORMATION ONLY: the code
 *   runs the coefficients of the law below, derived from these gains at export;
 *   to retune, change the spec and re-export (editing these numbers does nothing).
 *   Kp = 0.2 V/A (parallel proportional gain)
 *   Ki = 35.5239787 V/(A s) (parallel integral gain)
 *   Ki Ts = 0.0355239787 V/A (integral gain per sample)
 *   Ti = 0.00563 s (series form Kp (1 + 1/(Ti s)), Ti = Kp/Ki)
 */
/* q axis PI gains (method pi), FOR INFORMATION ONLY: the code
 *   runs the coefficients of the law below, derived from these gains at export;
 *   to retune, change the spec and re-export (editing these numbers does nothing).
 *   Kp = 0.2 V/A (parallel proportional gain)
 *   Ki = 35.5239787 V/(A s) (parallel integral gain)
 *   Ki Ts = 0.0355239787 V/A (integral gain per sample)
 *   Ti = 0.00563 s (series form Kp (1 + 1/(Ti s)), Ti = Kp/Ki)
 */

#define CCT_D_GAIN 2.177619934e-01f /* d axis SOS output gain, V/A */
#define CCT_D_NUM_STAGES 1
#define CCT_Q_GAIN 2.177619934e-01f /* q axis SOS output gain, V/A */
#define CCT_Q_NUM_STAGES 1

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
    float theta_e; /* measured ELECTRICAL angle of the d axis from phase a at the sampling instant, rad */
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
#define CCT_I_PLAUSIBLE 3.000000000e+02f /* A, 2 x motor.max_current (else 2 x max(2 x rated, V_MAX/R, flux/L)) */
#define CCT_W_PLAUSIBLE 9.367203522e+01f /* rad/s mechanical, 2 x drive.max_speed (else see the docs) */
#define CCT_VDC_MIN 1.200000010e-02f /* V, 1e-3 x DRIVE_VDC */
#define CCT_VDC_PLAUSIBLE 2.400000000e+01f /* V, 2 x DRIVE_VDC */

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
 * hexagon's apothem); call whenever a new bus measurement arrives (e.g. once per
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
        1.000000000e+00f, -8.368678689e-01f, 0.0f, 1.000000000e+00f, 0.0f,
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
        1.000000000e+00f, -8.368678689e-01f, 0.0f, 1.000000000e+00f, 0.0f,
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
    static const float g[2] = { 4.592169762e+00f, 0.0f };
    static const float h[4] = { 0.0f, 0.0f, -8.156606555e-02f, 8.156606555e-02f };
    const float c = v - (2.177619934e-01f * r + -2.177619934e-01f * y);
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
    static const float g[2] = { 4.592169762e+00f, 0.0f };
    static const float h[4] = { 0.0f, 0.0f, -8.156606555e-02f, 8.156606555e-02f };
    const float c = v - (2.177619934e-01f * r + -2.177619934e-01f * y);
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
          && cct_finite(in->omega_m) && cct_finite(in->theta_e))) {
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
          && cct_finite(in->omega_m) && cct_finite(in->theta_e))) {
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
    /* SVM hexagon in the stationary frame at the angle where the voltage is
     * placed (as the toolbox simulator): theta_e + DELAY_COMP_TIME w_e */
    const float th = in->theta_e + w * CCT_DELAY_COMP_TIME;
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
    /* back-calculation anti-windup */
    nx.d[0] += 7.491304278e-01f * (vds - vd);
    nx.q[0] += 7.491304278e-01f * (vqs - vq);
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
#error "fixed-point variant not available: voltage_limit = 'hexagon' is implemented in the float path only; the Q31 variant needs voltage_limit = 'circle'"
#endif /* CCT_FIXED_POINT */

#if defined(CCT_MCSDK) || defined(CCT_IQMATH)
#error "MCSDK/IQmath variants not available: voltage_limit = 'hexagon' is implemented in the float path only; the MCSDK/IQmath variants need voltage_limit = 'circle'"
#endif

/* Operating envelope (toolbox.plant.OperatingEnvelope, constant Ld, Lq, flux):
 * current references for a torque at a speed: MTPA below base speed, field
 * weakening above, the torque limit where the request exceeds it; voltage
 * limit 8.06102 V (the drive's circle less 5 % for the loop), current
 * limit 150 A. Table of 17 speeds (0 .. 27.2763 rad/s
 * mechanical) x 11 torques (0 .. the limit at that speed), interpolated linearly
 * in |speed| and in the torque's fraction of the limit; a negative torque mirrors
 * i_q. Memory: (N_SPEED + 2 N_SPEED N_TORQUE) x 4 = 1564 bytes of constants. */
#define CCT_ENV_N_SPEED 17
#define CCT_ENV_N_TORQUE 11
#define CCT_ENV_SPEED_STEP 1.704770088e+00f /* rad/s between rows */
static const float cct_env_t_max[17] = {5.435100174e+01f, 5.435100174e+01f, 5.435100174e+01f, 5.435100174e+01f, 5.435100174e+01f, 5.435100174e+01f, 5.435100174e+01f, 5.435100174e+01f, 5.435100174e+01f, 4.905006409e+01f, 4.178019333e+01f, 3.474204636e+01f, 2.814409637e+01f, 2.194275093e+01f, 1.604047585e+01f, 1.032488346e+01f, 4.670722008e+00f};
static const float cct_env_i_d[17][11] = {
    {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f},
    {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f},
    {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f},
    {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f},
    {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f},
    {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f},
    {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f},
    {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f},
    {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f},
    {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, -4.888180733e+00f, -6.461338806e+01f},
    {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, -3.566889524e+00f, -3.717758560e+01f, -9.593950653e+01f},
    {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f, -1.181453609e+01f, -3.496638870e+01f, -6.493975830e+01f, -1.153540497e+02f},
    {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, -1.198750401e+01f, -2.679880524e+01f, -4.375082397e+01f, -6.383325958e+01f, -8.926004028e+01f, -1.283233337e+02f},
    {0.0f, -6.221554279e+00f, -1.508666992e+01f, -2.463652611e+01f, -3.499552917e+01f, -4.633546448e+01f, -5.890566635e+01f, -7.309362793e+01f, -8.956533813e+01f, -1.096702118e+02f, -1.372321930e+02f},
    {-3.870724869e+01f, -4.562526321e+01f, -5.296881104e+01f, -6.080018234e+01f, -6.920002747e+01f, -7.827600098e+01f, -8.817757416e+01f, -9.912318420e+01f, -1.114557037e+02f, -1.257731400e+02f, -1.433186798e+02f},
    {-7.870826721e+01f, -8.384729004e+01f, -8.923283386e+01f, -9.489454651e+01f, -1.008689804e+02f, -1.072020874e+02f, -1.139529800e+02f, -1.212000046e+02f, -1.290508118e+02f, -1.376606750e+02f, -1.472685852e+02f},
    {-1.180811157e+02f, -1.208043823e+02f, -1.236016235e+02f, -1.264780502e+02f, -1.294394836e+02f, -1.324925842e+02f, -1.356449280e+02f, -1.389052734e+02f, -1.422837677e+02f, -1.457923279e+02f, -1.494450989e+02f},
};
static const float cct_env_i_q[17][11] = {
    {0.0f, 1.500000000e+01f, 3.000000000e+01f, 4.500000000e+01f, 6.000000000e+01f, 7.500000000e+01f, 9.000000000e+01f, 1.050000000e+02f, 1.200000000e+02f, 1.350000000e+02f, 1.500000000e+02f},
    {0.0f, 1.500000000e+01f, 3.000000000e+01f, 4.500000000e+01f, 6.000000000e+01f, 7.500000000e+01f, 9.000000000e+01f, 1.050000000e+02f, 1.200000000e+02f, 1.350000000e+02f, 1.500000000e+02f},
    {0.0f, 1.500000000e+01f, 3.000000000e+01f, 4.500000000e+01f, 6.000000000e+01f, 7.500000000e+01f, 9.000000000e+01f, 1.050000000e+02f, 1.200000000e+02f, 1.350000000e+02f, 1.500000000e+02f},
    {0.0f, 1.500000000e+01f, 3.000000000e+01f, 4.500000000e+01f, 6.000000000e+01f, 7.500000000e+01f, 9.000000000e+01f, 1.050000000e+02f, 1.200000000e+02f, 1.350000000e+02f, 1.500000000e+02f},
    {0.0f, 1.500000000e+01f, 3.000000000e+01f, 4.500000000e+01f, 6.000000000e+01f, 7.500000000e+01f, 9.000000000e+01f, 1.050000000e+02f, 1.200000000e+02f, 1.350000000e+02f, 1.500000000e+02f},
    {0.0f, 1.500000000e+01f, 3.000000000e+01f, 4.500000000e+01f, 6.000000000e+01f, 7.500000000e+01f, 9.000000000e+01f, 1.050000000e+02f, 1.200000000e+02f, 1.350000000e+02f, 1.500000000e+02f},
    {0.0f, 1.500000000e+01f, 3.000000000e+01f, 4.500000000e+01f, 6.000000000e+01f, 7.500000000e+01f, 9.000000000e+01f, 1.050000000e+02f, 1.200000000e+02f, 1.350000000e+02f, 1.500000000e+02f},
    {0.0f, 1.500000000e+01f, 3.000000000e+01f, 4.500000000e+01f, 6.000000000e+01f, 7.500000000e+01f, 9.000000000e+01f, 1.050000000e+02f, 1.200000000e+02f, 1.350000000e+02f, 1.500000000e+02f},
    {0.0f, 1.500000000e+01f, 3.000000000e+01f, 4.500000000e+01f, 6.000000000e+01f, 7.500000000e+01f, 9.000000000e+01f, 1.050000000e+02f, 1.200000000e+02f, 1.350000000e+02f, 1.500000000e+02f},
    {0.0f, 1.353702736e+01f, 2.707405472e+01f, 4.061108017e+01f, 5.414810944e+01f, 6.768513489e+01f, 8.122216034e+01f, 9.475918579e+01f, 1.082962189e+02f, 1.218332443e+02f, 1.353702698e+02f},
    {0.0f, 1.153065968e+01f, 2.306131935e+01f, 3.459197998e+01f, 4.612263870e+01f, 5.765329742e+01f, 6.918395996e+01f, 8.071461487e+01f, 9.224527740e+01f, 1.037759399e+02f, 1.153065948e+02f},
    {0.0f, 9.588244438e+00f, 1.917648888e+01f, 2.876473427e+01f, 3.835297775e+01f, 4.794122314e+01f, 5.752946854e+01f, 6.711771393e+01f, 7.670595551e+01f, 8.629419708e+01f, 9.588244629e+01f},
    {0.0f, 7.767316818e+00f, 1.553463364e+01f, 2.330195045e+01f, 3.106926727e+01f, 3.883658600e+01f, 4.660390091e+01f, 5.437121964e+01f, 6.213853455e+01f, 6.990585327e+01f, 7.767317200e+01f},
    {0.0f, 6.055845737e+00f, 1.211169147e+01f, 1.816753578e+01f, 2.422338295e+01f, 3.027922821e+01f, 3.633507156e+01f, 4.239091873e+01f, 4.844676590e+01f, 5.450260925e+01f, 6.055845642e+01f},
    {0.0f, 4.426912785e+00f, 8.853825569e+00f, 1.328073883e+01f, 1.770765114e+01f, 2.213456535e+01f, 2.656147766e+01f, 3.098838997e+01f, 3.541530228e+01f, 3.984221649e+01f, 4.426913071e+01f},
    {0.0f, 2.849501371e+00f, 5.699002743e+00f, 8.548504829e+00f, 1.139800549e+01f, 1.424750710e+01f, 1.709700966e+01f, 1.994651031e+01f, 2.279601097e+01f, 2.564551353e+01f, 2.849501419e+01f},
    {0.0f, 1.289043903e+00f, 2.578087807e+00f, 3.867131710e+00f, 5.156175613e+00f, 6.445219517e+00f, 7.734263420e+00f, 9.023307800e+00f, 1.031235123e+01f, 1.160139561e+01f, 1.289043903e+01f},
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
    in.theta_e = theta_e;
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
