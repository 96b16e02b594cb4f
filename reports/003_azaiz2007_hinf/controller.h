/*
 * controller.h -- current controller exported by current-control-toolbox
 * title:       Azaiz 2007 (paper 003): H-infinity current control, gamma = 1, third order
 * method:      hinf
 * version:     0.1.0
 * spec sha256: 725ca7e47e8fb783e32a98f3530d9f7f87e8372a8e40b66b26c2473ca062b79f
 * law sha256:  90ba78e33eff6fa13763b45b362bfe70b6a195854dbd4c79ee92e9c291e339e7
 * created:     2026-11-25T18:52:45+00:00
 * equations:   003 eq (33)-(34); 003 eq (35)-(40); 003 eq (10)-(32); 003 eq (65)-(67); 003 eq (41)-(43); 003 eq (71)-(72)
 *
 * C99, header-only, no dynamic memory; libm: sqrtf only (float path).
 * Call cct_init() once, then cct_set_vdc() with the measured bus voltage and
 * cct_step() once per controller period (example at the end of this file). The
 * voltage returned is applied by the inverter in the NEXT period: the
 * computation delay is part of the plant the design assumed, not of this code.
 * Law per axis: x' = A x + B [i_ref; i_meas], v = C x + D [i_ref; i_meas]
 *   (1-DOF laws as second-order sections of K(z) = v / (i_ref - i_meas)),
 * then decoupling  v_d += -cross w_e Lq_c i_q,
 *                  v_q +=  cross w_e Ld_c i_d + emf w_e flux_c,  w_e = p Omega_m,
 * then the circle limit |v| <= limit in use (radial scaling; the inscribed
 * circle of the SVM hexagon), and
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

#include <math.h> /* sqrtf */
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
#define CCT_DEC_LD 1.399999950e-03f /* H */
#define CCT_DEC_LQ 2.799999900e-03f /* H */
#define CCT_DEC_FLUX 1.199999973e-01f /* Wb */
#define CCT_POLE_PAIRS 4 /* w_e = POLE_PAIRS * Omega_m */

#define CCT_D_GAIN 4.345249326e-04f /* d axis SOS output gain, V/A */
#define CCT_D_NUM_STAGES 2
#define CCT_Q_GAIN 6.996610668e-03f /* q axis SOS output gain, V/A */
#define CCT_Q_NUM_STAGES 2

/* inputs: currents in A, measured MECHANICAL speed in rad/s */
typedef struct {
    float i_d_ref; /* A */
    float i_q_ref; /* A */
    float i_d;     /* measured, A */
    float i_q;     /* measured, A */
    float omega_m; /* measured mechanical speed, rad/s */
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

/* controller states (sos d axis: 4, sos q axis: 4; arrays have at least one element)
 * and the last good output, held when a period fails */
typedef struct {
    float d[4];
    float q[4];
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
    for (i = 0u; i < 4u; ++i) { s->d[i] = 0.0f; }
    for (i = 0u; i < 4u; ++i) { s->q[i] = 0.0f; }
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
 * circle's radius); call whenever a new bus measurement arrives (e.g. once per
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
    for (i = 0u; i < 4u; ++i) { ok &= cct_finite(s->d[i]); }
    for (i = 0u; i < 4u; ++i) { ok &= cct_finite(s->q[i]); }
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
    /* 2 stage(s) {b0, b1, b2, a1, a2} (a1, a2 negated, CMSIS df2T), gain CCT_D_GAIN */
    static const float c[10] = {
        1.000000000e+00f, 1.428571463e+00f, 4.285714328e-01f, 1.770198584e+00f, -7.842711210e-01f,
        1.000000000e+00f, -9.580419660e-01f, 0.0f, 1.000000000e+00f, 0.0f,
    };
    float in = r - y;
    unsigned k;
    for (k = 0u; k < 2u; ++k) {
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
    /* 2 stage(s) {b0, b1, b2, a1, a2} (a1, a2 negated, CMSIS df2T), gain CCT_Q_GAIN */
    static const float c[10] = {
        1.000000000e+00f, 1.428571463e+00f, 4.285714328e-01f, 1.569386482e+00f, -6.180329919e-01f,
        1.000000000e+00f, -9.787985682e-01f, 0.0f, 1.000000000e+00f, 0.0f,
    };
    float in = r - y;
    unsigned k;
    for (k = 0u; k < 2u; ++k) {
        const float *s = &c[5u * k];
        const float out = s[0] * in + x[2u * k];
        x[2u * k] = s[1] * in + s[3] * out + x[2u * k + 1u];
        x[2u * k + 1u] = s[2] * in + s[4] * out;
        in = out;
    }
    return CCT_Q_GAIN * in;
}

/* one controller period: the whole law (linear laws, decoupling, limit, anti-windup).
 * out->status: CCT_STATUS_OK, or _BAD_INPUT / _BAD_STATE with the last good
 * output repeated and the state left as it was (see the top of this file). */
static inline void cct_step(cct_state_t *s, const cct_input_t *in, cct_output_t *out)
{
    cct_state_t nx;
    if (!(cct_finite(in->i_d_ref) && cct_finite(in->i_q_ref)
          && cct_finite(in->i_d) && cct_finite(in->i_q)
          && cct_finite(in->omega_m))) {
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
    const float mag2 = vd * vd + vq * vq;
    if (mag2 > s->v_max * s->v_max) {
        const float k = s->v_max / sqrtf(mag2);
        vds = vd * k;
        vqs = vq * k;
        saturated = 1;
    }
    /* back-calculation anti-windup */
    nx.d[0] += 4.058364502e+03f * (vds - vd);
    nx.d[1] += -1.804893188e+03f * (vds - vd);
    nx.d[2] += 9.656072235e+01f * (vds - vd);
    nx.q[0] += 2.233436432e+02f * (vqs - vq);
    nx.q[1] += -8.833319855e+01f * (vqs - vq);
    nx.q[2] += 3.030240536e+00f * (vqs - vq);
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
/*
 * Fixed point: Q31 words (value / 2^31), int64 accumulators, arithmetic
 * right shifts (as gcc and arm-none-eabi implement >> on negative values).
 * Each coefficient set is an int32 mantissa vector m with one shift F:
 * c = m / 2^F (integer gains with power-of-two divisors, as STM32 MCSDK).
 * Inputs up to I_MAX = 20 A and W_MAX = 230 rad/s (mechanical),
 * voltage limit 86.6025 V: bases below are powers of two above rigorous
 * bounds of every signal and state, so no accumulator or word overflows.
 * Quantisation error bound, d axis: |v_q31 - v_exact| <= 0.0093 V over 20 ms from equal states.
 * Quantisation error bound, q axis: |v_q31 - v_exact| <= 0.00192 V over 20 ms from equal states.
 */
#include <stdint.h>
#define CCT_Q31_I_BASE 3.200000000e+01f /* A at full scale */
#define CCT_Q31_V_BASE 2.048000000e+03f /* V at full scale */
#define CCT_Q31_W_BASE 2.560000000e+02f /* mechanical rad/s at full scale */
#define CCT_Q31_I_MAX 2.000000000e+01f /* A, current range (cct_to_q31 clamps beyond) */
#define CCT_Q31_W_MAX 2.300000000e+02f /* rad/s, speed range (cct_to_q31 clamps beyond) */
#define CCT_Q31_V_MAX 90809345L /* V_MAX / V_BASE in Q31: the largest limit */
#define CCT_Q31_VDC_BASE 3.547239990e+03f /* V of bus at full scale (cct_set_vdc_q31) */
#define CCT_Q31_D_X0_BASE 2.097152000e+06f /* state 0 full scale */
#define CCT_Q31_D_X1_BASE 5.242880000e+05f /* state 1 full scale */
#define CCT_Q31_D_X2_BASE 5.242880000e+05f /* state 2 full scale */
#define CCT_Q31_D_X3_BASE 1.000000000e+00f /* state 3 full scale */
#define CCT_Q31_Q_X0_BASE 1.310720000e+05f /* state 0 full scale */
#define CCT_Q31_Q_X1_BASE 6.553600000e+04f /* state 1 full scale */
#define CCT_Q31_Q_X2_BASE 3.276800000e+04f /* state 2 full scale */
#define CCT_Q31_Q_X3_BASE 1.000000000e+00f /* state 3 full scale */
#define CCT_Q31_DEC_DD -769658139L /* decoupling coefficient -0.0448 p.u. = m / 2^shift */
#define CCT_Q31_DEC_DD_SHIFT 34u
#define CCT_Q31_DEC_DQ 769658139L /* decoupling coefficient 0.0224 p.u. = m / 2^shift */
#define CCT_Q31_DEC_DQ_SHIFT 35u
#define CCT_Q31_DEC_DE 1030792151L /* decoupling coefficient 0.06 p.u. = m / 2^shift */
#define CCT_Q31_DEC_DE_SHIFT 34u

typedef struct {
    int32_t i_d_ref; /* Q31 of Q31_I_BASE */
    int32_t i_q_ref;
    int32_t i_d;
    int32_t i_q;
    int32_t omega_m; /* Q31 of Q31_W_BASE (mechanical) */
} cct_input_q31_t;

typedef struct {
    int32_t v_d; /* Q31 of Q31_V_BASE */
    int32_t v_q;
    int saturated;
} cct_output_q31_t;

typedef struct {
    int32_t d[4];
    int32_t q[4];
    int32_t v_max; /* voltage limit in use, Q31 of Q31_V_BASE (cct_set_vdc_q31) */
} cct_state_q31_t;

static inline void cct_init_q31(cct_state_q31_t *s)
{
    unsigned i;
    for (i = 0u; i < 4u; ++i) { s->d[i] = 0; }
    for (i = 0u; i < 4u; ++i) { s->q[i] = 0; }
    s->v_max = CCT_Q31_V_MAX;
}

/* measured DC-link voltage as Q31 of CCT_Q31_VDC_BASE (chosen so that the
 * word IS the voltage limit in Q31 of Q31_V_BASE). The scaling and the state
 * bounds were derived for the nominal bus: above it the limit is clamped to
 * CCT_Q31_V_MAX and 1 is returned; a negative word is refused (-1, limit
 * unchanged); 0 otherwise. */
static inline int cct_set_vdc_q31(cct_state_q31_t *s, int32_t vdc)
{
    if (vdc < 0) { return -1; }
    if (vdc > CCT_Q31_V_MAX) {
        s->v_max = CCT_Q31_V_MAX;
        return 1;
    }
    s->v_max = vdc;
    return 0;
}

/* physical value -> Q31 word of base, clamped to +-range (the range the
 * scaling and state bounds were derived for) with *clamped = 1 beyond it or
 * for a non-finite value (then 0). E.g. currents: range CCT_Q31_I_MAX, base
 * CCT_Q31_I_BASE; speed: CCT_Q31_W_MAX, CCT_Q31_W_BASE. */
static inline int32_t cct_to_q31(float value, float range, float base, int *clamped)
{
    float v = value;
    if (!(v == v)) { *clamped = 1; return 0; }
    if (v > range) { v = range; *clamped = 1; }
    if (v < -range) { v = -range; *clamped = 1; }
    {
        const float q = v / base * 2147483648.0f; /* truncated towards zero below */
        if (q >= 2147483648.0f) { return INT32_MAX; }
        if (q <= -2147483648.0f) { return -INT32_MAX; }
        return (int32_t)q;
    }
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
    static const int32_t co[6] = { 238882606L, 0L, 59720652L, 0L, 3645L, -3645L };
    static const int32_t ca[28] = {
        118796013L, 16777216L, 0L, 0L, 3276L, -3276L, 265968983L,
        -105263085L, 0L, 0L, 0L, -728L, 728L, -236570964L,
        22526052L, 0L, 134217728L, 256L, 344L, -344L, 50625629L,
        0L, 0L, 0L, 0L, 0L, 0L, 0L,
    };
    static const unsigned fa[4] = { 26u, 25u, 27u, 31u };
    int32_t xn[4];
    unsigned i, j;
    int64_t acc = (int64_t)co[4] * r + (int64_t)co[5] * y;
    for (j = 0u; j < 4u; ++j) { acc += (int64_t)co[j] * x[j]; }
    acc = cct_shr(acc, 29u);
    for (i = 0u; i < 4u; ++i) {
        const int32_t *m = &ca[7u * i];
        int64_t a = (int64_t)m[4] * r + (int64_t)m[5] * y;
        for (j = 0u; j < 4u; ++j) { a += (int64_t)m[j] * x[j]; }
        xn[i] = cct_sat32(cct_shr(a, fa[i]));
    }
    for (i = 0u; i < 4u; ++i) { x[i] = xn[i]; }
    return acc;
}

static inline void cct_d_antiwindup_q31(int32_t *x, int64_t dv)
{
    static const int32_t aw[4] = { 265968983L, -236570964L, 50625629L, 0L };
    static const unsigned fa[4] = { 26u, 25u, 27u, 31u };
    unsigned i;
    for (i = 0u; i < 4u; ++i) {
        x[i] = cct_sat32((int64_t)x[i] + cct_shr((int64_t)aw[i] * dv, fa[i]));
    }
}

/* q axis: v_lin (Q31, int64 before limiting) and x <- A x + B u */
static inline int64_t cct_q_linear_q31(int32_t *x, int32_t r, int32_t y)
{
    static const int32_t co[6] = { 240401717L, 0L, 60100429L, 0L, 58692L, -58692L };
    static const int32_t ca[28] = {
        105319744L, 33554432L, 0L, 0L, 49119L, -49119L, 234192782L,
        -82950985L, 0L, 0L, 0L, -6208L, 6208L, -185248139L,
        11382422L, 0L, 134217728L, 4096L, 2779L, -2779L, 25419500L,
        0L, 0L, 0L, 0L, 0L, 0L, 0L,
    };
    static const unsigned fa[4] = { 26u, 26u, 27u, 31u };
    int32_t xn[4];
    unsigned i, j;
    int64_t acc = (int64_t)co[4] * r + (int64_t)co[5] * y;
    for (j = 0u; j < 4u; ++j) { acc += (int64_t)co[j] * x[j]; }
    acc = cct_shr(acc, 29u);
    for (i = 0u; i < 4u; ++i) {
        const int32_t *m = &ca[7u * i];
        int64_t a = (int64_t)m[4] * r + (int64_t)m[5] * y;
        for (j = 0u; j < 4u; ++j) { a += (int64_t)m[j] * x[j]; }
        xn[i] = cct_sat32(cct_shr(a, fa[i]));
    }
    for (i = 0u; i < 4u; ++i) { x[i] = xn[i]; }
    return acc;
}

static inline void cct_q_antiwindup_q31(int32_t *x, int64_t dv)
{
    static const int32_t aw[4] = { 234192782L, -185248139L, 25419500L, 0L };
    static const unsigned fa[4] = { 26u, 26u, 27u, 31u };
    unsigned i;
    for (i = 0u; i < 4u; ++i) {
        x[i] = cct_sat32((int64_t)x[i] + cct_shr((int64_t)aw[i] * dv, fa[i]));
    }
}

static inline void cct_step_q31(cct_state_q31_t *s, const cct_input_q31_t *in, cct_output_q31_t *out)
{
    const int64_t vd_lin = cct_d_linear_q31(s->d, in->i_d_ref, in->i_d);
    const int64_t vq_lin = cct_q_linear_q31(s->q, in->i_q_ref, in->i_q);
    const int64_t wiq = cct_shr((int64_t)in->omega_m * in->i_q, 31u);
    const int64_t wid = cct_shr((int64_t)in->omega_m * in->i_d, 31u);
    const int64_t vd = vd_lin + cct_shr((int64_t)CCT_Q31_DEC_DD * wiq, CCT_Q31_DEC_DD_SHIFT);
    const int64_t vq = vq_lin + cct_shr((int64_t)CCT_Q31_DEC_DQ * wid, CCT_Q31_DEC_DQ_SHIFT)
                     + cct_shr((int64_t)CCT_Q31_DEC_DE * in->omega_m, CCT_Q31_DEC_DE_SHIFT);
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
    cct_d_antiwindup_q31(s->d, vds - vd);
    cct_q_antiwindup_q31(s->q, vqs - vq);
    out->v_d = (int32_t)vds;
    out->v_q = (int32_t)vqs;
}
#endif /* CCT_FIXED_POINT */

#if defined(CCT_MCSDK) || defined(CCT_IQMATH)
#error "MCSDK/IQmath variants not available: d axis: the MCSDK/IQmath variants run a PI (one integrator); this law has order 3"
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
