"""Open the HTML report in headless Chromium (Playwright, system browser).

Fails on console errors, page errors, failed requests, any request that is
not file://, SVGs or images of zero size, and a blank render (pixel variance
of a screenshot). Needs /usr/bin/chromium (``.ci/browser-deps.sh`` installs
the Debian package); never downloads a browser.
"""

from __future__ import annotations

import os

import pytest

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync"]

# CI sets CCT_REQUIRE_BROWSER=1 (.ci/run installs Chromium): there a missing
# browser is a failure, not a skip.
REQUIRED = os.environ.get("CCT_REQUIRE_BROWSER") == "1"
pytestmark = [pytest.mark.skipif(not os.path.exists(CHROMIUM) and not REQUIRED,
                                 reason=f"{CHROMIUM} absent (run .ci/browser-deps.sh as root)"),
              pytest.mark.slow]   # a headless Chromium


@pytest.fixture(scope="module")
def browser():
    """One headless Chromium for the module's pages (each test opens its own page)."""
    from playwright import sync_api  # a test dependency: missing means broken set-up
    with sync_api.sync_playwright() as pw:
        chromium = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS, headless=True)
        try:
            yield chromium
        finally:
            chromium.close()


def _open(browser, page_path, shot):
    """Load ``page_path`` in a new page of ``browser``; return what went wrong
    and what it saw."""
    problems: list[str] = []
    requests: list[str] = []
    page = browser.new_page(viewport={"width": 1100, "height": 1400})
    try:
        page.on("console", lambda m: problems.append(f"console {m.type}: {m.text}")
                if m.type in ("error", "warning") else None)
        page.on("pageerror", lambda e: problems.append(f"page error: {e}"))
        page.on("requestfailed", lambda r: problems.append(f"request failed: {r.url}"))
        page.on("request", lambda r: requests.append(r.url))
        page.on("dialog", lambda d: (problems.append(f"dialog: {d.message}"), d.dismiss()))
        page.goto(page_path.as_uri(), wait_until="load")
        sizes = page.evaluate(
            "() => Array.from(document.querySelectorAll('svg, img')).map(e => {"
            " const r = e.getBoundingClientRect(); return [r.width, r.height]; })")
        title = page.evaluate("() => document.querySelector('h1').textContent")
        n_scripts = page.evaluate("() => document.scripts.length")
        page.screenshot(path=str(shot), full_page=True)
    finally:
        page.context.close()
    external = [u for u in requests if not u.startswith("file://")]
    return problems, requests, external, sizes, title, n_scripts


def test_report_renders_in_chromium(browser, full_data, full_html, tmp_path):
    page_path = tmp_path / "report.html"
    page_path.write_text(full_html, encoding="utf-8")
    shot = tmp_path / "report.png"
    problems, requests, external, sizes, title, n_scripts = _open(browser, page_path, shot)

    assert not problems, problems
    assert requests and not external, requests
    assert len(sizes) == 13  # 6 equations, 5 loop figures, robustness, 1 scenario
    assert all(w > 20 and h > 10 for w, h in sizes), sizes
    assert title == full_data.title  # hostile title shown literally
    assert n_scripts == 0

    from PIL import Image, ImageStat

    with Image.open(shot) as img:
        gray = img.convert("L")
        assert gray.size[1] > 3000  # a long page, not an error stub
        assert ImageStat.Stat(gray).stddev[0] > 10  # not blank


def test_checker_catches_bad_pages(browser, tmp_path):
    """Negative control: the checks above do fire on a script error, an external
    request and an empty image (the network request is refused by routing to an
    unroutable address and flags as external whatever its outcome)."""
    page_path = tmp_path / "bad.html"
    page_path.write_text(
        "<!DOCTYPE html><html><body><h1>x</h1><script>undefined_fn()</script>"
        '<img src="http://127.0.0.1:9/x.png"><svg width="0" height="0"></svg></body></html>',
        encoding="utf-8")
    problems, _, external, sizes, _, n_scripts = _open(browser, page_path, tmp_path / "bad.png")
    assert any("page error" in p for p in problems)
    assert external == ["http://127.0.0.1:9/x.png"]
    assert any(w == 0 or h == 0 for w, h in sizes)
    assert n_scripts == 1


#: The banner's colours (report.css --pass / --fail) as the browser computes them.
BANNER_RGB = {"pass": (31, 122, 58), "fail": (179, 38, 30)}
SCREENSHOTS = __import__("pathlib").Path(__file__).parents[2] / "reports" / "screenshots"


@pytest.mark.parametrize("verdict", ["pass", "fail"])
def test_verdict_banner_colour_and_text(browser, full_data, passing_data, verdict, tmp_path):
    """The report opens with the verdict: a green PASS or a red FAIL banner
    with the first failing reason, above the cards. CCT_WRITE_SCREENSHOTS=1
    also writes the top of the page to reports/screenshots/<verdict>.png (the
    gallery's; normal runs leave the tree alone)."""
    import dataclasses

    from toolbox.report import build_context
    from toolbox.report.html import render_html

    data = passing_data if verdict == "pass" else full_data
    data = dataclasses.replace(data, title="Paper 003 motor, PI at 1500 rad/s (report test "
                                           "fixture)")
    ctx = build_context(data)
    page_path = tmp_path / "report.html"
    page_path.write_text(render_html(ctx), encoding="utf-8")
    page = browser.new_page(viewport={"width": 1100, "height": 760})
    try:
        page.goto(page_path.as_uri(), wait_until="load")
        got = page.evaluate("""() => {
            const b = document.getElementById('verdict');
            const r = b.getBoundingClientRect();
            const first = document.querySelector('body > *:not(header)');
            return {bg: getComputedStyle(b).backgroundColor, text: b.innerText, left: r.left,
                    top: r.top, height: r.height, first: first.id,
                    cards: document.querySelector('.summary').getBoundingClientRect().top}; }""")
        shot = tmp_path / f"{verdict}.png"
        page.screenshot(path=str(shot))
    finally:
        page.context.close()
    assert got["bg"] == "rgb({}, {}, {})".format(*BANNER_RGB[verdict]), got
    assert got["first"] == "verdict" and got["top"] < got["cards"], got  # above the cards
    headline = got["text"].split()[0]
    assert headline == verdict.upper(), got["text"]
    assert ctx["banner"]["reason"] in got["text"]
    if verdict == "fail":
        assert "checks fail" in got["text"] and "min_gain_margin_db" in got["text"], got["text"]

    from PIL import Image

    with Image.open(shot) as img:  # the rendered pixels carry the colour, not only the CSS
        x, y = int(got["left"]) + 6, int(got["top"] + got["height"] / 2)
        r, g, b = img.convert("RGB").getpixel((x, y))
    assert max(abs(r - BANNER_RGB[verdict][0]), abs(g - BANNER_RGB[verdict][1]),
               abs(b - BANNER_RGB[verdict][2])) <= 8, (r, g, b)
    if os.environ.get("CCT_WRITE_SCREENSHOTS") == "1":
        SCREENSHOTS.mkdir(parents=True, exist_ok=True)
        (SCREENSHOTS / f"{verdict}.png").write_bytes(shot.read_bytes())
