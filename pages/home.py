"""Home: what the tool does, the case at a glance, a one-click balanced plan, loading cases."""

from collections import Counter

import streamlit as st

import rvpp
from dashboard import solving, state, svg, widgets
from rvpp import service
from rvpp.service import Variant

state.through_app("pages/home.py")

UPLOAD_TYPES = ["zip", "yaml", "yml", "csv", "xlsx"]
DESCRIPTION_CHARS = 1000
LINK_PX = 250  # [px] a page's link and what it is for: "Robust bidding explained" whole
GAP_PX = 32    # [px] Streamlit's "medium" gap between them  # of a case's description, shown on one line
HEADLINE = ("Net cost [kEUR]", "DAM revenue [kEUR]", "Reserve revenue [kEUR]", "Protection [kEUR]")
LINKS = (
    ("pages/portfolio.py", "Portfolio", "edit wind, PV, CSP and demands; see each unit's forecast band"),
    ("pages/markets.py", "Markets & tariffs", "DAM and reserve price bands, market switches, the HPA tariff"),
    ("pages/uncertainty.py", "Uncertainty", "delivery date, history window, budgets Γ and strategy presets"),
    ("pages/results.py", "Results", "solve; KPIs, bids, heat, dispatch, storage and reserve charts; downloads"),
    ("pages/compare.py", "Compare strategies", "deterministic to pessimistic side by side; the paper's tables"),
    ("pages/learn.py", "Robust bidding explained", "what Γ means and what robustness costs, with live charts"),
)


def expected_time(place, balanced) -> None:
    """How long the balanced solve takes, as this server measured it, in ``place``."""
    expected = solving.solver().expected_s(balanced)
    if expected:
        place.caption(f":material/timer: About {expected[0]:.1f} s ({expected[1]}), with {balanced.dt_h * 60:g}-minute "
                      "periods. Longer solves show their progress and can be stopped early or cancelled.")
    else:
        place.caption(f":material/timer: Not solved on this server yet ({balanced.dt_h * 60:g}-minute periods; "
                      "15-minute periods take several times longer than hourly ones). The solve shows its progress "
                      "and can be stopped early or cancelled.")


def load_upload() -> None:
    files = st.session_state.get("home_upload") or []
    twice = [twice_named(name, n) for name, n in Counter(f.name for f in files).items() if n > 1]
    if twice:  # one of them would silently replace the other
        st.session_state["home_load_problems"] = twice
        return
    try:
        case = service.read_case_files({f.name: f.getvalue() for f in files})
    except rvpp.CaseError as err:
        st.session_state["home_load_problems"] = err.problems
        return
    state.load(case, source="upload: " + ", ".join(f.name for f in files))
    st.session_state["home_load_problems"] = []


def twice_named(name: str, count: int) -> str:
    """Why ``count`` uploaded files named ``name`` are refused."""
    both = "two uploaded files are both" if count == 2 else f"{count} uploaded files are all"
    return f"{both} named {widgets.literal(name)}; upload one"


def load_from(load, name: str) -> None:
    """Load a shipped case or a server folder with ``load``; keep its problems for the page."""
    try:
        load(name)
    except rvpp.CaseError as err:
        st.session_state["home_load_problems"] = err.problems
        return
    st.session_state["home_load_problems"] = []


st.title("Robust day-ahead bids for a renewable virtual power plant")
case = state.case()
ask, about = st.columns([3, 2], gap="large")
with ask:
    st.header("What should I bid tomorrow?")
    balanced = Variant(strategy="balanced").apply(state.run_case())
    clicked = st.button("Solve the balanced strategy", type="primary", key="home_solve",
                        icon=":material/play_arrow:")
    timing = st.empty()  # said again once a solve below has measured it
    expected_time(timing, balanced)
    st.caption("One click plans tomorrow's bids for the current case with the balanced budgets of the paper's "
               "Table 7: energy in the day-ahead market (DAM), up and down secondary reserve, heat bought through "
               "the heat purchase agreement (HPA).")
    requested = clicked or state.is_requested(balanced)
    if not requested:
        problem = solving.prepare(state.run_case())
        if problem is not None:
            svg.draw(svg.price_band_svg(problem, "home-price-band"))  # drawn with the page: no chart code to load
with about:
    st.header("The case")
    st.markdown(f"**{widgets.literal(case.name)}** · {case.delivery_date:%a %d %b %Y} · "
                f"{case.budgets.strategy} · {case.markets.label} · {case.dt_h * 60:g}-min periods  \n"
                f"loaded from {widgets.literal(state.source(), widgets.LABEL_CHARS)}")
    widgets.case_summary(case)

if requested:
    state.mark_requested(balanced)
    result = solving.solve(balanced, "Solving the balanced strategy", again=clicked, stoppable=True)
    expected_time(timing, balanced)
    if result is not None:
        widgets.status_line(result)
        if result.has_plan:
            widgets.kpi_cards(result, only=HEADLINE)
            st.markdown("**Bids** (scroll for every period)")
            widgets.bids(result, key="home")
            st.plotly_chart(service.trades_figure(result), key="home_trades")
            st.markdown("The protection cost is what the balanced strategy sets aside against adverse prices. "
                        "**What does it cost to be safer?**")
            st.page_link("pages/compare.py", label="Compare the four strategies side by side",
                         icon=":material/compare_arrows:")
            st.page_link("pages/results.py", label="Every chart and download of the current case",
                         icon=":material/insights:")

st.header("About rvpp")
st.markdown(
    "**rvpp** plans tomorrow's bids of a virtual power plant made of a concentrated solar power plant "
    "with thermal storage, wind farms, PV plants and flexible electrical and thermal demands: energy in the "
    "day-ahead market, up and down secondary reserve, and heat bought through a heat purchase agreement. "
    "Prices, production and consumption are uncertain; a budget Γ per source sets in how many periods each "
    "may go against you, so a plan can be optimistic, balanced or pessimistic. "
    "The plan is the solution of a robust mixed-integer program. " + widgets.MONEY)
if case.description:
    st.caption(widgets.literal(case.description, DESCRIPTION_CHARS))
links = st.container(horizontal=True, gap="medium", width=3 * LINK_PX + 2 * GAP_PX)  # three to a row at most
for page, title, description in LINKS:
    with links.container(width=LINK_PX):
        st.page_link(page, label=title, icon=":material/arrow_forward:")
        st.caption(description)

st.header("Load another case")
folders = state.server_folders_allowed()  # off unless the server was started with RVPP_ALLOW_SERVER_FOLDERS=1
shipped, upload_tab, download_tab, *folder_tab = st.tabs(["Shipped cases", "Upload", "Download",
                                                          *(["Folder"] if folders else [])])
with shipped:
    choice = st.radio("Case", state.known_case_folders(), key="home_shipped")
    st.button("Load", key="home_load_shipped", on_click=load_from, args=(state.load_shipped, choice))
for tab in folder_tab:
    with tab:
        folder = st.text_input("Case folder on this machine (holding case.yaml)", key="home_folder")
        st.button("Load folder", key="home_load_folder", on_click=load_from, args=(state.load_folder, folder),
                  disabled=not folder)
with upload_tab:
    st.file_uploader("A zip of a case folder, case.yaml with its history CSV, or an Excel case workbook",
                     type=UPLOAD_TYPES, accept_multiple_files=True, key="home_upload")
    st.button("Load the uploaded case", key="home_load_upload", on_click=load_upload,
              disabled=not st.session_state.get("home_upload"))
with download_tab:
    st.caption("The current case with every edit, to keep or to load again later.")
    widgets.case_downloads(case, key="home")
if st.session_state.get("home_load_problems"):
    widgets.problems(st.session_state["home_load_problems"], "Case not loaded", note="The current case is unchanged.")
