"""Out-of-sample: the robust strategies against the scenario-based stochastic benchmark,
settled on the same test days (paper Case 4, Tables 13-14), computed by
``rvpp.studies.out_of_sample`` and ``rvpp.studies.stochastic``."""

import pandas as pd
import streamlit as st

from dashboard import state, studies, widgets
from rvpp import RvppError
from rvpp.service import (Penalties, STRATEGIES, StudySettings, evaluation_days, figures, realizations_used,
                          training_days)

state.through_app("pages/out_of_sample.py")

TEST_DAYS, SCENARIOS, TIME_LIMIT_S = 10, (5, 10), 60.0  # small enough for a browser
STUDIES = {"out-of-sample": "Robust strategies", "stochastic": "Stochastic benchmark"}
SUMMARY_COLUMNS = {
    "method": st.column_config.TextColumn("Method"),
    "n_scenarios": st.column_config.NumberColumn("N"),
    "status": st.column_config.TextColumn("Status", help="How the plan's solve ended"),
    "mip_gap": st.column_config.NumberColumn("MIP gap [-]", format="%.1e"),
    "avg_market_cost_keur": st.column_config.NumberColumn("Avg market cost [kEUR/day]", format=widgets.KEUR_FORMAT),
    "avg_penalty_keur": st.column_config.NumberColumn("Avg penalty [kEUR/day]", format=widgets.KEUR_FORMAT),
    "avg_net_cost_keur": st.column_config.NumberColumn("Avg net cost [kEUR/day]", format=widgets.KEUR_FORMAT),
    "solve_s": st.column_config.NumberColumn("Solve time [s]", format="%.2f"),
    "test_days": st.column_config.NumberColumn("Test days"),
    "settlements_optimal": st.column_config.TextColumn(
        "Settlements optimal", help="Settlements that ended optimal, out of those settled; only these are averaged"),
    "realization_set": st.column_config.TextColumn("Realization set"),
}
TABLE13 = ["method", "status", "avg_market_cost_keur", "avg_penalty_keur", "avg_net_cost_keur", "solve_s",
           "settlements_optimal", "realization_set"]
TABLE14 = ["n_scenarios", "status", "mip_gap", "avg_market_cost_keur", "avg_penalty_keur", "avg_net_cost_keur",
           "solve_s", "settlements_optimal", "realization_set"]

st.title("Out-of-sample: robust strategies against the stochastic benchmark")
run = state.run_case()
window = run.uncertainty.window_days
st.markdown(f"**How it works.** Each method makes one plan for **{run.delivery_date:%d %B %Y}** from the {window} "
            "days before it: the robust strategies from their forecast bands, the stochastic program from N whole "
            "days sampled from that window. That one plan is then settled against the realized prices, production "
            "and demand of every test day from the delivery day on, the same days for every method. The settlement "
            "prices each deviation from the plan: energy short of the DAM bid at **m_def** × the realized DAM "
            "price, energy beyond it at **m_sur** × that price (a credit), reserve not delivered at **m_sr** × its "
            "price, and heat not served at the unserved-heat price.")
st.caption(f"The defaults ({TEST_DAYS} test days, N = {', '.join(map(str, SCENARIOS))}, {TIME_LIMIT_S:.0f} s per "
           "stochastic program) are sized for a browser: each stochastic program stops at its time limit. The "
           "paper's 30 days and N up to 25 take many times longer (the command line: python -m rvpp study "
           "reproduce).")

penalties = Penalties()
with st.form("out_of_sample_form"):
    first, second, third = st.columns(3)
    test_days = first.number_input("Test days", min_value=1, max_value=366, value=TEST_DAYS, step=1,
                                   key="out_of_sample_test_days", persist_state="session",
                                   help="Realized days from the delivery day on (days with a clock change are "
                                        "skipped)")
    scenarios_text = second.text_input("Scenario counts N", value=", ".join(map(str, SCENARIOS)),
                                       key="out_of_sample_scenarios", persist_state="session",
                                       help="One stochastic program per N, whole numbers separated by commas")
    time_limit = third.number_input("Time limit per stochastic program [s]", min_value=1.0, value=TIME_LIMIT_S,
                                    step=10.0, key="out_of_sample_time_limit", persist_state="session",
                                    help="A program stopped by the limit is settled with the best bids found")
    strategies = st.multiselect("Robust strategies", STRATEGIES, default=list(STRATEGIES),
                                key="out_of_sample_strategies", persist_state="session")
    st.markdown("**Penalties** of the settlement")
    p1, p2, p3, p4 = st.columns(4)
    m_def = p1.number_input("Deficit multiplier m_def [-]", min_value=0.0, value=penalties.m_def, step=0.25,
                            key="out_of_sample_m_def", persist_state="session",
                            help="Energy delivered short of the DAM bid costs m_def × the realized DAM price")
    m_sur = p2.number_input("Surplus multiplier m_sur [-]", min_value=0.0, value=penalties.m_sur, step=0.25,
                            key="out_of_sample_m_sur", persist_state="session",
                            help="Energy delivered beyond the DAM bid earns m_sur × the realized DAM price")
    m_sr = p3.number_input("Reserve shortfall multiplier m_sr [-]", min_value=0.0, value=penalties.m_sr, step=0.25,
                           key="out_of_sample_m_sr", persist_state="session",
                           help="Reserve that could not be delivered costs m_sr × its realized price")
    c_heat = p4.number_input("Unserved heat [EUR/MWh_th]", min_value=0.0, value=None, step=10.0,
                             key="out_of_sample_c_heat", persist_state="session",
                             placeholder=f"{penalties.heat_price(run):g} (default)",
                             help=f"Empty: twice the highest HPA tariff of the case, "
                                  f"{penalties.heat_price(run):g} EUR/MWh_th")
    with st.expander("More settings"):
        seed = st.number_input("Seed of the scenario sampling", min_value=0, value=StudySettings().seed, step=1,
                               key="out_of_sample_seed", persist_state="session")
        fix_commitment = st.checkbox("Settle with the plan's CSP turbine schedule", key="out_of_sample_fix",
                                     persist_state="session",
                                     help="The turbine never starts where the plan has it off")
    submitted = st.form_submit_button("Run", type="primary", key="out_of_sample_run", icon=":material/play_arrow:")

try:
    scenarios = studies.numbers(scenarios_text, "Scenario counts N", whole=True)
    if not scenarios:
        raise RvppError("Scenario counts N: give at least one, e.g. 5, 10")
    settings = StudySettings(
        strategies=tuple(strategies), test_days=int(test_days), scenario_counts=scenarios, seed=int(seed),
        sp_time_limit_s=float(time_limit), fix_commitment=fix_commitment,
        penalties=Penalties(m_def=m_def, m_sur=m_sur, m_sr=m_sr, c_heat_eur_per_mwh=c_heat))
    days = evaluation_days(run, settings.test_days)
    pool = training_days(run)
except RvppError as err:
    widgets.refusal(err, "Settings refused", note="Fix them and press Run.")
    st.stop()
st.caption(f"Test days {days[0]:%d %b} – {days[-1]:%d %b %Y}; scenarios drawn from the {len(pool)} days "
           f"before the delivery day. {len(strategies)} robust plans and {len(scenarios)} stochastic programs, each "
           f"settled on {len(days)} days.")

outputs = studies.run(STUDIES, run, settings, "out_of_sample", submitted)
if outputs is None:
    st.stop()
robust, stochastic = outputs["out-of-sample"], outputs["stochastic"]
evaluations = pd.concat([robust.tables["out_of_sample_days"], stochastic.tables["stochastic_days"]],
                        ignore_index=True)
summaries = pd.concat([robust.tables["table13_out_of_sample"], stochastic.tables["table14_stochastic"]],
                      ignore_index=True)

for warning in robust.warnings + stochastic.warnings:
    st.warning(warning, icon=":material/warning:")

st.header("Same days for every method")
used = realizations_used(evaluations)
sets = sorted({robust.facts["realization_set"], stochastic.facts["realization_set"]})
if len(sets) == 1 and used["day"].is_unique:
    st.success(f"Every method was settled on the same {len(used)} days: realization set **`{sets[0]}`** "
               "(a fingerprint of every realized value of every day).", icon=":material/verified:")
else:
    st.error(f"The methods met different data: realization sets {', '.join(sets)}.", icon=":material/error:")
with st.expander("Test days and their fingerprints"):
    st.dataframe(used, hide_index=True, column_config={
        "day": st.column_config.TextColumn("Test day"), "fingerprint": st.column_config.TextColumn("Fingerprint"),
        "methods": st.column_config.NumberColumn("Methods settled on it")})

st.header("Robust strategies (paper Table 13)")
st.dataframe(robust.tables["table13_out_of_sample"][TABLE13], hide_index=True, column_config=SUMMARY_COLUMNS)
st.header("Stochastic benchmark (paper Table 14)")
st.dataframe(stochastic.tables["table14_stochastic"][TABLE14], hide_index=True, column_config=SUMMARY_COLUMNS)
st.caption("Averages over the test days. Net cost = market cost + penalty; a negative penalty is surplus energy "
           "bought back at m_sur × the DAM price. Solve time: the plan's own solve (shared study process).")

st.plotly_chart(figures.out_of_sample_figure(summaries), key="out_of_sample_cost")
st.header("Where the penalties come from")
st.caption("The average penalty per test day split by cause. A plan made for one day meets other days' wind, sun "
           "and prices, so penalties can exceed the market cost: every MWh short of the bid costs m_def times the "
           "DAM price, and reserve that cannot be delivered costs m_sr times its price.")
st.plotly_chart(figures.penalty_causes_figure(evaluations), key="out_of_sample_penalties")
st.plotly_chart(figures.net_cost_by_day_figure(evaluations), key="out_of_sample_days")
st.plotly_chart(figures.solve_time_figure(summaries), key="out_of_sample_solve_time")
st.caption(f"Computed in {robust.seconds:.1f} s (robust) and {stochastic.seconds:.1f} s (stochastic), side by side.")
st.header("Downloads")
studies.downloads([robust, stochastic], f"{run.name}_{run.delivery_date:%Y%m%d}_out_of_sample",
                  key="out_of_sample_download")
