"""Dashboard timings, printed as JSON.

* ``first_load_*_s``: from opening Home to its heading being drawn, in a new browser
  session; ``cold`` is the first session of a fresh server (it pays the Python imports),
  ``warm`` a later one.
* ``solve_to_charts_s``: from clicking Solve on Results (default balanced case, not yet
  cached) until all five charts are drawn; ``solve_s`` is the solve's own time as the
  page reports it (build + HiGHS + tables), ``overhead_s`` the difference.
* ``revisit_s``: back to Results after another page (the solve comes from the cache).
* ``compare_*``: the four strategies solved serially in one process, and through a
  pool of two worker processes (cold: the pool starts with the batch; warm: it was
  already running); ``compare_page_s`` is the Compare page's button to its chart.

Needs Chromium at ``/usr/bin/chromium`` for the browser timings:
``python benchmarks/dashboard.py``.
"""

from __future__ import annotations

import json
import multiprocessing
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
from rvpp.batch import solve_many  # noqa: E402
from rvpp.case import STRATEGIES  # noqa: E402

CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"]
WORKERS = 2
WAIT_MS = 180_000
CHARTS_ON_RESULTS = 5


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
                page.get_by_role("heading", name="Robust day-ahead bids").wait_for()
                timings[f"first_load_{label}_s"] = round(time.perf_counter() - started, 2)
            page.get_by_test_id("stSidebarNav").get_by_role("link", name="Results").click()
            page.get_by_role("button", name="Solve", exact=True).wait_for()
            page.wait_for_timeout(3000)  # let the worker processes finish warming up
            started = time.perf_counter()
            page.get_by_role("button", name="Solve", exact=True).click()
            charts = page.get_by_test_id("stPlotlyChart")
            charts.nth(CHARTS_ON_RESULTS - 1).locator(".main-svg").first.wait_for()
            timings["solve_to_charts_s"] = round(time.perf_counter() - started, 2)
            card = page.get_by_test_id("stMetric").filter(has_text="Solve time")
            timings["solve_s"] = float(re.search(r"(\d+\.\d+)", card.inner_text()).group(1))
            timings["overhead_s"] = round(timings["solve_to_charts_s"] - timings["solve_s"], 2)
            page.get_by_test_id("stSidebarNav").get_by_role("link", name="Markets & tariffs").click()
            page.get_by_role("heading", name="Markets & tariffs").wait_for()
            started = time.perf_counter()
            page.get_by_test_id("stSidebarNav").get_by_role("link", name="Results").click()
            charts.nth(CHARTS_ON_RESULTS - 1).locator(".main-svg").first.wait_for()
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
    report = compare_timings()
    if CHROMIUM.exists():
        report.update(browser_timings())
    else:
        report["browser"] = f"skipped: no Chromium at {CHROMIUM}"
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
