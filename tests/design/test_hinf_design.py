"""H-infinity design from a spec (paper 003): read_cfg + design on top of the
tested numerics (tests/design/test_hinf.py, tests/papers/test_003_hinf.py).

Tolerances are those of tests/papers/test_003_hinf.py: 0.5 % on gain, zeros and
poles of eq (68) (the paper prints 4 digits) and on the frequency response of
the reduced controllers eq (71)-(72).
"""

from pathlib import Path

import control as ct
import numpy as np
import pytest

from toolbox.artifact import ControllerArtifact
from toolbox.design import design
from toolbox.design.hinf import read_weight
from toolbox.errors import SpecError
from toolbox.spec import load_spec, spec_from_dict

ROOT = Path(__file__).resolve().parents[2]
s = ct.tf("s")

WEIGHTS = {   # eq (44)-(49); w2 = 0.5(1 + 1e-3 s)/(1 + 2e-5 s) = 25 (s + 1e3)/(s + 5e4)
    "q": {"w1": {"num": [1 / 1.51, 177.3493 / 1.51], "den": [1, 0.0117]},
          "w2": {"num": [25, 25000], "den": [1, 50000]},
          "w3": {"num": [1e4, 1.3568e6], "den": [1, 2.7135e6]}},
    "d": {"w1": {"num": [1 / 1.7, 68.7386 / 1.7], "den": [1, 0.0040]},
          "w2": {"num": [25, 25000], "den": [1, 50000]},
          "w3": {"num": [1e4, 1e4 * 577.3503], "den": [1, 1.1547e7]}},
}
PAPER_KR = {"q": 49.7026 * (s + 5e4) * (s + 214.3) / (s * (s * s + 4793 * s + 6.104e6)),
            "d": 2.7364 * (s + 5e4) * (s + 428.6) / (s * (s * s + 2428 * s + 1.584e6))}


def spec(weights=WEIGHTS, **hinf):
    return spec_from_dict({"motor": {"catalog": "azaiz2007"},
                           "drive": {"vdc": 150, "sample_time": 1e-4},
                           "controller": {"method": "hinf",
                                          "hinf": {"weights": weights, **hinf}}})


@pytest.fixture(scope="module")
def art():
    return design(load_spec(ROOT / "designs" / "003_azaiz2007_hinf.toml"))


def test_q_controller_matches_eq68(art):
    """K_q = 49.70 (s + 2.714e6)(s + 5e4)(s + 214.3) /
    ((s + 2.717e6)(s + 0.01174)(s^2 + 4793 s + 6.104e6)), 0.5 %: the full-order
    design, kept (not executed) under full_order since the law runs eq (72)."""
    z = art.axes["q"].full_order.zpk
    assert z.gain == pytest.approx(49.70, rel=5e-3)
    assert np.sort(-z.zeros.real) == pytest.approx([214.3, 5e4, 2.714e6], rel=5e-3)
    real = np.sort(-z.poles[np.abs(z.poles.imag) < 1e-9].real)
    assert real == pytest.approx([0.01174, 2.717e6], rel=5e-3)
    quad = np.real(np.poly(z.poles[np.abs(z.poles.imag) >= 1e-9]))[1:]
    assert quad == pytest.approx([4793, 6.104e6], rel=5e-3)
    assert art.design_parameters["gamma"]["q"] == 1.0
    assert all(b["worst_ratio"] < 1 for b in art.design_parameters["weight_bounds"]["q"].values())


@pytest.mark.parametrize("axis", ["d", "q"])
def test_reduced_matches_eq71_72(art, axis):
    """Reduced to 3 states (cancellation + integrator); frequency response within
    0.5 % of eq (71)/(72) from 1 to 1e5 rad/s; executed by the law: the axis
    itself is the reduced controller (law, continuous twin and derived discrete
    view all of order 3), the 4th-order design sits apart under full_order."""
    red = art.axes[axis]
    assert red.continuous.order == 3 and red.law.order == 3 and red.discrete.order == 3
    w = np.logspace(0, 5, 200)
    a = np.asarray(ct.frequency_response(red.to_statespace(domain="continuous").to_control(),
                                         w).complex).ravel()
    b = np.asarray(ct.frequency_response(ct.ss(PAPER_KR[axis]), w).complex).ravel()
    assert float(np.max(np.abs(a - b) / np.abs(b))) < 5e-3
    assert red.reduced is None
    assert red.full_order.continuous.order == 4 and red.full_order.law.order == 4
    # the derived error -> voltage view is minus the law's measurement channel
    assert np.array_equal(red.discrete.A, red.law.A)
    assert np.array_equal(red.discrete.B, -red.law.B[:, 1:2])
    assert art.design_parameters["reduction"][axis]["margin_flags"] == []


def test_json_round_trip(art):
    text = art.dumps()
    back = ControllerArtifact.loads(text)
    assert back.dumps() == text
    assert back.axes["q"].continuous.order == 3
    assert back.axes["q"].full_order.continuous.order == 4


def test_optimal_spec_file():
    """gamma = "optimal": gamma_opt = 0.952 on q (paper 003 / sb10ad, 1e-3), designed
    at 1.05 gamma_opt, realisable at Ts (no pole beyond pi/Ts)."""
    a = design(load_spec(ROOT / "designs" / "003_azaiz2007_hinf_optimal.toml"))
    assert a.design_parameters["gamma_opt"]["q"] == pytest.approx(0.952, abs=1e-3)
    assert a.design_parameters["gamma"]["q"] == pytest.approx(1.05 * a.design_parameters["gamma_opt"]["q"], rel=1e-9)
    assert a.design_parameters["fastest_pole_rad_s"]["q"] <= np.pi / 1e-4


def test_infeasible_gamma_names_key_and_best():
    with pytest.raises(SpecError) as err:
        design(spec(gamma=0.9))
    assert err.value.key == "controller.hinf.gamma"
    # d is feasible at 0.9 (gamma_opt 0.646), q is not (gamma_opt 0.952)
    assert str(err.value) == ('controller.hinf.gamma: expected gamma >= the best achievable '
                              '0.9518 (both axes), got 0.9 (q axis: X of eq (18) is '
                              'stabilising but not >= 0 at gamma = 0.9; best per axis: '
                              'd 0.6463, q 0.9518; set gamma above 0.9518 or "optimal")')


def test_executed_full_and_no_reduction():
    a = design(spec(gamma=1.0, reduce_order=3, executed="full"))
    assert a.axes["q"].law.order == 4 and a.axes["q"].continuous.order == 4
    assert a.axes["q"].reduced.law.order == 3 and a.axes["q"].full_order is None
    b = design(spec(gamma=1.0))
    assert b.axes["q"].reduced is None and b.axes["q"].full_order is None
    assert "reduction" not in b.design_parameters


def test_margin_loss_refused_or_flagged():
    """Order 1 (balanced truncation down to the integrator) loses the margins."""
    with pytest.raises(SpecError) as err:
        design(spec(gamma=1.0, reduce_order=1))
    assert err.value.key == "controller.hinf.reduce_order"
    assert "keeps GM, PM and M_m within 10 %" in str(err.value)
    a = design(spec(gamma=1.0, reduce_order=1, on_margin_loss="flag"))
    assert a.design_parameters["reduction"]["d"]["margin_flags"] or a.design_parameters["reduction"]["q"]["margin_flags"]


def test_weight_forms():
    """zpk and makeweight forms give the same filters as num/den (1e-9)."""
    w1 = read_weight({"zeros": [-177.3493], "poles": [-0.0117], "gain": 1 / 1.51}, "k")
    ref = read_weight(WEIGHTS["q"]["w1"], "k")
    for f in (0.0, 10.0, 1e4):
        assert abs(complex(w1(1j * f))) == pytest.approx(abs(complex(ref(1j * f))), rel=1e-9)
    mw = read_weight({"dc_gain": 1e4, "crossover": 156.0, "crossover_gain": 1.0,
                      "hf_gain": 1 / 1.51}, "k")
    assert abs(complex(mw(1j * 156.0))) == pytest.approx(1.0, rel=1e-9)
    assert abs(complex(read_weight(0.5, "k")(1j))) == 0.5
    cplx = read_weight({"zeros": [[-10, 5], [-10, -5]], "poles": [-100, -200], "gain": 1.0}, "k")
    assert cplx.poles().size == 2


def test_bad_hinf_input():
    with pytest.raises(SpecError, match=r'controller\.hinf\.gamma: expected a number > 0 or "optimal"'):
        spec(gamma="best")
    with pytest.raises(SpecError, match=r"controller\.hinf\.gamma: expected a number > 0"):
        spec(gamma=-1.0)
    with pytest.raises(SpecError, match=r"controller\.hinf\.weights\.q\.w1: expected one of the forms"):
        spec(weights={"d": WEIGHTS["d"], "q": {"w1": {"numer": [1]}}})
    # defaults for every method (README.md "Defaults (no method parameters)"): a missing
    # axis table or w1 is not an error, the weights are
    # defaulted (toolbox.design._hinf_defaults): w2 at read time, w1 at design time
    cfg = spec(weights={"q": WEIGHTS["q"]}).controller.cfg
    assert cfg.weights["d"]["w1"] is None and "w2" in cfg.stated["d"]
    cfg = spec(weights={"d": WEIGHTS["d"], "q": {"w2": WEIGHTS["q"]["w2"]}}).controller.cfg
    assert cfg.weights["q"]["w1"] is None and "w2" not in cfg.stated.get("q", {})
    with pytest.raises(SpecError, match=r"controller\.hinf\.weights\.q\.w2"):
        spec(weights={"d": WEIGHTS["d"], "q": {**WEIGHTS["q"], "w2": -1.0}})
    with pytest.raises(SpecError, match=r"controller\.hinf\.executed"):
        spec(executed="reduced")
    with pytest.raises(SpecError, match=r"controller\.hinf\.reduce_order: expected an integer >= 1"):
        spec(reduce_order=0)


def test_antiwindup_recursion_is_schur(art):
    """Tustin puts a zero of K at z = -1; the default back-calculation gain would
    leave A - aw C with spectral radius 1; the artifact's gain moves it to z = 0 and
    keeps the other zeros (0.958 on d, 0.979 on q: the PI-like zeros 428.6 and
    214.3 rad/s mapped by Tustin)."""
    for ax in ("d", "q"):
        for axis in (art.axes[ax], art.axes[ax].full_order):
            law = axis.law
            rho = np.max(np.abs(np.linalg.eigvals(law.A - axis.antiwindup @ law.C)))
            assert rho < 0.99
    law = art.axes["q"].law
    zq = (1 - 214.3 * 5e-5) / (1 + 214.3 * 5e-5)            # Tustin image of -214.3 rad/s
    eig = np.linalg.eigvals(law.A - art.axes["q"].antiwindup @ law.C)
    assert np.min(np.abs(eig - zq)) < 1e-3
