"""Vendor-style integer variants of a PI current law: STM32 MCSDK and TI IQmath.

Both execute the artifact's own PI law exactly as written (per axis the
discrete law ``x+ = x + b (r - y) + aw dv``, ``v = c x + d (r - y)``: one
integrator, one degree of freedom) in the "forward" PI form of the vendors'
libraries, the integral term ``I = c x`` (V) added before its update::

    v = Kp e + I,     I+ = I + Ki e + Kaw (v_sat - v)

with ``Kp = d``, ``Ki = c b`` (per sample) and ``Kaw = c aw``, plus the
decoupling terms, the radial voltage limit and the back-calculation
anti-windup of the float path. Scaling comes from the drive's ranges:
``I_FS`` = the current range (``motor.max_current``, else 2 x rated),
``W_FS`` = the speed range, ``V_FS`` = twice the nominal voltage limit (the
bus may rise above nominal at run time).

* **MCSDK** (STM32 Motor Control SDK ``PI_Controller``): int16 signals in
  digits (``s16A``: twice ``I_FS`` is 32768 digits, so a reading beyond the
  plausible range is on the rail; ``s16V`` of ``V_FS``; speed: twice
  ``W_FS``), int16 gains with power-of-two divisors (``KP_GAIN / 2^KP_DIV``,
  divisors up to 2^15 as the SDK), an int32 integral term holding
  ``I x 2^KI_DIV``, arithmetic right shifts.
* **IQmath** (TI ``_IQ24``): int32 per-unit words with 24 fractional bits
  (range +-128 p.u.), bases ``I_FS``, ``V_MAX`` (nominal), ``W_FS``;
  ``_IQmpy(a, b) = (a b) >> 24`` in int64.

Inputs beyond their range (|i| > I_FS, |Omega| > W_FS) are clamped and flagged
(``status = <P>STATUS_CLAMPED``) instead of wrapping; measurements beyond twice
it (the plausible range) are replaced by the last plausible ones, without an
integral update (``<P>STATUS_IMPLAUSIBLE``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._plausible import PLAUSIBLE_MARGIN

__all__ = ["VendorPlan", "plan_vendor", "quantise_pow2", "mcsdk_constants", "iq_constants"]

IQ = 24                    # fractional bits of _IQ24


@dataclass
class VendorPlan:
    """Per-axis PI coefficients (physical) and ranges of the integer variants.

    Attributes
    ----------
    kp, ki, kaw : dict
        Per axis: proportional gain (V/A), integral gain per sample (V/A),
        anti-windup gain (dimensionless).
    I_FS, W_FS, V_MAX, V_FS : float
        Current range (A), mechanical speed range (rad/s), nominal voltage
        limit (V) and the MCSDK voltage full scale (V).
    dec : dict
        Decoupling coefficients ``dd``, ``dq`` (V per (rad/s x A)), ``de``
        (V per rad/s) of the mechanical speed.
    """

    kp: dict
    ki: dict
    kaw: dict
    I_FS: float
    W_FS: float
    V_MAX: float
    V_FS: float
    dec: dict

    @property
    def mc_I_FS(self) -> float:
        """The MCSDK's current full scale (A = 32768 digits): ``PLAUSIBLE_MARGIN``
        x the range, so a measurement beyond the plausible range is on the rail."""
        return PLAUSIBLE_MARGIN * self.I_FS

    @property
    def mc_W_FS(self) -> float:
        """The MCSDK's speed full scale (rad/s = 32768 digits), likewise."""
        return PLAUSIBLE_MARGIN * self.W_FS


def quantise_pow2(value: float, bits: int = 15, max_shift: int = 15) -> tuple[int, int]:
    """``(gain, shift)`` with ``gain / 2^shift ~ value``, ``|gain| < 2^bits``,
    ``shift`` in ``[0, max_shift]`` as large as the gain allows (the MCSDK's
    int16 gain with a power-of-two divisor)."""
    if value == 0.0:
        return 0, 0
    shift = max_shift
    while shift > 0 and abs(round(value * 2.0 ** shift)) >= 2 ** bits:
        shift -= 1
    g = int(round(value * 2.0 ** shift))
    if abs(g) >= 2 ** bits:
        raise OverflowError(f"{value} does not fit {bits} bits")
    return g, shift


def plan_vendor(mins: dict, I_FS: float, W_FS: float, V_MAX: float,
                dec_coeffs: dict) -> tuple[VendorPlan | None, str]:
    """The vendor plan of a PI law, or (None, why) for laws of another shape.

    Parameters
    ----------
    mins : dict
        ``{"d": MinimalLaw, "q": MinimalLaw}`` (:func:`toolbox.export._check.minimal_laws`).
    I_FS, W_FS, V_MAX : float
        Current range (A), speed range (mechanical rad/s), nominal voltage limit (V).
    dec_coeffs : dict
        ``dd``, ``dq``, ``de`` as in :func:`toolbox.export._fixed.plan_fixed`.
    """
    kp, ki, kaw = {}, {}, {}
    for ax, m in mins.items():
        A, B, C, D = (np.atleast_2d(np.asarray(v, float)) for v in (m.A, m.B, m.C, m.D))
        if A.shape != (1, 1) or abs(A[0, 0] - 1.0) > 1e-9:
            return None, (f"{ax} axis: the MCSDK/IQmath variants run a PI (one integrator); "
                          f"this law has order {A.shape[0]}")
        if abs(B[0, 0] + B[0, 1]) > 1e-12 * abs(B[0, 0]) or \
                abs(D[0, 0] + D[0, 1]) > 1e-12 * max(abs(D[0, 0]), 1e-300):
            return None, (f"{ax} axis: the MCSDK/IQmath variants run a one-degree-of-freedom "
                          "PI (v from i_ref - i_meas); this law weights them differently")
        aw = 0.0 if m.aw is None else float(np.ravel(m.aw)[0])
        kp[ax] = float(D[0, 0])
        ki[ax] = float(C[0, 0] * B[0, 0])
        kaw[ax] = float(C[0, 0] * aw)
    return VendorPlan(kp, ki, kaw, float(I_FS), float(W_FS), float(V_MAX),
                      2.0 * float(V_MAX), dict(dec_coeffs)), ""


def mcsdk_constants(plan: VendorPlan) -> dict:
    """Integer gains/divisors of the MCSDK variant (digits in, digits out)."""
    g = plan.mc_I_FS / plan.V_FS           # V digits per A digit, per V/A
    out = {}
    for ax in ("d", "q"):
        out[f"{ax}_kp"] = quantise_pow2(plan.kp[ax] * g)
        out[f"{ax}_ki"] = quantise_pow2(plan.ki[ax] * g)
        out[f"{ax}_kaw"] = quantise_pow2(plan.kaw[ax])
    # decoupling: v digits = c * (w digits * i digits) / 32768, c below
    wi = plan.mc_W_FS * plan.mc_I_FS / plan.V_FS    # times (w digits x i digits) >> 15
    out["dd"] = quantise_pow2(plan.dec["dd"] * wi)
    out["dq"] = quantise_pow2(plan.dec["dq"] * wi)
    out["de"] = quantise_pow2(plan.dec["de"] * plan.mc_W_FS / plan.V_FS)
    return out


def iq_constants(plan: VendorPlan) -> dict:
    """_IQ24 per-unit coefficients of the IQmath variant (ints)."""
    g = plan.I_FS / plan.V_MAX
    q = lambda v: int(round(v * 2.0 ** IQ))
    out = {}
    for ax in ("d", "q"):
        out[f"{ax}_kp"] = q(plan.kp[ax] * g)
        out[f"{ax}_ki"] = q(plan.ki[ax] * g)
        out[f"{ax}_kaw"] = q(plan.kaw[ax])
    out["dd"] = q(plan.dec["dd"] * plan.W_FS * plan.I_FS / plan.V_MAX)
    out["dq"] = q(plan.dec["dq"] * plan.W_FS * plan.I_FS / plan.V_MAX)
    out["de"] = q(plan.dec["de"] * plan.W_FS / plan.V_MAX)
    for k, v in out.items():
        if abs(v) >= 2 ** 31:
            raise OverflowError(f"IQ24 coefficient {k} = {v / 2 ** IQ:g} p.u. beyond +-128")
    return out
