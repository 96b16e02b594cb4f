"""Motors of the four source papers.

Each entry gives the motor keys of a spec (``[motor] catalog = "name"``);
explicit keys in the spec override them. Sources are cited per value.
"""

from __future__ import annotations

import math

__all__ = ["CATALOG", "CATALOG_NOTES"]

CATALOG: dict[str, dict] = {
    # Le Pioufle, Georgiou, Louis 1992 (paper 000), appendix. Torque eq (2) has
    # no 3/2 factor, so the flux refers to the power-invariant dq convention
    # (consistent with the appendix: p*flux*I_max = 4*0.12*30 = 14.4 N m, the
    # stated maximum transient torque 14 N m). J from C_nom/J = 7720 rad/s^2
    # with C_nom = 8.5 N m gives 1.10e-3; paper 003 states 1.11e-3 for the same
    # motor, used here. Friction from paper 003 sect. 6.
    "lepioufle1992": dict(R=0.6, Ld=1.4e-3, Lq=2.8e-3, flux=0.12, pole_pairs=4,
                          J=1.11e-3, friction=1.4e-3, convention="power",
                          rated_current=20.0, max_current=30.0, rated_speed=230.0),
    # Azaiz et al. 2007 (paper 003), sect. 6: the same motor as paper 000, but
    # with the torque of eq (5) carrying 3/2 (amplitude-invariant dq).
    "azaiz2007": dict(R=0.6, Ld=1.4e-3, Lq=2.8e-3, flux=0.12, pole_pairs=4,
                      J=1.11e-3, friction=1.4e-3, convention="amplitude",
                      rated_current=20.0, max_current=20.0, rated_speed=230.0),
    # Takami 2004 (paper 001), Tables 1-2: 1.3 kW, 1500 rpm, 8.34 N m, 8 poles,
    # 10.7 A (rms phase current, peak 15.1 A), L1 = Ld = Lq = 1.78783 mH,
    # lambda_f = 0.11896 Wb (EMF 49.83 V at 1000 rpm = p*lambda_f*omega, read here
    # as the phase-peak EMF: amplitude-invariant dq), J = 0.00123 kg m^2,
    # D = 0.036607 N m s/rad. The paper gives NO resistance: R = 0.4 ohm is our
    # assumption (typical of 1-2 kW, 8-pole servo motors of this inductance,
    # tau = L/R = 4.5 ms); the robustness claims are tested over R x0.5..x2.
    # Convention: the paper states none. Its Table 1 fits power-invariant dq better
    # (p lambda_f sqrt(3) 10.7 A = 8.82 N m vs the printed 8.34; amplitude-invariant
    # gives 10.80 N m at sqrt(2) 10.7 A), i.e. the EMF is then line-to-line rms. The
    # amplitude reading is kept: the reproduced figures do not depend on it
    # (tests/papers/test_001_speed_step.py, "dq convention of Tables 1-2").
    "takami2004": dict(R=0.4, Ld=1.78783e-3, Lq=1.78783e-3, flux=0.11896, pole_pairs=4,
                       J=0.00123, friction=0.036607, convention="amplitude",
                       rated_current=10.7 * math.sqrt(2), max_current=30.0,
                       rated_speed=1500 * 2 * math.pi / 60),
    # Cormerais et al. 2002 (paper 002), sect. 3.2: Ld = Lq = 112.6 uH,
    # R = 0.02 ohm, flux 60.39e-3 (power-invariant Park, eq (2)-(3)),
    # 6 pole pairs, J = 1 kg m^2, no friction; Gamma_c = 36 N m at i_q = 100 A
    # (= 6 * 60.39e-3 * 100 = 36.2 N m, torque factor 1).
    "cormerais2002": dict(R=0.02, Ld=112.6e-6, Lq=112.6e-6, flux=60.39e-3, pole_pairs=6,
                          J=1.0, friction=0.0, convention="power",
                          rated_current=100.0, max_current=150.0, rated_speed=None),
}

CATALOG_NOTES: dict[str, str] = {
    "lepioufle1992": "paper 000 appendix (Le Pioufle 1992); power-invariant dq",
    "azaiz2007": "paper 003 sect. 6 (Azaiz 2007); same motor, amplitude-invariant dq",
    "takami2004": "paper 001 Tables 1-2 (Takami 2004); R = 0.4 ohm assumed (not given)",
    "cormerais2002": "paper 002 sect. 3.2 (Cormerais 2002); power-invariant dq",
}
