"""Accessibility of the states a user reaches past each page's first screen, in both colour schemes: a refused
upload, the plans of Home, Results and Compare, three saved runs with two ticked and compared, the backtests
(one running, one finished with its recommendation, refused dates), with expanders open and every tab shown.

axe-core runs with its whole rule set (best practices too) in each state; besides, the tests measure what
axe-core skips: the labels of disabled buttons and the texts of Plotly charts (SVG), against the page's
background behind them, by WCAG 2's relative luminance.
"""

from __future__ import annotations

import datetime as dt
import re

import pytest

import rvpp
from rvpp.store import RunLibrary
from tests.test_browser import (
    ARTIFACTS,
    CHART_TEXTS,
    DISABLED_LABELS,
    EDIT_TRIES,
    EDIT_WAIT_MS,
    GRID_HEADER_PX,
    GRID_ROW_PX,
    P_MAX_X_PX,
    PlaywrightTimeout,
    axe_script,
    chromium_page,
    edit_grid_cell,
    open_page,
    require_browser,
    settle,
    streamlit_server,
)

pytestmark = pytest.mark.browser

# What axe-core's whole rule set finds in Streamlit's own markup, each where it is: rule -> the test of a node.
# Listed in docs/dashboard.md.
STREAMLIT_MARKUP = {
    "list": "node.closest('[data-testid=stSidebarNav]')",
    "listitem": "node.closest('[data-testid=stSidebarNav]')",
    # The data editor's cell editor, a text area without a label outside every landmark.
    "label": "node.closest('#portal') && node.matches('.gdg-input, textarea')",
    "region": "node.closest('#portal, [data-testid=stSelectboxVirtualDropdown]')",
    # The file uploader's drop zone: role="presentation" on an element that takes the focus.
    "presentation-role-conflict": "node.closest('[data-testid=stFileUploaderDropzone]')",
}
QUIET_MS = 400  # a state counts as drawn once Streamlit's running indicator stays off twice this long


def axe_all(page, script: str) -> list[dict]:
    """Every violation axe-core's whole rule set finds on the page, with whether each node is Streamlit's own
    markup as :data:`STREAMLIT_MARKUP` places it."""
    page.add_script_tag(content=script)
    return page.evaluate("""async (markup) => {
        const result = await axe.run(document, {resultTypes: ['violations']});
        return result.violations.map(v => ({id: v.id, impact: v.impact, nodes: v.nodes.map(n => {
            const node = document.querySelector(n.target.join(' '));
            return {target: n.target.join(' '), streamlit: !!(node && markup[v.id] && eval(markup[v.id]))}; })}));
    }""", STREAMLIT_MARKUP)


def check(page, script: str, state: str, scheme: str) -> None:
    """axe-core's whole rule set and the contrast of every chart text and disabled button label in ``state``."""
    quiet(page)
    page.screenshot(path=ARTIFACTS / f"state-{scheme}-{re.sub(r'[^a-z0-9]+', '-', state.lower())}.png")
    for violation in axe_all(page, script):
        assert violation["id"] in STREAMLIT_MARKUP and all(n["streamlit"] for n in violation["nodes"]), (state, violation)
    charts = page.evaluate(CHART_TEXTS)
    assert all(ratio >= 4.5 for *_, ratio in charts), (state, [c for c in charts if c[-1] < 4.5][:5])
    disabled = page.evaluate(DISABLED_LABELS)
    assert all(ratio >= 4.5 for _, ratio in disabled), (state, disabled)


def quiet(page) -> None:
    """Wait until Streamlit's running indicator has stayed off for a moment (a shorter :func:`settle`)."""
    for _ in range(2):
        page.wait_for_function("() => !document.querySelector('[data-testid=stStatusWidget]')")
        page.wait_for_timeout(QUIET_MS)


def every_tab(page, script: str, state: str, scheme: str) -> None:
    tabs = page.get_by_test_id("stMain").get_by_role("tab")
    for index in range(tabs.count()):
        tabs.nth(index).click()
        check(page, script, f"{state}, tab {tabs.nth(index).inner_text().strip()}", scheme)


def open_expanders(page) -> None:
    closed = page.get_by_test_id("stMain").locator("[data-testid=stExpander] details:not([open]) > summary")
    for _ in range(closed.count()):
        closed.first.click()


@pytest.fixture(scope="module")
def states_url(tmp_path_factory, paper_case, paper_solve):
    """A dashboard whose store holds three saved runs and a finished two-day backtest."""
    require_browser()
    from rvpp.backtest import BacktestSettings, variants_of
    from rvpp.backtest.engine import run_backtest
    from rvpp.store import BacktestStore

    data_dir = tmp_path_factory.mktemp("rvpp-states")
    library = RunLibrary(f"sqlite:///{data_dir / 'rvpp.sqlite3'}")
    for strategy in ("deterministic", "pessimistic", "balanced"):
        library.save(f"{strategy} · DAM+SRM+HPA", rvpp.with_options(paper_case, strategy=strategy),
                     paper_solve(strategy=strategy))
    store = BacktestStore(f"sqlite:///{data_dir / 'rvpp.sqlite3'}")
    day = paper_case.delivery_date
    run_backtest(paper_case, BacktestSettings(day - dt.timedelta(days=1), day, variants_of(["deterministic"], [0.25])),
                 store, label="two May days")
    store.engine.dispose()
    with streamlit_server("streamlit-states.log", data_dir) as url:
        yield url, data_dir


@pytest.mark.slow
@pytest.mark.parametrize("scheme", ["light", "dark"])
def test_the_states_past_each_first_screen_pass_axe_and_their_chart_and_disabled_texts_reach_4_5_to_1(
        states_url, scheme):
    # Streamlit's Plotly theme drew tick labels, axis titles and the texts beside bars in #808495, 3.7:1 on the
    # light background; the label of a disabled button was the text colour at 40 %: 2.8:1 light, 3.8:1 dark.
    url, _ = states_url
    script = axe_script()
    with chromium_page({"width": 1280, "height": 800}, scheme) as page:
        page.goto(url)
        page.get_by_role("button", name="Solve the balanced strategy").wait_for()
        every_tab(page, script, "Home", scheme)  # Upload: "Load the uploaded case" disabled until a file is chosen
        page.get_by_role("tab", name="Upload").click()
        assert page.get_by_role("button", name="Load the uploaded case").is_disabled()
        page.locator("input[type=file]").set_input_files(files=[{"name": "case.yaml", "mimeType": "text/yaml",
                                                                 "buffer": b"name: [unclosed\n"}])
        page.get_by_role("button", name="Load the uploaded case").click()
        page.get_by_test_id("stAlert").filter(has_text="case.yaml").wait_for()
        check(page, script, "Home, upload refused", scheme)
        page.get_by_role("button", name="Solve the balanced strategy").click()
        page.get_by_test_id("stPlotlyChart").locator(".main-svg").first.wait_for()
        check(page, script, "Home, solved", scheme)

        open_page(page, "Results")
        page.get_by_role("button", name="Solve", exact=True).click()
        page.get_by_test_id("stPlotlyChart").nth(4).locator(".main-svg").first.wait_for()
        open_expanders(page)
        check(page, script, "Results, solved, expanders open", scheme)

        open_page(page, "Compare strategies")
        page.get_by_role("button", name="Solve 4 plans").click()
        page.get_by_role("heading", name="Trades").wait_for()
        check(page, script, "Compare, solved", scheme)

        open_page(page, "Saved runs")
        grid = page.get_by_test_id("stDataFrame").first
        grid.locator("#glide-cell-1-2").wait_for(state="attached")
        settle(page)
        for row in (0, 1):
            box = grid.bounding_box()
            page.mouse.click(box["x"] + 16, box["y"] + GRID_HEADER_PX + GRID_ROW_PX * (row + 0.5))
            page.get_by_role("button", name=re.compile(f"Delete {row + 1} runs?")).wait_for()
        check(page, script, "Saved runs, two ticked", scheme)
        page.get_by_role("button", name="Compare these 2 runs").click()
        page.get_by_role("heading", name="Compare strategies").wait_for()
        page.get_by_test_id("stTable").wait_for()
        check(page, script, "Compare, two saved runs", scheme)

        open_page(page, "Backtest")
        page.get_by_role("heading", name="Price of robustness and the recommended Γ").wait_for()
        open_expanders(page)
        check(page, script, "Backtest, finished, recommendation", scheme)


@pytest.mark.slow
@pytest.mark.parametrize("scheme", ["light", "dark"])
def test_refusals_open_editors_every_tab_and_a_running_backtest_pass_axe(states_url, paper_case, scheme):
    url, data_dir = states_url
    from rvpp.backtest import BacktestSettings, variants_of
    from rvpp.store import BacktestStore

    day = paper_case.delivery_date
    store = BacktestStore(f"sqlite:///{data_dir / 'rvpp.sqlite3'}")
    running = store.open(paper_case, BacktestSettings(day, day, variants_of(["balanced"], [])).stored(), keys_total=2,
                         label=f"running {scheme}")
    store.set_progress(running, "running", 0, 2)  # this process plays the backtest's own
    script = axe_script()
    try:
        with chromium_page({"width": 1280, "height": 800}, scheme) as page:
            page.goto(url)
            open_page(page, "Uncertainty")
            every_tab(page, script, "Uncertainty", scheme)

            open_page(page, "Portfolio")
            page.get_by_role("heading", name="Wind farms").wait_for()
            letters = page.get_by_text('WF1: P max [MW] "abc" is not a number')
            for _ in range(EDIT_TRIES):  # the canvas grid sometimes drops keys typed while it redraws
                edit_grid_cell(page, 0, 0, P_MAX_X_PX, "abc")
                try:
                    letters.wait_for(timeout=EDIT_WAIT_MS)
                    break
                except PlaywrightTimeout:
                    continue
            check(page, script, "Portfolio, letters refused", scheme)
            grid = page.get_by_test_id("stDataFrame").first
            box = grid.bounding_box()
            page.mouse.dblclick(box["x"] + P_MAX_X_PX, box["y"] + GRID_HEADER_PX + GRID_ROW_PX / 2)
            page.locator(".gdg-input").first.wait_for(state="visible")
            check(page, script, "Portfolio, a cell's editor open", scheme)
            page.keyboard.press("Escape")
            every_tab(page, script, "Portfolio", scheme)

            open_page(page, "Backtest")
            page.get_by_test_id("stProgress").filter(has_text="running").first.wait_for()
            check(page, script, "Backtest, one running", scheme)
            page.get_by_test_id("stSelectbox").filter(has_text="Backtest shown below").click()
            page.get_by_role("option").first.wait_for()
            check(page, script, "Backtest, its list of backtests open", scheme)
            page.keyboard.press("Escape")
            page.get_by_text("Start a backtest of the current case").click()
            first_day, last_day = (page.get_by_test_id("stDateInput").nth(i).locator("input") for i in (0, 1))
            first, last = first_day.input_value(), last_day.input_value()
            first_day.fill(last)
            first_day.press("Enter")
            last_day.fill(first)
            last_day.press("Enter")
            page.get_by_role("button", name="Start the backtest").click()
            page.get_by_test_id("stAlert").filter(has_text="Not started").wait_for()
            check(page, script, "Backtest, dates refused", scheme)

            open_page(page, "Sensitivity to Γ")
            page.get_by_test_id("stTextInputField").first.fill("0, 24")
            page.get_by_role("button", name="Run").click()
            page.get_by_test_id("stPlotlyChart").nth(1).locator(".main-svg").first.wait_for()
            check(page, script, "Sensitivity, run", scheme)
    finally:
        store.set_progress(running, "stopped", 0, 2)
        store.engine.dispose()


# The focused element's indicator: its outline (drawn, at least 2 px) or else its box-shadow ring, each colour laid
# over the background behind the element (the first opaque one up its ancestors) and measured against it.
FOCUS_RING = """() => {
    const element = document.activeElement;
    if (!element || element === document.body) return null;
    const parse = text => { const n = text.match(/[\\d.]+/g).map(Number);
        return text.startsWith('color(') ? [n[0] * 255, n[1] * 255, n[2] * 255, n[3] ?? 1] : [n[0], n[1], n[2], n[3] ?? 1]; };
    const over = (top, base) => [0, 1, 2].map(i => top[3] * top[i] + (1 - top[3]) * base[i]).concat([1]);
    const luminance = rgb => { const c = rgb.slice(0, 3).map(v => v / 255).map(v => v <= 0.03928 ? v / 12.92 : ((v + 0.055) / 1.055) ** 2.4);
        return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; };
    const contrast = (a, b) => { const [high, low] = [luminance(a), luminance(b)].sort((x, y) => y - x);
        return (high + 0.05) / (low + 0.05); };
    let layers = [];
    for (let e = element.parentElement; e; e = e.parentElement) {
        const c = parse(getComputedStyle(e).backgroundColor);
        if (c[3] > 0) layers.push(c);
        if (c[3] >= 1) break;
    }
    const back = layers.reduceRight((base, layer) => over(layer, base), [255, 255, 255, 1]);
    const marked = element.matches('input[type=checkbox], input[type=radio]') ? element.closest('label') : element;
    const style = getComputedStyle(marked);
    const rings = style.outlineStyle !== 'none' && parseFloat(style.outlineWidth) >= 2 ? [style.outlineColor]
        : (style.boxShadow.match(/(rgba?|color)\\([^)]*\\)/g) || []);
    const kind = element.getAttribute('role') || (element.matches('input[type=checkbox]') ? 'checkbox' : element.tagName.toLowerCase());
    return {kind, name: element.innerText.trim().slice(0, 40),
            ring: Math.max(0, ...rings.map(c => contrast(over(parse(c), back), back)))};
}"""
FOCUS_PAGES = ("Home", "Markets & tariffs", "Uncertainty", "Backtest")  # Backtest's form (opened): a checkbox
TAB_PRESSES = 40  # per page, from its top
KINDS = ("button", "a", "tab", "radio", "switch", "checkbox", "summary")  # radio: a segmented control's option


@pytest.mark.parametrize("scheme", ["light", pytest.param("dark", marks=pytest.mark.slow)])  # one rule draws both
def test_every_control_reached_by_the_keyboard_is_marked_at_3_to_1(states_url, scheme):
    # Streamlit ringed them in the primary colour at 50 %: 2.5:1 on the light background; a switch or a checkbox
    # (its label, which holds the hidden input that takes the focus) was not marked at all.
    url, _ = states_url
    with chromium_page({"width": 1280, "height": 800}, scheme) as page:
        page.goto(url)
        focused = {}
        for title in FOCUS_PAGES:
            if title != "Home":
                open_page(page, title)
            settle(page)
            if title == "Backtest":
                page.get_by_text("Start a backtest of the current case").click()
                page.get_by_text("Perfect-information plan").wait_for()
            page.get_by_test_id("stMain").locator("h1").first.click()  # the keyboard starts from the page's top
            for _ in range(TAB_PRESSES):
                page.keyboard.press("Tab")
                found = page.evaluate(FOCUS_RING)
                if found and found["kind"] in KINDS:
                    focused.setdefault((title, found["kind"], found["name"]), found["ring"])
        assert {kind for _, kind, _ in focused} == set(KINDS), focused
        faint = {key: ring for key, ring in focused.items() if ring < 3}
        assert not faint, faint
