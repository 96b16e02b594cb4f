"""Kernel part: the direct discrete-time complex-vector law (method ``cv``).

Executes law (L) of :mod:`toolbox.design.cv_discrete` once per period with
the gains recomputed at the measured electrical speed ``w`` (the artifact's
:class:`toolbox.artifact.CvLaw`, toolbox/ARCHITECTURE.md "Direct
discrete-time complex-vector control"), in this order:

1. ``Phi - I`` and ``Gamma`` of the controller's dq model (``R_c``, ``Ld_c``,
   ``Lq_c``; rotor hold) at ``w`` in closed form (:func:`_cv_zoh`):
   ``A = [[a00, a01], [a10, a11]]``, ``m = tr A / 2``, ``h = (a00 - a11) / 2``,
   ``q = (h^2 + a01 a10) Ts^2`` (``= (m^2 - det A) Ts^2``, no cancellation),
   ``e^{A Ts} = e^{m Ts} (ch I + shc (A - m I))`` with ``ch = cosh sqrt(q)``,
   ``shc = Ts sinh(sqrt q)/sqrt q`` (``cos``/``sin`` of ``sqrt(-q)`` when
   ``q < 0``, a 4-term series when ``|q| < 1e-4``), so
   ``Phi - I = (expm1(m Ts) ch + (ch - 1)) I + e^{m Ts} shc (A - m I)``
   with ``ch - 1 = 2 sinh^2(x/2)`` (or ``-2 sin^2``): accurate however small
   ``|A| Ts`` is; ``Gamma = A^-1 (Phi - I) B R(eps)``, ``det A = R^2/(Ld Lq)
   + w^2 > 0``, ``eps = (t_c - (d + 1/2) Ts) w``.
2. The coefficients ``a_m`` of ``delta(z) = (z - p_c)(z - p_i)(z - p_d)^d``
   (:func:`_cv_coef`), the scalars ``C_m = a_0 + .. + a_m`` and the matrices
   ``kappa_m = C_m I + kappa_{m-1} Phi`` (``kappa_0 = I``), accumulating
   ``h = sum_j kappa_j Gamma v_{k-j}`` on the way (``K2_j = Gamma^-1 kappa_j
   Gamma``, so ``sum K2_j v_{k-j} = Gamma^-1 h``).
3. ``Gamma K1 = (a_{d+1} + C_d) I + kappa_d Phi``, ``Gamma Ki = delta(1) I``,
   ``Gamma Kt = delta(1) / (1 - p_i) I``: the linear voltage
   ``v = Gamma^-1 (delta(1)/(1 - p_i) r - Gamma K1 i - h) + x``, plus the EMF
   feedforward ``(0, emf w flux_c)``; the drive's voltage limit
   (``_kernel._voltage_limit``, passed in as the limited voltage);
   ``x += delta(1) Gamma^-1 (r - i) + (1 - p_i) (v_real - v_cmd)``; the delay
   states shift, the newest the realised linear voltage ``v_real - ff``.

The law's states live in the kernel's per-axis state arrays in the
coordinates of the artifact's standstill axes
(:func:`toolbox.design.cv_discrete.standstill_axes`): ``x[0]`` the
integrator, ``x[j]`` the voltage of ``j`` periods ago (``j = 1..d``).
"""

from __future__ import annotations

import math

from ._kernel_layout import _jit_inline

#: Below this ``|q| = |m^2 - det A| Ts^2`` the hyperbolic/trigonometric factors
#: are their series (4 terms; the first dropped term is < 1e-4^4 / 8! ~ 3e-21).
Q_SERIES = 1e-4


@_jit_inline
def _cv_zoh(R, Ld, Lq, w, Ts):
    """``Phi - I`` and ``Gamma`` (unrotated) of the dq model at ``w``: eight
    scalars ``e00, e01, e10, e11, g00, g01, g10, g11`` (module docstring, step 1)."""
    a00 = -R / Ld
    a01 = w * Lq / Ld
    a10 = -w * Ld / Lq
    a11 = -R / Lq
    m = 0.5 * (a00 + a11)
    h = 0.5 * (a00 - a11)
    q = (h * h + a01 * a10) * Ts * Ts
    if abs(q) < Q_SERIES:
        ch = 1.0 + q / 2.0 + q * q / 24.0 + q * q * q / 720.0
        ch1 = q / 2.0 + q * q / 24.0 + q * q * q / 720.0
        shc = Ts * (1.0 + q / 6.0 + q * q / 120.0 + q * q * q / 5040.0)
    elif q > 0.0:
        x = math.sqrt(q)
        ch = math.cosh(x)
        s2 = math.sinh(0.5 * x)
        ch1 = 2.0 * s2 * s2
        shc = Ts * math.sinh(x) / x
    else:
        x = math.sqrt(-q)
        ch = math.cos(x)
        s2 = math.sin(0.5 * x)
        ch1 = -2.0 * s2 * s2
        shc = Ts * math.sin(x) / x
    em1 = math.expm1(m * Ts)
    f = (em1 + 1.0) * shc
    d0 = em1 * ch + ch1
    e00 = d0 + f * h
    e11 = d0 - f * h
    e01 = f * a01
    e10 = f * a10
    det = a00 * a11 - a01 * a10
    # Gamma = A^-1 (Phi - I) B, B = diag(1/Ld, 1/Lq)
    g00 = (a11 * e00 - a01 * e10) / (det * Ld)
    g01 = (a11 * e01 - a01 * e11) / (det * Lq)
    g10 = (-a10 * e00 + a00 * e10) / (det * Ld)
    g11 = (-a10 * e01 + a00 * e11) / (det * Lq)
    return e00, e01, e10, e11, g00, g01, g10, g11


@_jit_inline
def _cv_coef(m, d, pc, pi, pd):
    """``a_m`` of ``(z - pc)(z - pi)(z - pd)^d`` (``a_0 = 1``), ``0 <= m <= d + 2``."""
    e1 = -(pc + pi)
    e2 = pc * pi
    out = 0.0
    for j in range(3):          # a_m = b_m + e1 b_{m-1} + e2 b_{m-2}, b the binomial part
        k = m - j
        if k < 0 or k > d:
            continue
        b = 1.0
        for t in range(1, k + 1):
            b *= -pd * (d - t + 1) / t
        out += (1.0 if j == 0 else e1 if j == 1 else e2) * b
    return out


@_jit_inline
def _cv_linear(xd, xq, idr, iqr, i_d, i_q, w, Ts, d, t_comp, R, Ld, Lq, pc, pi, pd):
    """Steps 1-3 up to the linear voltage: returns ``(vd, vq, k_int, gi00, gi01,
    gi10, gi11)``: the linear voltage (without feedforward), ``delta(1)`` and
    ``Gamma^-1`` (for the integrator update of :func:`_cv_update`)."""
    e00, e01, e10, e11, g00, g01, g10, g11 = _cv_zoh(R, Ld, Lq, w, Ts)
    eps = (t_comp - (d + 0.5) * Ts) * w
    ce = math.cos(eps)
    se = math.sin(eps)
    # Gamma R(eps)
    G00 = g00 * ce + g01 * se
    G01 = -g00 * se + g01 * ce
    G10 = g10 * ce + g11 * se
    G11 = -g10 * se + g11 * ce
    p00 = 1.0 + e00
    p11 = 1.0 + e11
    # kappa_m = C_m I + kappa_{m-1} Phi, h = sum_j kappa_j Gamma v_{k-j}
    k00 = 1.0
    k01 = 0.0
    k10 = 0.0
    k11 = 1.0
    C = 1.0
    h0 = 0.0
    h1 = 0.0
    for j in range(1, d + 1):
        C += _cv_coef(j, d, pc, pi, pd)
        n00 = C + k00 * p00 + k01 * e10
        n01 = k00 * e01 + k01 * p11
        n10 = k10 * p00 + k11 * e10
        n11 = C + k10 * e01 + k11 * p11
        k00, k01, k10, k11 = n00, n01, n10, n11
        u0 = G00 * xd[j] + G01 * xq[j]
        u1 = G10 * xd[j] + G11 * xq[j]
        h0 += k00 * u0 + k01 * u1
        h1 += k10 * u0 + k11 * u1
    a1 = _cv_coef(d + 1, d, pc, pi, pd)
    delta1 = C + a1 + _cv_coef(d + 2, d, pc, pi, pd)
    c1 = a1 + C
    # Gamma K1 = c1 I + kappa_d Phi
    K00 = c1 + k00 * p00 + k01 * e10
    K01 = k00 * e01 + k01 * p11
    K10 = k10 * p00 + k11 * e10
    K11 = c1 + k10 * e01 + k11 * p11
    kt = delta1 / (1.0 - pi)
    w0 = kt * idr - (K00 * i_d + K01 * i_q) - h0
    w1 = kt * iqr - (K10 * i_d + K11 * i_q) - h1
    det = G00 * G11 - G01 * G10
    gi00 = G11 / det
    gi01 = -G01 / det
    gi10 = -G10 / det
    gi11 = G00 / det
    vd = gi00 * w0 + gi01 * w1 + xd[0]
    vq = gi10 * w0 + gi11 * w1 + xq[0]
    return vd, vq, delta1, gi00, gi01, gi10, gi11


@_jit_inline
def _cv_update(xd, xq, idr, iqr, i_d, i_q, d, pi, delta1, gi00, gi01, gi10, gi11,
               dvd, dvq, vd_new, vq_new):
    """Integrator ``x += delta(1) Gamma^-1 (r - i) + (1 - p_i) dv`` (``dv = v_real -
    v_cmd``) and the delay states shifted, ``v_{k-1}`` = the realised linear
    voltage ``(vd_new, vq_new)``."""
    ed = idr - i_d
    eq = iqr - i_q
    xd[0] += delta1 * (gi00 * ed + gi01 * eq) + (1.0 - pi) * dvd
    xq[0] += delta1 * (gi10 * ed + gi11 * eq) + (1.0 - pi) * dvq
    for j in range(d, 1, -1):
        xd[j] = xd[j - 1]
        xq[j] = xq[j - 1]
    if d >= 1:
        xd[1] = vd_new
        xq[1] = vq_new
