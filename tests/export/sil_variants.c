/*
 * Period routines of the integer variants for tests/export/sil_plant.c, in
 * the image of the header's usage example (which shows the float path
 * only): bus voltage, sampled currents, speed and angle converted with the
 * header's own helpers where it has them (<p>to_q31, <p>to_s16a), one
 * <p>step_*, the compensated output converted to volts and handed to
 * pwm_apply with the sampled angle. Prefix cct_.
 *
 * SIL_NO_COMP: the variant's output has no v_d_comp/v_q_comp; the test
 * then fails, and this rotation by DELAY_COMP_TIME w_e done here (what the
 * float path's step does) only gives the table a diagnostic number.
 */
#include <stdint.h>
#include "controller.h"

#ifdef SIL_NO_COMP
static void sil_rotate(float *vd, float *vq)
{
#ifdef CCT_DELAY_COMP_TIME
    const double th = (double)CCT_DELAY_COMP_TIME * (double)CCT_POLE_PAIRS
                      * (double)encoder_speed();
    const double d = (double)*vd, q = (double)*vq;
    *vd = (float)(d * cos(th) - q * sin(th));
    *vq = (float)(d * sin(th) + q * cos(th));
#else
    (void)vd;
    (void)vq;
#endif
}
#endif

#if defined(SIL_Q31)
static cct_state_q31_t ctl;
static void sil_init(void) { cct_init_q31(&ctl); }

static float sil_q31_volts(int32_t w) { return (float)((double)w * CCT_Q31_V_BASE / 2147483648.0); }

static void control_isr(float i_d_ref, float i_q_ref)
{
    cct_input_q31_t in;
    cct_output_q31_t out;
    int flag = 0, bus = 0;
    float vd, vq;
    const float theta_e = encoder_theta_e();
    /* the bus as Q31 of Q31_VDC_BASE; 1 = clamped to the nominal limit (not a fault) */
    if (cct_set_vdc_q31(&ctl, cct_to_q31(adc_vdc(), CCT_Q31_VDC_BASE, CCT_Q31_VDC_BASE, &bus)) < 0) {
        fault_report(1);
    }
    in.i_d_ref = cct_to_q31(i_d_ref, CCT_Q31_I_PLAUSIBLE, CCT_Q31_I_BASE, &flag);
    in.i_q_ref = cct_to_q31(i_q_ref, CCT_Q31_I_PLAUSIBLE, CCT_Q31_I_BASE, &flag);
    in.i_d = cct_to_q31(adc_i_d(), CCT_Q31_I_PLAUSIBLE, CCT_Q31_I_BASE, &flag);
    in.i_q = cct_to_q31(adc_i_q(), CCT_Q31_I_PLAUSIBLE, CCT_Q31_I_BASE, &flag);
    in.omega_m = cct_to_q31(encoder_speed(), CCT_Q31_W_PLAUSIBLE, CCT_Q31_W_BASE, &flag);
    cct_step_q31(&ctl, &in, &out);
    if (flag || out.status == CCT_STATUS_CLAMPED) { ++clamped_; }
    if (out.status == CCT_STATUS_IMPLAUSIBLE) { fault_report(out.status); }
#ifdef SIL_NO_COMP
    vd = sil_q31_volts(out.v_d);
    vq = sil_q31_volts(out.v_q);
    sil_rotate(&vd, &vq);
#else
    vd = sil_q31_volts(out.v_d_comp);
    vq = sil_q31_volts(out.v_q_comp);
#endif
    pwm_apply(vd, vq, theta_e);
}

#elif defined(SIL_MCSDK)
static cct_state_s16_t ctl;
static void sil_init(void) { cct_init_s16(&ctl); }

/* value / full_scale -> int16 digits, rounded, clamped to +-32767 (flagged) */
static int16_t sil_s16(float value, float full_scale, int *clamped)
{
    const float d = value * (32768.0f / full_scale);
    if (!(d < 32767.0f)) { *clamped = 1; return (int16_t)32767; }
    if (!(d > -32767.0f)) { *clamped = 1; return (int16_t)-32767; }
    return (int16_t)lrintf(d);
}

static float sil_s16_volts(int v) { return (float)((double)v * CCT_MCSDK_V_FS / 32768.0); }

static void control_isr(float i_d_ref, float i_q_ref)
{
    cct_input_s16_t in;
    cct_output_s16_t out;
    int flag = 0;
    float vd, vq;
    const float theta_e = encoder_theta_e();
    /* the limit in s16V digits: V_MAX_PER_VDC x bus */
    if (cct_set_vdc_s16(&ctl, (int32_t)lrintf(CCT_V_MAX_PER_VDC * adc_vdc()
                                              * (32768.0f / CCT_MCSDK_V_FS))) < 0) {
        fault_report(1);
    }
    in.i_d_ref = cct_to_s16a(i_d_ref, &flag);
    in.i_q_ref = cct_to_s16a(i_q_ref, &flag);
    in.i_d = cct_to_s16a(adc_i_d(), &flag);
    in.i_q = cct_to_s16a(adc_i_q(), &flag);
    in.omega_m = sil_s16(encoder_speed(), CCT_MCSDK_W_FS, &flag);
    cct_step_s16(&ctl, &in, &out);
    if (flag || out.status == CCT_STATUS_CLAMPED) { ++clamped_; }
#ifdef SIL_NO_COMP
    vd = sil_s16_volts(out.v_d);
    vq = sil_s16_volts(out.v_q);
    sil_rotate(&vd, &vq);
#else
    vd = sil_s16_volts(out.v_d_comp);
    vq = sil_s16_volts(out.v_q_comp);
#endif
    pwm_apply(vd, vq, theta_e);
}

#elif defined(SIL_IQMATH)
static cct_state_iq_t ctl;
static void sil_init(void) { cct_init_iq(&ctl); }

/* per-unit value -> _IQ24 word, rounded (the step clamps beyond +-1 p.u. itself) */
static int32_t sil_iq(float pu)
{
    const double w = (double)pu * 16777216.0;
    if (w > 2147483647.0) { return INT32_MAX; }
    if (w < -2147483647.0) { return -INT32_MAX; }
    return (int32_t)lrint(w);
}

static float sil_iq_volts(int32_t v) { return (float)((double)v * CCT_IQ_V_BASE / 16777216.0); }

static void control_isr(float i_d_ref, float i_q_ref)
{
    cct_input_iq_t in;
    cct_output_iq_t out;
    float vd, vq;
    const float theta_e = encoder_theta_e();
    if (cct_set_vdc_iq(&ctl, sil_iq(adc_vdc() / CCT_DRIVE_VDC)) < 0) {
        fault_report(1);
    }
    in.i_d_ref = sil_iq(i_d_ref / CCT_IQ_I_BASE);
    in.i_q_ref = sil_iq(i_q_ref / CCT_IQ_I_BASE);
    in.i_d = sil_iq(adc_i_d() / CCT_IQ_I_BASE);
    in.i_q = sil_iq(adc_i_q() / CCT_IQ_I_BASE);
    in.omega_m = sil_iq(encoder_speed() / CCT_IQ_W_BASE);
    cct_step_iq(&ctl, &in, &out);
    if (out.status == CCT_STATUS_CLAMPED) { ++clamped_; }
#ifdef SIL_NO_COMP
    vd = sil_iq_volts(out.v_d);
    vq = sil_iq_volts(out.v_q);
    sil_rotate(&vd, &vq);
#else
    vd = sil_iq_volts(out.v_d_comp);
    vq = sil_iq_volts(out.v_q_comp);
#endif
    pwm_apply(vd, vq, theta_e);
}
#endif
