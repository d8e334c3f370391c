"""The dashboard in a real browser: Debian's Chromium driven by Playwright against
``streamlit run app.py`` on a free local port.

Skipped when Chromium is not installed at ``/usr/bin/chromium`` (``.ci/run`` installs
it). Screenshots and the server log are written to ``test-artifacts/``.
"""

from __future__ import annotations

import contextlib
import io
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

pytestmark = pytest.mark.browser

ROOT = Path(__file__).resolve().parent.parent
ARTIFACTS = ROOT / "test-artifacts"
CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"]
VIEWPORT = {"width": 1400, "height": 4200}  # tall: full-page screenshots stop at the viewport
START_TIMEOUT_S = 90    # ceilings for waiting, never performance assertions
WAIT_MS = 120_000
MARKET_COLUMNS = ["t", "start", "clock", "p_da_mw", "r_sr_up_mw", "r_sr_dn_mw", "h_hpa_mw", "price_da_mid",
                  "price_da_pos", "price_da_neg", "price_sr_up_hi", "price_sr_up_neg", "price_sr_dn_hi",
                  "price_sr_dn_neg", "tariff_hpa"]


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def require_browser() -> None:
    if not CHROMIUM.exists():
        pytest.skip(f"Chromium is not installed at {CHROMIUM} (Debian: apt-get install chromium); "
                    "the real-browser test needs it")
    pytest.importorskip("playwright.sync_api", reason="the Playwright Python package is not installed")


@contextlib.contextmanager
def streamlit_server(log_name: str):
    """A fresh ``streamlit run app.py`` on a free port; yields its URL."""
    ARTIFACTS.mkdir(exist_ok=True)
    port = free_port()
    log = open(ARTIFACTS / log_name, "w")
    server = subprocess.Popen(
        [sys.executable, "-m", "streamlit", "run", "app.py", "--server.headless", "true",
         "--server.address", "127.0.0.1", "--server.port", str(port)],
        cwd=ROOT, stdout=log, stderr=subprocess.STDOUT)
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
def chromium_page(viewport: dict = VIEWPORT):
    """A page of Debian's Chromium, driven by Playwright, that accepts downloads."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS)
        try:
            page = browser.new_page(viewport=viewport, accept_downloads=True)
            page.set_default_timeout(WAIT_MS)
            yield page
        finally:
            browser.close()


@pytest.fixture(scope="module")
def app_url():
    require_browser()
    with streamlit_server("streamlit.log") as url:
        yield url


def test_home_then_results_solve_draws_the_charts(app_url, paper_solve):
    expected = paper_solve()
    with chromium_page() as page:
        page.goto(app_url)
        page.get_by_role("heading", name="Robust day-ahead bids").wait_for()
        page.get_by_role("button", name="Solve the balanced strategy").wait_for()
        page.get_by_role("table").first.wait_for()
        page.screenshot(path=ARTIFACTS / "home.png", full_page=True)

        page.get_by_test_id("stSidebarNav").get_by_role("link", name="Results").click()
        page.get_by_role("heading", name="Results").wait_for()
        page.get_by_role("button", name="Solve", exact=True).click()
        charts = page.get_by_test_id("stPlotlyChart")
        charts.first.locator(".main-svg").first.wait_for()
        charts.nth(4).locator(".main-svg").first.wait_for()
        assert charts.count() == 5
        page.get_by_text(f"{expected.objective_eur / 1000:,.1f}".replace("-", "−"), exact=True).first.wait_for()

        with page.expect_download() as download:
            page.get_by_role("button", name="Bids (CSV)").click()
        bids = pd.read_csv(io.BytesIO(Path(download.value.path()).read_bytes()))
        assert list(bids.columns) == MARKET_COLUMNS
        np.testing.assert_allclose(bids["p_da_mw"], expected.market["p_da_mw"], atol=1e-5)
        page.screenshot(path=ARTIFACTS / "results.png", full_page=True)


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
