"""Dashboard timings, printed as JSON.

* ``first_load_*_s``: from opening Home until it can be used (its case table and its
  Solve button drawn), in a new browser session; ``cold`` is the first session of a fresh server (it pays the Python imports),
  ``warm`` a later one.
* ``solve_to_charts_*``: from clicking Solve on Results until all five charts are drawn;
  ``solve_*_s`` is the solve's own time as the page reports it (build + HiGHS + tables)
  and ``overhead_*_s`` the difference. ``first``: the default balanced case a few
  seconds after the first page load (the worker processes may still be starting);
  ``warm``: the pessimistic strategy afterwards.
* ``revisit_s``: back to Results after another page (the solve comes from the cache).
* ``compare_*``: the four strategies solved serially in one process, and through a
  pool of two worker processes (cold: the pool starts with the batch; warm: it was
  already running); ``compare_page_s`` is the Compare page's button to its chart
  (the pessimistic and balanced plans are cached by then, two are solved).
* ``load_average``: the host's one-minute load average before and after (the numbers
  are only comparable on a quiet machine).

Needs Chromium at ``/usr/bin/chromium`` for the browser timings:
``python benchmarks/dashboard.py``.
"""

from __future__ import annotations

import json
import multiprocessing
import os
import re
import socket
import subprocess
import sys
import time
import urllib.request
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import rvpp  # noqa: E402
from rvpp.solving.batch import solve_many  # noqa: E402
from rvpp.data.case import STRATEGIES  # noqa: E402

CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"]
WORKERS = 2
WAIT_MS = 180_000
CHARTS_ON_RESULTS = 5
FIRST_CLICK_DELAY_MS = 3000  # a user reading Home before the first click


def compare_timings() -> dict:
    case = rvpp.load_case(ROOT / "data" / "cases" / "paper")
    cases = [rvpp.with_options(case, strategy=s) for s in STRATEGIES]
    rvpp.solve(cases[0])  # imports and first-solve effects out of the way
    started = time.perf_counter()
    solve_many(cases)
    serial = time.perf_counter() - started
    with ProcessPoolExecutor(WORKERS, mp_context=multiprocessing.get_context("spawn")) as pool:
        started = time.perf_counter()
        solve_many(cases, executor=pool)
        cold = time.perf_counter() - started
        started = time.perf_counter()
        solve_many(cases, executor=pool)
        warm = time.perf_counter() - started
    return {"compare_serial_s": round(serial, 2), "compare_pool_cold_s": round(cold, 2),
            "compare_pool_warm_s": round(warm, 2)}


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def solve_to_charts(page, label: str) -> dict:
    """Click Solve on Results and wait for every chart; the solve time as the page reports it."""
    started = time.perf_counter()
    page.get_by_role("button", name="Solve", exact=True).click()
    page.get_by_test_id("stPlotlyChart").nth(CHARTS_ON_RESULTS - 1).locator(".main-svg").first.wait_for()
    total = time.perf_counter() - started
    card = page.get_by_test_id("stMetric").filter(has_text="Solve time")
    solve_s = float(re.search(r"(\d+\.\d+)", card.inner_text()).group(1))
    return {f"solve_to_charts_{label}_s": round(total, 2), f"solve_{label}_s": solve_s,
            f"overhead_{label}_s": round(total - solve_s, 2)}


def browser_timings() -> dict:
    from playwright.sync_api import sync_playwright

    port = free_port()
    url = f"http://127.0.0.1:{port}"
    server = subprocess.Popen([sys.executable, "-m", "streamlit", "run", "app.py", "--server.headless", "true",
                               "--server.address", "127.0.0.1", "--server.port", str(port)],
                              cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        while True:
            try:
                urllib.request.urlopen(f"{url}/_stcore/health", timeout=1).close()
                break
            except OSError:
                time.sleep(0.1)
        timings = {}
        with sync_playwright() as playwright:
            browser = playwright.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS)
            for label in ("cold", "warm"):
                page = browser.new_context(viewport={"width": 1400, "height": 1000}).new_page()
                page.set_default_timeout(WAIT_MS)
                started = time.perf_counter()
                page.goto(url)
                page.get_by_role("button", name="Solve the balanced strategy").wait_for()
                page.get_by_role("table").first.wait_for()
                timings[f"first_load_{label}_s"] = round(time.perf_counter() - started, 2)
            page.get_by_test_id("stSidebarNav").get_by_role("link", name="Results").click()
            page.get_by_role("button", name="Solve", exact=True).wait_for()
            page.wait_for_timeout(FIRST_CLICK_DELAY_MS)
            timings.update(solve_to_charts(page, "first"))
            page.get_by_test_id("stSidebarNav").get_by_role("link", name="Uncertainty").click()
            page.get_by_text("Pessimistic", exact=True).first.click()
            page.get_by_test_id("stSidebar").get_by_text("pessimistic, DAM+SRM+HPA").wait_for()
            page.get_by_test_id("stSidebarNav").get_by_role("link", name="Results").click()
            page.get_by_role("button", name="Solve", exact=True).wait_for()
            timings.update(solve_to_charts(page, "warm"))
            page.get_by_test_id("stSidebarNav").get_by_role("link", name="Markets & tariffs").click()
            page.get_by_role("heading", name="Markets & tariffs").wait_for()
            started = time.perf_counter()
            page.get_by_test_id("stSidebarNav").get_by_role("link", name="Results").click()
            page.get_by_test_id("stPlotlyChart").nth(CHARTS_ON_RESULTS - 1).locator(".main-svg").first.wait_for()
            timings["revisit_s"] = round(time.perf_counter() - started, 2)
            page.get_by_test_id("stSidebarNav").get_by_role("link", name="Compare strategies").click()
            started = time.perf_counter()
            page.get_by_role("button", name="Solve 4 plans").click()
            page.get_by_role("heading", name="Trades per strategy").wait_for()
            page.get_by_test_id("stPlotlyChart").first.locator(".main-svg").first.wait_for()
            timings["compare_page_s"] = round(time.perf_counter() - started, 2)
            browser.close()
        return timings
    finally:
        server.terminate()
        server.wait()


def main() -> None:
    report = {"load_average_before": os.getloadavg()[0]}
    report.update(compare_timings())
    if CHROMIUM.exists():
        report.update(browser_timings())
    else:
        report["browser"] = f"skipped: no Chromium at {CHROMIUM}"
    report["load_average_after"] = os.getloadavg()[0]
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
