"""Compare strategies: the four strategies in one click, the paper's cost and flexibility
tables, and the runs saved in this session side by side."""

import streamlit as st

from dashboard import solving, state, widgets
from rvpp import RvppError
from rvpp.data.case import STRATEGIES
from rvpp.data.variants import Variant, describe
from rvpp.outputs.compare import MARKET_SETS, cost_table, flexibility_table, kpi_table
from rvpp.outputs.plots import compare_trades_figure

state.through_app("pages/compare.py")

KEUR = st.column_config.NumberColumn(format="%.1f")


def save_all(results: dict) -> None:
    for result in results.values():
        state.save_run(describe(result.case), result)


st.title("Compare strategies")
run = state.run_case()
st.markdown("Solve the deterministic, optimistic, balanced and pessimistic strategies of the current case "
            "(budgets of the paper's Table 7; individual Γ edits are set aside) and see what being safer costs.")
market_sets = st.multiselect(
    "Market sets (columns of the cost table)", MARKET_SETS, default=[run.markets.label], key="compare_sets",
    help="Each market set adds four solves. The paper's Table 10 has all four; Table 11 is the same without "
         "the CSP (switch it off on Portfolio).")
cases = {(s, m): Variant(strategy=s, markets=m).apply(run) for m in market_sets for s in STRATEGIES}
ready = bool(cases) and all(state.is_requested(c) for c in cases.values())
clicked = st.button(f"Solve {len(cases)} plans", type="primary", key="compare_solve", disabled=not cases,
                    icon=":material/play_arrow:")

if cases and (clicked or ready):
    for case in cases.values():
        state.mark_requested(case)
    try:
        solved = solving.solve_all(list(cases.values()), "Solving the strategies")
    except RvppError as err:
        widgets.refusal(err, "Cannot solve", note="Fix the case on the other pages and solve again.")
        st.stop()
    results = dict(zip(cases, solved))
    failed = [f"{s} / {m}: {r.status} {r.message}" for (s, m), r in results.items() if not r.has_plan]
    if failed:
        st.warning("Some plans could not be made:\n\n" + "\n".join(f"- {f}" for f in failed))

    st.subheader("Cost [kEUR]")
    st.caption("Cost = −profit, as in the paper's Tables 10 and 11; lower is better.")
    st.dataframe(cost_table(results), column_config={m: KEUR for m in market_sets})

    shown = market_sets[0] if len(market_sets) == 1 else st.segmented_control(
        "Market set shown below", market_sets, default=market_sets[0], required=True, key="compare_shown")
    by_strategy = {s: results[(s, shown)] for s in STRATEGIES if results[(s, shown)].has_plan}
    if by_strategy:
        st.subheader(f"Trades per strategy ({shown})")
        st.plotly_chart(compare_trades_figure(by_strategy), key="compare_trades")
        st.subheader("Profit and its parts")
        st.caption("What being safer costs: the extra cost of each strategy over the deterministic plan.")
        kpis = kpi_table(by_strategy, baseline="deterministic" if "deterministic" in by_strategy else None)
        st.dataframe(kpis, column_config=widgets.number_formats(kpis))
        st.subheader("Flexibility per strategy")
        st.caption("Paper Table 9 layout: reserve energy over the day and the same divided by installed "
                   "capacity [h].")
        flexibility = flexibility_table(by_strategy)
        st.dataframe(flexibility, column_config=widgets.number_formats(flexibility))
        st.button("Save these plans to the session", key="compare_save", on_click=save_all,
                  args=(by_strategy,))

st.subheader("Saved runs")
runs = state.saved_runs()
if not runs:
    st.caption("Runs saved on Results (or with the button above) appear here side by side.")
else:
    saved = kpi_table(runs)
    st.dataframe(saved, column_config=widgets.number_formats(saved))
    chosen = st.multiselect("Overlay the trades of", list(runs), default=list(runs)[-4:], key="compare_saved")
    with_plan = {label: runs[label] for label in chosen if runs[label].has_plan}
    if with_plan:
        st.plotly_chart(compare_trades_figure(with_plan), key="compare_saved_trades")
    remove = st.selectbox("Remove a saved run", list(runs), index=None, key="compare_remove")
    st.button("Remove", key="compare_remove_button", on_click=state.drop_run, args=(remove,), disabled=remove is None)
