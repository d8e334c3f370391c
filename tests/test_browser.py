"""The dashboard in a real browser: Debian's Chromium driven by Playwright against
``python -m dashboard`` (``make run``'s command) on a free local port.

Skipped when Chromium is not installed at ``/usr/bin/chromium`` (``.ci/run`` installs
it). Screenshots (1280×800, every page) and the server logs are written to
``test-artifacts/``. Accessibility is measured with axe-core (``tests/node``, installed
by ``make axe`` or, when missing, by ``npm ci`` here) on every page; without axe-core that test fails.
"""

from __future__ import annotations

import contextlib
import datetime as dt
import io
import itertools
import os
import re
import shutil
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import rvpp
from rvpp.store import RunLibrary

try:
    from playwright.sync_api import TimeoutError as PlaywrightTimeout
except ImportError:  # the tests skip without Playwright (require_browser)
    PlaywrightTimeout = TimeoutError

pytestmark = pytest.mark.browser

ROOT = Path(__file__).resolve().parent.parent
ARTIFACTS = ROOT / "test-artifacts"
CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"]
VIEWPORT = {"width": 1400, "height": 4200}  # tall: full-page screenshots stop at the viewport
START_TIMEOUT_S = 90    # ceilings for waiting, never performance assertions
WAIT_MS = 120_000
RECONNECT_MS = 20_000  # how long a tab is given to reconnect to a restarted server before it is reloaded
AXE_DIR = ROOT / "tests" / "node"
GRID_HEADER_PX, GRID_ROW_PX = 35, 35   # Streamlit's data editor: header and row height
P_MAX_X_PX = 168                       # the middle of the "P max [MW]" column of the wind table
GRID_READY_MS = 1000                   # a data editor takes a moment to accept input once drawn
EDIT_TRIES, EDIT_WAIT_MS = 3, 20_000
EDITOR_WAIT_MS = 5_000                 # a double-click opens the cell's editor within this
QUIET_POLLS, POLL_MS = 3, 1000         # a page counts as drawn after 3 s without Streamlit running
PAGES = {"Home": "home", "Portfolio": "portfolio", "Markets & tariffs": "markets", "Uncertainty": "uncertainty",
         "Results": "results", "Compare strategies": "compare", "Saved runs": "runs",
         "Sensitivity to Γ": "sensitivity", "Market sets & HPA prices": "market-sets",
         "Out-of-sample vs stochastic": "out-of-sample", "Backtest": "backtest", "Robust bidding explained": "learn"}
# Violations the project can fix: contrast, and every rule about a control's label or name.
FIXABLE = {"color-contrast", "label", "button-name", "link-name", "input-button-name", "aria-input-field-name",
           "aria-toggle-field-name", "select-name", "image-alt", "label-title-only", "frame-title",
           "document-title", "aria-command-name", "aria-meter-name", "aria-progressbar-name", "svg-img-alt"}
# Streamlit 1.67's sidebar navigation puts section headers (div) inside its <ul>: axe-core 4.14
# reports "list" for the <ul> and "listitem" for its <li>. Listed in docs/dashboard.md.
STREAMLIT_KNOWN = ("list", "listitem")
MARKET_COLUMNS = ["t", "start", "clock", "p_da_mw", "r_sr_up_mw", "r_sr_dn_mw", "h_hpa_mw", "price_da_mid",
                  "price_da_pos", "price_da_neg", "price_sr_up_hi", "price_sr_up_neg", "price_sr_dn_hi",
                  "price_sr_dn_neg", "tariff_hpa"]


def free_port() -> int:
    """A free local port; from the range ``RVPP_TEST_PORTS`` (``8610-8619``) when set."""
    first, _, last = os.environ.get("RVPP_TEST_PORTS", "0-0").partition("-")
    for port in range(int(first), int(last or first) + 1):
        with socket.socket() as probe:
            try:
                probe.bind(("127.0.0.1", port))
            except OSError:
                continue
            return probe.getsockname()[1]
    raise OSError(f"no free port in RVPP_TEST_PORTS={os.environ['RVPP_TEST_PORTS']}")


def require_browser() -> None:
    if not CHROMIUM.exists():
        pytest.skip(f"Chromium is not installed at {CHROMIUM} (Debian: apt-get install chromium); "
                    "the real-browser test needs it")
    pytest.importorskip("playwright.sync_api", reason="the Playwright Python package is not installed")


@contextlib.contextmanager
def streamlit_server(log_name: str, data_dir: Path | None = None, port: int | None = None):
    """A fresh dashboard as ``make run`` starts it (``python -m dashboard``) on a free port (or
    ``port``), whose saved runs go to ``data_dir``; yields its URL."""
    ARTIFACTS.mkdir(exist_ok=True)
    port = port or free_port()
    log = open(ARTIFACTS / log_name, "a")
    env = {**os.environ, "RVPP_DATA_DIR": str(data_dir or ARTIFACTS / "rvpp-data")}
    env.pop("RVPP_STORE_URL", None)
    server = subprocess.Popen(
        [sys.executable, "-m", "dashboard", "--server.headless", "true",
         "--server.address", "127.0.0.1", "--server.port", str(port)],
        cwd=ROOT, stdout=log, stderr=subprocess.STDOUT, env=env)
    url = f"http://127.0.0.1:{port}"
    deadline = time.monotonic() + START_TIMEOUT_S
    try:
        while True:
            try:
                with urllib.request.urlopen(f"{url}/_stcore/health", timeout=1) as response:
                    if response.status == 200:
                        break
            except OSError:
                if server.poll() is not None or time.monotonic() > deadline:
                    pytest.fail(f"streamlit did not start; see {ARTIFACTS / log_name}")
                time.sleep(0.2)
        yield url
    finally:
        server.terminate()
        try:
            server.wait(timeout=10)
        except subprocess.TimeoutExpired:
            server.kill()
        log.close()


@contextlib.contextmanager
def chromium_page(viewport: dict = VIEWPORT, scheme: str = "light", scale: float = 1):
    """A page of Debian's Chromium, driven by Playwright, that accepts downloads, in the colour ``scheme``
    (``light`` or ``dark``: the viewer's preference, which the dashboard's theme follows), ``scale`` device
    pixels to a CSS pixel (1.5: a browser zoomed to 150 %)."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS)
        try:
            page = browser.new_page(viewport=viewport, accept_downloads=True, color_scheme=scheme,
                                    device_scale_factor=scale)
            page.set_default_timeout(WAIT_MS)
            yield page
        finally:
            browser.close()


@pytest.fixture(scope="module")
def app_url(tmp_path_factory):
    require_browser()
    with streamlit_server("streamlit.log", tmp_path_factory.mktemp("rvpp-data")) as url:
        yield url


def test_home_then_results_solve_draws_the_charts(app_url, paper_solve):
    expected = paper_solve()
    with chromium_page() as page:
        page.goto(app_url)
        page.get_by_role("heading", name="Robust day-ahead bids").wait_for()
        page.get_by_role("button", name="Solve the balanced strategy").wait_for()
        page.get_by_role("table").first.wait_for()
        # Home's first chart, drawn on the server as SVG: first an image, then the SVG in its place
        # (it must reach the page whole: an element that kept only HTML would drop it), one image
        # named by its title either way, with a tooltip per period once in place.
        page.locator("svg.rvpp-chart").wait_for()
        band = page.get_by_role("img", name="Day-ahead price: forecast band", exact=True)
        assert band.count() == 1 and band.evaluate("element => element.tagName") == "svg"
        image = page.locator('[data-testid="stMarkdownContainer"] img[alt="Day-ahead price: forecast band"]')
        assert image.evaluate("img => img.hidden && img.complete && img.naturalWidth > 0")
        assert len(band.locator("polyline.median").get_attribute("points").split()) == 24
        assert band.locator("g.tips rect").count() == 24
        assert "Day-ahead price on Mon 05 May 2025, 24 periods of 60 minutes." in band.evaluate(
            "svg => document.getElementById(svg.getAttribute('aria-describedby')).textContent")
        assert band.bounding_box()["width"] > 300
        # Only an image whose SVG carries this server's token is put in place as markup.
        page.evaluate("""([root, token]) => {
            const add = (markup) => {
                const img = document.createElement('img');
                img.src = 'data:image/svg+xml;base64,' + btoa(markup);
                document.querySelector('[data-testid="stMarkdownContainer"]').append(img);
            };
            add(root + 'data-rvpp="forged" id="forged"><title>x</title></svg>');
            add(root + 'data-rvpp="' + token + '" id="genuine"><title>y</title></svg>');
        }""", ['<svg class="rvpp-chart" ', band.get_attribute("data-rvpp")])
        page.locator("svg#genuine").wait_for(state="attached")
        assert page.locator("#forged").count() == 0
        page.screenshot(path=ARTIFACTS / "home.png", full_page=True)

        page.get_by_test_id("stSidebarNav").get_by_role("link", name="Results").click()
        page.get_by_role("heading", name="Results").wait_for()
        page.get_by_role("button", name="Solve", exact=True).click()
        charts = page.get_by_test_id("stPlotlyChart")
        charts.first.locator(".main-svg").first.wait_for()
        charts.nth(5).locator(".main-svg").first.wait_for()
        assert charts.count() == 6
        page.get_by_text(f"{-expected.objective_eur / 1000:,.1f}".replace("-", "−"), exact=True).first.wait_for()

        with page.expect_download() as download:
            page.get_by_role("button", name="Bids (CSV)").click()
        bids = pd.read_csv(io.BytesIO(Path(download.value.path()).read_bytes()))
        assert list(bids.columns) == MARKET_COLUMNS
        np.testing.assert_allclose(bids["p_da_mw"], expected.market["p_da_mw"], atol=1e-5)
        page.screenshot(path=ARTIFACTS / "results.png", full_page=True)


@pytest.mark.slow
def test_a_first_plan_finds_the_code_of_its_elements_loaded_ahead(tmp_path):
    """Home has its browser load the code of Plotly charts, cards, text fields and tables while
    idle, so a server's first plan on Results fetches none of it, nor the markdown's emoji code."""
    require_browser()
    wanted = ("PlotlyChart.", "Metric.", "TextInput.", "DataFrame.")
    with streamlit_server("streamlit-first-plan.log", tmp_path) as url, chromium_page() as page:
        page.goto(url)
        page.locator("svg.rvpp-chart").first.wait_for()
        page.wait_for_function("(names) => names.every(n => performance.getEntriesByType('resource')"
                               ".some(e => e.name.split('/').pop().startsWith(n) && e.name.endsWith('.js')))",
                               arg=list(wanted))
        page.get_by_test_id("stSidebarNav").get_by_role("link", name="Results").click()
        page.get_by_role("button", name="Solve", exact=True).wait_for()
        fetched = []
        page.on("request", lambda request: fetched.append(request.url.rsplit("/", 1)[-1]))
        page.get_by_role("button", name="Solve", exact=True).click()
        page.get_by_test_id("stPlotlyChart").nth(5).locator(".main-svg").first.wait_for()
        page.get_by_test_id("stDataFrame").first.wait_for()
        page.get_by_text("The solver's answer came back at").wait_for(state="attached")  # in a closed expander
        scripts = [name for name in fetched if name.endswith(".js")]
        assert not [name for name in scripts if name.startswith((*wanted, "remark-emoji."))], scripts
        clock = page.get_by_text("The solver's answer came back at").text_content()
        assert re.search(r"at \d\d:\d\d:\d\d\.\d{3} \(server clock\)", clock), clock


@pytest.mark.slow
def test_the_learn_gamma_slider_moves_by_keyboard_to_the_plan_of_each_gamma(app_url, paper_case, paper_solve):
    with chromium_page() as page:
        page.goto(app_url)
        open_page(page, "Robust bidding explained")
        slider = page.get_by_test_id("stSlider").filter(has_text="Γ of every source")
        compute = page.get_by_role("button", name=re.compile("Compute the plans for every Γ"))
        curve = page.locator(".gtitle", has_text="plan shown: Γ =").first
        compute.or_(curve).first.wait_for()
        if compute.count():  # another test of this server may have swept the case already
            compute.click()
        curve.wait_for()
        thumb = slider.get_by_role("slider")
        start = int(thumb.input_value())
        for gamma in (start + 1, start + 2):
            page.wait_for_function("() => !document.querySelector('[data-testid=stStatusWidget]')")
            thumb.focus()
            page.keyboard.press("ArrowRight")
            page.locator(".gtitle", has_text=f"Bids at Γ = {gamma}:").first.wait_for()
            expected = paper_solve(gammas={source: gamma for source in paper_case.sources()})
            card = page.get_by_test_id("stMetric").filter(has_text="Net cost [kEUR]").first
            shown = float(card.get_by_test_id("stMetricValue").inner_text().replace("−", "-").replace(",", ""))
            assert shown == pytest.approx(-expected.objective_eur / 1000, abs=0.051 + 1e-4 * abs(expected.cost_keur))
        page.screenshot(path=ARTIFACTS / "learn-gamma-slider.png", full_page=True)


@pytest.mark.slow
def test_a_link_straight_to_a_page_on_a_fresh_server_opens_that_page():
    # Until a session has opened the app, Streamlit runs a page linked directly (a
    # bookmark, a tab reconnecting after a restart) without app.py; the page must
    # route itself through the app and come back, with the app's navigation.
    require_browser()
    with streamlit_server("streamlit-deep-link.log") as url, chromium_page({"width": 1400, "height": 1600}) as page:
        page.goto(f"{url}/portfolio")
        page.get_by_role("heading", name="Portfolio").wait_for()
        page.get_by_role("heading", name="Wind farms").wait_for()
        navigation = page.get_by_test_id("stSidebarNav")
        navigation.get_by_role("link", name="Compare strategies").wait_for()
        assert page.url.endswith("/portfolio")
        assert page.get_by_test_id("stException").count() == 0
        page.screenshot(path=ARTIFACTS / "deep-link.png", full_page=True)


@pytest.mark.slow
def test_a_study_page_runs_its_study_with_progress_and_downloads_its_table(app_url, paper_solve):
    # The study runs in a study process spawned under the real server; its table must
    # carry the same numbers as a plain solve (Γ = 0 everywhere is the deterministic plan).
    deterministic = paper_solve(strategy="deterministic")
    with chromium_page() as page:
        page.goto(app_url)
        page.get_by_test_id("stSidebarNav").get_by_role("link", name="Sensitivity to Γ").click()
        page.get_by_role("heading", name="Sensitivity to the uncertainty budget Γ").wait_for()
        page.get_by_test_id("stTextInputField").first.fill("0, 24")
        page.get_by_role("button", name="Run").click()
        page.get_by_text("Done in").wait_for()
        page.get_by_test_id("stPlotlyChart").nth(1).locator(".main-svg").first.wait_for()
        assert page.get_by_role("button", name="Cancel").count() == 0
        page.screenshot(path=ARTIFACTS / "sensitivity.png", full_page=True)

        with page.expect_download() as download:
            page.get_by_role("button", name="Table (CSV)").click()
        table = pd.read_csv(io.BytesIO(Path(download.value.path()).read_bytes()))
        assert list(table["gamma"]) == [0, 24]
        assert list(table["status"]) == ["optimal", "optimal"]
        assert table["cost_keur"][0] == pytest.approx(-deterministic.objective_eur / 1000, rel=1e-6)
        assert table["cost_keur"][1] > table["cost_keur"][0]


def test_homes_first_screen_holds_the_question_the_solve_button_and_the_case():
    require_browser()
    with streamlit_server("streamlit-first-screen.log") as url, chromium_page({"width": 1280, "height": 800}) as page:
        page.goto(url)
        question = page.get_by_role("heading", name="What should I bid tomorrow?")
        solve = page.get_by_role("button", name="Solve the balanced strategy")
        case = page.get_by_role("table").filter(has=page.get_by_role("columnheader", name="Installed")).first
        for element in (question, solve, case):
            element.wait_for()
        settle(page)
        page.screenshot(path=ARTIFACTS / "home-first-screen.png")
        for name, element in (("question", question), ("Solve", solve), ("case", case)):
            box = element.bounding_box()
            assert box["y"] >= 0 and box["y"] + box["height"] <= 800, (name, box)
            assert box["x"] + box["width"] <= 1280, (name, box)


def test_homes_case_table_is_whole_in_a_1024_pixel_window(app_url):
    # Beside the question, the case's table ran 54 px past the window's edge, its "Installed" column cut off.
    with chromium_page({"width": 1024, "height": 800}) as page:
        page.goto(app_url)
        case = page.get_by_role("table").filter(has=page.get_by_role("columnheader", name="Installed")).first
        case.wait_for()
        settle(page)
        page.screenshot(path=ARTIFACTS / "home-1024.png")
        right = case.evaluate("table => table.getBoundingClientRect().right")
        main = page.get_by_test_id("stMain").evaluate("main => [main.scrollWidth, main.clientWidth]")
        assert right <= 1024 and main[0] <= main[1], (right, main)


def test_the_conversion_curve_table_is_whole_at_1280_pixels(app_url):
    # Its two columns and row markers (327 px) had 320 px beside the chart: the efficiencies ran under the edge.
    with chromium_page({"width": 1280, "height": 800}) as page:
        page.goto(app_url)
        open_page(page, "Portfolio")
        page.get_by_role("heading", name="Power-block conversion curve").scroll_into_view_if_needed()
        settle(page)
        page.wait_for_function("""() => [...document.querySelectorAll('[data-testid=stDataFrame]')]
            .some(d => d.textContent.includes('Efficiency [-]') && d.querySelector('.dvn-scroller'))""")
        widths = page.evaluate("""() => [...document.querySelectorAll('[data-testid=stDataFrame]')]
            .filter(d => d.textContent.includes('Efficiency [-]'))
            .map(d => [d.querySelector('.dvn-scroller').scrollWidth, d.querySelector('.dvn-scroller').clientWidth])""")
        assert len(widths) == 1 and widths[0][0] <= widths[0][1], widths


# What a 1366×768 laptop at 150 % zoom shows: 911×512 CSS pixels, the sidebar open beside a main area of 611.
LAPTOP_150 = {"width": 911, "height": 512}
CUT_TEXTS = """() => [...document.querySelectorAll('[data-testid=stMain] *')]
    .filter(e => !e.closest('[data-testid=stDataFrame], .js-plotly-plot') && e.innerText && e.innerText.trim())
    .filter(e => { const style = getComputedStyle(e);
        const clips = style.overflowX !== 'visible' || style.textOverflow === 'ellipsis';
        return clips && e.scrollWidth > e.clientWidth + 1; })
    .map(e => e.innerText.trim().slice(0, 60))"""
PAST_THE_EDGE = """() => {
    const edge = document.querySelector('[data-testid=stMainBlockContainer]').getBoundingClientRect().right;
    return [...document.querySelectorAll('[data-testid=stMain] *')]
        .filter(e => !e.closest('[data-testid=stDataFrame]') && e.getBoundingClientRect().right > edge + 1)
        .map(e => e.getAttribute('data-testid') || e.tagName); }"""
CUT_CHART_TITLES = """() => [...document.querySelectorAll('.js-plotly-plot')].filter(plot => {
    const title = plot.querySelector('.gtitle'), frame = plot.querySelector('.main-svg').getBoundingClientRect();
    return title && title.getBoundingClientRect().right > frame.right + 1;
}).map(plot => plot.querySelector('.gtitle').textContent)"""


# Home and Results in every run (make test); the pages a teacher presents in the slow runs (make test-all)
@pytest.mark.parametrize("title", ["Home", "Results", *(pytest.param(title, marks=pytest.mark.slow) for title in
                                                        ("Robust bidding explained", "Uncertainty", "Markets & tariffs"))])
def test_a_page_shown_on_a_laptop_at_150_percent_cuts_no_text(app_url, title):
    # At 911 CSS px the controls beside Learn's charts were 112 px wide: "Energy at ri…", "260.…" MWh, the
    # Price "Day-ahea…" and its chart's title ran under the edge; Markets' switches read "Day-ahead…",
    # "Secondary…"; Uncertainty's band charts were 220 px wide, their titles and axis titles cut.
    with chromium_page(LAPTOP_150, scale=1.5) as page:
        page.goto(app_url)
        if title == "Home":  # its links to the other pages were cut: "Compare strate…", "Robust bidding expl…"
            page.get_by_role("heading", name="Load another case").wait_for()
        else:
            open_page(page, title)
        if title == "Results":  # its cards were 101 px wide: "Net cost [k…", "Reserve revenue [k…", "Bids (C…"
            page.get_by_role("button", name="Solve", exact=True).click()
        if title != "Home":
            page.get_by_test_id("stPlotlyChart").first.locator(".main-svg").first.wait_for()
        if title == "Uncertainty":
            page.get_by_role("button", name="Solve to mark the deviating periods χ").click()
            page.get_by_text("Shaded, with a cross", exact=False).wait_for()
        if title == "Robust bidding explained":
            page.get_by_text("Protection [kEUR]").first.wait_for()
        settle(page)
        main = page.get_by_test_id("stMain").evaluate("main => [main.scrollWidth, main.clientWidth]")
        page.screenshot(path=ARTIFACTS / f"laptop-150-{title.split()[0].lower()}.png")
        assert main[0] <= main[1], main
        assert page.evaluate(CUT_TEXTS) == []
        assert page.evaluate(PAST_THE_EDGE) == []  # Results: the waterfall's title ran past its chart
        assert page.evaluate(CUT_CHART_TITLES) == []


@pytest.mark.slow  # a server started twice; tests/test_app_newcomer.py checks the same in every run without a server
def test_a_tab_open_through_a_server_restart_says_its_edited_case_is_gone(tmp_path):
    # A tab set 30-minute periods and the server restarted under it: the tab reconnected to a new session that
    # showed the shipped case at 60 minutes without a word, "Press Solve to compute the plan of the current case".
    require_browser()
    port = free_port()
    with chromium_page({"width": 1280, "height": 800}) as page:
        with streamlit_server("streamlit-restart.log", tmp_path, port) as url:
            page.goto(url)
            open_page(page, "Markets & tariffs")
            page.get_by_role("radio", name="30", exact=True).click()
            page.wait_for_url(re.compile(r"own_case=1"))
            open_page(page, "Results")
            page.wait_for_url(re.compile(r"/results\?own_case=1$"))
        with streamlit_server("streamlit-restart.log", tmp_path, port):
            gone = page.get_by_test_id("stAlert").filter(
                has_text="This tab's case (loaded, opened or edited here) is gone")
            try:
                gone.wait_for(timeout=RECONNECT_MS)  # the tab reconnected and ran its page again by itself
            except PlaywrightTimeout:  # Streamlit's client does not always run the page again on reconnecting
                page.reload()
                gone.wait_for()
            settle(page)
            page.screenshot(path=ARTIFACTS / "restart-case-gone.png")
            assert page.get_by_role("heading", name="Results").count() == 1
            assert "30-min" not in page.get_by_test_id("stSidebarUserContent").inner_text()


@pytest.mark.slow
def test_a_started_backtest_shows_up_and_its_progress_moves_until_finished(tmp_path):
    """Started on the page, the backtest appears there without a reload and its progress is
    redrawn as days settle, until it says finished."""
    require_browser()
    with streamlit_server("streamlit-backtest.log", tmp_path) as url, \
            chromium_page({"width": 1280, "height": 1600}) as page:
        page.goto(url)
        open_page(page, "Backtest")
        page.get_by_text("Start a backtest of the current case").click()
        first_day = page.get_by_test_id("stDateInput").first.locator("input")
        last_day = page.get_by_test_id("stDateInput").nth(1).locator("input").input_value()
        first_day.fill(last_day)  # one day: five chains (four presets and perfect information)
        first_day.press("Enter")
        page.get_by_test_id("stTextInput").filter(has_text="Label").locator("input").fill("browser backtest")
        page.get_by_role("button", name="Start the backtest").click()
        started = time.monotonic()
        page.get_by_test_id("stProgress").filter(has_text="browser backtest").first.wait_for()  # at once: starting
        appeared_s = time.monotonic() - started
        bar = page.get_by_test_id("stProgress").filter(has_text="days × strategies settled")
        bar.first.wait_for()  # listed once its process registered it, without a reload
        listed_s = time.monotonic() - started
        seen = []
        while True:
            text = bar.first.inner_text()
            if not seen or seen[-1] != text:
                seen.append(text)
            if "finished" in text:
                break
            assert time.monotonic() - started < WAIT_MS / 1000, seen  # a ceiling for the work, not a speed test
            page.wait_for_timeout(200)
        print(f"backtest shown {appeared_s:.2f} s, listed {listed_s:.2f} s after the click; progress seen: {seen}")
        done = [int(re.match(r"(\d+) of (\d+)", t).group(1)) for t in seen]
        assert done == sorted(done) and len(set(done)) >= 2, seen  # it moved, forwards
        assert seen[-1].startswith("5 of 5 days × strategies settled · finished"), seen
        page.screenshot(path=ARTIFACTS / "backtest-finished.png")
        shown = page.get_by_test_id("stSelectbox").filter(has_text="Backtest shown below")
        assert shown.locator("input").input_value().startswith("browser backtest · ")


@pytest.mark.slow
def test_a_running_backtest_draws_its_figures_once_its_first_days_settle(tmp_path, paper_case):
    """The page said "No day settled yet; the figures appear with the first days" until the backtest ended
    (minutes later), while its progress bar counted the days settled."""
    require_browser()
    from rvpp.backtest import BacktestSettings, variants_of
    from rvpp.backtest.engine import run_backtest
    from rvpp.store import BacktestStore

    day = paper_case.delivery_date
    settings = BacktestSettings(day, day, variants_of(["deterministic", "balanced"], []))
    settled = BacktestStore(f"sqlite:///{tmp_path / 'settled.sqlite3'}")
    records = settled.record_map(run_backtest(paper_case, settings, settled))
    store = BacktestStore(f"sqlite:///{tmp_path / 'rvpp.sqlite3'}")
    ident = store.open(paper_case, settings.stored(), keys_total=len(records), label="still running")
    store.set_progress(ident, "running", 0, len(records))  # this process plays the backtest's own
    try:
        with streamlit_server("streamlit-backtest-running.log", tmp_path) as url, \
                chromium_page({"width": 1280, "height": 1600}) as page:
            page.goto(url)
            open_page(page, "Backtest")
            page.get_by_text("No day settled yet").wait_for()
            key, record = next(iter(records.items()))
            store.record(ident, key, record)
            store.set_progress(ident, "running", 1, len(records))
            page.get_by_role("heading", name="Cost over the period").wait_for(timeout=30_000)
            assert page.get_by_text("No day settled yet").count() == 0
            assert "1 of 3 days × strategies settled · running" in page.get_by_test_id("stProgress").first.inner_text()
            page.screenshot(path=ARTIFACTS / "backtest-running-figures.png")
    finally:
        store.set_progress(ident, "stopped", 1, len(records))


def cut_off_buttons(page) -> list[str]:
    """The labels of the page's buttons drawn cut off (ending in an ellipsis)."""
    return page.evaluate("""() => [...document.querySelectorAll('[data-testid=stMain] button')]
        .filter(b => [...b.querySelectorAll('*')].some(e => e.scrollWidth > e.clientWidth + 1))
        .map(b => b.innerText.trim())""")


@pytest.mark.slow
def test_the_sweep_button_shows_its_whole_label_with_the_expected_time_at_1280_pixels(tmp_path):
    # Once this server has timed a solve, the button of the Γ sweep says how long its solves take;
    # beside the text in half a row, that end of its label was cut off.
    require_browser()
    with streamlit_server("streamlit-sweep-button.log", tmp_path) as url, \
            chromium_page({"width": 1280, "height": 800}) as page:
        page.goto(url)
        open_page(page, "Results")
        page.get_by_role("button", name="Solve", exact=True).click()
        page.get_by_test_id("stMetric").first.wait_for()
        for title in ("Robust bidding explained", "Compare strategies"):
            open_page(page, title)
            button = page.get_by_role("button", name=re.compile(r"Compute the plans for every Γ \(25 solves · about"))
            button.wait_for()
            settle(page)
            button.scroll_into_view_if_needed()
            page.screenshot(path=ARTIFACTS / f"sweep-button-{title.split()[0].lower()}.png")
            assert cut_off_buttons(page) == [], title


@pytest.mark.parametrize(("page_name", "button"), [("Home", "Solve the balanced strategy"), ("Results", "Solve")])
def test_the_sidebar_says_solved_only_of_a_solve_that_gave_a_plan(app_url, paper_solve, page_name, button):
    # With the HPA off the day has no plan (heat short at night): Home said so, and the sidebar beside it
    # said "solved — see Results" with a tick; Results said so, and the sidebar beside it said nothing of the solve.
    assert not paper_solve(markets="DAM+SRM").has_plan  # the library agrees: no plan without the HPA
    with chromium_page({"width": 1280, "height": 800}) as page:
        page.goto(app_url)
        open_page(page, "Markets & tariffs")
        page.get_by_text("Heat purchase (HPA)").click()
        page.get_by_test_id("stSidebar").get_by_text(re.compile(r"balanced · DAM\+SRM$")).wait_for()
        open_page(page, page_name)
        page.get_by_role("button", name=button, exact=True).click()
        page.get_by_test_id("stAlert").filter(has_text="No plan").wait_for()
        settle(page)
        sidebar = page.get_by_test_id("stSidebarUserContent").inner_text()
        page.screenshot(path=ARTIFACTS / f"sidebar-no-plan-{page_name.lower()}.png")
        assert "solved" not in sidebar and "no plan" in sidebar, sidebar


# ----------------------------------------------------------------------------- saved runs, edits


def open_page(page, name: str) -> None:
    page.get_by_test_id("stSidebarNav").get_by_role("link", name=name, exact=True).click()
    page.locator("h1").first.wait_for()


def edit_grid_cell(page, table: int, row: int, x_offset: float, value: str) -> None:
    """Type ``value`` into a cell of the ``table``-th data editor (the grid is a canvas:
    double-click at the cell's position, select its text, type, Enter)."""
    settle(page)  # an editor redrawn by a run still under way drops what is typed into it
    grid = page.get_by_test_id("stDataFrame").nth(table)
    grid.scroll_into_view_if_needed()
    grid.locator(f"#glide-cell-1-{row}").wait_for(state="attached")
    page.wait_for_timeout(GRID_READY_MS)
    editor = page.locator(".gdg-input").first  # the cell's overlay editor, open while editing
    for _ in range(EDIT_TRIES):
        box = grid.bounding_box()
        page.mouse.dblclick(box["x"] + x_offset, box["y"] + GRID_HEADER_PX + GRID_ROW_PX * (row + 0.5))
        try:
            editor.wait_for(state="visible", timeout=EDITOR_WAIT_MS)
            break
        except PlaywrightTimeout:
            page.wait_for_timeout(GRID_READY_MS)
    editor.fill(value)
    editor.press("Enter")


def chart_data(page, title: str) -> list[dict]:
    """The traces of the Plotly chart titled ``title`` as drawn in the page."""
    return page.evaluate("""title => {
        const plot = [...document.querySelectorAll('.js-plotly-plot')]
            .find(p => p.layout && p.layout.title && p.layout.title.text.replace(/<[/]?b>/g, "") === title);
        return plot ? plot._fullData.map(t => ({name: t.name, y: Array.from(t.y || [])})) : null;
    }""", title)


def saved_labels(page) -> list[str]:
    open_page(page, "Saved runs")
    settle(page)
    table = page.get_by_test_id("stDataFrame").first
    page.wait_for_function("""() => [...document.querySelectorAll('[data-testid=stDataFrame] [id^=glide-cell-1-]')]
        .some(cell => cell.innerText.trim())""")
    return table.locator("[id^=glide-cell-1-]").all_inner_texts()


def table_cells(page, column: int) -> list[str]:
    """The texts of a column of the page's first table as its grid draws them."""
    return page.get_by_test_id("stDataFrame").first.locator(f"[id^=glide-cell-{column}-]").all_inner_texts()


def first_table_headers(page, screenshot: str) -> list[str]:
    """The column headers the page's first table draws, once the page has settled (kept as ``screenshot``)."""
    table = page.get_by_test_id("stDataFrame").first
    table.wait_for()
    settle(page)
    page.screenshot(path=ARTIFACTS / screenshot)
    return table.evaluate("table => [...table.querySelectorAll('[role=columnheader]')].map(h => h.innerText.trim())")


def table_overflow(page, table: int = 0) -> int:
    """How many pixels of the ``table``-th table's columns lie past its right edge (0: every column in view)."""
    return page.get_by_test_id("stDataFrame").nth(table).evaluate("""table => {
        const scroller = table.querySelector('.dvn-scroller');
        return Math.max(0, scroller.scrollWidth - scroller.clientWidth - 1); }""")


def text_table_spill(page, table) -> tuple[float, float, int]:
    """How far a text table (``st.table``) spills: past its own box [px], past the page's main area [px], and
    how many of its cells cut their text."""
    spill, cells = table.evaluate("""t => [t.scrollWidth - t.clientWidth, [...t.querySelectorAll('th, td')].map(c =>
        [c.getBoundingClientRect().right, c.scrollWidth - c.clientWidth])]""")
    right = page.get_by_test_id("stMain").evaluate("m => m.getBoundingClientRect().right")
    return spill, max(edge for edge, _ in cells) - right, sum(hidden > 1 for _, hidden in cells)


def number(text: str) -> float:
    return float(text.replace("−", "-").replace(",", ""))


@pytest.mark.slow
def test_the_saved_runs_table_shows_every_column_whole_at_1280_pixels(tmp_path, paper_case, paper_solve):
    # The net cost, the number a run is saved for, was cut off at the right edge of the table at 1280
    # pixels, after the case, the day, the strategy and the markets; then the time saved and the link were.
    require_browser()
    library = RunLibrary(f"sqlite:///{tmp_path / 'rvpp.sqlite3'}")
    pessimistic = rvpp.with_options(paper_case, strategy="pessimistic")
    library.save("balanced · DAM+SRM+HPA", paper_case, paper_solve())
    library.save("pessimistic · DAM+SRM+HPA", pessimistic, paper_solve(strategy="pessimistic"))
    with streamlit_server("streamlit-runs-table.log", tmp_path) as url, \
            chromium_page({"width": 1280, "height": 800}) as page:
        page.goto(url)
        open_page(page, "Saved runs")
        # The grid lists the columns it draws, each at least in part: one drawn after the net cost shows it whole.
        headers = first_table_headers(page, "saved-runs-1280.png")
        assert headers[:3] == ["Label", "Net cost [kEUR]", "Status"], headers
        assert headers[-2:] == ["Saved (UTC)", "Link"], headers
        assert not table_overflow(page), headers
        # The strategy and the markets, no longer columns, are said of a ticked run.
        box = page.get_by_test_id("stDataFrame").first.bounding_box()
        page.mouse.click(box["x"] + 16, box["y"] + GRID_HEADER_PX + GRID_ROW_PX / 2)
        page.get_by_text(f"pessimistic strategy · DAM+SRM+HPA · case paper · delivery day {paper_case.delivery_date}"
                         " · saved ").wait_for()
        cells = table_cells(page, 2)
        assert [number(cell) for cell in cells] == [pytest.approx(-paper_solve(strategy="pessimistic").objective_eur
                                                                  / 1000, abs=0.05),
                                                    pytest.approx(-paper_solve().objective_eur / 1000, abs=0.05)]


@pytest.mark.slow
def test_compare_shows_every_part_of_two_saved_runs_whole_at_1280_pixels(tmp_path, paper_case, paper_solve):
    # With two saved runs under their default labels the table of parts needed 130 px more than it had: the
    # robust protection, the last part of the net cost, was out of view; a narrower label column cut the
    # labels to "balanced · DAM+SRM+HPA…", which two runs of other capacities share.
    require_browser()
    library = RunLibrary(f"sqlite:///{tmp_path / 'rvpp.sqlite3'}")
    labels = ["pessimistic · DAM+SRM+HPA · WF1 80 MW *safe* [open](https://evil.example) :red[x]",
              "balanced · DAM+SRM+HPA · WF1 80 MW"]
    library.save(labels[0], rvpp.with_options(paper_case, strategy="pessimistic"), paper_solve(strategy="pessimistic"))
    library.save(labels[1], paper_case, paper_solve())
    with streamlit_server("streamlit-compare-runs.log", tmp_path) as url, \
            chromium_page({"width": 1280, "height": 1600}) as page:
        page.goto(url)
        open_page(page, "Compare strategies")
        page.get_by_test_id("stButtonGroup").get_by_text("Saved runs", exact=True).click()
        table = page.get_by_test_id("stTable")
        table.wait_for()
        settle(page)
        page.screenshot(path=ARTIFACTS / "compare-runs-1280.png")
        headers = table.evaluate("t => [...t.querySelectorAll('thead th')].map(h => h.innerText.trim())")
        assert headers[-1] == "Robust protection [kEUR]", headers
        spill, past_main, cut = text_table_spill(page, table)
        assert spill <= 1 and past_main <= 1 and cut == 0, (spill, past_main, cut)
        rows = table.evaluate("t => [...t.querySelectorAll('tbody tr th')].map(h => h.innerText.trim())")
        assert sorted(rows) == sorted(labels), rows  # whole, as typed: a label's markdown is not drawn
        assert table.locator("em, strong, span[style]").count() == 0
        # A web address typed in a label may be linked by the markdown renderer, but only as itself: no text hides a link
        links = table.evaluate("t => [...t.querySelectorAll('a')].map(a => [a.innerText, a.getAttribute('href')])")
        assert all(text == href for text, href in links), links
        assert "Extra cost vs balanced · DAM+SRM+HPA · WF1 80 MW [kEUR]" in headers, headers


@pytest.mark.slow
def test_the_backtest_list_shows_state_and_progress_whole_at_1280_pixels(tmp_path, paper_case):
    # "Days × strategies" was cut off at the table's right edge, after the period and the strategies.
    require_browser()
    from rvpp.backtest import BacktestSettings, variants_of
    from rvpp.backtest.engine import run_backtest
    from rvpp.store import BacktestStore

    store = BacktestStore(f"sqlite:///{tmp_path / 'rvpp.sqlite3'}")
    day = paper_case.delivery_date
    run_backtest(paper_case, BacktestSettings(day, day, variants_of(["deterministic", "balanced"], [])), store,
                 label="one May day")
    store.engine.dispose()
    with streamlit_server("streamlit-backtest-list.log", tmp_path) as url, \
            chromium_page({"width": 1280, "height": 800}) as page:
        page.goto(url)
        open_page(page, "Backtest")
        # The grid lists the columns it draws, each at least in part: the fifth drawn shows the fourth whole.
        headers = first_table_headers(page, "backtest-list-1280.png")
        assert headers[:5] == ["Label", "State", "Progress", "Days × strategies", "Period"], headers
        assert table_cells(page, 1) == ["finished"] and table_cells(page, 3) == ["3 of 3"]  # and perfect information


@pytest.mark.slow
def test_the_backtest_tables_of_strategies_and_of_the_recommendation_fit_1280_pixels(tmp_path, paper_case):
    # The per-strategy table hid the total and the regret past its right edge at 1280 pixels, its second half the
    # days without a plan, the recommendation's table the test period's CVaR and regret; the worst days drew
    # whether each day had a plan last, out of view.
    require_browser()
    from rvpp.backtest import BacktestSettings, variants_of
    from rvpp.backtest.engine import run_backtest
    from rvpp.store import BacktestStore

    store = BacktestStore(f"sqlite:///{tmp_path / 'rvpp.sqlite3'}")
    day = paper_case.delivery_date
    run_backtest(paper_case, BacktestSettings(day - dt.timedelta(days=1), day, variants_of(["deterministic"], [0.25])),
                 store, label="two May days")
    store.engine.dispose()
    with streamlit_server("streamlit-backtest-tables.log", tmp_path) as url, \
            chromium_page({"width": 1280, "height": 800}) as page:
        page.goto(url)
        open_page(page, "Backtest")
        page.get_by_role("heading", name="Price of robustness and the recommended Γ").wait_for()
        settle(page)
        tables = page.evaluate("""() => [...document.querySelectorAll('[data-testid=stDataFrame]')]
            .filter(t => t.querySelector('.dvn-scroller'))
            .map(t => ({headers: [...t.querySelectorAll('[role=columnheader]')].map(h => h.innerText.trim()),
                        scroll: t.querySelector('.dvn-scroller').scrollWidth,
                        visible: t.querySelector('.dvn-scroller').clientWidth}))""")
        page.screenshot(path=ARTIFACTS / "backtest-tables-1280.png")
        whole = [t["headers"] for t in tables if t["scroll"] <= t["visible"] + 1]
        for header in ("Total net cost [kEUR]", "Mean regret [kEUR/day]", "Days without plan", "Audit violations",
                       "Test: CVaR 95 % [kEUR/day]", "Test: mean regret [kEUR/day]"):
            assert any(header in headers for headers in whole), (header, tables)
        # The worst days, a text table: every column in view (1,024 px of columns had 818 px as a grid).
        worst = page.get_by_test_id("stTable").filter(has_text="Heat not served")
        headers = worst.evaluate("t => [...t.querySelectorAll('thead th')].map(h => h.innerText.trim()).filter(h => h)")
        assert headers[0] == "Delivery day" and headers[1] == "Plan" and headers[-1] == "Heat not served [MWh_th]", headers
        worst.screenshot(path=ARTIFACTS / "backtest-worst-days-1280.png")
        spill, past_main, cut = text_table_spill(page, worst)
        assert spill <= 1 and past_main <= 1 and cut == 0, (spill, past_main, cut)


@pytest.mark.slow
def test_compare_draws_its_tables_whole_at_1280_pixels(app_url):
    # The flexibility table's long headers ("Downward reserve to capacity [h]") pushed its last column
    # past the right edge at 1280 pixels.
    with chromium_page({"width": 1280, "height": 800}) as page:
        page.goto(app_url)
        open_page(page, "Compare strategies")
        page.get_by_role("button", name="Solve 4 plans").click()
        page.get_by_role("heading", name="Flexibility").wait_for()
        settle(page)
        page.get_by_role("heading", name="Flexibility").scroll_into_view_if_needed()
        page.screenshot(path=ARTIFACTS / "compare-flexibility-1280.png")
        widths = page.evaluate("""() => [...document.querySelectorAll('[data-testid=stDataFrame] .dvn-scroller')]
            .map(s => [s.scrollWidth, s.clientWidth])""")
        assert len(widths) == 2 and all(scroll <= visible + 1 for scroll, visible in widths), widths


@pytest.mark.slow
def test_saved_runs_survive_a_reload_and_a_restart_and_a_capacity_edit_moves_the_plan(tmp_path, paper_case,
                                                                                       paper_solve):
    require_browser()
    data_dir, port = tmp_path / "rvpp-data", free_port()
    edited = paper_case.replace(wind=[paper_case.wind[0].model_copy(
        update={"p_max_mw": 80.0, "series_scale": 1.6}), paper_case.wind[1]])
    expected = rvpp.solve(edited)
    with streamlit_server("streamlit-runs.log", data_dir, port) as url, \
            chromium_page({"width": 1280, "height": 1600}) as page:
        page.goto(url)
        open_page(page, "Results")
        page.get_by_role("button", name="Solve", exact=True).click()
        page.get_by_role("button", name="Save run").click()
        page.get_by_text("Saved as").wait_for()

        open_page(page, "Portfolio")
        page.get_by_role("heading", name="Wind farms").wait_for()
        band = "WF1 (wind): forecast band"
        page.get_by_text(band).first.wait_for()
        before = max(chart_data(page, band)[0]["y"])
        # Letters typed into a number cell reach the server and are refused by name (a number cell of
        # the grid used to drop them without a word).
        letters = page.get_by_text('WF1: P max [MW] "abc" is not a number')
        for _ in range(EDIT_TRIES):
            edit_grid_cell(page, 0, 0, P_MAX_X_PX, "abc")
            try:
                letters.wait_for(timeout=EDIT_WAIT_MS)
                break
            except PlaywrightTimeout:
                page.screenshot(path=ARTIFACTS / "portfolio-letters.png")
        letters.wait_for()
        edited_label = page.get_by_test_id("stSidebar").get_by_text("balanced · DAM+SRM+HPA · WF1 80 MW")
        for _ in range(EDIT_TRIES):  # the canvas grid sometimes drops keys typed while it redraws: type again
            edit_grid_cell(page, 0, 0, P_MAX_X_PX, "80")
            try:
                edited_label.wait_for(timeout=EDIT_WAIT_MS)  # the sidebar follows the edit in the same run
                break
            except PlaywrightTimeout:
                page.screenshot(path=ARTIFACTS / "portfolio-typed.png")
        edited_label.wait_for()
        page.wait_for_function("""([title, before]) => {
            const p = [...document.querySelectorAll('.js-plotly-plot')]
                .find(p => p.layout && p.layout.title && p.layout.title.text.replace(/<[/]?b>/g, "") === title);
            return p && Math.max(...p._fullData[0].y) > before + 1; }""", arg=[band, before])
        upper = chart_data(page, band)[0]["y"]
        assert max(upper) == pytest.approx(expected.problem.sources["WF1"].nominal.max(), abs=0.01)
        page.screenshot(path=ARTIFACTS / "portfolio-edited.png")

        open_page(page, "Results")
        page.get_by_role("button", name="Solve", exact=True).click()
        page.get_by_role("button", name="Save run").wait_for()
        with page.expect_download() as download:
            page.get_by_role("button", name="Full plan (Excel)").click()
        units = pd.read_excel(Path(download.value.path()), sheet_name="units")
        bound = units[units["unit"] == "WF1"].sort_values("t")["bound_mw"].to_numpy()
        np.testing.assert_allclose(bound, expected.units.query("unit == 'WF1'")["bound_mw"], atol=1e-6)
        default = paper_solve().units.query("unit == 'WF1'")["bound_mw"].to_numpy()
        assert bound.max() > default.max() + 1  # the plan's bound moved with the capacity
        dispatch = {t["name"]: t["y"] for t in chart_data(page, "Electrical dispatch by unit (consumption negative)")}
        np.testing.assert_allclose(dispatch["WF1"], expected.units.query("unit == 'WF1'")["p_mw"], atol=1e-6)
        page.get_by_role("button", name="Save run").click()
        page.get_by_test_id("stAlert").filter(has_text="Saved as").filter(has_text="WF1 80 MW").wait_for()
        labels = ["balanced · DAM+SRM+HPA · WF1 80 MW", "balanced · DAM+SRM+HPA"]
        assert saved_labels(page) == labels

        page.reload()
        page.get_by_test_id("stSidebarNav").wait_for()
        assert saved_labels(page) == labels
    with streamlit_server("streamlit-runs.log", data_dir, port) as url, \
            chromium_page({"width": 1280, "height": 1600}) as page:
        page.goto(url)
        assert saved_labels(page) == labels
        run_id = RunLibrary(f"sqlite:///{data_dir / 'rvpp.sqlite3'}").list()[0].id
        page.goto(f"{url}/?run={run_id}")
        page.get_by_role("heading", name="Results").wait_for()
        page.get_by_test_id("stMetric").first.wait_for()
        net = page.get_by_test_id("stMetric").filter(has_text="Net cost").inner_text()
        assert f"{-expected.objective_eur / 1000:,.1f}".replace("-", "−") in net
        assert page.get_by_role("button", name="Cancel").count() == 0  # shown from the library, not solved
        opened = page.get_by_test_id("stCaptionContainer").filter(has_text="opened from the library")
        assert f"The saved run {labels[0]}" in opened.inner_text()  # the link's reader is told what it shows
        assert opened.bounding_box()["y"] < 800  # on the first screen
        page.screenshot(path=ARTIFACTS / "results-from-link.png")


# ----------------------------------------------------------------------------- accessibility


# The contrast of each Plotly text (ticks, axis and legend titles, texts beside bars, annotations: not the hover
# label, drawn over its trace's colour, nor a text inside a bar) over the page's background behind the chart (the
# figures' paper and plot area are transparent), from the fill and fill-opacity the browser drew it with.
CHART_TEXTS = """() => {
    const parse = text => { const n = text.match(/[\\d.]+/g).map(Number);
        return text.startsWith('color(') ? [n[0] * 255, n[1] * 255, n[2] * 255, n[3] ?? 1] : [n[0], n[1], n[2], n[3] ?? 1]; };
    const over = (top, base) => [0, 1, 2].map(i => top[3] * top[i] + (1 - top[3]) * base[i]);
    const luminance = rgb => { const c = rgb.map(v => v / 255).map(v => v <= 0.03928 ? v / 12.92 : ((v + 0.055) / 1.055) ** 2.4);
        return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; };
    const page = parse(getComputedStyle(document.querySelector('.stApp')).backgroundColor);
    return [...document.querySelectorAll('.js-plotly-plot .main-svg text')]
        .filter(t => t.textContent.trim() && !t.closest('.hoverlayer') && !t.classList.contains('bartext-inside'))
        .map(t => { const style = getComputedStyle(t), fill = parse(style.fill);
            const drawn = over([fill[0], fill[1], fill[2], fill[3] * parseFloat(style.fillOpacity)], page);
            const [high, low] = [luminance(drawn), luminance(page.slice(0, 3))].sort((a, b) => b - a);
            return [t.textContent.trim(), t.getAttribute('class') || '', style.fill, (high + 0.05) / (low + 0.05)]; });
}"""
# The same for the labels of the page's disabled buttons, over the background the browser drew behind them.
DISABLED_LABELS = """() => {
    const parse = text => { const n = text.match(/[\\d.]+/g).map(Number);
        return text.startsWith('color(') ? [n[0] * 255, n[1] * 255, n[2] * 255, n[3] ?? 1] : [n[0], n[1], n[2], n[3] ?? 1]; };
    const over = (top, base) => [0, 1, 2].map(i => top[3] * top[i] + (1 - top[3]) * base[i]).concat([1]);
    const luminance = rgb => { const c = rgb.slice(0, 3).map(v => v / 255).map(v => v <= 0.03928 ? v / 12.92 : ((v + 0.055) / 1.055) ** 2.4);
        return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; };
    return [...document.querySelectorAll('button:disabled p')].filter(p => p.innerText.trim()).map(p => {
        let back = [0, 0, 0, 0], layers = [];
        for (let e = p; e; e = e.parentElement) {
            const c = parse(getComputedStyle(e).backgroundColor);
            if (c[3] > 0) layers.push(c);
            if (c[3] >= 1) break;
        }
        back = layers.reduceRight((base, layer) => over(layer, base), [255, 255, 255, 1]);
        const drawn = over(parse(getComputedStyle(p).color), back);
        const [high, low] = [luminance(drawn), luminance(back)].sort((a, b) => b - a);
        return [p.innerText.trim(), (high + 0.05) / (low + 0.05)]; });
}"""

def axe_script() -> str:
    """axe-core's axe.min.js from tests/node (``make axe``, which ``make test`` runs); installed here by
    ``npm ci`` when missing. Without it the accessibility check fails: it never passes by not running."""
    script = AXE_DIR / "node_modules" / "axe-core" / "axe.min.js"
    why = "npm is not installed (Debian: apt-get install nodejs npm; .ci/run does)"
    if not script.exists() and shutil.which("npm"):
        done = subprocess.run(["npm", "ci", "--no-audit", "--no-fund", "--prefix", str(AXE_DIR)], check=False,
                              capture_output=True, text=True, timeout=300)
        why = f"npm ci ended with code {done.returncode}: {done.stderr.strip()[-300:]}"
    if not script.exists():
        pytest.fail(f"axe-core is not installed in {AXE_DIR.relative_to(ROOT)} and could not be installed "
                    f"({why}); run `make axe`", pytrace=False)
    return script.read_text(encoding="utf-8")


def axe_violations(page, script: str) -> list[dict]:
    """WCAG 2 A and AA violations axe-core finds on the page, with whether each node is in
    the sidebar navigation (Streamlit's own markup)."""
    page.add_script_tag(content=script)
    return page.evaluate("""async () => {
        const result = await axe.run(document, {runOnly: {type: 'tag', values: ['wcag2a', 'wcag2aa']}});
        return result.violations.map(v => ({id: v.id, impact: v.impact, nodes: v.nodes.map(n => ({
            target: n.target.join(' '),
            navigation: !!document.querySelector(n.target.join(' '))?.closest('[data-testid=stSidebarNav]')}))}));
    }""")


def settle(page) -> None:
    """Wait until the page has drawn and Streamlit's running indicator stayed off for a while."""
    page.locator("h1").first.wait_for()
    quiet = 0
    while quiet < QUIET_POLLS:
        page.wait_for_timeout(POLL_MS)
        quiet = 0 if page.query_selector("[data-testid=stStatusWidget]") else quiet + 1


# The contrast of each text against the backgrounds behind it (of the elements whose boxes cover the text's, up to
# the first opaque one), computed here from the colours the browser drew, each with its alpha laid over what is
# below it, by WCAG 2's relative luminance.
CONTRASTS = """selector => [...document.querySelectorAll(selector)].map(element => {
    const parse = text => { const n = text.match(/[\\d.]+/g).map(Number);
        return text.startsWith('color(') ? [n[0] * 255, n[1] * 255, n[2] * 255, n[3] ?? 1] : [n[0], n[1], n[2], n[3] ?? 1]; };
    element.scrollIntoView({block: 'center'});  // the app's background covers what is in view
    const box = element.getBoundingClientRect();
    const covers = outer => { const b = outer.getBoundingClientRect();
        return b.left <= box.left + 1 && b.right >= box.right - 1 && b.top <= box.top + 1 && b.bottom >= box.bottom - 1; };
    const over = (top, base) => [0, 1, 2].map(i => top[3] * top[i] + (1 - top[3]) * base[i]).concat([1]);
    let behind = element, layers = [];
    while (behind && !(layers.length && layers[layers.length - 1][3] >= 1)) {  // up to the first opaque one
        const colour = parse(getComputedStyle(behind).backgroundColor);
        if (covers(behind) && colour[3] > 0) layers.push(colour);  // a slider's thumb, beside its value, is not
        behind = behind.parentElement;
    }
    const back = layers.reduceRight((base, layer) => over(layer, base), [255, 255, 255, 1]);
    const drawn = over(parse(getComputedStyle(element).color), back);
    const luminance = rgb => { const c = rgb.map(v => v / 255).map(v => v <= 0.03928 ? v / 12.92 : ((v + 0.055) / 1.055) ** 2.4);
        return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; };
    const [high, low] = [luminance(drawn), luminance(back.slice(0, 3))].sort((a, b) => b - a);
    return [element.innerText.trim(), (high + 0.05) / (low + 0.05)];
})"""
# What the theme draws in its primary colour or dimmed, each checked on a page that shows it.
CONTRAST_TEXTS = {"Markets & tariffs": ('[data-testid=stButtonGroup] button[data-selected=true] p',
                                        'label[data-disabled=true] p'),
                  "Uncertainty": ('[data-testid=stTab][aria-selected=true] p', '[data-testid=stSliderThumbValue] p')}


@pytest.mark.parametrize("scheme", ["light", "dark"])
def test_selected_options_tabs_slider_values_and_disabled_labels_reach_4_5_to_1(app_url, scheme):
    # In the dark theme the selected option of a segmented control (3.6:1), the selected tab and a slider's
    # value (3.9:1) were in the primary colour on the dark background; in both the label of the day-ahead
    # market's switch, which cannot be turned off, was the text colour at 40 % (2.8:1 light, 3.8:1 dark).
    script = axe_script()
    with chromium_page({"width": 1280, "height": 800}, scheme) as page:
        page.goto(app_url)
        for title, selectors in CONTRAST_TEXTS.items():
            open_page(page, title)
            settle(page)
            page.screenshot(path=ARTIFACTS / f"contrast-{scheme}-{PAGES[title]}.png")
            for selector in selectors:
                page.locator(selector).first.wait_for()
                found = page.evaluate(CONTRASTS, selector)
                assert found and all(ratio >= 4.5 for _, ratio in found), (title, selector, found)
            violations = [v for v in axe_violations(page, script) if v["id"] == "color-contrast"]
            assert not violations, (title, violations)


def wcag_contrast(first: str, second: str) -> float:
    """WCAG 2's contrast of two opaque CSS colours written ``rgb(r, g, b)``."""
    def luminance(colour: str) -> float:
        channels = [int(v) / 255 for v in re.findall(r"\d+", colour)[:3]]
        linear = [c / 12.92 if c <= 0.03928 else ((c + 0.055) / 1.055) ** 2.4 for c in channels]
        return 0.2126 * linear[0] + 0.7152 * linear[1] + 0.0722 * linear[2]
    high, low = sorted((luminance(first), luminance(second)), reverse=True)
    return (high + 0.05) / (low + 0.05)


@pytest.mark.parametrize("scheme", ["light", "dark"])
def test_the_sidebar_link_reached_by_the_keyboard_is_outlined_at_3_to_1(app_url, scheme):
    # Streamlit marked it only with the 15 % grey of a link under the mouse, fainter than the page shown.
    with chromium_page({"width": 1280, "height": 800}, scheme) as page:
        page.goto(app_url)
        settle(page)
        for _ in range(4):  # past "Skip to main content", Home and Portfolio
            page.keyboard.press("Tab")
        focused = page.evaluate("""() => { const link = document.activeElement, style = getComputedStyle(link);
            return [link.innerText, style.outlineStyle, parseFloat(style.outlineWidth), style.outlineColor,
                    getComputedStyle(document.querySelector('[data-testid=stSidebar]')).backgroundColor]; }""")
        name, style, width, colour, sidebar = focused
        assert name.endswith("Markets & tariffs"), focused
        assert style == "solid" and width >= 2 and wcag_contrast(colour, sidebar) >= 3, focused


def test_every_page_passes_axe_and_fits_1280_pixels(app_url):
    script = axe_script()
    found, drawn = {}, {}
    with chromium_page({"width": 1280, "height": 800}) as page:
        page.goto(app_url)
        for title, slug in PAGES.items():
            if title != "Home":
                open_page(page, title)
            if title == "Results":
                page.get_by_role("button", name="Solve", exact=True).click()
                page.get_by_test_id("stPlotlyChart").nth(5).locator(".main-svg").first.wait_for()
            if title == "Compare strategies":
                page.get_by_role("button", name="Solve 4 plans").click()
                page.get_by_role("heading", name="Trades").wait_for()
            settle(page)
            page.screenshot(path=ARTIFACTS / f"page-{slug}.png")
            found[title] = axe_violations(page, script)
            charts, disabled = page.evaluate(CHART_TEXTS), page.evaluate(DISABLED_LABELS)
            assert all(ratio >= 4.5 for *_, ratio in charts), (title, [c for c in charts if c[-1] < 4.5][:5])
            assert all(ratio >= 4.5 for _, ratio in disabled), (title, disabled)
            drawn[title] = len(charts)
            levels = page.evaluate("() => [...document.querySelectorAll('[data-testid=stMain] :is(h1, h2, h3, h4, h5, h6)')]"
                                   ".map(h => Number(h.tagName[1]))")
            assert levels[0] == 1 and all(b <= a + 1 for a, b in itertools.pairwise(levels)), (title, levels)
            overflowing = page.evaluate("""() => [...document.querySelectorAll('[data-testid=stPlotlyChart]')]
                .filter(c => c.scrollWidth > c.clientWidth + 1).length""")
            assert overflowing == 0, f"{title}: {overflowing} chart(s) wider than their place"
    assert drawn["Results"] > 50 and drawn["Compare strategies"] > 20, drawn  # the chart texts were measured
    for title, violations in found.items():
        ids = {v["id"] for v in violations}
        assert not ids & FIXABLE, f"{title}: {[v for v in violations if v['id'] in FIXABLE]}"
        # What remains is Streamlit's own navigation markup, exactly as listed in docs/dashboard.md.
        assert ids == set(STREAMLIT_KNOWN), f"{title}: {violations}"
        for v in violations:
            assert all(node["navigation"] for node in v["nodes"]), f"{title}: {v}"
            assert v["impact"] != "critical"
