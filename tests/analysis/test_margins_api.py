"""The one margins API (toolbox.analysis.margins: lti_loop_margins,
frequency_margins, grid_margins) against python-control and against itself."""

import math

import control as ct
import numpy as np
import pytest

from tests.tolerances import REORDERED_RTOL
from toolbox.analysis import frequency_margins, grid_margins, lti_loop_margins

s = ct.tf("s")
#: Loops with known crossings: a PI on a first-order plant with a 3rd-order
#: Pade delay (finite GM and PM), the paper-003-like G K with an integrator,
#: and a sampled loop (Tustin PI, ZOH plant, one period delay).
LOOPS = {
    "pi_pade": (ct.tf(*ct.pade(2e-4, 3)) * 5.0 * (s + 100) / s / (1e-3 * s + 0.5)),
    "lag": 40.0 * (s + 50) / (s * (s + 300) * (0.01 * s + 1)),
    "discrete": (ct.c2d(ct.tf([2.0 * 1e-3, 2.0], [1e-3, 0]), 1e-4, "tustin")
                 * ct.c2d(ct.tf([1.0], [2e-3, 0.4]), 1e-4, "zoh") * ct.tf([1], [1, 0], 1e-4)),
}


@pytest.mark.parametrize("name", list(LOOPS))
def test_lti_loop_margins_equal_python_control(name):
    """Same GM, PM, crossover frequencies and M_m as control.stability_margins.

    Tolerance: relative 1e-6. Both refine the same crossing (python-control by
    polynomial roots, ours by Brent to 1e-13 in log w), so they agree to
    rounding; 1e-6 leaves room for the conditioning of the polynomial route
    while a crossing picked from the grid without refinement (cell 0.13 %)
    would fail it.
    """
    L = LOOPS[name]
    gm, pm, sm, wpc, wgc, _ = ct.stability_margins(L)
    m = lti_loop_margins(L)
    assert m.gain_margin_db == pytest.approx(20 * math.log10(gm), rel=1e-6)  # inf == inf
    assert m.phase_crossover_rad_s == pytest.approx(wpc, rel=1e-6, nan_ok=True)  # nan: no phase crossover
    assert m.phase_margin_deg == pytest.approx(pm, rel=1e-6)
    assert m.gain_crossover_rad_s == pytest.approx(wgc, rel=1e-6)
    assert m.stability_margin == pytest.approx(sm, rel=1e-6)
    assert m.sensitivity_peak == pytest.approx(1 / m.stability_margin, rel=1e-12)


def test_grid_margins_interpolate_close_to_refined():
    """grid_margins (stacked, linear interpolation) agrees with the refined
    frequency_margins on a 2000-point grid and stacks rows independently.

    Tolerance: 0.05 dB / 0.05 deg / 0.2 % for M_m: interpolation error on
    cells of 0.6 % in frequency, where |L| and angle L change by well under
    1 % per cell for these smooth loops.
    """
    L = LOOPS["pi_pade"]
    w = np.logspace(-1, 6, 2000)
    resp = np.asarray(ct.frequency_response(L, w).complex).reshape(-1)
    ref = frequency_margins(lambda x: np.asarray(ct.frequency_response(L, x).complex).reshape(-1), w)
    g = grid_margins(w, np.vstack([resp, 2 * resp]))
    assert g["gain_margin_db"][0] == pytest.approx(ref.gain_margin_db, abs=0.05)
    assert g["phase_margin_deg"][0] == pytest.approx(ref.phase_margin_deg, abs=0.05)
    assert g["stability_margin"][0] == pytest.approx(ref.stability_margin, rel=2e-3)
    # doubling the loop gain removes 6.02 dB of gain margin (exact: 20 log10 2)
    assert g["gain_margin_db"][1] == pytest.approx(ref.gain_margin_db - 20 * math.log10(2), abs=0.05)
    single = grid_margins(w, resp)
    assert single["phase_margin_deg"] == g["phase_margin_deg"][0]


def test_grid_margins_without_crossing_is_infinite():
    """|L| < 1 everywhere and no phase crossover: both margins are +inf."""
    w = np.logspace(0, 3, 50)
    g = grid_margins(w, 0.5 / (1 + 1j * w / 100))
    assert g["gain_margin_db"] == math.inf and g["phase_margin_deg"] == math.inf


def test_grid_margins_checks_lengths():
    """A response not sampled on the grid is refused, naming both lengths."""
    with pytest.raises(ValueError, match="3 points, grid 4"):
        grid_margins(np.arange(1.0, 5.0), np.ones(3))


@pytest.mark.parametrize("nyquist", [False, True])
def test_grid_margins_equal_the_full_array_formulation(nyquist):
    """grid_margins interpolates at the crossing cells only; the reference
    interpolates every cell and masks (the implementation before). The
    crossings' margins agree within ``REORDERED_RTOL``: the same operations on
    the same numbers, only not carried out where they are discarded. The stability
    and disk margins are computed in real arithmetic (``|1 + L|^2`` and
    ``|S - 1/2| = |1 - L|/(2 |1 + L|)``): equal to 1e-14 relative (a few
    roundings; observed 4e-16). Rows: random integrator-delay loops (several
    crossings), a NaN sample and a loop without any crossing."""
    from toolbox.analysis import _siso

    def closest(x):
        mag = np.where(np.isnan(x), np.inf, np.abs(x))
        j = np.argmin(mag, axis=1)
        v = x[np.arange(x.shape[0]), j]
        return np.where(np.isinf(mag[np.arange(x.shape[0]), j]), np.inf, v)

    def reference(Lw):
        S = 1.0 / (1.0 + Lw)
        sm = np.min(np.abs(1.0 + Lw), axis=1)
        dm = 1.0 / np.max(np.abs(S - 0.5), axis=1)
        lg = np.log(np.abs(Lw))
        cr = np.sign(lg[:, :-1]) * np.sign(lg[:, 1:]) < 0
        t = lg[:, :-1] / (lg[:, :-1] - lg[:, 1:])
        Lc = Lw[:, :-1] + t * (Lw[:, 1:] - Lw[:, :-1])
        pm = np.where(cr, np.degrees(np.angle(-Lc)), np.nan)
        im = Lw.imag
        cr2 = np.sign(im[:, :-1]) * np.sign(im[:, 1:]) < 0
        t2 = im[:, :-1] / np.where(cr2, im[:, :-1] - im[:, 1:], 1.0)
        re = Lw.real[:, :-1] + t2 * (Lw.real[:, 1:] - Lw.real[:, :-1])
        cr2 &= re < 0
        gm = np.where(cr2, -20 * np.log10(np.abs(np.where(cr2, re, 1.0))), np.nan)
        if nyquist:
            nyq = Lw[:, -1]
            gm = np.hstack([gm, np.where(nyq.real < 0, -20 * np.log10(np.abs(nyq.real)),
                                         np.nan)[:, None]])
        return {"gain_margin_db": closest(gm), "phase_margin_deg": closest(pm),
                "stability_margin": sm, "disk_margin": dm}

    rng = np.random.default_rng(0)
    w = np.logspace(-2, 4.5, 800)
    k = rng.uniform(0.1, 1e4, size=(60, 1))
    tau = rng.uniform(1e-5, 1e-3, size=(60, 1))
    L = k / (1j * w) * np.exp(-1j * w * tau) / (1 + 1j * w * tau)
    L[0, 5] = np.nan
    L[1, :] = 0.5
    with np.errstate(all="ignore"):
        want = reference(L)
    got = _siso.grid_margins(w, L, nyquist=nyquist)
    assert np.isfinite(got["phase_margin_deg"][2:]).all()  # crossings were found
    for key in ("gain_margin_db", "phase_margin_deg"):   # same formulas, another order
        assert np.allclose(got[key], want[key], rtol=REORDERED_RTOL, atol=0.0,
                           equal_nan=True), key
    for key in ("stability_margin", "disk_margin"):
        np.testing.assert_allclose(got[key], want[key], rtol=1e-14, err_msg=key)


def test_grid_kernel_equals_numpy():
    """The compiled pass of grid_margins gives numpy's numbers within
    ``REORDERED_RTOL`` (the same formulas; the cells are exact structure): ``min (1 + re)^2 + im^2``, ``max ((1 - re)^2 + im^2)/that`` per row
    (NaN rows NaN), and the strict sign changes of ``|L| - 1`` and ``Im L``
    (a sample exactly at the level or NaN starts or ends none)."""
    from toolbox.analysis._grid_kernel import grid_pass

    rng = np.random.default_rng(3)
    L = (rng.normal(size=(40, 300)) + 1j * rng.normal(size=(40, 300))) * rng.uniform(0.1, 5, (40, 1))
    L[3, 17] = np.nan
    L[4, 10] = 1.0            # |L| = 1 exactly, Im L = 0 exactly
    L[5, :] = 0.5
    re, im, mag = L.real, L.imag, np.abs(L)
    one2_min, ratio_max, gain_cells, phase_cells = grid_pass(re, im, mag)
    with np.errstate(invalid="ignore"):
        one2 = (1.0 + re) ** 2 + im * im
        want_min = np.min(one2, axis=1)
        want_max = np.max(((1.0 - re) ** 2 + im * im) / one2, axis=1)
        sg = np.sign(mag - 1.0)
        want_gain = sg[:, :-1] * sg[:, 1:] < 0
        sg = np.sign(im)
        want_phase = sg[:, :-1] * sg[:, 1:] < 0
    assert np.allclose(one2_min, want_min, rtol=REORDERED_RTOL, atol=0.0, equal_nan=True)
    assert np.allclose(ratio_max, want_max, rtol=REORDERED_RTOL, atol=0.0, equal_nan=True)
    assert np.isnan(one2_min[3]) and np.isnan(ratio_max[3])
    assert np.array_equal(gain_cells, want_gain)
    assert np.array_equal(phase_cells, want_phase)


def test_plant_factors_equal_numpy():
    """The compiled ``qr - j qi`` and ``b/(qr^2 + qi^2)`` of the sweep's loops
    are numpy's ``zr - a``, ``qr - 1j qi``, ``b/(qr * qr + qi * qi)`` within
    ``REORDERED_RTOL`` (the same operations)."""
    from toolbox.analysis._grid_kernel import plant_factors

    z = np.exp(1j * np.linspace(0.0, np.pi, 500))
    rng = np.random.default_rng(4)
    a, b = rng.uniform(0.0, 1.0, 30), rng.uniform(1e-3, 1.0, 30)
    conj, scale = plant_factors(z.real, z.imag, a, b)
    qr = z.real[None, :] - a[:, None]
    want = qr - 1j * z.imag[None, :]
    assert np.allclose(conj, want, rtol=REORDERED_RTOL, atol=0.0)
    assert np.allclose(scale, b[:, None] / (qr * qr + z.imag * z.imag), rtol=REORDERED_RTOL,
                       atol=0.0)
