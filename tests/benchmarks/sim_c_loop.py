"""The plain C yardstick of the closed-loop simulator (``bench_sim``) and its
agreement check, shared by the benchmark and by
``tests/sim/test_bench_c_loop.py``.

The scenario (:data:`M`, :data:`LAW`, :data:`DRIVE`, :func:`scenario`): the
Le Pioufle 1992 motor (paper 000) started unloaded by an i_q step to 10 A at
t = 0; dq PI current controllers (``toolbox.sim.discrete_pi``: Kp = L wc,
Ki = R wc, wc = 2000 rad/s, forward-Euler integrator, Hanus anti-windup
aw = Ts/Kp) with cross-coupling and back-EMF decoupling; Ts = 100 us, one
period of computation delay; the voltage placed at the middle of its
application period (``drive.angle_compensation = "mid_period"``, the
default of every ``cct design``: ``t_c = (d + 1/2) Ts``); circle voltage
limit vdc/sqrt(2) (vdc = 150 V), radial; average inverter held in the rotor
frame; plant integrated by RK4 at 1 us.

:data:`C_SOURCE` is that closed loop written out in C, operation for
operation in the order ``toolbox.sim._kernel`` evaluates it for this
scenario (toolbox/ARCHITECTURE.md "The digital loop"):

* the law as the kernel's state-space axis law: ``v = (Kp r + (-Kp) y) + Ki x``,
  ``x+ = ((Ts r + (-Ts) y) + aw (v_sat - v)) + x``, then the decoupling
  ``- w Lq i_q``, ``+ w Ld i_d + w flux`` (``_kernel._law_step``);
* the radial circle limit ``v v_max / |v|`` with libm's ``hypot``
  (``_kernel._voltage_limit``);
* the delay line of the voltage and of its placement angle
  ``theta_k + t_c w_k``; the delayed voltage held in the rotor frame,
  rotated by the placement's error from the true mid-period angle
  ``phi - (theta + w Ts / 2)`` with libm's ``cos``, ``sin`` (``_kernel._periods``);
* RK4 steps of ``Ts / ceil(Ts / h)`` (``_kernel_steps._split``), the
  derivatives times ``1/Ld``, ``1/Lq``, ``1/J`` (``_kernel_plant._deriv``,
  ``_rk4``), the squared torque error of each step's start state times the
  step (``_kernel_metrics._accumulate``) against the reference torque
  ``tf p (flux iq_ref + (Ld - Lq) id_ref iq_ref)``.

Every operation is a correctly rounded IEEE operation (gcc's ``-std=c99``
does not contract multiply-adds into FMAs, numba without ``fastmath``
neither) or a call of the same glibc ``hypot``, ``cos``, ``sin`` in the same
process environment, so the builds of that arithmetic print the final speed
and mean-square torque error of ``simulate()`` bit for bit
(:data:`C_BUILDS` tolerance 0). The ``DIVIDE`` build divides by Ld, Lq, J
in every stage (the model as written): each derivative then rounds once
less (<= 1 ulp apart), and its results may differ from ours in the last
bit; measured over horizons of 0.01 to 1 s: the same bits at 0.03, 0.05,
0.1, 0.2, 0.5 and 1 s, 1.7e-16 relative (final speed, 10 ms) and 2.3e-16
(mse_torque, 60 ms) otherwise: the stable loop contracts the roundings
instead of accumulating them. :data:`DIVIDE_RTOL` = 1e-13 leaves a factor
~400 over that and is 1e11 times below the 2.5e-2 of a loop that places
the voltage elsewhere (the yardstick before this one applied the delayed
``v_dq`` unrotated, while the kernel, given ``t_c = 0``, rotated it by its
placement error, ~``-(d + 1/2) Ts w``: 219.50 against 214.09 rad/s after 1 s).
"""

from __future__ import annotations

import math
import os
import shutil
import subprocess

from toolbox.artifact import Decoupling
from toolbox.spec import Motor, Scenario
from toolbox.sim import ControlLaw, DriveParams, discrete_pi

M = Motor(R=0.6, Ld=1.4e-3, Lq=2.8e-3, flux=0.12, pole_pairs=4,
          J=1.11e-3, friction=1.4e-3, convention="power")
TS, H, WC, VDC, IQ_REF, DURATION = 1e-4, 1e-6, 2000.0, 150.0, 10.0, 1.0
DELAY = 1
#: The placement time of ``drive.angle_compensation = "mid_period"``
#: (``toolbox.spec.Drive.angle_compensation_time``): ``(d + 1/2) Ts``.
T_COMP = (DELAY + 0.5) * TS
V_MAX = VDC / math.sqrt(2.0)
LAW = ControlLaw(d=discrete_pi(M.Ld * WC, M.R * WC, TS), q=discrete_pi(M.Lq * WC, M.R * WC, TS),
                 sample_time=TS,
                 decoupling=Decoupling.from_motor(M, delay_compensation_time=T_COMP))
DRIVE = DriveParams(vdc=VDC, sample_time=TS, delay_samples=DELAY, v_limit="circle",
                    v_max=V_MAX, hold_frame="rotor")

#: Relative tolerance of the dividing build (module docstring).
DIVIDE_RTOL = 1e-13

#: The C builds: (label, gcc flags, relative tolerance against ours). The
#: loop of the kernel's arithmetic at -O2 and -O3 -march=native (bit for
#: bit: tolerance 0), and the model as written, dividing by Ld, Lq, J in
#: every stage (the yardstick before the kernel multiplied by reciprocals).
C_BUILDS = (("C -O2", ("-O2",), 0.0),
            ("C -O3 -march=native", ("-O3", "-march=native"), 0.0),
            ("C -O3 -march=native /L", ("-O3", "-march=native", "-DDIVIDE"), DIVIDE_RTOL))


def scenario(duration: float = DURATION) -> Scenario:
    """The benchmark's scenario over ``duration`` seconds."""
    return Scenario(kind="unloaded_start", duration=duration, iq_ref=IQ_REF, plant_step=H)


C_SOURCE = r"""
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <time.h>
static const double R=%(R)r, Ld=%(Ld)r, Lq=%(Lq)r, FL=%(flux)r, P=%(p)r, J=%(J)r, FR=%(fr)r, TF=%(tf)r;
#ifdef DIVIDE  /* the model as written: one division per equation and stage */
#define OVER(l, v) (v) / (l)
#else          /* as toolbox.sim's kernel: times the reciprocal, computed once */
#define OVER(l, v) (v) * (1.0 / (l))
#endif
static void f(const double *x, double vd, double vq, double *dx) {
  double w = P * x[2];
  dx[0] = OVER(Ld, vd - R * x[0] + w * Lq * x[1]);
  dx[1] = OVER(Lq, vq - R * x[1] - w * Ld * x[0] - w * FL);
  dx[2] = OVER(J, TF * P * (FL * x[1] + (Ld - Lq) * x[0] * x[1]) - FR * x[2]);
  dx[3] = w;
}
int main(void) {
  const double Ts = %(Ts)r, h = %(h)r, vmax = %(vmax)r, tc = %(tc)r;
  const double idr = %(idr)r, iqr = %(iqr)r;
  const double kpd = %(kpd)r, kid = %(kid)r, awd = %(awd)r;
  const double kpq = %(kpq)r, kiq = %(kiq)r, awq = %(awq)r;
  const long nper = %(nper)d; const int nsub = %(nsub)d;
  const double tref = TF * P * (FL * iqr + (Ld - Lq) * idr * iqr);
  double x[4] = {0, 0, 0, 0}, k1[4], k2[4], k3[4], k4[4], xt[4];
  double xd = 0, xq = 0, sq = 0;
  double vd_app = 0, vq_app = 0, ph_app = 0;  /* one-period delay line */
  struct timespec t0, t1; clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t0);
  for (long k = 0; k < nper; ++k) {
    double idm = x[0], iqm = x[1], thm = x[3], wm = P * x[2];
    /* the axis laws v = D [r, y] + C x, then the decoupling */
    double ud = kpd * idr + (-kpd) * idm; ud += kid * xd;
    double uq = kpq * iqr + (-kpq) * iqm; uq += kiq * xq;
    double vd = ud - wm * Lq * iqm;
    double vq = uq + wm * Ld * idm + wm * FL;
    double vds = vd, vqs = vq, mag = hypot(vd, vq);
    if (mag > vmax) { vds = vd * vmax / mag; vqs = vq * vmax / mag; }
    /* x+ = (B [r, y] + aw (v_sat - v)) + A x, A = 1: Hanus, aw = Ts / Kp */
    xd = (Ts * idr + (-Ts) * idm + awd * (vds - vd)) + xd;
    xq = (Ts * iqr + (-Ts) * iqm + awq * (vqs - vq)) + xq;
    /* the voltage of period k - 1, placed at its sampled angle + tc w,
       held in the rotor frame: rotated by its error from the true
       mid-period angle of this period */
    double err = ph_app - (thm + P * x[2] * Ts * 0.5);
    double c = cos(err), s = sin(err);
    double va = vd_app * c - vq_app * s, vb = vd_app * s + vq_app * c;
    vd_app = vds; vq_app = vqs; ph_app = thm + tc * wm;
    for (int j = 0; j < nsub; ++j) {
      double T = TF * P * (FL * x[1] + (Ld - Lq) * x[0] * x[1]);
      double e = T - tref; sq += e * e * h;
      f(x, va, vb, k1);
      for (int i = 0; i < 4; ++i) xt[i] = x[i] + 0.5 * h * k1[i];
      f(xt, va, vb, k2);
      for (int i = 0; i < 4; ++i) xt[i] = x[i] + 0.5 * h * k2[i];
      f(xt, va, vb, k3);
      for (int i = 0; i < 4; ++i) xt[i] = x[i] + h * k3[i];
      f(xt, va, vb, k4);
      for (int i = 0; i < 4; ++i) x[i] += h / 6.0 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
    }
  }
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t1);
  double el = (t1.tv_sec - t0.tv_sec) + 1e-9 * (t1.tv_nsec - t0.tv_nsec);
  printf("%%.17g %%.17g %%.17g %%.17g %%.17g\n", el, x[0], x[1], x[2], sq / (nper * Ts));
  return 0;
}
"""


def c_source(duration: float = DURATION, law: ControlLaw = LAW) -> str:
    """:data:`C_SOURCE` with the scenario's numbers over ``duration`` seconds:
    the PI gains, anti-windup gains and placement time ``t_c`` read from
    ``law`` (:data:`LAW` or a variant of it: PI axes with decoupling), the
    plant step split as the kernel splits a period (``_kernel_steps._split``)."""
    nsub = max(1, math.ceil(TS / H - 1e-9))
    d, q = law.d, law.q
    for name, ax in (("d", d), ("q", q)):  # the C loop hard-codes discrete_pi's form
        if not (ax.A.tolist() == [[1.0]] and ax.B.tolist() == [[TS, -TS]]
                and ax.D[0, 1] == -ax.D[0, 0] and ax.antiwindup is not None):
            raise ValueError(f"law.{name}: a discrete_pi with anti-windup at Ts = {TS} s "
                             f"expected, found A {ax.A.tolist()}, B {ax.B.tolist()}")
    if not (law.decoupling.cross and law.decoupling.emf and law.cv is None
            and law.speed_loop is None and law.fcs is None):
        raise ValueError("law: PI axes with cross and EMF decoupling expected")
    return C_SOURCE % dict(
        R=M.R, Ld=M.Ld, Lq=M.Lq, flux=M.flux, p=float(M.pole_pairs), J=M.J, fr=M.friction,
        tf=M.torque_factor, Ts=TS, h=TS / nsub, vmax=V_MAX,
        tc=law.decoupling.delay_compensation_time, idr=0.0, iqr=IQ_REF,
        kpd=float(d.D[0, 0]), kid=float(d.C[0, 0]), awd=float(d.antiwindup[0]),
        kpq=float(q.D[0, 0]), kiq=float(q.C[0, 0]), awq=float(q.antiwindup[0]),
        nper=int(round(duration / TS)), nsub=nsub)


def compile_c(directory: str, flags=("-O2",), duration: float = DURATION,
              law: ControlLaw = LAW):
    """Compile the C loop of ``law`` over ``duration`` with ``flags`` into
    ``directory``; (exe, None) or (None, reason)."""
    gcc = shutil.which("gcc")
    if gcc is None:
        return None, "gcc not found"
    tag = "".join(c for c in "".join(flags) if c.isalnum())
    c_path, exe = os.path.join(directory, f"loop{tag}.c"), os.path.join(directory, f"loop{tag}")
    with open(c_path, "w") as fh:
        fh.write(c_source(duration, law))
    subprocess.run([gcc, *flags, "-std=c99", "-o", exe, c_path, "-lm"], check=True)
    return exe, None


def run_c(exe: str) -> list[float]:
    """One run of a compiled loop: [its loop's CPU s, id, iq, final speed, mse_torque]."""
    return [float(v) for v in subprocess.run([exe], check=True, capture_output=True,
                                             text=True).stdout.split()]


class YardstickMismatch(AssertionError):
    """The C loop computed another closed loop than ``simulate()``."""


def check_agreement(label: str, ours: tuple[float, float], other: tuple[float, float],
                    rtol: float) -> str:
    """Raise :class:`YardstickMismatch` unless the C build's (final speed,
    mse_torque) equals ours bit for bit (``rtol`` 0) or within ``rtol``
    relative; return the agreement as printed."""
    if ours == other:
        return "same bits as ours"
    rel = max(abs(a - b) / max(abs(a), abs(b)) for a, b in zip(ours, other))
    if not rel <= rtol:  # NaN fails too
        want = "bit for bit" if rtol == 0.0 else f"within {rtol:.0e} relative"
        raise YardstickMismatch(
            f"{label}: (final speed, mse_torque) = {other!r}, ours {ours!r}: differs by "
            f"{rel:.1e} relative, expected {want}: the C loop no longer computes the "
            "kernel's closed loop (tests/benchmarks/sim_c_loop.py), its ratio is meaningless")
    return f"differs from ours by {rel:.1e} relative (tolerance {rtol:.0e})"
