"""Results: solve the current case; KPIs, the plan's charts, flexibility and downloads."""

import streamlit as st

from dashboard import solving, state, widgets
from rvpp.outputs.plots import (KIND_LABELS, dispatch_figure, heat_figure, reserve_share_figure, storage_figure,
                        trades_figure)

state.through_app("pages/results.py")

FLEXIBILITY_COLUMNS = {
    "kind": st.column_config.TextColumn("Unit kind"),
    "r_up_mwh": st.column_config.NumberColumn("Up reserve [MWh]", format="%.1f"),
    "r_dn_mwh": st.column_config.NumberColumn("Down reserve [MWh]", format="%.1f"),
    "capacity_mw": st.column_config.NumberColumn("Capacity [MW]", format="%.0f"),
    "r_up_h": st.column_config.NumberColumn("Up / capacity [h]", format="%.2f"),
    "r_dn_h": st.column_config.NumberColumn("Down / capacity [h]", format="%.2f"),
}


def save(result, key: str) -> None:
    state.save_run(st.session_state[key] or widgets.run_label(result.case), result)


st.title("Results")
run = state.run_case()
st.markdown(f"Plan for **{run.delivery_date:%A %d %B %Y}** · {widgets.run_label(run)}")
clicked = st.button("Solve", type="primary", key="results_solve", icon=":material/play_arrow:")
if not (clicked or state.is_requested(run)):
    waiting = "The inputs changed since the last solve." if st.session_state[state.REQUESTED] else ""
    st.info(f"{waiting} Press **Solve** to compute the plan of the current case (about a second).",
            icon=":material/info:")
    st.stop()

state.mark_requested(run)
result = solving.solve(run, "Solving the current case")
if result is None:
    st.stop()
widgets.status_line(result)
if not result.has_plan:
    st.stop()

widgets.kpi_cards(result)
with st.expander("Save this run to compare it later", icon=":material/bookmark_add:"):
    st.text_input("Label", value=widgets.run_label(run), key="results_run_label")
    st.button("Save run", key="results_save", on_click=save, args=(result, "results_run_label"))
    if state.saved_runs():
        st.caption("Saved: " + "; ".join(state.saved_runs()) + ". See them on Compare strategies.")

st.subheader("Bids")
st.plotly_chart(trades_figure(result), key="results_trades")
st.subheader("Heat")
st.plotly_chart(heat_figure(result), key="results_heat")
st.subheader("Electrical dispatch")
st.plotly_chart(dispatch_figure(result), key="results_dispatch")
if result.case.csp:
    st.subheader("Thermal storage")
    st.caption("The margins above the minimum and below the maximum (σ) are kept free so the CSP can deliver "
               "the up and down reserve it offers (paper constraints TS9-TS11).")
    for csp in result.case.csp:
        st.plotly_chart(storage_figure(result, csp.name), key=f"results_storage_{csp.name}")
st.subheader("Reserve by unit kind")
st.plotly_chart(reserve_share_figure(result), key="results_reserve")

st.subheader("Flexibility")
st.caption("Reserve energy over the day per unit kind, and the same divided by installed capacity "
           "(paper Table 9; the paper's \"%\" columns are this ratio in hours).")
flexibility = result.flexibility.assign(kind=result.flexibility["kind"].map(KIND_LABELS))
st.dataframe(flexibility, hide_index=True, column_config=FLEXIBILITY_COLUMNS)

st.subheader("Downloads")
widgets.plan_downloads(result, run, key="results")
