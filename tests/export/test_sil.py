"""Software in the loop: the exported controller.h, used exactly as its own
usage example says, behaves like the toolbox's simulator in closed loop.

DESIGN.md "The digital loop" and toolbox/ARCHITECTURE.md "controller.h",
"Inverter models". For every design of the gallery (``designs/*.toml``,
designed here) and seven variations of one key (:data:`VARIATIONS`: 003's PI
with ``rule = "complex_vector"``, which no gallery spec uses; 003's PI and
000's total compensation with its hexagon limit, both with
``drive.angle_compensation = "none"``; the complex-vector law of method
``cv`` with ``angle_compensation = "none"``, whose gains then compensate
the placement error, with ``voltage_priority = "d_axis"`` and with 0 and 2
periods of delay), the header
is compiled
(gcc -std=c99 -Wall -Wextra -Werror -pedantic -Wconversion -O2) with

* ``sil_plant.c``: a PMSM written for this test (salient dq model at an
  imposed constant speed, double-precision RK4 at Ts/200, theta = w t
  exactly; not the simulator's numba kernel), the drivers of the example
  (ADC, encoder, PWM, fault output) connected to it, the d-period delay line
  of ``pwm_apply`` (inverse Park at the SAMPLED angle, applied d periods
  later) and the average inverter held in the rotor or the stationary frame;
* the float path: the header's usage example itself
  (:func:`toolbox.export.example_source`) with its driver stand-ins and its
  ``main`` removed, so its ``control_isr`` runs verbatim;
* each integer variant the header offers (``-DCCT_FIXED_POINT``,
  ``-DCCT_MCSDK``, ``-DCCT_IQMATH``): a period routine in the example's
  image, ``sil_variants.c`` (the example shows the float path only).

The same cases run through :func:`toolbox.sim.simulate` (``current_step``:
imposed speed, same references, same drive and hold frame); the currents
sampled at every ``t_k`` are compared. Cases, with the step ``I`` = half the
current scale (``toolbox.design.current_scale``): ``i_q`` 0 -> I and ``i_d``
0 -> -I/4 at period 10, over 150 periods, at standstill, at 30 % of the base
speed ``V_max / flux`` (electrical; ``V_max`` the simulator's circle
radius) and near base speed where the steady state of the references asks
1.05 V_max, so that the voltage limit acts (checked with the simulator's
``saturation_time``; see :func:`_scales` for designs whose speed scale stays
below that speed). Each case runs with the average inverter held in the
rotor and in the stationary frame (``drive.hold_frame``).

Bounds (``I`` the step):

* float path: ``1e-3 I``. What separates the two loops there is float32
  arithmetic (relative 6e-8 on the voltages and the sampled currents, the
  wrapped angle to 4e-7 rad) and RK4 at two step sizes (local error
  ~(h/tau)^5, tau >= 0.1 ms): orders of magnitude below the bound, which
  leaves room for the loop's amplification near saturation;
* integer variants: the same ``1e-3 I`` plus what their words quantise,
  carried through the loop: ``4 (q_i + q_v / R)`` (a current word ``q_i``
  read as measurement noise reaches the current through the complementary
  sensitivity, peak <~ 2, counted twice for the reference and the
  measurement; a voltage word ``q_v`` is at most ``q_v / R`` of current in
  steady state) plus ``2 e_g I`` (the largest relative rounding ``e_g`` of
  the variant's gains and decoupling coefficients changes the transient's
  amplitude by at most that much of the step, twice for the two axes'
  coupling). ``q_i``, ``q_v`` and ``e_g`` are read from the header's macros.

``cv`` headers compute the complex-vector law's gains each period at the
measured speed (float only; the integer variants are ``#error``s, skipped):
the same harness, the same bound.

``fcs_mpc`` headers output the inverter state (gates): ``gates_apply``
holds its vector ``r_hex (s_a + a s_b + a^2 s_c)`` over the period, as the
simulator's ``fcs_mpc`` inverter does; no hold frame applies (one run).
A choice that differs on a near tie (float32 against double) would make the
trajectories part; the bound is the float path's.

Run with ``-s`` for the table of the worst deviation per design and variant.
"""

from __future__ import annotations

import math
import re
import subprocess
import tomllib
from dataclasses import replace
from functools import cache
from pathlib import Path

import numpy as np
import pytest

import export_c_helpers as C

ROOT = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent
DESIGNS = sorted(p.stem for p in (ROOT / "designs").glob("*.toml"))

def _complex_vector(data):
    data["controller"]["pi"]["rule"] = "complex_vector"


def _no_angle_compensation(data):
    data["drive"]["angle_compensation"] = "none"


def _d_axis_priority(data):
    data["drive"]["voltage_priority"] = "d_axis"


def _delay(n):
    def change(data):
        data["drive"]["delay_samples"] = n
    return change


#: gallery specs changed in one key: the complex-vector PI rule (no gallery
#: spec uses it), and no angle compensation (DELAY_COMP_TIME 0, the voltage
#: placed at the sampled angle; with a hexagon limit for 000_tc)
VARIATIONS = {"003_azaiz2007_pi+complex_vector": ("003_azaiz2007_pi", _complex_vector),
              "003_azaiz2007_pi+angle_none": ("003_azaiz2007_pi", _no_angle_compensation),
              "000_lepioufle1992_tc+angle_none": ("000_lepioufle1992_tc",
                                                  _no_angle_compensation),
              "003_azaiz2007_cv+angle_none": ("003_azaiz2007_cv", _no_angle_compensation),
              "003_azaiz2007_cv+d_axis": ("003_azaiz2007_cv", _d_axis_priority),
              "003_azaiz2007_cv+delay0": ("003_azaiz2007_cv", _delay(0)),
              "003_azaiz2007_cv+delay2": ("003_azaiz2007_cv", _delay(2))}
NAMES = DESIGNS + list(VARIATIONS)
#: Designs whose making is itself a long optimisation: tune ~20 CPU-s (its
#: optimisation over the model set and the 2,000-point dense check), robust_pi
#: ~3 CPU-s (its search over the model set); their cases run with the slow
#: tests (pytest -m slow; pyproject.toml's markers).
SLOW_DESIGNS = ("003_azaiz2007_tune", "003_azaiz2007_robust_pi")


def marked(names) -> list:
    """``names`` as parameters, those of SLOW_DESIGNS marked slow."""
    return [pytest.param(n, marks=pytest.mark.slow) if n in SLOW_DESIGNS else n for n in names]
VARIANTS = {"float": None, "q31": "CCT_FIXED_POINT", "mcsdk": "CCT_MCSDK",
            "iqmath": "CCT_IQMATH"}
#: the section of the header each variant lives in, and the macro it is switched on by
_OUTPUT_STRUCT = {"float": "cct_output_t", "q31": "cct_output_q31_t",
                  "mcsdk": "cct_output_s16_t", "iqmath": "cct_output_iq_t"}
HOLDS = ("rotor", "stationary")
N_PERIODS = 150
K_STEP = 10
N_SUB = 200                      # harness RK4 steps per period
CASES = ("standstill", "30% base", "saturating")
SATURATION = 1.05                # the saturating case's steady state asks this x V_max
FLOAT_BOUND = 1e-3               # of the step I
#: the usage example's driver stand-ins, replaced by sil_plant.c's
STAND_INS = ("adc_i_d", "adc_i_q", "adc_vdc", "encoder_speed", "encoder_theta_e",
             "fault_report")

_RESULTS: dict[tuple[str, str], dict] = {}


# ---------------------------------------------------------------- designs and headers
@cache
def _designed(name: str):
    """(spec, artifact, header text) of a gallery spec, designed here."""
    import toolbox
    from toolbox.export import write_header
    if name in VARIATIONS:
        base, change = VARIATIONS[name]
        data = tomllib.loads((ROOT / "designs" / f"{base}.toml").read_text())
        change(data)
        spec = toolbox.spec_from_dict(data)
    else:
        spec = toolbox.load_spec(ROOT / "designs" / f"{name}.toml")
    art = toolbox.design_spec(spec)
    return spec, art, write_header(art, spec.motor, spec.drive, prefix="cct_")


def _strip_function(src: str, name: str) -> str:
    """``src`` without the top-level definition of function ``name`` (its
    signature line through the matching closing brace); fails when absent,
    so a changed usage example is noticed, not silently half-replaced."""
    m = re.search(rf"^(?:static\s+)?[\w ]+\b{name}\s*\([^)]*\)\s*\{{", src, re.M)
    assert m, f"the usage example no longer defines {name}(): update sil_plant.c's drivers"
    depth, i = 0, m.end() - 1
    while True:
        depth += {"{": 1, "}": -1}.get(src[i], 0)
        i += 1
        if depth == 0:
            break
    end = src.find("\n", i)
    return src[:m.start()] + src[end + 1:]


def example_isr(header: str) -> tuple[str, str]:
    """The usage example minus its stand-ins and main (``control_isr`` and
    the state verbatim), and the init call of its main as ``sil_init``."""
    from toolbox.export import example_source
    src = example_source(header)
    init = re.search(r"\b(\w+_init)\(&(\w+)\);", src[src.index("int main"):])
    assert init, "the usage example's main no longer calls <p>init(&state)"
    gates = "gates_apply(" in src
    for fn in STAND_INS + (("gates_apply",) if gates else ("pwm_apply",)) + ("main",):
        src = _strip_function(src, fn)
    return src, f"static void sil_init(void) {{ {init.group(1)}(&{init.group(2)}); }}\n"


@cache
def _binary(name: str, variant: str, tmp: Path) -> tuple[str | None, str, bool]:
    """Compile the harness: (executable or None, compiler message, comp missing)."""
    _, art, header = _designed(name)
    d = tmp / f"{name}-{variant}"
    d.mkdir(parents=True, exist_ok=True)
    (d / "controller.h").write_text(header)
    (d / "sil_plant.c").write_text((HERE / "sil_plant.c").read_text())
    defines = []
    no_comp = False
    if variant == "float":
        isr, init = example_isr(header)
        if art.method == "fcs_mpc":
            defines.append("-DSIL_GATES")
    else:
        isr, init = (HERE / "sil_variants.c").read_text(), ""
        defines += [f"-D{VARIANTS[variant]}", f"-DSIL_{variant.upper()}"]
        no_comp = not _has_comp(header, variant)
        if no_comp:
            defines.append("-DSIL_NO_COMP")
    (d / "sil_isr.c").write_text(isr)
    (d / "sil_init.c").write_text(init)
    exe = d / "sil"
    res = subprocess.run([C.require_gcc(), *C.CFLAGS, *defines, "-I", str(d),
                          str(d / "sil_plant.c"), "-o", str(exe), "-lm"],
                         capture_output=True, text=True, timeout=120)
    return (str(exe) if res.returncode == 0 else None), res.stderr, no_comp


def _has_comp(header: str, variant: str) -> bool:
    """The variant's output struct has v_d_comp and v_q_comp."""
    m = re.search(r"typedef struct \{([^}]*)\}\s*" + _OUTPUT_STRUCT[variant] + ";", header)
    return bool(m) and "v_d_comp" in m.group(1) and "v_q_comp" in m.group(1)


def _offered(header: str, variant: str) -> str | None:
    """None when the header offers the variant, else its #error text."""
    if variant == "float":
        return None
    if variant == "q31":
        m = re.search(r"#ifdef CCT_FIXED_POINT\s*\n\s*#error (\".*\")", header)
        if m or "cct_step_q31" not in header:
            return m.group(1) if m else "no cct_step_q31"
        return None
    m = re.search(r"#if defined\(CCT_MCSDK\) \|\| defined\(CCT_IQMATH\)\s*\n\s*#error (\".*\")",
                  header)
    fn = {"mcsdk": "cct_step_s16", "iqmath": "cct_step_iq"}[variant]
    if m or fn not in header:
        return m.group(1) if m else f"no {fn}"
    return None


# ---------------------------------------------------------------- cases
def _scales(spec) -> tuple[float, dict[str, tuple[float, float]]]:
    """The step I (A) and each case's (mechanical speed rad/s, bus V).

    Speeds: 0; 30 % of the base speed V_max / (p flux); the speed at which the
    steady state of the references asks SATURATION x V_max (bisection), near
    base speed. All within the design's speed scale
    (``toolbox.design.speed_scale``: rated speed, at most the base speed): a
    design whose voltage does not limit there (001's rated speed is below
    it; 003_speed's 1000 V bus) runs the saturating case at the speed scale
    with the bus lowered until the steady state asks SATURATION x V_max (the
    header reads the bus each period through <p>set_vdc).
    """
    from toolbox.design import current_scale, speed_scale
    from toolbox.sim import drive_params
    m = spec.motor
    p = m.pole_pairs
    i_step = 0.5 * current_scale(m, spec.drive)[0]
    v_max = drive_params(spec.drive).radii(m.torque_factor)[1]
    w_base = v_max / m.flux                       # electrical
    w_top = speed_scale(m, spec.drive)[0] * p
    i_d, i_q = -0.25 * i_step, i_step

    def v_ss(w):
        return math.hypot(m.R * i_d - w * m.Lq * i_q, m.R * i_q + w * (m.Ld * i_d + m.flux))

    vdc = spec.drive.vdc
    lo, hi = 0.0, w_top
    if v_ss(hi) < SATURATION * v_max:             # not at the speed scale: lower the bus
        vdc *= v_ss(hi) / (SATURATION * v_max)
    else:
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if v_ss(mid) < SATURATION * v_max else (lo, mid)
    return i_step, {"standstill": (0.0, spec.drive.vdc),
                    "30% base": (min(0.3 * w_base, w_top) / p, spec.drive.vdc),
                    "saturating": (hi / p, vdc)}


def _references(i_step: float) -> np.ndarray:
    k = np.arange(N_PERIODS)
    on = (k >= K_STEP).astype(float)
    return np.column_stack([-0.25 * i_step * on, i_step * on])


def _r_hex(spec) -> float:
    """Length of an active inverter vector: 2/3 vdc (amplitude-invariant dq),
    sqrt(2/3) vdc (power-invariant)."""
    vdc = spec.drive.vdc
    return 2.0 / 3.0 * vdc if spec.motor.convention == "amplitude" else math.sqrt(2 / 3) * vdc


def run_harness(exe: str, spec, hold: str, omega_m: float, vdc: float, refs: np.ndarray):
    m, dr = spec.motor, replace(spec.drive, vdc=vdc)
    g = "{:.17g}".format
    head = (f"{g(m.R)} {g(m.Ld)} {g(m.Lq)} {g(m.flux)} {int(m.pole_pairs)} {g(dr.vdc)} "
            f"{g(_r_hex(spec))} {g(dr.sample_time)} {dr.delay_samples} "
            f"{1 if hold == 'stationary' else 0} {N_SUB} {g(omega_m)} {len(refs)}\n")
    text = head + "".join(f"{g(a)} {g(b)}\n" for a, b in refs)
    out = subprocess.run([exe], input=text, capture_output=True, text=True, timeout=60,
                         check=True).stdout.strip().splitlines()
    currents = np.array([[float(x) for x in ln.split()] for ln in out[:-2]])
    faults = int(out[-2].split()[1])
    clamped = int(out[-1].split()[1])
    return currents, faults, clamped


def run_simulator(spec, art, hold: str, omega_m: float, vdc: float, i_step: float):
    from toolbox.sim import control_law, drive_params, simulate
    from toolbox.spec import Scenario
    fcs = art.method == "fcs_mpc"
    drive = replace(drive_params(spec.drive, "fcs_mpc" if fcs else "average"), hold_frame=hold,
                    vdc=vdc)
    Ts = spec.drive.sample_time
    sc = Scenario(kind="current_step", duration=N_PERIODS * Ts, step_time=K_STEP * Ts,
                  iq_ref=i_step, id_ref=-0.25 * i_step, initial_speed=omega_m,
                  keep_traces=True, inverter="fcs_mpc" if fcs else "average")
    res = simulate(control_law(art), spec.motor, sc, drive)
    return np.column_stack([res.id, res.iq]), res.metrics["saturation_time"]


# ---------------------------------------------------------------- bounds
def _macro(header: str, name: str) -> float:
    m = re.search(rf"#define {name} \(?\(?(?:int32_t\))?\s*([-+0-9.eE]+)L?f?\)?", header)
    assert m, name
    return float(m.group(1))


def quantisation_bound(header: str, variant: str, spec, i_step: float) -> tuple[float, str]:
    """Deviation (A) the variant's words allow (module docstring), and how."""
    R = spec.motor.R
    if variant == "q31":
        q_i = _macro(header, "CCT_Q31_I_BASE") * 2.0 ** -31 * 2   # to_q31 truncates: 1 LSB
        q_v = _macro(header, "CCT_Q31_V_BASE") * 2.0 ** -31
        bounds = [float(x) for x in re.findall(r"\|v_q31 - v_exact\| <= ([0-9.eE+-]+) V", header)]
        q_v += max(bounds, default=0.0)                 # the header's own bound of its law
        e_g = 2.0 ** -29                                # int32 mantissas scaled to >= 2^30
    elif variant == "mcsdk":
        q_i = _macro(header, "CCT_MCSDK_I_FS") / 32768.0
        q_v = _macro(header, "CCT_MCSDK_V_FS") / 32768.0
        gains = [abs(_macro(header, f"CCT_MCSDK_{n}_GAIN"))
                 for n in ("D_KP", "D_KI", "Q_KP", "Q_KI", "DD", "DQ", "DE")]
        e_g = max((0.5 / g for g in gains if g), default=0.0)   # 0: an exact zero (no term)
    else:
        q_i = _macro(header, "CCT_IQ_I_BASE") * 2.0 ** -24
        q_v = _macro(header, "CCT_IQ_V_BASE") * 2.0 ** -24
        gains = [abs(_macro(header, f"CCT_IQ_{n}"))
                 for n in ("D_KP", "D_KI", "Q_KP", "Q_KI", "DD", "DQ", "DE")]
        e_g = max((0.5 / g for g in gains if g), default=0.0)   # 0: an exact zero (no term)
    b = 4.0 * (q_i + q_v / R) + 2.0 * e_g * i_step
    return b, f"4 (q_i {q_i:.2g} A + q_v {q_v:.2g} V / R) + 2 e_g {e_g:.2g} I"


# ---------------------------------------------------------------- the test
@pytest.fixture(scope="module", autouse=True)
def table():
    yield
    if not _RESULTS:
        return
    lines = ["", "SIL: worst |i_header - i_simulator| over the sampled currents "
             f"({N_PERIODS} periods; step I = 0.5 x current scale)",
             f"{'design':<34} {'variant':<7} {'I (A)':>6} {'standstill':>11} {'30% base':>11} "
             f"{'saturating':>11} {'worst/I':>9} {'bound/I':>8}  note"]
    for (name, variant), r in sorted(_RESULTS.items()):
        cells = " ".join(f"{r['cases'].get(c, float('nan')):11.3g}" for c in CASES)
        lines.append(f"{name:<34} {variant:<7} {r['I']:6.3g} {cells} {r['worst'] / r['I']:9.2g} "
                     f"{r['bound'] / r['I']:8.2g}  {r['note']}")
    print("\n".join(lines))


#: The designs whose closed-loop header cases the everyday selection runs (a
#: PI, a static law, an H-infinity state space, the FCS-MPC law): here their
#: float header, in test_preset.py their preset and handover; every other case
#: (the other designs, the fixed-point variants) runs with the slow tests.
EVERYDAY = ("003_azaiz2007_pi", "000_lepioufle1992_tc", "003_azaiz2007_hinf",
            "002_cormerais2002_fcs_mpc")


def everyday(names) -> list:
    """``names`` as parameters, those not in EVERYDAY marked slow."""
    return [n if n in EVERYDAY else pytest.param(n, marks=pytest.mark.slow) for n in names]


def _cases() -> list:
    """(name, variant) parameters, id ``name-variant``, marked as EVERYDAY says."""
    return [pytest.param(n, v, id=f"{n}-{v}",
                         marks=() if v == "float" and n in EVERYDAY else pytest.mark.slow)
            for n in NAMES for v in VARIANTS]


@pytest.mark.parametrize("name, variant", _cases())
def test_header_in_the_loop_matches_simulator(name, variant, tmp_path_factory):
    spec, art, header = _designed(name)
    why = _offered(header, variant)
    if why is not None:
        pytest.skip(f"{name}: the header offers no {variant} variant ({why})")
    tmp = tmp_path_factory.getbasetemp() / "sil"
    exe, err, no_comp = _binary(name, variant, tmp)
    assert exe is not None, f"{name} {variant}: the harness did not compile:\n{err}"
    i_step, speeds = _scales(spec)
    refs = _references(i_step)
    holds = ("stationary",) if art.method == "fcs_mpc" else HOLDS
    if variant == "float":
        bound, how = FLOAT_BOUND * i_step, "1e-3 I"
    else:
        qb, how = quantisation_bound(header, variant, spec, i_step)
        bound = FLOAT_BOUND * i_step + qb
    cases, worst, faults, clamped, sat = {}, 0.0, 0, 0, {}
    for label in CASES:
        omega_m, vdc = speeds[label]
        for hold in holds:
            i_c, f, cl = run_harness(exe, spec, hold, omega_m, vdc, refs)
            i_s, sat_time = run_simulator(spec, art, hold, omega_m, vdc, i_step)
            assert i_c.shape == i_s.shape
            dev = float(np.abs(i_c - i_s).max()) if np.isfinite(i_c).all() else math.inf
            cases[label] = max(cases.get(label, 0.0), dev)
            worst = max(worst, dev)
            faults += f
            clamped += cl
            sat[label] = max(sat.get(label, 0.0), sat_time)
    note = ("NO v_d_comp/v_q_comp in the output: rotated by the harness"
            if no_comp else "") + (f" clamped {clamped}" if clamped else "")
    _RESULTS[(name, variant)] = dict(I=i_step, cases=cases, worst=worst, bound=bound,
                                     note=note.strip())
    print(f"\n{name} {variant}: worst {worst:.3g} A (bound {bound:.3g} A = {how}); per case "
          + ", ".join(f"{k} {v:.3g}" for k, v in cases.items())
          + f"; speeds {', '.join(f'{v[0]:.4g}' for v in speeds.values())} rad/s; "
          + f"bus {speeds['saturating'][1]:.4g} V in the saturating case; saturated "
          + ", ".join(f"{k} {1e3 * v:.3g} ms" for k, v in sat.items()))
    assert faults == 0, f"{name} {variant}: the header reported {faults} faults"
    if art.method != "fcs_mpc":                   # a switch state has no saturation
        assert sat["saturating"] > 0, f"{name}: the saturating case did not saturate: {sat}"
    assert not no_comp, (f"{name} {variant}: the {_OUTPUT_STRUCT[variant]} output has no "
                         "v_d_comp/v_q_comp, so the delay compensation the design assumes "
                         "(DELAY_COMP_TIME w_e) is not in the header's output")
    assert worst <= bound, (f"{name} {variant}: header and simulator differ by {worst:.3g} A "
                            f"> {bound:.3g} A ({how}); per case {cases}")
