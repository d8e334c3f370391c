"""Results: solve the current case; the day's economics, the plan's charts, flexibility,
downloads, and saving the run to the library."""

import streamlit as st

from dashboard import backtests, library, solving, state, widgets
from dashboard.figures import heat_bought, plan_figures
from rvpp import RvppError
from rvpp.service import KIND_LABELS

state.through_app("pages/results.py")

LABEL_KEY = "results_run_label"
LABEL_FOR = "results_label_for"  # the case key the label field was filled for
SHOWN = "results_shown"    # (case key, net cost [kEUR], run case) of the plan Results shows
BEFORE = "results_before"  # the same of the plan it showed before
BIDS = {"case": "the current case's budgets", "recommended": "the recommended Γ"}
FLEXIBILITY_COLUMNS = {
    "kind": st.column_config.TextColumn("Unit kind"),
    "r_up_mwh": st.column_config.NumberColumn("Up reserve [MWh]", format="%.1f"),
    "r_dn_mwh": st.column_config.NumberColumn("Down reserve [MWh]", format="%.1f"),
    "capacity_mw": st.column_config.NumberColumn("Capacity [MW]", format="%.0f"),
    "r_up_h": st.column_config.NumberColumn("Up / capacity [h]", format="%.2f"),
    "r_dn_h": st.column_config.NumberColumn("Down / capacity [h]", format="%.2f"),
}


def save(result, edited, run) -> None:
    label = (st.session_state.get(LABEL_KEY) or "").strip() or state.default_label(edited)
    try:
        info = library.save(label, edited, result)
    except RvppError as err:
        st.session_state[state.SAVED_RUN] = None
        st.session_state["results_save_problem"] = str(err)
        return
    st.session_state["results_save_problem"] = None
    st.session_state[state.SAVED_RUN] = (info.id, info.label, state.case_key(run), "saved")


def what_changed(result, run) -> None:
    """After an edit: the net cost of the plan shown before and of this one, and the fields edited
    between them."""
    key = state.case_key(run)
    shown = st.session_state.get(SHOWN)
    if shown is None or shown[0] != key:
        st.session_state[BEFORE] = shown
        st.session_state[SHOWN] = shown = (key, result.cost_keur, run)
    before = st.session_state.get(BEFORE)
    if before is None or before[1] is None or shown[1] is None:
        return
    edits = widgets.changes(before[2], run)
    difference = shown[1] - before[1]
    costs = f"{before[1]:,.1f} → {shown[1]:,.1f} kEUR ({difference:+,.1f} kEUR)".replace("-", "−")  # as the cards
    st.info(f"**What changed** since the plan shown before: net cost {costs}; "
            + "; ".join(widgets.literal(e, limit=None) for e in edits) + ".", icon=":material/compare_arrows:")


def plan(result, edited, run) -> None:
    """The plan of a solve that gave one: what changed, the cards, the charts, saving it, the downloads."""
    what_changed(result, run)
    widgets.kpi_cards(result)
    # Every figure before the first is drawn: the browser draws each chart twice (Streamlit applies its theme
    # once a chart is mounted), and the second drawing of a chart sent alone comes before the next chart's first.
    figures = plan_figures(result)
    st.plotly_chart(figures["economics"], key="results_economics")

    with st.expander("Save this run to the library", icon=":material/bookmark_add:", expanded=True):
        key = state.case_key(run)
        if st.session_state.get(LABEL_FOR) != key:
            st.session_state[LABEL_FOR] = key
            st.session_state[LABEL_KEY] = state.default_label(edited)
        row = st.container(horizontal=True, vertical_alignment="bottom")
        row.text_input("Label (unique; a taken label gets a number)", key=LABEL_KEY, max_chars=190,
                       help="By default: strategy, market set and what you edited since the case was loaded.")
        row.button("Save run", key="results_save", on_click=save, args=(result, edited, run), icon=":material/save:")
        if st.session_state.get("results_save_problem"):
            widgets.problems([widgets.literal(st.session_state["results_save_problem"], limit=None)], "Not saved",
                             note="Nothing was changed.")
        elif (st.session_state.get(state.SAVED_RUN) or (None,) * 4)[2] == key:  # saved or opened for this case
            run_id, label, _, how = st.session_state[state.SAVED_RUN]
            shown = widgets.literal(label, widgets.LABEL_CHARS)
            said = f"Saved as **{shown}**" if how == "saved" else f"This plan is the saved run **{shown}**, opened from the library"
            st.success(f"{said}. It stays in the library across reloads and restarts; "
                       f"[open it by link]({library.link(run_id)}) or see it on Saved runs.", icon=":material/check:")
        st.page_link("pages/runs.py", label="Saved runs: rename, delete, export, compare", icon=":material/bookmarks:")

    st.header("Bids")
    widgets.bids(result, key="results")
    st.plotly_chart(figures["trades"], key="results_trades")
    st.header("Heat")
    if figures.get("heat") is None:
        st.caption("No thermal demand in this case: no heat to show.")
    else:
        if not heat_bought(result):
            st.caption("No heat bought through the HPA: the CSP covers the thermal demands all day.")
        st.plotly_chart(figures["heat"], key="results_heat")
    st.header("Electrical dispatch")
    st.plotly_chart(figures["dispatch"], key="results_dispatch")
    if result.case.csp:
        st.header("Thermal storage")
        st.caption("The margins above the minimum and below the maximum (σ) are kept free so the CSP can deliver "
                   "the up and down reserve it offers (paper constraints TS9-TS11).")
        for csp in result.case.csp:
            st.plotly_chart(figures[f"storage {csp.name}"], key=f"results_storage_{csp.name}")
    batteries = [name.removeprefix("battery ") for name in figures if name.startswith("battery ")]
    if batteries:
        st.header("Batteries")
        st.caption("State of charge; the margins (σ) are kept free so the battery can deliver the reserve it offers.")
        for name in batteries:
            st.plotly_chart(figures[f"battery {name}"], key=f"results_battery_{name}")
    st.header("Reserve by unit kind")
    st.plotly_chart(figures["reserve"], key="results_reserve")

    st.header("Flexibility")
    st.caption("Reserve energy over the day per unit kind, and the same divided by installed capacity "
               "(paper Table 9; the paper's \"%\" columns are this ratio in hours).")
    flexibility = result.flexibility.assign(kind=result.flexibility["kind"].map(KIND_LABELS))
    st.dataframe(flexibility, hide_index=True, column_config=FLEXIBILITY_COLUMNS)

    st.header("Downloads")
    widgets.plan_downloads(result, run, key="results")


st.title("Results")
edited, run = state.case(), state.run_case()
recommendation = backtests.recommended()
if recommendation is None:
    st.caption(":material/lightbulb: " + backtests.HOW_TO_RECOMMEND)
else:
    labels = {**BIDS, "recommended": backtests.recommended_label(recommendation)}
    bid = st.radio("Bid with", list(labels), format_func=labels.get, key="results_bid", horizontal=True,
                   help="The recommended Γ replaces the case's strategy and Γ edits by one Γ for every source.")
    if bid == "recommended":
        st.caption(backtests.recommendation_note(recommendation))
        edited, run = (backtests.recommended_case(c, recommendation) for c in (edited, run))
st.markdown(f"Plan for **{run.delivery_date:%A %d %B %Y}** · {state.default_label(edited)}")
opened = st.session_state.get(state.SAVED_RUN) or (None,) * 4
if opened[3] in ("opened", "opened without a plan") and opened[2] == state.case_key(run):
    said = ("its plan as saved, shown without a solve" if opened[3] == "opened"
            else "it was saved without a plan; Solve computes one")
    st.caption(f":material/bookmark: The saved run **{widgets.literal(opened[1], widgets.LABEL_CHARS)}**, "
               f"opened from the library: {said}.")
clicked = st.button("Solve", type="primary", key="results_solve", icon=":material/play_arrow:")
if not (clicked or state.is_requested(run)):
    cancelled = "The last solve was cancelled." if solving.cancelled() else ""
    changed = "The inputs changed since the last solve." if st.session_state[state.REQUESTED] else ""
    expected = solving.solver().expected_s(run)
    timing = f" (about {expected[0]:.0f} s, from {expected[1]})" if expected and expected[0] >= 1 else ""
    st.info(f"{cancelled} {changed} Press **Solve** to compute the plan of the current case{timing}.",
            icon=":material/info:")
    if ties := solving.tied(run):
        st.caption(f"This day has deviations tied at the Γ boundary ({'; '.join(ties)}): the model chooses "
                   "which of them count, the exact rule, which makes such a day several times slower to solve. "
                   f"{solving.EARLIEST_HINT}")
    st.stop()

state.mark_requested(run)
result = solving.solve(run, "Solving the current case", again=clicked, stoppable=True)
if result is None:
    st.stop()
widgets.status_line(result)
if result.has_plan:  # without a plan the page ends here, not by st.stop(): app.py then says "no plan" in the sidebar
    plan(result, edited, run)
