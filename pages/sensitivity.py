"""Sensitivity to Γ: cost, traded energy and reserve by unit kind over a grid of budgets
(paper Case 2, Figures 15-16), computed by ``rvpp.studies.sensitivity``."""

import streamlit as st

from dashboard import solving, state, studies, widgets
from rvpp import RvppError
from rvpp.service import Outcome, StudySettings, figures, sensitivity

state.through_app("pages/sensitivity.py")

ALL_AT_ONCE = "Every source at once"
ONE_AT_A_TIME = "Chosen sources one at a time"
COLUMNS = {
    "sources": st.column_config.TextColumn("Sources swept"),
    "gamma": st.column_config.NumberColumn("Γ [periods]"),
    "variant": st.column_config.TextColumn("Variant solved", help="Strategy, markets and the Γ edits of the plan"),
    "status": st.column_config.TextColumn("Status"),
    "cost_keur": st.column_config.NumberColumn("Cost [kEUR]", format=widgets.KEUR_FORMAT),
    "profit_eur": None,  # the cost beside it is minus the profit, in kEUR; exports keep profit_eur
    "mip_gap": st.column_config.NumberColumn("MIP gap [-]", format="%.1e"),
    "solve_s": st.column_config.NumberColumn("Solve [s]", format="%.2f"),
    "sold_mwh": st.column_config.NumberColumn("Sold [MWh]", format="%.1f"),
    "bought_mwh": st.column_config.NumberColumn("Bought [MWh]", format="%.1f"),
    "net_traded_mwh": st.column_config.NumberColumn("Net sold [MWh]", format="%.1f"),
    "heat_bought_mwh": st.column_config.NumberColumn("Heat bought [MWh_th]", format="%.1f"),
    "sr_up_mwh": st.column_config.NumberColumn("SR up [MWh]", format="%.1f"),
    "sr_dn_mwh": st.column_config.NumberColumn("SR down [MWh]", format="%.1f"),
    **{f"{kind}_{d}_mwh": st.column_config.NumberColumn(f"{label} {word} [MWh]", format="%.1f")
       for kind, label in figures.KIND_LABELS.items() for d, word in (("up", "up"), ("dn", "down"))},
    "audit_violations": st.column_config.NumberColumn("Rules broken", help="Rules of the model the plan breaks "
                                                                           "(0 expected)"),
}

st.title("Sensitivity to the uncertainty budget Γ")
run = state.run_case()
grid = sensitivity.gamma_grid(run, StudySettings())
st.markdown(f"How the plan of **{run.delivery_date:%d %B %Y}** ({state.default_label()}) changes as the "
            "uncertainty budget Γ grows: one deterministic plan with the same Γ for the swept sources, per value "
            "of the grid (paper Case 2, Figures 15 and 16). Γ is the number of periods in which a source may "
            f"deviate from its forecast; the day has {grid[-1]} periods.")

with st.form("sensitivity_form"):
    left, right = st.columns(2)
    gammas_text = left.text_input(
        "Γ grid [periods]", key="sensitivity_gammas", persist_state="session",
        placeholder=f"every hour: {', '.join(map(str, grid[:3]))}, …, {grid[-1]}",
        help=f"Whole numbers from 0 to {grid[-1]} separated by commas. Empty: every hour of the day.")
    mode = right.radio("Sources", (ALL_AT_ONCE, ONE_AT_A_TIME), key="sensitivity_mode", horizontal=True,
                       persist_state="session",
                       help="At once: every price and unit gets the same Γ (the paper's figures). One at a time: "
                            "each chosen source or kind is swept on its own while the others keep Γ = 0.")
    chosen = right.multiselect("Sources or kinds swept one at a time", sensitivity.sweep_choices(run),
                               key="sensitivity_sources", persist_state="session",
                               help="A kind (wind, pv, price, …) sweeps all of its sources together.")
    submitted = st.form_submit_button("Run", type="primary", key="sensitivity_run", icon=":material/play_arrow:")

try:
    gammas = studies.numbers(gammas_text, "Γ grid", whole=True)
    if mode == ONE_AT_A_TIME and not chosen:
        raise RvppError("Sources: choose at least one source or kind to sweep one at a time, or sweep every "
                        "source at once")
    settings = StudySettings(gammas=gammas or None, sources=tuple(chosen) if mode == ONE_AT_A_TIME else ())
    solves = len(sensitivity.configurations(run, settings))
except RvppError as err:
    widgets.refusal(err, "Settings refused", note="Fix them and press Run.")
    st.stop()
expected = solving.solver().expected_s(run)
each = f"about {expected[0]:.1f} s each ({expected[1]})" if expected else "each as long as one plan of this case"
st.caption(f"{solves} plans to solve, {each}, one after the other in a study process.")

outputs = studies.run({"sensitivity": "Sensitivity"}, run, settings, "sensitivity", submitted)
if outputs is None:
    st.stop()
out = outputs["sensitivity"]
table = out.tables["sensitivity"]
without_plan = table[table["status"].map(lambda status: Outcome(status) is not Outcome.OPTIMAL)]
if not without_plan.empty:
    st.warning("Not optimal: " + "; ".join(f"{r.sources}, Γ = {r.gamma}: {r.status}"
                                           for r in without_plan.itertuples()), icon=":material/warning:")

st.header("Cost and traded energy (paper Figure 15)")
st.plotly_chart(out.figures["sensitivity_trades"], key="sensitivity_trades")
st.header("Reserve by unit kind (paper Figure 16)")
groups = list(dict.fromkeys(table["sources"]))
shown = groups[0] if len(groups) == 1 else st.segmented_control(
    "Sweep shown", groups, default=groups[0], required=True, key="sensitivity_shown")
st.plotly_chart(figures.sensitivity_reserve_figure(table, shown), key="sensitivity_reserve")
st.header("Table")
st.caption("One row per plan. Energies are sums over the day; reserve is the band offered per unit kind. "
           f"Computed in {out.seconds:.1f} s.")
st.dataframe(table, hide_index=True, column_config=COLUMNS)
st.header("Downloads")
studies.downloads([out], f"{run.name}_{run.delivery_date:%Y%m%d}_sensitivity", key="sensitivity_download")
