/*
 * controller.h -- current controller exported by current-control-toolbox
 * title:       Paper 003 motor: direct discrete-time complex-vector current control (Hinkkanen et al. 2016), poles placed in z at the measured speed
 * method:      cv
 * version:     0.1.0
 * spec sha256: a9f8aec8d5e9e1a399111942f235c54b3cd088fa80e01537474797a5841ede56
 * law sha256:  270d14572051e839e1c286c27b7e8b9848bee503e822a8ac5b366addb504d824
 * created:     2026-11-28T00:23:51+00:00
 *
 * C99, header-only, no dynamic memory; libm: sqrtf, expm1f, expf, coshf,
 * sinhf, cosf, sinf. Float only (the integer variants CCT_FIXED_POINT,
 * CCT_MCSDK and CCT_IQMATH are errors).
 * Direct discrete-time complex-vector current control (Hinkkanen, Awan, Qu,
 * Tuovinen, Briz, IEEE Trans. Ind. Appl. 52(2), 2016; toolbox method cv,
 * toolbox/design/cv_discrete.py). Every period cct_step() discretises the
 * controller's dq model exactly at the measured electrical speed w (voltage
 * held in the rotor frame over the period, placed at theta_e + DELAY_COMP_TIME w),
 * places the closed-loop poles CV_PC (tracking), CV_PI (integral) and
 * CV_PD (each of the 1 delay state(s)) and runs
 *   v = Kt r - K1 i - sum_j K2_j v(k-j) + x,  x += Ki (r - i) + (1 - CV_PI) (v_real - v)
 * with the gains of that speed, the back-EMF feed-forward
 * (0, DEC_EMF w DEC_FLUX) and the voltage limit (radial).
 * Call cct_init() once, then cct_set_vdc() with the measured bus voltage and
 * cct_step() once per period (example at the end of this file).
 * Faults: out->status CCT_STATUS_BAD_INPUT (an input is inf/nan),
 * CCT_STATUS_IMPLAUSIBLE (a measured current or the speed beyond
 * CCT_I_PLAUSIBLE / CCT_W_PLAUSIBLE) or CCT_STATUS_BAD_STATE (a non-finite
 * result): the last good output is repeated and the state kept.
 */
#ifndef CCT_CONTROLLER_H
#define CCT_CONTROLLER_H

#include <math.h> /* sqrtf, expm1f, expf, coshf, sinhf, cosf, sinf */
#include <stdint.h> /* uint32_t */

#ifdef CCT_FIXED_POINT
#error "fixed-point variant not available: the cv law computes its gains at the measured speed each period (exponentials, a 2x2 inverse) and is exported in float only"
#endif /* CCT_FIXED_POINT */
#if defined(CCT_MCSDK) || defined(CCT_IQMATH)
#error "MCSDK/IQmath variants not available: they execute a one-degree-of-freedom PI law; the cv law is exported in float only"
#endif /* CCT_MCSDK || CCT_IQMATH */

#define CCT_SAMPLE_TIME 9.999999747e-05f /* controller period, s */
#define CCT_DELAY_SAMPLES 1 /* computation delay the design assumed, periods */
#define CCT_V_MAX 8.660253906e+01f /* voltage limit (circle radius) at the nominal bus voltage, V; cct_init's default */
#define CCT_V_MAX_PER_VDC 5.773502588e-01f /* voltage limit per volt of measured bus (cct_set_vdc) */
#define CCT_DRIVE_VDC 1.500000000e+02f /* nominal DC-link voltage, V */
/* the controller's dq model (amplitude-invariant dq convention) */
#define CCT_DEC_R 6.000000238e-01f /* ohm */
#define CCT_DEC_LD 1.399999950e-03f /* H */
#define CCT_DEC_LQ 2.799999900e-03f /* H */
#define CCT_DEC_FLUX 1.199999973e-01f /* Wb */
#define CCT_DEC_EMF 1 /* 1: back-EMF feed-forward on */
#define CCT_POLE_PAIRS 4 /* w_e = POLE_PAIRS * Omega_m */
#define CCT_DELAY_COMP_TIME 1.500000071e-04f /* s (1.5 Ts, drive.angle_compensation = "mid_period"): v_dq is placed at theta_e + DELAY_COMP_TIME w_e; outputs v_d_comp, v_q_comp */
#define CCT_CV_EPS_PER_W 0.0f /* s, DELAY_COMP_TIME - (DELAY_SAMPLES + 1/2) SAMPLE_TIME: the placement error the gains expect, per rad/s */
/* placed poles (z): exp(-alpha_c Ts), exp(-alpha_i Ts), the delay states' */
#define CCT_CV_PC 7.408182025e-01f /* alpha_c = 3000 rad/s */
#define CCT_CV_PI 5.488116145e-01f /* alpha_i = 6000 rad/s */
#define CCT_CV_PD 0.0f

/* inputs: currents in A, measured MECHANICAL speed in rad/s.
 * dq frame (amplitude-invariant Park transform): d along the rotor's
 * permanent-magnet flux, q 90 electrical degrees ahead of it in the direction
 * of positive rotation (phase order a, b, c). */
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
#define CCT_STATUS_IMPLAUSIBLE 4 /* a measurement beyond its plausible range: output held, state kept */

/* plausible ranges (a sample beyond them is a sensor or ADC fault) */
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
    int sat_d;     /* 1 when the limit changed v_d */
    int sat_q;     /* 1 when the limit changed v_q */
    int status;    /* CCT_STATUS_* */
} cct_output_t;

/* law state per axis (the coordinates of the artifact's standstill axes):
 * [0] the integrator x (V), [1 ..] the realised linear voltages of the last
 * DELAY_SAMPLES periods (newest first); and the last good output */
typedef struct {
    float d[2];
    float q[2];
    float v_d_hold; /* V */
    float v_q_hold; /* V */
    float v_d_comp_hold; /* V */
    float v_q_comp_hold; /* V */
    float v_max;    /* V, voltage limit in use (cct_set_vdc); CCT_V_MAX after init */
} cct_state_t;

/* zero states and held outputs (0 V), keeping the voltage limit in use */
static inline void cct_reset(cct_state_t *s)
{
    unsigned i;
    for (i = 0u; i < 2u; ++i) { s->d[i] = 0.0f; s->q[i] = 0.0f; }
    s->v_d_hold = 0.0f;
    s->v_q_hold = 0.0f;
    s->v_d_comp_hold = 0.0f;
    s->v_q_comp_hold = 0.0f;
}

/* cct_reset and the voltage limit CCT_V_MAX (nominal bus CCT_DRIVE_VDC) */
static inline void cct_init(cct_state_t *s)
{
    cct_reset(s);
    s->v_max = CCT_V_MAX;
}

/* 1 when v is neither inf nor nan (IEEE-754 bits, immune to -ffast-math) */
static inline int cct_finite(float v)
{
    union { float f; uint32_t u; } b;
    b.f = v;
    return (b.u & 0x7f800000u) != 0x7f800000u;
}

/* measured DC-link voltage (V) -> voltage limit CCT_V_MAX_PER_VDC * vdc.
 * Returns CCT_STATUS_OK; CCT_STATUS_BAD_INPUT (not finite or not > 0) or
 * CCT_STATUS_IMPLAUSIBLE (outside [CCT_VDC_MIN, CCT_VDC_PLAUSIBLE]) leave
 * the limit in use unchanged. */
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

/* exact ZOH (rotor-frame hold) of the controller's dq model at the electrical
 * speed w: e = Phi - I and g = Gamma (row-major 2x2), closed form
 * (toolbox/sim/_kernel_cv.py, _cv_zoh): e^{A Ts} = e^{m Ts} (ch I + shc (A - m I)),
 * m = tr A / 2, q = (m^2 - det A) Ts^2; Gamma = A^-1 (Phi - I) B */
static inline void cct_cv_zoh(float w, float e[4], float g[4])
{
    const float ts = CCT_SAMPLE_TIME;
    const float a00 = -CCT_DEC_R / CCT_DEC_LD;
    const float a01 = w * CCT_DEC_LQ / CCT_DEC_LD;
    const float a10 = -w * CCT_DEC_LD / CCT_DEC_LQ;
    const float a11 = -CCT_DEC_R / CCT_DEC_LQ;
    const float m = 0.5f * (a00 + a11);
    const float h = 0.5f * (a00 - a11);
    const float q = (h * h + a01 * a10) * ts * ts;
    float ch, ch1, shc;
    if (q < 1e-4f && q > -1e-4f) {
        ch1 = q / 2.0f + q * q / 24.0f + q * q * q / 720.0f;
        ch = 1.0f + ch1;
        shc = ts * (1.0f + q / 6.0f + q * q / 120.0f + q * q * q / 5040.0f);
    } else if (q > 0.0f) {
        const float x = sqrtf(q);
        const float s2 = sinhf(0.5f * x);
        ch = coshf(x);
        ch1 = 2.0f * s2 * s2;
        shc = ts * sinhf(x) / x;
    } else {
        const float x = sqrtf(-q);
        const float s2 = sinf(0.5f * x);
        ch = cosf(x);
        ch1 = -2.0f * s2 * s2;
        shc = ts * sinf(x) / x;
    }
    {
        const float em1 = expm1f(m * ts);
        const float f = (em1 + 1.0f) * shc;
        const float d0 = em1 * ch + ch1;
        const float det = a00 * a11 - a01 * a10;
        e[0] = d0 + f * h;
        e[1] = f * a01;
        e[2] = f * a10;
        e[3] = d0 - f * h;
        g[0] = (a11 * e[0] - a01 * e[2]) / (det * CCT_DEC_LD);
        g[1] = (a11 * e[1] - a01 * e[3]) / (det * CCT_DEC_LQ);
        g[2] = (-a10 * e[0] + a00 * e[2]) / (det * CCT_DEC_LD);
        g[3] = (-a10 * e[1] + a00 * e[3]) / (det * CCT_DEC_LQ);
    }
}

/* the law's voltage at the electrical speed w for the states xd, xq (the
 * integrator excluded, which the caller adds), and the integrator's gains
 * delta(1) and gi = Gamma^-1 (row-major): steps 1-2 of the gains
 * (toolbox/sim/_kernel_cv.py) and v = Gamma^-1 (kt r - Gamma K1 i - h) */
static inline void cct_cv_law(const float *xd, const float *xq, float r_d, float r_q,
                               float i_d, float i_q, float w, float *vd, float *vq,
                               float *delta1, float gi[4])
{
    /* a_0 .. a_{DELAY_SAMPLES + 2} of delta(z) = (z - CV_PC)(z - CV_PI)(z - CV_PD)^DELAY_SAMPLES */
    static const float a[4] = { 1.000000000e+00f, -1.289629817e+00f, 4.065696597e-01f, 0.0f };
    float e[4], g[4];
    const float eps = CCT_CV_EPS_PER_W * w;
    const float ce = cosf(eps);
    const float se = sinf(eps);
    float G00, G01, G10, G11, k00 = 1.0f, k01 = 0.0f, k10 = 0.0f, k11 = 1.0f;
    float C = 1.0f, h0 = 0.0f, h1 = 0.0f;
    unsigned j;
    cct_cv_zoh(w, e, g);
    /* Gamma R(eps): the placement error the gains expect */
    G00 = g[0] * ce + g[1] * se;
    G01 = -g[0] * se + g[1] * ce;
    G10 = g[2] * ce + g[3] * se;
    G11 = -g[2] * se + g[3] * ce;
    /* kappa_j = C_j I + kappa_{j-1} Phi; h = sum_j kappa_j Gamma v(k-j) */
    for (j = 1u; j <= 1u; ++j) {
        const float n00 = (C + a[j]) + k00 * (1.0f + e[0]) + k01 * e[2];
        const float n01 = k00 * e[1] + k01 * (1.0f + e[3]);
        const float n10 = k10 * (1.0f + e[0]) + k11 * e[2];
        const float n11 = (C + a[j]) + k10 * e[1] + k11 * (1.0f + e[3]);
        const float u0 = G00 * xd[j] + G01 * xq[j];
        const float u1 = G10 * xd[j] + G11 * xq[j];
        C += a[j];
        k00 = n00; k01 = n01; k10 = n10; k11 = n11;
        h0 += k00 * u0 + k01 * u1;
        h1 += k10 * u0 + k11 * u1;
    }
    {
        const float c1 = a[2] + C;
        const float dl = c1 + a[3]; /* delta(1): Gamma Ki = delta(1) I */
        const float kt = dl / (1.0f - CCT_CV_PI); /* Gamma Kt = kt I */
        /* Gamma K1 = c1 I + kappa_d Phi */
        const float K00 = c1 + k00 * (1.0f + e[0]) + k01 * e[2];
        const float K01 = k00 * e[1] + k01 * (1.0f + e[3]);
        const float K10 = k10 * (1.0f + e[0]) + k11 * e[2];
        const float K11 = c1 + k10 * e[1] + k11 * (1.0f + e[3]);
        const float w0 = kt * r_d - (K00 * i_d + K01 * i_q) - h0;
        const float w1 = kt * r_q - (K10 * i_d + K11 * i_q) - h1;
        const float det = G00 * G11 - G01 * G10;
        gi[0] = G11 / det;
        gi[1] = -G01 / det;
        gi[2] = -G10 / det;
        gi[3] = G00 / det;
        *vd = gi[0] * w0 + gi[1] * w1;
        *vq = gi[2] * w0 + gi[3] * w1;
        *delta1 = dl;
    }
}

/* 1 when every input is finite and the measurements plausible (else the status) */
static inline int cct_check(const cct_input_t *in)
{
    if (!(cct_finite(in->i_d_ref) && cct_finite(in->i_q_ref) && cct_finite(in->i_d)
          && cct_finite(in->i_q) && cct_finite(in->omega_m))) {
        return CCT_STATUS_BAD_INPUT;
    }
    if (!(in->i_d <= CCT_I_PLAUSIBLE && in->i_d >= -CCT_I_PLAUSIBLE
          && in->i_q <= CCT_I_PLAUSIBLE && in->i_q >= -CCT_I_PLAUSIBLE
          && in->omega_m <= CCT_W_PLAUSIBLE && in->omega_m >= -CCT_W_PLAUSIBLE)) {
        return CCT_STATUS_IMPLAUSIBLE;
    }
    return CCT_STATUS_OK;
}

/* the states where the law outputs the linear voltage (vl_d, vl_q) for the
 * inputs (r, i) at the speed w, on its steady-state manifold: every delayed
 * voltage equal to it, the integrator making up the rest (exactly: the step
 * recomputes the same terms) */
static inline void cct_place(cct_state_t *s, float vl_d, float vl_q, float r_d,
                               float r_q, float i_d, float i_q, float w)
{
    float ld, lq, dl, gi[4];
    unsigned j;
    for (j = 1u; j <= 1u; ++j) {
        s->d[j] = vl_d;
        s->q[j] = vl_q;
    }
    cct_cv_law(s->d, s->q, r_d, r_q, i_d, i_q, w, &ld, &lq, &dl, gi);
    s->d[0] = vl_d - ld;
    s->q[0] = vl_q - lq;
}

/* bumpless transfer (e.g. open-loop voltage -> closed loop): puts the states
 * where the next cct_step with the inputs *in outputs v_d, v_q (V, the
 * law's output: the back-EMF feed-forward included, before the limit, so keep
 * |v| within it), and holds that voltage as the last good output. Call it in
 * the period of the handover, with the inputs of the step that follows.
 * Returns CCT_STATUS_OK, or _BAD_INPUT / _IMPLAUSIBLE (nothing changed). */
static inline int cct_preset_at(cct_state_t *s, const cct_input_t *in, float v_d, float v_q)
{
    const int st = cct_finite(v_d) && cct_finite(v_q) ? cct_check(in)
                                                              : CCT_STATUS_BAD_INPUT;
    if (st != CCT_STATUS_OK) {
        return st;
    }
    {
        const float w = (float)CCT_POLE_PAIRS * in->omega_m; /* electrical speed, rad/s */
        const float ff = (float)CCT_DEC_EMF * w * CCT_DEC_FLUX;
        const float thc = CCT_DELAY_COMP_TIME * w;
        const float cc = cosf(thc);
        const float sc = sinf(thc);
        cct_place(s, v_d, v_q - ff, in->i_d_ref, in->i_q_ref, in->i_d, in->i_q, w);
        s->v_d_hold = v_d;
        s->v_q_hold = v_q;
        s->v_d_comp_hold = v_d * cc - v_q * sc;
        s->v_q_comp_hold = v_d * sc + v_q * cc;
    }
    return CCT_STATUS_OK;
}

/* the law's states where it outputs v_d, v_q (V) at zero speed with zero
 * references and currents (its steady state there); held output set to
 * (v_d, v_q). Use cct_preset_at for an exact handover at speed or with currents. */
static inline void cct_preset(cct_state_t *s, float v_d, float v_q)
{
    cct_place(s, v_d, v_q, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f);
    s->v_d_hold = v_d;
    s->v_q_hold = v_q;
    s->v_d_comp_hold = v_d;
    s->v_q_comp_hold = v_q;
}

/* one controller period: gains at the measured speed, the law, the back-EMF
 * feed-forward, the limit, the realised-voltage integrator and the delay states.
 * out->status: CCT_STATUS_OK, or _BAD_INPUT / _IMPLAUSIBLE / _BAD_STATE with
 * the last good output repeated and the state left as it was. */
static inline void cct_step(cct_state_t *s, const cct_input_t *in, cct_output_t *out)
{
    cct_state_t nx;
    const int st = cct_check(in);
    if (st != CCT_STATUS_OK) {
        cct_hold(s, out, st);
        return;
    }
    nx = *s;
    {
        const float w = (float)CCT_POLE_PAIRS * in->omega_m; /* electrical speed, rad/s */
        const float ff = (float)CCT_DEC_EMF * w * CCT_DEC_FLUX;
        const float ed = in->i_d_ref - in->i_d;
        const float eq = in->i_q_ref - in->i_q;
        float ld, lq, delta1, gi[4];
        cct_cv_law(nx.d, nx.q, in->i_d_ref, in->i_q_ref, in->i_d, in->i_q, w, &ld, &lq,
                     &delta1, gi);
        {
            const float vd = ld + nx.d[0];
            const float vq = lq + nx.q[0] + ff;
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
            /* integrator: x += delta(1) Gamma^-1 (r - i) + (1 - CV_PI) (v_real - v) */
            nx.d[0] += delta1 * (gi[0] * ed + gi[1] * eq) + (1.0f - CCT_CV_PI) * (vds - vd);
            nx.q[0] += delta1 * (gi[2] * ed + gi[3] * eq) + (1.0f - CCT_CV_PI) * (vqs - vq);
            {
                /* delay states: the realised linear voltage is the newest */
                unsigned j;
                for (j = 1u; j > 1u; --j) {
                    nx.d[j] = nx.d[j - 1u];
                    nx.q[j] = nx.q[j - 1u];
                }
            }
            nx.d[1] = vds;
            nx.q[1] = vqs - ff;
            if (!(cct_finite(vds) && cct_finite(vqs) && cct_finite(nx.d[0])
                  && cct_finite(nx.q[0]))) {
                cct_hold(s, out, CCT_STATUS_BAD_STATE);
                return;
            }
            {
                /* voltage placement (toolbox/ARCHITECTURE.md "The digital loop") */
                const float thc = CCT_DELAY_COMP_TIME * w;
                const float cc = cosf(thc);
                const float sc = sinf(thc);
                const float vdr = vds * cc - vqs * sc;
                const float vqr = vds * sc + vqs * cc;
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
                out->sat_d = vds != vd;
                out->sat_q = vqs != vq;
                out->status = CCT_STATUS_OK;
            }
        }
    }
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
