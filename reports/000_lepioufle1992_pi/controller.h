/*
 * controller.h -- current controller exported by current-control-toolbox
 * title:       Paper 000 (Le Pioufle 1992): PI in the dq frame, gains of sect. 2
 * method:      pi
 * version:     0.1.0
 * spec sha256: 896f40f9f1f00250e5b0e90b0c443f9b5de36c81eb978506b0cbaeb2dfcdcdea
 * created:     2026-11-23T19:26:57+00:00
 * equations:   000 sect. 2, Fig. 2a and eq (3): v = E k_i (Kp e + KI int e); 002 eq (19)-(20): K = 10 R, Ti = L/R (pole-zero cancellation); Kp = E k_i Kp_n, Ki = E k_i Ki_n (000 appendix: E = 150 V, k_i = 256/50)
 *
 * C99, header-only, no dynamic memory; libm: sqrtf only (float path).
 * Call cct_init() once, then cct_step() once per controller period. The
 * voltage returned is applied by the inverter in the NEXT period: the
 * computation delay is part of the plant the design assumed, not of this code.
 * Law per axis: x' = A x + B [i_ref; i_meas], v = C x + D [i_ref; i_meas]
 *   (1-DOF laws as second-order sections of K(z) = v / (i_ref - i_meas)),
 * then decoupling  v_d += -cross w_e Lq_c i_q,
 *                  v_q +=  cross w_e Ld_c i_d + emf w_e flux_c,  w_e = p Omega_m,
 * then the circle limit |v| <= V_MAX (radial scaling; the inscribed circle of
 * the SVM hexagon), and
 * back-calculation anti-windup x += aw (v_sat - v_unsat).
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
#define CCT_V_MAX 1.060660172e+02f /* voltage-limit circle radius, V */
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
#define CCT_DEC_CROSS 0 /* 1: cross-coupling terms on */
#define CCT_DEC_EMF 0 /* 1: back-EMF term on */
#define CCT_DEC_LD 1.399999950e-03f /* H */
#define CCT_DEC_LQ 2.799999900e-03f /* H */
#define CCT_DEC_FLUX 1.199999973e-01f /* Wb */
#define CCT_POLE_PAIRS 4 /* w_e = POLE_PAIRS * Omega_m */
/* d axis PI gains (method pi); the law below is what runs */
#define CCT_D_KP 1.050000000e+01f /* parallel proportional gain, V/A */
#define CCT_D_KI 1.980000000e+03f /* parallel integral gain, V/(A s) */
#define CCT_D_KI_TS 1.979999989e-01f /* integral gain per sample Ki*Ts, V/A */
#define CCT_D_TI 5.303030368e-03f /* series form Kp (1 + 1/(Ti s)): Ti = Kp/Ki, s */
/* q axis PI gains (method pi); the law below is what runs */
#define CCT_Q_KP 1.050000000e+01f /* parallel proportional gain, V/A */
#define CCT_Q_KI 1.980000000e+03f /* parallel integral gain, V/(A s) */
#define CCT_Q_KI_TS 1.979999989e-01f /* integral gain per sample Ki*Ts, V/A */
#define CCT_Q_TI 5.303030368e-03f /* series form Kp (1 + 1/(Ti s)): Ti = Kp/Ki, s */

#define CCT_D_GAIN 1.059899998e+01f /* d axis SOS output gain, V/A */
#define CCT_D_NUM_STAGES 1
#define CCT_Q_GAIN 1.059899998e+01f /* q axis SOS output gain, V/A */
#define CCT_Q_NUM_STAGES 1

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
    float v_d;     /* V, to apply next period */
    float v_q;     /* V */
    int saturated; /* 1 when the voltage limit acted */
    int status;    /* CCT_STATUS_* */
} cct_output_t;

/* controller states (sos d axis: 2, sos q axis: 2; arrays have at least one element)
 * and the last good output, held when a period fails */
typedef struct {
    float d[2];
    float q[2];
    float v_d_hold; /* V */
    float v_q_hold; /* V */
} cct_state_t;

static inline void cct_init(cct_state_t *s)
{
    unsigned i;
    for (i = 0u; i < 2u; ++i) { s->d[i] = 0.0f; }
    for (i = 0u; i < 2u; ++i) { s->q[i] = 0.0f; }
    s->v_d_hold = 0.0f;
    s->v_q_hold = 0.0f;
}

/* 1 when v is neither inf nor nan. Tested on the IEEE-754 bits, so that
 * -ffast-math / -ffinite-math-only cannot remove the test (isfinite() may be). */
static inline int cct_finite(float v)
{
    union { float f; uint32_t u; } b;
    b.f = v;
    return (b.u & 0x7f800000u) != 0x7f800000u;
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
    out->saturated = 0;
    out->status = status;
}

/* d axis linear law: returns v (V); updates the state to A x + B u */
static inline float cct_d_linear(float *x, float r, float y)
{
    /* 1 stage(s) {b0, b1, b2, a1, a2} (a1, a2 negated, CMSIS df2T), gain CCT_D_GAIN */
    static const float c[5] = {
        1.000000000e+00f, -9.813190103e-01f, 0.0f, 1.000000000e+00f, 0.0f,
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
        1.000000000e+00f, -9.813190103e-01f, 0.0f, 1.000000000e+00f, 0.0f,
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
    if (mag2 > CCT_V_MAX * CCT_V_MAX) {
        const float k = CCT_V_MAX / sqrtf(mag2);
        vds = vd * k;
        vqs = vq * k;
        saturated = 1;
    }
    /* back-calculation anti-windup */
    nx.d[0] += 1.762525528e-03f * (vds - vd);
    nx.q[0] += 1.762525528e-03f * (vqs - vq);
    if (!(cct_finite(vds) && cct_finite(vqs) && cct_state_finite(&nx))) {
        cct_hold(s, out, CCT_STATUS_BAD_STATE);
        return;
    }
    nx.v_d_hold = vds;
    nx.v_q_hold = vqs;
    *s = nx;
    out->v_d = vds;
    out->v_q = vqs;
    out->saturated = saturated;
    out->status = CCT_STATUS_OK;
}

#ifdef CCT_FIXED_POINT
/*
 * Fixed point: Q31 words (value / 2^31), int64 accumulators, arithmetic
 * right shifts (as gcc and arm-none-eabi implement >> on negative values).
 * Each coefficient set is an int32 mantissa vector m with one shift F:
 * c = m / 2^F (integer gains with power-of-two divisors, as STM32 MCSDK).
 * Inputs up to I_MAX = 30 A and W_MAX = 230 rad/s (mechanical),
 * voltage limit 106.066 V: bases below are powers of two above rigorous
 * bounds of every signal and state, so no accumulator or word overflows.
 * Quantisation error bound, d axis: |v_q31 - v_exact| <= 0.000104 V over 20 ms from equal states.
 * Quantisation error bound, q axis: |v_q31 - v_exact| <= 0.000104 V over 20 ms from equal states.
 */
#include <stdint.h>
#define CCT_Q31_I_BASE 3.200000000e+01f /* A at full scale */
#define CCT_Q31_V_BASE 1.024000000e+03f /* V at full scale */
#define CCT_Q31_W_BASE 2.560000000e+02f /* mechanical rad/s at full scale */
#define CCT_Q31_V_MAX 222436560L /* V_MAX / V_BASE in Q31 */
#define CCT_Q31_D_X0_BASE 1.600000000e+01f /* state 0 full scale */
#define CCT_Q31_D_X1_BASE 1.000000000e+00f /* state 1 full scale */
#define CCT_Q31_Q_X0_BASE 1.600000000e+01f /* state 0 full scale */
#define CCT_Q31_Q_X1_BASE 1.000000000e+00f /* state 1 full scale */
#define CCT_Q31_DEC_DD 0L /* decoupling coefficient -0 p.u. = m / 2^shift */
#define CCT_Q31_DEC_DD_SHIFT 31u
#define CCT_Q31_DEC_DQ 0L /* decoupling coefficient 0 p.u. = m / 2^shift */
#define CCT_Q31_DEC_DQ_SHIFT 31u
#define CCT_Q31_DEC_DE 0L /* decoupling coefficient 0 p.u. = m / 2^shift */
#define CCT_Q31_DEC_DE_SHIFT 31u
#define CCT_Q31_D_KP_GAIN 704643072L /* per-unit KP: 0.328125 */
#define CCT_Q31_D_KP_DIV_LOG2 31 /* divisor 2^31 */
#define CCT_Q31_D_KI_TS_GAIN 850403525L /* per-unit KI_TS: 0.0061875 */
#define CCT_Q31_D_KI_TS_DIV_LOG2 37 /* divisor 2^37 */
#define CCT_Q31_Q_KP_GAIN 704643072L /* per-unit KP: 0.328125 */
#define CCT_Q31_Q_KP_DIV_LOG2 31 /* divisor 2^31 */
#define CCT_Q31_Q_KI_TS_GAIN 850403525L /* per-unit KI_TS: 0.0061875 */
#define CCT_Q31_Q_KI_TS_DIV_LOG2 37 /* divisor 2^37 */

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
    int32_t d[2];
    int32_t q[2];
} cct_state_q31_t;

static inline void cct_init_q31(cct_state_q31_t *s)
{
    unsigned i;
    for (i = 0u; i < 2u; ++i) { s->d[i] = 0; }
    for (i = 0u; i < 2u; ++i) { s->q[i] = 0; }
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
    static const int32_t co[4] = { 88910856L, 0L, 177821712L, -177821712L };
    static const int32_t ca[10] = {
        134217728L, 8388608L, 5014645L, -5014645L, 15139979L,
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

static inline void cct_d_antiwindup_q31(int32_t *x, int64_t dv)
{
    static const int32_t aw[2] = { 15139979L, 0L };
    static const unsigned fa[2] = { 27u, 31u };
    unsigned i;
    for (i = 0u; i < 2u; ++i) {
        x[i] = cct_sat32((int64_t)x[i] + cct_shr((int64_t)aw[i] * dv, fa[i]));
    }
}

/* q axis: v_lin (Q31, int64 before limiting) and x <- A x + B u */
static inline int64_t cct_q_linear_q31(int32_t *x, int32_t r, int32_t y)
{
    static const int32_t co[4] = { 88910856L, 0L, 177821712L, -177821712L };
    static const int32_t ca[10] = {
        134217728L, 8388608L, 5014645L, -5014645L, 15139979L,
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
    static const int32_t aw[2] = { 15139979L, 0L };
    static const unsigned fa[2] = { 27u, 31u };
    unsigned i;
    for (i = 0u; i < 2u; ++i) {
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
    if (mag2 > (uint64_t)CCT_Q31_V_MAX * (uint64_t)CCT_Q31_V_MAX) {
        const int64_t mag = (int64_t)cct_isqrt64(mag2);
        vds = (vdc * CCT_Q31_V_MAX) / mag;
        vqs = (vqc * CCT_Q31_V_MAX) / mag;
        out->saturated = 1;
    }
    cct_d_antiwindup_q31(s->d, vds - vd);
    cct_q_antiwindup_q31(s->q, vqs - vq);
    out->v_d = (int32_t)vds;
    out->v_q = (int32_t)vqs;
}
#endif /* CCT_FIXED_POINT */

#endif /* CCT_CONTROLLER_H */
