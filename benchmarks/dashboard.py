"""Dashboard timings, printed as JSON and written to ``benchmarks/results/dashboard.json``.

* ``solve_s_by_case``: wall time of ``rvpp.solve`` on the default case per period length
  and strategy (in this process, after a warm-up). No page reads it: the dashboard's
  estimates come from the running server's own solves.
* ``draw_*``: after the solve returns, what the Results page still does: build every
  figure of the plan (``first``; ``cached``: the figures are kept per plan) and turn
  them into the JSON the browser receives.
* ``first_chart_*_s``: from opening Home in a new browser session until its first chart
  is on show (:data:`FIRST_CHART`: the first element of the page that is either a Plotly
  chart with its drawing, ``.main-svg``, or a chart drawn on the server as SVG by
  ``dashboard.svg``, as its first image or in place as ``svg.rvpp-chart``, once it is
  visible: in the page with a box of non-zero size, not hidden, an image decoded). Home's first chart is the day's DAM price band, an SVG that
  arrives drawn. ``cold`` is the first session of a fresh server (timed from the moment
  the server answers its health check), ``warm`` a later one; ``first_chart_top_px`` is
  where the chart begins in the page (below 800: on the first screen at 1280×800). Each of
  these sessions has a browser profile of its own, with nothing cached: a newcomer.
  ``first_chart_same_browser_*`` are later sessions in one browser profile that has shown
  Home before (Streamlit's scripts in its cache: a reload or a new tab). ``bare_page_*``
  times the same first chart on a bare Streamlit page (``benchmarks/bare_page.py``: a title
  and one SVG chart, drawn as Home draws its chart) on a server of its own: the time
  Streamlit itself takes on this machine, under which no page of the dashboard can come.
* ``solve_to_charts_*``: from clicking Solve on Results until all six charts are drawn;
  ``solve_*_s`` is the solve's own time as the page reports it (build + HiGHS + tables)
  and ``overhead_*_s`` the difference (process start, transfer, drawing).
  ``drawn_after_solve_*_s``: from the moment the solver's answer reached the server (the
  time the page states under its status line, to the millisecond) until the sixth chart
  is drawn in the browser (both on this machine's clock). ``first`` is the server's first
  solve (once: a server has one); ``warm`` the median of later solves of the
  ``WARM_STRATEGIES``, each in ``drawn_after_solve_warm_all_s``.
* ``sweep_s_by_case``: wall time of ``sweep_gamma`` over Γ = 0..NT on the default case
  (in this process), for comparison with the sweep timed in the browser below.
* ``gamma_sweep_warmup_s``: on Learn, from clicking "Compute the plans for every Γ" until
  the cost curve is drawn (the sweep in a solver process, then the page).
* ``gamma_slider_redraw_*``: once the sweep is warm, from pressing an arrow key on the
  Γ slider (Learn, Compare) until the plan chart titled with the new Γ is drawn;
  ``GAMMA_MOVES`` moves each, their median in ``gamma_slider_redraw_s`` (both pages).
  A press the slider has not taken within ``KEY_TAKEN_MS`` is made again and timed from
  the press that moved it; ``gamma_slider_lost_presses`` counts the lost ones. A step that
  fails (``gamma_slider_error``) leaves the other timings in the file, a screenshot of the
  page in ``dashboard-failure.png``, and the benchmark's exit status non-zero.
* ``revisit_s``: back to Results after another page (the plan is kept).
* ``library_*``: a run library of ``LIBRARY_RUNS`` saved runs: listing it in this
  process, and opening the Saved runs page in the browser until its table is drawn.
* ``load_average``: the host's one-minute load average before and after (the numbers
  are only comparable on a quiet machine).

Every browser timing is measured ``REPEAT`` times on the same server (the first chart's
later sessions ``FIRST_CHART_SESSIONS`` times of each kind); the JSON keeps each
measurement and the median. Needs Chromium at ``/usr/bin/chromium`` for the
browser timings: ``python benchmarks/dashboard.py``; ``--first-chart`` measures only
Home's first chart (fresh server and later sessions), prints it and writes it to
``benchmarks/results/dashboard-first-chart.json``; ``--port N`` runs the server on port N.
"""

from __future__ import annotations

import json
import os
import re
import socket
import statistics
import subprocess
import sys
import tempfile
import time
import urllib.request
from datetime import datetime, timedelta
from pathlib import Path

from playwright.sync_api import TimeoutError as PlaywrightTimeoutError, sync_playwright

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import rvpp  # noqa: E402
from benchmarks.common import header, write_result  # noqa: E402
from rvpp.data.case import STRATEGIES  # noqa: E402

CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"]
RESULTS = ROOT / "benchmarks" / "results" / "dashboard.json"
FIRST_CHART_RESULTS = RESULTS.with_name("dashboard-first-chart.json")
FIRST_CHART = ('[data-testid=stPlotlyChart] .main-svg, svg.rvpp-chart, '  # a drawn chart, of any kind
               '[data-testid=stMarkdownContainer] img[src^="data:image/svg+xml"]:not([hidden])')
SHOWN_CHART = """selector => {
    for (const element of document.querySelectorAll(selector)) {
        const box = element.getBoundingClientRect();
        const style = getComputedStyle(element);
        const decoded = element.tagName !== 'IMG' || (element.complete && element.naturalWidth > 0);
        if (box.width > 0 && box.height > 0 && style.visibility !== 'hidden' && decoded) return {top: box.top + window.scrollY};
    }
    return null;
}"""  # where the first chart on show begins [px], once there is one
FAILURE_SCREENSHOT = RESULTS.with_name("dashboard-failure.png")
BARE_PAGE = ROOT / "benchmarks" / "bare_page.py"
WAIT_MS = 180_000
CHARTS_ON_RESULTS = 6
LIBRARY_RUNS = 200
REPEAT = 3
FIRST_CHART_SESSIONS = 5  # later sessions per kind: the first after a server start meets the fork server's imports
WARM_STRATEGIES = ("Pessimistic", "Optimistic", "Deterministic")  # later solves: strategies not solved before
GAMMA_MOVES = 6
KEY_TAKEN_MS = 5_000  # a key press the Γ slider has not taken by then is taken as lost
KEY_PRESSES = 3
FIRST_CLICK_DELAY_MS = 3000  # a user reading Home before the first click
PERIODS = {60: 1.0, 15: 0.25}


def median(values: list[float]) -> float:
    return round(statistics.median(values), 3)


def solve_times(case: rvpp.Case) -> dict:
    """Wall time of one solve per period length and strategy [s] (median of two)."""
    rvpp.solve(case)  # imports and first-solve effects out of the way
    measured = {}
    for minutes, dt_h in PERIODS.items():
        for strategy in STRATEGIES:
            variant = rvpp.with_options(case, strategy=strategy, dt_h=dt_h)
            runs = []
            for _ in range(2):
                started = time.perf_counter()
                rvpp.solve(variant)
                runs.append(time.perf_counter() - started)
            measured[f"{case.name}/{minutes} min/{strategy}"] = median(runs)
            print(f"solve {minutes} min {strategy}: {measured[f'{case.name}/{minutes} min/{strategy}']} s",
                  file=sys.stderr, flush=True)
    return measured


def sweep_times(case: rvpp.Case) -> dict:
    """Wall time of the dashboard's Γ sweep (every Γ from 0 to NT) per period length [s]."""
    from dashboard.solving import sweep_grid
    from rvpp.solving.sweep import sweep_gamma

    measured = {}
    for minutes, dt_h in PERIODS.items():
        day = rvpp.with_options(case, dt_h=dt_h)
        grid = sweep_grid(rvpp.prepare(day).nt, dt_h)
        started = time.perf_counter()
        sweep_gamma(day, grid)
        measured[f"{case.name}/{minutes} min/{len(grid)} Γ"] = round(time.perf_counter() - started, 2)
        print(f"sweep {minutes} min: {measured[f'{case.name}/{minutes} min/{len(grid)} Γ']} s", file=sys.stderr,
              flush=True)
    return measured


def draw_times(case: rvpp.Case) -> dict:
    """Building and serializing the Results page's figures after the solve returned [s]."""
    import plotly.io as pio

    from rvpp.outputs import plots
    from rvpp.outputs.economics import waterfall_figure

    result = rvpp.solve(case)

    def build() -> list:
        figures = [waterfall_figure({"balanced": result}), plots.trades_figure(result), plots.heat_figure(result),
                   plots.dispatch_figure(result), plots.reserve_share_figure(result)]
        return figures + [plots.storage_figure(result, c.name) for c in case.csp]

    builds, serial = [], []
    for _ in range(REPEAT):
        started = time.perf_counter()
        figures = build()
        builds.append(time.perf_counter() - started)
        started = time.perf_counter()
        for figure in figures:
            pio.to_json(figure, validate=False)
        serial.append(time.perf_counter() - started)
    return {"draw_build_figures_s": median(builds), "draw_serialize_s": median(serial),
            "draw_first_s": median([b + s for b, s in zip(builds, serial)]),
            "draw_cached_s": median(serial)}


def fill_library(folder: Path, case: rvpp.Case) -> dict:
    """A run library of LIBRARY_RUNS saved runs; the time to list it in this process."""
    from rvpp.store import RunLibrary

    result = rvpp.solve(case)
    library = RunLibrary(f"sqlite:///{folder / 'rvpp.sqlite3'}")
    started = time.perf_counter()
    for i in range(LIBRARY_RUNS):
        library.save(f"balanced · DAM+SRM+HPA · variant {i}", case, result, settings={"csp": True})
    save_s = (time.perf_counter() - started) / LIBRARY_RUNS
    listed = []
    for _ in range(REPEAT):
        started = time.perf_counter()
        assert len(library.list()) == LIBRARY_RUNS
        listed.append(time.perf_counter() - started)
    return {"library_save_each_s": round(save_s, 4), "library_list_s": median(listed)}


class BenchmarkStepFailed(Exception):
    """A browser step that did not reach the state it waits for."""


def free_port() -> int:
    """A free local port: ``--port N`` if given, else one the system chooses."""
    if "--port" in sys.argv[:-1]:
        return int(sys.argv[sys.argv.index("--port") + 1])
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


# Records in the page, on the browser's clock (epoch ms), when the n-th chart first has its
# drawing (Plotly's .main-svg) and when a chart title first reads a given text.
WATCH = """() => {
  window.__drawn = {}; window.__titles = {};
  if (window.__watching) return;
  window.__watching = true;
  new MutationObserver(() => {
    const now = Date.now();
    document.querySelectorAll('[data-testid=stPlotlyChart]').forEach((chart, i) => {
      if (!(i in window.__drawn) && chart.querySelector('.main-svg')) window.__drawn[i] = now;
    });
    document.querySelectorAll('.gtitle').forEach(title => {
      if (!(title.textContent in window.__titles)) window.__titles[title.textContent] = now;
    });
  }).observe(document.body, {subtree: true, childList: true, characterData: true, attributes: true});
}"""


def server_epoch(clock: str) -> float:
    """``HH:MM:SS.mmm`` of the server (same machine, same time zone) as epoch seconds, on the day
    that puts it nearest to now."""
    now = datetime.now()
    moment = datetime.combine(now.date(), datetime.strptime(clock, "%H:%M:%S.%f").time())
    nearest = min((moment + timedelta(days=d) for d in (-1, 0, 1)), key=lambda m: abs((m - now).total_seconds()))
    return nearest.timestamp()


def solve_to_charts(page, label: str) -> dict:
    """Click Solve on Results and wait for every chart; the solve time as the page reports it, and
    the time from the solver's answer (as the page states it) to the last chart drawn."""
    page.evaluate(WATCH)
    started = time.perf_counter()
    page.get_by_role("button", name="Solve", exact=True).click()
    page.get_by_test_id("stPlotlyChart").nth(CHARTS_ON_RESULTS - 1).locator(".main-svg").first.wait_for()
    total = time.perf_counter() - started
    card = page.get_by_test_id("stMetric").filter(has_text="Solve time")
    solve_s = float(re.findall(r"\d+\.\d+", card.inner_text())[-1])
    note = page.get_by_text("The solver's answer came back at").text_content()
    returned = server_epoch(re.search(r"at (\d\d:\d\d:\d\d\.\d{3})", note).group(1))
    drawn = page.evaluate("() => window.__drawn")[str(CHARTS_ON_RESULTS - 1)] / 1000
    return {f"solve_to_charts_{label}_s": round(total, 2), f"solve_{label}_s": solve_s,
            f"overhead_{label}_s": round(total - solve_s, 2),
            f"drawn_after_solve_{label}_s": round(drawn - returned, 3)}


def wait_idle(page) -> None:
    """Until Streamlit shows no run under way (its status widget), as a user waits to see the page."""
    page.wait_for_function("() => !document.querySelector('[data-testid=stStatusWidget]')")


def gamma_slider(page, title: str, chart_title: str, timings: dict) -> list[float]:
    """Move the Γ slider of the page ``title`` with the keyboard, GAMMA_MOVES times; the time from
    each key press until the chart titled ``chart_title`` (with the new Γ) is drawn [s]."""
    nav(page, title)
    slider = page.get_by_test_id("stSlider").filter(has_text="Γ of every source")
    button = page.get_by_role("button", name=re.compile("Compute the plans for every Γ"))
    thumb = slider.get_by_role("slider")
    button.or_(page.locator(".gtitle", has_text=chart_title.split("{")[0])).first.wait_for()
    if button.count():
        started = time.perf_counter()
        button.click()
        page.locator(".gtitle", has_text="plan shown: Γ =").first.wait_for()
        timings["gamma_sweep_warmup_s"] = round(time.perf_counter() - started, 2)
    # The Γ on show, as the chart's title states it: the slider's thumb, read while the page is
    # still being redrawn after the sweep, once gave 0 for a plan shown at 5.
    shown = page.locator(".gtitle", has_text=chart_title.split("{")[0]).first
    shown.wait_for()
    wait_idle(page)
    gamma = int(re.search(r"Γ = (\d+)", shown.text_content()).group(1))
    page.evaluate(WATCH)
    moves = []
    for i in range(GAMMA_MOVES):
        # Up to new plans (their figures are built on the way), then back to plans already drawn.
        key, gamma = ("ArrowRight", gamma + 1) if i < GAMMA_MOVES // 2 else ("ArrowLeft", gamma - 1)
        wanted = chart_title.format(gamma=gamma)
        pressed, lost = press_until_moved(page, thumb, key, gamma)
        timings["gamma_slider_lost_presses"] = timings.get("gamma_slider_lost_presses", 0) + lost
        try:
            page.locator(".gtitle", has_text=wanted).first.wait_for()
        except PlaywrightTimeoutError:
            on_show = [title.text_content() for title in page.locator(".gtitle").all()]
            raise BenchmarkStepFailed(f"the Γ slider shows {thumb.get_attribute('aria-valuetext')}, but no chart "
                                      f"titled {wanted!r} came in {WAIT_MS / 1000:.0f} s; titles on show: {on_show}")
        shown = page.evaluate("(wanted) => Object.entries(window.__titles).find(([t]) => t.includes(wanted))[1]",
                              wanted)
        moves.append(round(shown / 1000 - pressed, 3))
        page.wait_for_timeout(500)  # a user looks at the plan before the next move
    return moves


def press_until_moved(page, thumb, key: str, gamma: int) -> tuple[float, int]:
    """Press ``key`` on the Γ slider's ``thumb`` until it shows ``gamma``: the time of the press that
    moved it (epoch seconds) and the number of presses lost before it.

    A press that lands while the page replaces the slider reaches no slider, and the chart
    of the new Γ would never come; such a press is counted and made again, not timed.
    """
    before = thumb.get_attribute("aria-valuetext")
    for lost in range(KEY_PRESSES):
        wait_idle(page)
        page.evaluate("() => { window.__titles = {}; }")
        thumb.focus()
        pressed = time.time()
        page.keyboard.press(key)
        try:
            thumb.and_(page.locator(f'[aria-valuetext="{gamma}"]')).wait_for(timeout=KEY_TAKEN_MS)
            return pressed, lost
        except PlaywrightTimeoutError:
            now = thumb.get_attribute("aria-valuetext")
            if now != before:
                raise BenchmarkStepFailed(f"{key} moved the Γ slider from {before} to {now}, not to {gamma}")
    raise BenchmarkStepFailed(f"{KEY_PRESSES} presses of {key} left the Γ slider at {before}, not {gamma}")


def nav(page, name: str) -> None:
    page.get_by_test_id("stSidebarNav").get_by_role("link", name=name, exact=True).click()


def start_server(command: list[str], data_dir: Path, port: int) -> subprocess.Popen:
    """Start a Streamlit server with ``command`` (its options added) and return once it answers
    its health check."""
    env = {**os.environ, "RVPP_DATA_DIR": str(data_dir)}
    env.pop("RVPP_STORE_URL", None)
    server = subprocess.Popen([sys.executable, *command, "--server.headless", "true", "--server.address", "127.0.0.1",
                               "--server.port", str(port)],
                              cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    while True:
        try:
            urllib.request.urlopen(f"http://127.0.0.1:{port}/_stcore/health", timeout=1).close()
            return server
        except OSError:
            if server.poll() is not None:
                raise BenchmarkStepFailed(f"the server ({' '.join(command)}) ended with status {server.returncode}")
            time.sleep(0.1)


def stop_server(server: subprocess.Popen) -> None:
    server.terminate()
    server.wait()


def open_first_chart(context, url: str) -> tuple[float, object, float]:
    """Open ``url`` in a new page of ``context``: seconds until its first chart is on show, the
    page, and where the chart begins in it [px]."""
    page = context.new_page()
    page.set_default_timeout(WAIT_MS)
    started = time.perf_counter()
    page.goto(url)
    shown = page.wait_for_function(SHOWN_CHART, arg=FIRST_CHART, polling="raf").json_value()
    return time.perf_counter() - started, page, shown["top"]


def first_chart_sessions(browser, url: str, prefix: str) -> dict:
    """The first chart of ``url``: a first session, then :data:`FIRST_CHART_SESSIONS` later ones each in a
    new browser profile and as many more in one profile that has opened the page before (see the module's notes)."""
    timings: dict = {}
    fresh, same = [], []
    for _ in range(FIRST_CHART_SESSIONS + 1):
        context = browser.new_context(viewport={"width": 1280, "height": 2400})
        seconds, page, top = open_first_chart(context, url)
        fresh.append(seconds)
        timings[f"{prefix}_top_px"] = round(top)
        context.close()
    returning = browser.new_context(viewport={"width": 1280, "height": 2400})
    open_first_chart(returning, url)[1].close()  # this profile's first visit fills its cache
    for _ in range(FIRST_CHART_SESSIONS):
        seconds, page, _ = open_first_chart(returning, url)
        same.append(seconds)
        page.close()
    returning.close()
    timings[f"{prefix}_cold_s"] = round(fresh[0], 2)
    timings[f"{prefix}_warm_s"] = [round(v, 2) for v in fresh[1:]]
    timings[f"{prefix}_warm_median_s"] = median(fresh[1:])
    timings[f"{prefix}_same_browser_s"] = [round(v, 2) for v in same]
    timings[f"{prefix}_same_browser_median_s"] = median(same)
    return timings


def bare_page_timings(data_dir: Path) -> dict:
    """:func:`first_chart_sessions` of ``benchmarks/bare_page.py`` on a server of its own."""
    port = free_port()  # the dashboard's server has stopped by now
    server = start_server(["-m", "streamlit", "run", str(BARE_PAGE)], data_dir, port)
    try:
        with sync_playwright() as playwright:
            browser = playwright.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS)
            timings = first_chart_sessions(browser, f"http://127.0.0.1:{port}", "bare_page")
            browser.close()
        return timings
    finally:
        stop_server(server)


def browser_timings(data_dir: Path, first_chart_only: bool = False) -> dict:
    port = free_port()
    url = f"http://127.0.0.1:{port}"
    server = start_server(["-m", "dashboard"], data_dir, port)  # as `make run` starts it
    try:
        library_open, revisit = [], []
        with sync_playwright() as playwright:
            browser = playwright.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS)
            timings = first_chart_sessions(browser, url, "first_chart")
            if first_chart_only:
                browser.close()
                return timings
            page = browser.new_context(viewport={"width": 1280, "height": 2400}).new_page()
            page.set_default_timeout(WAIT_MS)
            page.goto(url)
            page.locator(FIRST_CHART).first.wait_for(state="visible")
            nav(page, "Results")
            page.get_by_role("button", name="Solve", exact=True).wait_for()
            page.wait_for_timeout(FIRST_CLICK_DELAY_MS)
            timings.update(solve_to_charts(page, "first"))
            try:
                learn = gamma_slider(page, "Robust bidding explained", "Bids at Γ = {gamma}:", timings)
                compare = gamma_slider(page, "Compare strategies", "Bids at Γ = {gamma}:", timings)
            except (BenchmarkStepFailed, PlaywrightTimeoutError) as failure:
                # The other timings are still worth having; the failure is reported and fails the run.
                timings["gamma_slider_error"] = str(failure).splitlines()[0]
                page.screenshot(path=FAILURE_SCREENSHOT, full_page=True)
            else:
                timings["gamma_slider_redraw_learn_s"] = learn
                timings["gamma_slider_redraw_learn_median_s"] = median(learn)
                timings["gamma_slider_redraw_compare_s"] = compare
                timings["gamma_slider_redraw_compare_median_s"] = median(compare)
                timings["gamma_slider_redraw_s"] = median(learn + compare)
            warm = []
            for strategy in WARM_STRATEGIES[:REPEAT]:
                nav(page, "Uncertainty")
                page.get_by_text(strategy, exact=True).first.click()
                page.get_by_test_id("stSidebar").get_by_text(f"{strategy.lower()} · DAM+SRM+HPA").wait_for()
                nav(page, "Results")
                page.get_by_role("button", name="Solve", exact=True).wait_for()
                warm.append(solve_to_charts(page, "warm"))
            timings.update({key: median([solve[key] for solve in warm]) for key in warm[0]})
            timings["drawn_after_solve_warm_all_s"] = [solve["drawn_after_solve_warm_s"] for solve in warm]
            for _ in range(REPEAT):
                nav(page, "Markets & tariffs")
                page.get_by_role("heading", name="Markets & tariffs").wait_for()
                page.wait_for_timeout(1000)
                started = time.perf_counter()
                nav(page, "Results")
                page.get_by_test_id("stPlotlyChart").nth(CHARTS_ON_RESULTS - 1).locator(".main-svg").first.wait_for()
                revisit.append(time.perf_counter() - started)
                nav(page, "Home")
                page.locator("h1").first.wait_for()
                page.wait_for_timeout(1000)
                started = time.perf_counter()
                nav(page, "Saved runs")
                page.get_by_test_id("stDataFrame").first.locator("#glide-cell-1-0").wait_for(state="attached")
                library_open.append(time.perf_counter() - started)
            timings["revisit_s"] = [round(v, 2) for v in revisit]
            timings["revisit_median_s"] = median(revisit)
            timings[f"library_{LIBRARY_RUNS}_open_s"] = [round(v, 2) for v in library_open]
            timings[f"library_{LIBRARY_RUNS}_open_median_s"] = median(library_open)
            browser.close()
        return timings
    finally:
        stop_server(server)


# (label, key in the report, target [s] or None) of the short table.
TABLE = (("solver's answer -> six charts, a server's first solve", "drawn_after_solve_first_s", 0.5),
         ("solver's answer -> six charts, later solves (median)", "drawn_after_solve_warm_s", 0.5),
         ("Γ slider: key press -> plan drawn (median, Learn and Compare)", "gamma_slider_redraw_s", 1.0),
         ("Γ sweep behind the slider: button -> curve drawn", "gamma_sweep_warmup_s", None),
         ("Home's first chart, a fresh server", "first_chart_cold_s", 3.0),
         ("Home's first chart, a later session (median)", "first_chart_warm_median_s", 2.0),
         ("Home's first chart, a later session in the same browser (median)", "first_chart_same_browser_median_s", None),
         ("a bare Streamlit page's first chart, a later session (median)", "bare_page_warm_median_s", None),
         ("a bare Streamlit page's first chart, same browser (median)", "bare_page_same_browser_median_s", None),
         ("back to Results after another page (median)", "revisit_median_s", None),
         (f"Saved runs with {LIBRARY_RUNS} runs: page -> table (median)", f"library_{LIBRARY_RUNS}_open_median_s", None))


def print_table(report: dict) -> None:
    print(f"dashboard, {report['case']} case; load average {report['load_average_before']} before, "
          f"{report['load_average_after']} after")
    for label, key, target in TABLE:
        value = report.get(key)
        shown = "not measured" if value is None else f"{value:.2f} s"
        verdict = "" if target is None or value is None else f"  target <= {target:g} s{'' if value <= target else ' (missed)'}"
        print(f"  {label:66s} {shown:>12s}{verdict}")
    for key, value in report.items():
        if key.endswith("_error") or key == "browser":
            print(f"  {key}: {value}")


def first_chart_main() -> None:
    """``--first-chart``: only Home's first chart on a fresh server and in later sessions, printed
    and written to a file of its own (the full run's file is left as it wrote it)."""
    if not CHROMIUM.exists():
        sys.exit(f"no Chromium at {CHROMIUM}")
    report = header("dashboard-first-chart", "first chart")
    with tempfile.TemporaryDirectory(prefix="rvpp-bench-") as folder:
        report.update(browser_timings(Path(folder), first_chart_only=True))
        report.update(bare_page_timings(Path(folder)))
    write_result(report, FIRST_CHART_RESULTS)
    print(json.dumps({key: value for key, value in report.items() if key != "machine"}, indent=2))


def main() -> None:
    if "--first-chart" in sys.argv[1:]:
        first_chart_main()
        return
    case = rvpp.load_case(ROOT / "data" / "cases" / "paper")
    report = {**header("dashboard", "full"), "case": case.name}
    report["solve_s_by_case"] = solve_times(case)
    report["sweep_s_by_case"] = sweep_times(case)
    report.update(draw_times(case))
    with tempfile.TemporaryDirectory(prefix="rvpp-bench-") as folder:
        report.update(fill_library(Path(folder), case))
        if CHROMIUM.exists():
            report.update(browser_timings(Path(folder)))
            report.update(bare_page_timings(Path(folder)))
        else:
            report["browser"] = f"skipped: no Chromium at {CHROMIUM}"
    write_result(report, RESULTS)
    print_table(report)
    failed = {key: value for key, value in report.items() if key.endswith("_error")}
    if failed:
        sys.exit(f"dashboard benchmark: {len(failed)} step(s) failed ({', '.join(failed)}); the other timings "
                 f"are in {RESULTS.name}, a screenshot of the page in {FAILURE_SCREENSHOT.name}")


if __name__ == "__main__":
    main()
