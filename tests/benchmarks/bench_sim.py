"""Closed-loop simulation benchmark (toolbox.sim) against the peers a user would pick.

Scenario (identical for every route): 1 s of an i_q step to 10 A at t = 0 with
free acceleration (unloaded start) of the Le Pioufle 1992 motor (paper 000),
dq PI current controllers (Kp = L wc, Ki = R wc, wc = 2000 rad/s, forward-Euler
integrator, Hanus anti-windup aw = Ts/Kp as toolbox.sim.discrete_pi) with decoupling, Ts = 100 us, one
period of computation delay, circle voltage limit vdc/sqrt(2) (vdc = 150 V),
plant integrated by RK4 at 1 us.

Routes:
1. ours: toolbox.sim.simulate (numba kernel, metrics only);
2. a plain C loop of the same model, integrator and step, written to a
   temporary directory and compiled here, with the motor's numbers as
   compile-time constants (ours reads them at run time and also accumulates
   the id/iq errors, step metrics and a load torque, which the C loop does
   not). Three builds (:data:`C_BUILDS`): -O2 and -O3 -march=native of the
   loop with ours' arithmetic (the derivatives times 1/Ld, 1/Lq, 1/J, no FMA
   contraction: gcc's -std=c99 does not contract, numba without fastmath
   neither), which print the same final speed and mean-square torque error
   as ours bit for bit, so the two compute the same thing; and -O3
   -march=native of the model as written, dividing by Ld, Lq, J in every
   stage (the yardstick before the kernel took reciprocals; its
   currents differ from ours in the last bits, its final speed and torque
   error agree to the 17 digits printed, checked at every run). The
   ratio against the same-arithmetic -O3 build is the compiler comparison;
   the one against the dividing build includes the reciprocals' gain, which
   a C author can have as well. Ours and the C builds are run alternately
   (ours, C..., ours, ...), each timed by its own process CPU time (the C
   loop reads CLOCK_PROCESS_CPUTIME_ID around its loop; see ``_timing`` for
   why not the wall clock; ours' wall time per call is printed too), with
   Python's cyclic garbage collector run once before the rounds and off
   through them (``interleaved(quiet_gc=True)``, as ``timeit``: the
   collections of what the C routes' ``subprocess`` calls left behind
   otherwise landed in ours' calls, 0.3-0.4 ms of a 26 ms call; a
   collection before every turn cost ours 3-4 % instead, see ``_timing``); each
   ratio is the median of the per-round ratios with its interquartile range;
3. scipy.integrate.solve_ivp (RK45, rtol 1e-8, atol 1e-10) once per control
   period, run on a shorter horizon and reported per simulated second;
4. gym-electric-motor, if installed (skipped with a message otherwise): its
   ``Cont-CC-PMSM-v0`` environment at default settings (its own motor and
   random references, so only the rate compares), 1 s of its 100 us steps
   driven by a dq PI agent (see :func:`bench_gem`);
5. a batch of 10,000 closed-loop simulations of 20 ms (parameter sweep on
   R, Ld, Lq) on all cores, with a tqdm progress bar.

Run: ``python tests/benchmarks/bench_sim.py`` (from the repository root).
"""

from __future__ import annotations

import math
import os
import shutil
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from _timing import fmt_ratio, fmt_time, interleaved, pin_blas_threads, quartiles  # noqa: E402

pin_blas_threads(1)  # before numpy: the batch's parallelism is numba's, not BLAS's

import numpy as np  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))

from toolbox.spec import Scenario  # noqa: E402
from toolbox.spec import Motor  # noqa: E402
from toolbox.artifact import Decoupling  # noqa: E402
from toolbox.sim._simulate import (ControlLaw, DriveParams,  # noqa: E402
                                   discrete_pi, simulate, simulate_batch)

M = Motor(R=0.6, Ld=1.4e-3, Lq=2.8e-3, flux=0.12, pole_pairs=4,
          J=1.11e-3, friction=1.4e-3, convention="power")
TS, H, WC, VDC, IQ_REF, DURATION = 1e-4, 1e-6, 2000.0, 150.0, 10.0, 1.0
V_MAX = VDC / math.sqrt(2.0)
LAW = ControlLaw(d=discrete_pi(M.Ld * WC, M.R * WC, TS), q=discrete_pi(M.Lq * WC, M.R * WC, TS),
                 sample_time=TS, decoupling=Decoupling.from_motor(M))
DRIVE = DriveParams(vdc=VDC, sample_time=TS, delay_samples=1, v_limit="circle", v_max=V_MAX)


def ours_route():
    """Warm the kernel; return a route timing one 1 s simulation and its result holder."""
    sc = Scenario(kind="unloaded_start", duration=DURATION, iq_ref=IQ_REF, plant_step=H)
    simulate(LAW, M, Scenario(kind="unloaded_start", duration=1e-3, iq_ref=IQ_REF), DRIVE)
    last = {"cpu": [], "wall": []}

    def run():
        t0, c0 = time.perf_counter(), time.process_time()
        last["metrics"] = simulate(LAW, M, sc, DRIVE).metrics
        last["cpu"].append(time.process_time() - c0)
        last["wall"].append(time.perf_counter() - t0)

    return run, last


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
  const double Ts = %(Ts)r, h = %(h)r, vmax = %(vmax)r, iqr = %(iqr)r, idr = 0.0;
  const double kpd = %(kpd)r, kid = %(kid)r, kpq = %(kpq)r, kiq = %(kiq)r;
  const long nper = %(nper)d; const int nsub = %(nsub)d;
  double x[4] = {0, 0, 0, 0}, k1[4], k2[4], k3[4], k4[4], xt[4];
  double xd = 0, xq = 0, vd_app = 0, vq_app = 0, sq = 0;
  struct timespec t0, t1; clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t0);
  for (long k = 0; k < nper; ++k) {
    double idm = x[0], iqm = x[1], wm = P * x[2];
    double ed = idr - idm, eq = iqr - iqm;
    double vd = kpd * ed + kid * xd - wm * Lq * iqm;
    double vq = kpq * eq + kiq * xq + wm * Ld * idm + wm * FL;
    double mag = hypot(vd, vq), s = mag > vmax ? vmax / mag : 1.0;
    double vds = vd * s, vqs = vq * s;
    xd += Ts * ed + (vds - vd) * Ts / kpd;   /* Hanus: aw = Ts / Kp */
    xq += Ts * eq + (vqs - vq) * Ts / kpq;
    double vda = vd_app, vqa = vq_app;      /* one-period delay */
    vd_app = vds; vq_app = vqs;
    for (int j = 0; j < nsub; ++j) {
      double T = TF * P * (FL * x[1] + (Ld - Lq) * x[0] * x[1]);
      double e = T - TF * P * FL * iqr; sq += e * e * h;
      f(x, vda, vqa, k1);
      for (int i = 0; i < 4; ++i) xt[i] = x[i] + 0.5 * h * k1[i];
      f(xt, vda, vqa, k2);
      for (int i = 0; i < 4; ++i) xt[i] = x[i] + 0.5 * h * k2[i];
      f(xt, vda, vqa, k3);
      for (int i = 0; i < 4; ++i) xt[i] = x[i] + h * k3[i];
      f(xt, vda, vqa, k4);
      for (int i = 0; i < 4; ++i) x[i] += h / 6.0 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
    }
  }
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t1);
  double el = (t1.tv_sec - t0.tv_sec) + 1e-9 * (t1.tv_nsec - t0.tv_nsec);
  printf("%%.17g %%.17g %%.17g %%.17g %%.17g\n", el, x[0], x[1], x[2], sq / (nper * Ts));
  return 0;
}
"""


def compile_c(directory: str, flags=("-O2",)):
    """Compile the C loop with ``flags`` into ``directory``; (exe, None) or (None, reason)."""
    gcc = shutil.which("gcc")
    if gcc is None:
        return None, "gcc not found"
    src = C_SOURCE % dict(R=M.R, Ld=M.Ld, Lq=M.Lq, flux=M.flux, p=float(M.pole_pairs),
                          J=M.J, fr=M.friction, tf=M.torque_factor, Ts=TS, h=H, vmax=V_MAX,
                          iqr=IQ_REF, kpd=M.Ld * WC, kid=M.R * WC, kpq=M.Lq * WC,
                          kiq=M.R * WC, nper=int(round(DURATION / TS)),
                          nsub=int(round(TS / H)))
    tag = "".join(c for c in "".join(flags) if c.isalnum())
    c_path, exe = os.path.join(directory, f"loop{tag}.c"), os.path.join(directory, f"loop{tag}")
    with open(c_path, "w") as fh:
        fh.write(src)
    subprocess.run([gcc, *flags, "-std=c99", "-o", exe, c_path, "-lm"], check=True)
    return exe, None


#: The C builds timed against ours: the loop as the kernel computes (bit for
#: bit the same results, gcc's ISO C mode not contracting FMAs, as ours does
#: not) at -O2 and -O3 -march=native, and the model as written, dividing by
#: Ld, Lq, J in every stage (the yardstick before the kernel
#: multiplied by reciprocals).
C_BUILDS = (("C -O2", ("-O2",)), ("C -O3 -march=native", ("-O3", "-march=native")),
            ("C -O3 -march=native /L", ("-O3", "-march=native", "-DDIVIDE")))


def agreement(ours: tuple[float, float], other: tuple[float, float]) -> str:
    """'same bits' or the largest relative difference of (final speed, mse_torque)."""
    if ours == other:
        return "same bits as ours"
    rel = max(abs(a - b) / max(abs(a), abs(b)) for a, b in zip(ours, other))
    return f"differs from ours by {rel:.1e} relative"


def c_route(exe: str):
    """A route running the compiled loop; it returns the loop's own elapsed time
    (process start-up excluded) and keeps its printed state in ``last``."""
    last = {}

    def run() -> float:
        vals = [float(v) for v in subprocess.run([exe], check=True, capture_output=True,
                                                 text=True).stdout.split()]
        last["out"] = vals
        return vals[0]

    return run, last


def bench_scipy(horizon=0.05):
    from scipy.integrate import solve_ivp

    p, R, Ld, Lq, fl, J, fr, tf = (M.pole_pairs, M.R, M.Ld, M.Lq, M.flux, M.J,
                                   M.friction, M.torque_factor)

    def rhs(t, x, vd, vq):
        w = p * x[2]
        return [(vd - R * x[0] + w * Lq * x[1]) / Ld,
                (vq - R * x[1] - w * Ld * x[0] - w * fl) / Lq,
                (tf * p * (fl * x[1] + (Ld - Lq) * x[0] * x[1]) - fr * x[2]) / J, w]

    kpd, kid, kpq, kiq = M.Ld * WC, M.R * WC, M.Lq * WC, M.R * WC
    x = np.zeros(4)
    xd = xq = 0.0
    v_app = (0.0, 0.0)
    n = int(round(horizon / TS))
    t0 = time.process_time()
    for k in range(n):
        idm, iqm, wm = x[0], x[1], p * x[2]
        ed, eq = -idm, IQ_REF - iqm
        vd = kpd * ed + kid * xd - wm * Lq * iqm
        vq = kpq * eq + kiq * xq + wm * Ld * idm + wm * fl
        mag = math.hypot(vd, vq)
        s = V_MAX / mag if mag > V_MAX else 1.0
        xd += TS * ed + (vd * s - vd) * TS / kpd
        xq += TS * eq + (vq * s - vq) * TS / kpq
        sol = solve_ivp(rhs, (k * TS, (k + 1) * TS), x, args=v_app, rtol=1e-8, atol=1e-10)
        x = sol.y[:, -1]
        v_app = (vd * s, vq * s)
    el = time.process_time() - t0
    return horizon / el, x


def bench_gem(duration=DURATION, wc=WC):
    """gym-electric-motor's ``Cont-CC-PMSM-v0`` at its default settings.

    Its own motor (p = 3, Ld 0.37 mH, Lq 1.2 mH, R 18 mOhm, psi 66 mWb),
    300 V ideal supply, averaged B6 bridge, speed held at 100 rad/s by its
    ConstantSpeedLoad, scipy ``ode`` dopri5 solver, tau = 100 us, random
    (Wiener-process) i_sd/i_sq references; episodes that hit its current limit
    are reset. The agent is a dq PI with decoupling (Kp = L wc, Ki = R wc,
    Hanus anti-windup aw = tau/Kp, circle limit u_sup/2), inverse Park at the
    step's mean angle, duty cycles u_abc / (u_sup/2). ``duration / tau`` steps.
    The tracking error only shows that the agent closes the loop: the default
    random-walk references move ~1 A per step (median, up to ~30 A) and differ
    from run to run (median errors of 17-24 A seen).

    Returns ``None`` if the package is missing, else
    (simulated s per CPU s, median |i_dq error| (A), resets, tau (s), solver).
    """
    try:
        import gym_electric_motor as gem
    except ImportError:
        return None
    env = gem.make("Cont-CC-PMSM-v0")
    ps = env.unwrapped.physical_system
    tau, lim, names = ps.tau, ps.limits, ps.state_names
    ix = {n: names.index(n) for n in ("omega", "i_sd", "i_sq", "epsilon", "u_sup")}
    mp = ps.electrical_motor.motor_parameter
    p, R, Ld, Lq, psi = mp["p"], mp["r_s"], mp["l_d"], mp["l_q"], mp["psi_p"]
    i_lim = lim[ix["i_sd"]]
    (state, ref), _ = env.reset(seed=0)
    xd = xq = 0.0
    n = int(round(duration / tau))
    errs = np.empty(n)
    resets = 0
    t0 = time.process_time()
    for k in range(n):
        u_half = 0.5 * state[ix["u_sup"]] * lim[ix["u_sup"]]
        i_d, i_q = state[ix["i_sd"]] * i_lim, state[ix["i_sq"]] * i_lim
        e_d, e_q = ref[0] * i_lim - i_d, ref[1] * i_lim - i_q
        errs[k] = math.hypot(e_d, e_q)
        w = p * state[ix["omega"]] * lim[ix["omega"]]
        v_d = Ld * wc * e_d + R * wc * xd - w * Lq * i_q
        v_q = Lq * wc * e_q + R * wc * xq + w * (Ld * i_d + psi)
        mag = math.hypot(v_d, v_q)
        sc = min(1.0, u_half / mag) if mag > 0 else 1.0
        xd += tau * e_d + (sc - 1.0) * v_d * tau / (Ld * wc)
        xq += tau * e_q + (sc - 1.0) * v_q * tau / (Lq * wc)
        eps = state[ix["epsilon"]] * math.pi + 0.5 * w * tau
        u_abc = np.asarray(ps.dq_to_abc_space((sc * v_d, sc * v_q), eps)) / u_half
        (state, ref), _, term, trunc, _ = env.step(np.clip(u_abc, -1.0, 1.0))
        if term or trunc:
            resets += 1
            (state, ref), _ = env.reset()
            xd = xq = 0.0
    el = time.process_time() - t0
    env.close()
    return (duration / el, float(np.median(errs)), resets, tau,
            type(ps._ode_solver).__name__)


def bench_batch(n=10_000, duration=0.02):
    from tqdm import tqdm
    rng = np.random.default_rng(0)
    plants = {"R": M.R * rng.uniform(0.8, 1.2, n), "Ld": M.Ld * rng.uniform(0.5, 2.0, n),
              "Lq": M.Lq * rng.uniform(0.5, 2.0, n), "flux": M.flux,
              "pole_pairs": M.pole_pairs, "J": M.J, "friction": M.friction,
              "torque_factor": M.torque_factor}
    sc = Scenario(kind="unloaded_start", duration=duration, iq_ref=IQ_REF, step_time=0.001)
    # warm-up (load the compiled kernel) outside the timing
    simulate_batch(LAW, {k: (v[:4] if np.ndim(v) else v) for k, v in plants.items()},
                   sc, DRIVE)
    # a bar on a terminal only: in a log, tqdm's carriage returns garble the report
    bar = tqdm(total=n, unit="sim", desc="batch", disable=not sys.stderr.isatty())
    last = [0]

    def progress(done, total):
        bar.update(done - last[0])
        last[0] = done

    # wall clock here: the batch runs on several threads (CPU time would add them up)
    t0 = time.perf_counter()
    out = simulate_batch(LAW, plants, sc, DRIVE, progress=progress, chunk=200)
    el = time.perf_counter() - t0
    bar.close()
    # the same number of simulations one after the other on one core, sampled
    t1 = time.perf_counter()
    n_serial = 200
    for i in range(n_serial):
        simulate(LAW, M.with_overrides({"R": plants["R"][i], "Ld": plants["Ld"][i],
                                        "Lq": plants["Lq"][i]}), sc, DRIVE)
    serial_rate = n_serial / (time.perf_counter() - t1)
    return n / el, serial_rate, out


def main():
    import numba
    print(f"machine: {os.cpu_count()} cores, numba {numba.__version__}, "
          f"batch threads {numba.config.NUMBA_NUM_THREADS}, load average {os.getloadavg()[0]:.2f} "
          "(other processes on the machine lower every rate, the parallel batch most)")
    print(f"scenario: {DURATION} s unloaded start, iq_ref {IQ_REF} A, PI wc {WC} rad/s, "
          f"Ts {TS} s, delay 1, plant RK4 at {H} s\n")
    ours_run, ours_last = ours_route()
    routes = {"ours": ours_run}
    c_last = {}
    with tempfile.TemporaryDirectory() as d:
        for label, flags in C_BUILDS:
            exe, why = compile_c(d, flags)
            if exe is None:
                print(f"plain C loop ({label}): skipped ({why})")
                continue
            routes[label], c_last[label] = c_route(exe)
        times = interleaved(routes, rounds=9, quiet_gc=True)
    rate = {k: DURATION / quartiles(v)[1] for k, v in times.items()}
    m = ours_last["metrics"]
    ours_end = (m["final_speed"], m["mse_torque"])
    print(f"ours (numba)          : {rate['ours']:10.2f} simulated s / CPU s, median of "
          f"{len(times['ours'])} (final speed {ours_end[0]:.6f} rad/s, "
          f"mse_torque {ours_end[1]:.6g})")
    for label, last in c_last.items():
        out = last["out"]
        print(f"{label:22s}: {rate[label]:10.2f} simulated s / CPU s "
              f"(final speed {out[3]:.6f} rad/s, mse_torque {out[4]:.6g}; "
              f"{agreement(ours_end, (out[3], out[4]))})")
    steps = DURATION / H
    print(f"ours per call, ns per plant step: CPU {fmt_time(ours_last['cpu'], 1e9 / steps, 'ns')}"
          f", wall {fmt_time(ours_last['wall'], 1e9 / steps, 'ns')} (wall above CPU: "
          "waiting for a core: the slow spells of docs/performance.md)")
    sp_rate, _ = bench_scipy()
    print(f"scipy solve_ivp/period: {sp_rate:10.4f} simulated s / CPU s (RK45, 50 ms run)")
    gem = bench_gem()
    if gem is None:
        print("gym-electric-motor    : skipped (not installed: pip install gym-electric-motor)")
    else:
        gem_rate, gem_err, gem_resets, gem_tau, gem_solver = gem
        print(f"gym-electric-motor    : {gem_rate:10.4f} simulated s / CPU s (Cont-CC-PMSM-v0 "
              f"defaults: its own motor, {gem_solver}, tau {gem_tau} s, {DURATION} s = "
              f"{int(round(DURATION / gem_tau))} steps, dq PI agent; median |i_dq error| "
              f"{gem_err:.2f} A, {gem_resets} episode reset(s))")
    print("\nratios (speed, ours / other; >1 means ours is faster):")
    for label in c_last:
        # speed ratio = time ratio inverted: other_i / ours_i per round
        print(f"  ours / {label:22s} = {fmt_ratio(times[label], times['ours'], 3)}")
    ours = rate["ours"]
    print(f"  ours / scipy  = {ours / sp_rate:8.1f} (one run each: order of magnitude only)")
    if gem is not None:
        print(f"  ours / gym-electric-motor = {ours / gem[0]:8.1f} (different motor and "
              "scenario: a rate comparison only)")
    rate, serial, out = bench_batch()
    print(f"\nbatch: 10000 sims of 20 ms in parallel: {rate:8.1f} sims/s "
          f"({rate * 0.02:.2f} simulated s / wall s); serial simulate(): {serial:.1f} sims/s; "
          f"parallel speed-up {rate / serial:.2f}x")
    rt = out.metrics["response_time_5pct"]
    print(f"  response time over the sweep: min {np.nanmin(rt) * 1e3:.3f} ms, "
          f"max {np.nanmax(rt) * 1e3:.3f} ms, unsettled {int(np.isnan(rt).sum())}")


if __name__ == "__main__":
    main()
