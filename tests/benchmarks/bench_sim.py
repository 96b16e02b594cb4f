"""Closed-loop simulation benchmark (toolbox.sim) against the peers a user would pick.

Scenario (identical for every route; ``sim_c_loop``): 1 s of an i_q step to
10 A at t = 0 with free acceleration (unloaded start) of the Le Pioufle 1992
motor (paper 000), dq PI current controllers (Kp = L wc, Ki = R wc, wc =
2000 rad/s, forward-Euler integrator, Hanus anti-windup aw = Ts/Kp as
toolbox.sim.discrete_pi) with decoupling, Ts = 100 us, one period of
computation delay, the voltage placed at (d + 1/2) Ts (``drive.angle_compensation
= "mid_period"``, the default of every design; toolbox/ARCHITECTURE.md "The
digital loop") and held in the rotor frame, circle voltage limit vdc/sqrt(2)
(vdc = 150 V), plant integrated by RK4 at 1 us.

Routes:
1. ours: toolbox.sim.simulate (numba kernel, metrics only);
2. a plain C loop of the same closed loop, operation for operation in the
   kernel's order (``sim_c_loop.C_SOURCE``: the axis laws in their
   state-space form, the decoupling, the radial limit, the delay line of the
   voltage and of its placement angle, the rotation of the held voltage by
   its placement error, RK4, the torque error), written to a temporary
   directory and compiled here, with the motor's numbers as compile-time
   constants (ours reads them at run time and also accumulates the id/iq
   errors, step metrics, the saturation time and a load torque, which the C
   loop does not). Three builds (``sim_c_loop.C_BUILDS``): -O2 and -O3
   -march=native of the loop with ours' arithmetic (the derivatives times
   1/Ld, 1/Lq, 1/J, no FMA contraction: gcc's -std=c99 does not contract,
   numba without fastmath neither; glibc's hypot, cos, sin as ours), which
   must print ours' final speed and mean-square torque error bit for bit;
   and -O3 -march=native of the model as written, dividing by Ld, Lq, J in
   every stage (the yardstick before the kernel took reciprocals), which
   must agree within ``sim_c_loop.DIVIDE_RTOL`` = 1e-13 relative (its
   derivatives round differently: the same bits or 1-2 ulp measured).
   Checked on a run of each before the timing and on every timed run: a
   build that computes another closed loop raises
   ``sim_c_loop.YardstickMismatch`` (the benchmark stops, exit status 1)
   instead of printing a ratio against something else;
   ``tests/sim/test_bench_c_loop.py`` checks the same on 60 ms. The
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
   ratio is the median of the per-round ratios with its interquartile range.
   Measured on the shared 2-core machine (load average 3.3 at the start,
   3.7 at the end of the run; gcc 12): ours 40.0 ns CPU per plant step
   (IQR 38.9-41.5), ours / C -O2 = 1.95 [IQR 1.87..1.96], ours / C -O3
   -march=native = 0.925 [0.900..0.931], ours / dividing -O3 -march=native
   = 1.35 [1.28..1.37]; all ten runs of each build the same bits as ours
   (the dividing build too, this run); placement and rotation cost the C
   loop nothing measurable (one cos and sin per 100 plant steps);
3. scipy.integrate.solve_ivp (RK45, rtol 1e-8, atol 1e-10) once per control
   period (the same law, placement and hold), run on a shorter horizon and
   reported per simulated second;
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
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from _timing import fmt_ratio, fmt_time, interleaved, pin_blas_threads, quartiles  # noqa: E402

pin_blas_threads(1)  # before numpy: the batch's parallelism is numba's, not BLAS's

import numpy as np  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))

from toolbox.sim import simulate, simulate_batch  # noqa: E402
from toolbox.spec import Scenario  # noqa: E402
from sim_c_loop import (C_BUILDS, DELAY, DRIVE, DURATION, H, IQ_REF, LAW, M, T_COMP,  # noqa: E402
                        TS, V_MAX, WC, check_agreement, compile_c, run_c, scenario)


def ours_route():
    """Warm the kernel; return a route timing one 1 s simulation and its result holder."""
    sc = scenario(DURATION)
    simulate(LAW, M, scenario(1e-3), DRIVE)
    last = {"cpu": [], "wall": []}

    def run():
        t0, c0 = time.perf_counter(), time.process_time()
        last["metrics"] = simulate(LAW, M, sc, DRIVE).metrics
        last["cpu"].append(time.process_time() - c0)
        last["wall"].append(time.perf_counter() - t0)

    return run, last


def c_route(exe: str):
    """A route running the compiled loop; it returns the loop's own elapsed time
    (process start-up excluded) and keeps every run's printed state in ``last["outs"]``."""
    last = {"outs": []}

    def run() -> float:
        vals = run_c(exe)
        last["outs"].append(vals)
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
    v_app, ph_app = (0.0, 0.0), 0.0
    n = int(round(horizon / TS))
    t0 = time.process_time()
    for k in range(n):
        idm, iqm, thm, wm = x[0], x[1], x[3], p * x[2]
        ed, eq = -idm, IQ_REF - iqm
        vd = kpd * ed + kid * xd - wm * Lq * iqm
        vq = kpq * eq + kiq * xq + wm * Ld * idm + wm * fl
        mag = math.hypot(vd, vq)
        s = V_MAX / mag if mag > V_MAX else 1.0
        xd += TS * ed + (vd * s - vd) * TS / kpd
        xq += TS * eq + (vq * s - vq) * TS / kpq
        # the delayed voltage, placed at its sample's angle + T_COMP w and held
        # in the rotor frame: rotated by its error from the mid-period angle
        err = ph_app - (thm + wm * TS * 0.5)
        c, sn = math.cos(err), math.sin(err)
        v_rot = (v_app[0] * c - v_app[1] * sn, v_app[0] * sn + v_app[1] * c)
        sol = solve_ivp(rhs, (k * TS, (k + 1) * TS), x, args=v_rot, rtol=1e-8, atol=1e-10)
        x = sol.y[:, -1]
        v_app, ph_app = (vd * s, vq * s), thm + T_COMP * wm
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
          f"Ts {TS} s, delay {DELAY}, voltage placed at (d + 1/2) Ts = {T_COMP} s, "
          f"rotor-frame hold, plant RK4 at {H} s\n")
    ours_run, ours_last = ours_route()
    routes = {"ours": ours_run}
    c_last, c_tol = {}, {}
    with tempfile.TemporaryDirectory() as d:
        for label, flags, rtol in C_BUILDS:
            exe, why = compile_c(d, flags)
            if exe is None:
                print(f"plain C loop ({label}): skipped ({why})")
                continue
            routes[label], c_last[label] = c_route(exe)
            c_tol[label] = rtol
        # one run of each before the timing: a yardstick that computes another
        # closed loop fails here, before its ratio is timed (YardstickMismatch)
        for route in routes.values():
            route()
        m = ours_last["metrics"]
        ours_end = (m["final_speed"], m["mse_torque"])
        for label, last in c_last.items():
            out = last["outs"][0]
            check_agreement(label, ours_end, (out[3], out[4]), c_tol[label])
        ours_last["cpu"].clear()
        ours_last["wall"].clear()
        times = interleaved(routes, rounds=9, quiet_gc=True)
    rate = {k: DURATION / quartiles(v)[1] for k, v in times.items()}
    # every timed run checked too: ours' last, each C run
    m = ours_last["metrics"]
    if (m["final_speed"], m["mse_torque"]) != ours_end:
        raise RuntimeError(f"ours is not deterministic: {(m['final_speed'], m['mse_torque'])!r}"
                           f" after {ours_end!r}")
    print(f"ours (numba)          : {rate['ours']:10.2f} simulated s / CPU s, median of "
          f"{len(times['ours'])} (final speed {ours_end[0]:.6f} rad/s, "
          f"mse_torque {ours_end[1]:.6g})")
    for label, last in c_last.items():
        said = {check_agreement(label, ours_end, (o[3], o[4]), c_tol[label])
                for o in last["outs"]}
        out = last["outs"][-1]
        print(f"{label:22s}: {rate[label]:10.2f} simulated s / CPU s "
              f"(final speed {out[3]:.6f} rad/s, mse_torque {out[4]:.6g}; "
              f"{'; '.join(sorted(said))}, all {len(last['outs'])} runs)")
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
