"""The report's robustness card (toolbox/ARCHITECTURE.md "Robustness
verdict"): at the top next to the margin cards, green on pass, red on fail,
with the worst disk margin, unstable sets / sets and the box."""

import dataclasses
import re

from toolbox.report import build_context, write_html

ROB = {"source": "default", "box_text": "default drift box: R x0.843..1.511, Ld/Lq x0.8..1.1",
       "n_sets": 1065, "worst_disk_margin": 0.41, "n_unstable": 0, "first_unstable": None}


def _card(full_data, rob):
    verification = dict(full_data.verification or {}, robustness=rob)
    html = write_html(build_context(dataclasses.replace(full_data, verification=verification)))
    summary = html[html.index('<div class="summary">'):html.index("<nav>")]
    match = re.search(r'<div class="card (\w+)" id="robustness-card">(.*?)</div>', summary)
    assert match, summary
    return html, match.group(1), match.group(2)


def test_pass_card_is_green(full_data):
    html, status, text = _card(full_data, ROB)
    assert status == "pass" and '<span class="status pass">pass</span>' in text
    assert "disk margin 0.41, unstable 0 / 1065 sets" in text
    assert "default drift box: R x0.843..1.511, Ld/Lq x0.8..1.1" in text
    assert ".summary div.card.pass" in html and "var(--pass)" in html


def test_fail_card_is_red_and_names_the_set(full_data):
    rob = dict(ROB, n_unstable=551, worst_disk_margin=0.0,
               first_unstable={"R": 0.843, "Ld": 0.8, "speed_rad_s": -920.0,
                               "spectral_radius": 1.058})
    _, status, text = _card(full_data, rob)
    assert status == "fail" and '<span class="status fail">fail</span>' in text
    assert "unstable 551 / 1065 sets" in text
    assert "first unstable: R 0.843, Ld 0.8, speed_rad_s -920" in text


def test_no_card_without_verification(full_data):
    html = write_html(build_context(dataclasses.replace(full_data, verification=None)))
    assert "robustness-card" not in html
