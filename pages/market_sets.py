"""Market sets and HPA prices: cost by market set and strategy, without the CSP and by HPA
tariff (paper Case 3, Tables 10-12), computed by ``rvpp.studies.markets``."""

import pandas as pd
import streamlit as st

from dashboard import state, studies, widgets
from rvpp import RvppError
from rvpp.service import HPA_FLAT_PRICES, MARKET_SETS, MARKET_SETS_WITHOUT_CSP, STRATEGIES, StudySettings, markets

state.through_app("pages/market_sets.py")

NOT_AVAILABLE = "n/a"  # a configuration without a plan, as the warning above the tables says
TABLES = (  # table, figure, heading, what the columns are
    ("table10_markets", "markets_cost", "Cost by market set (paper Table 10)", "Market set"),
    ("table11_without_csp", "markets_without_csp", "Cost without the CSP (paper Table 11)", "Market set, no CSP"),
    ("table12_hpa_price", "hpa_price_cost", "Cost by HPA tariff, DAM+SRM+HPA (paper Table 12)",
     "HPA tariff [EUR/MWh_th]"),
)
PLAN_COLUMNS = {
    "table": st.column_config.TextColumn("Table"),
    "strategy": st.column_config.TextColumn("Strategy"),
    "column": st.column_config.TextColumn("Column"),
    "variant": st.column_config.TextColumn("Variant solved", help="Strategy, markets and what else the plan changes"),
    "status": st.column_config.TextColumn("Status"),
    "cost_keur": st.column_config.NumberColumn("Cost [kEUR]", format=widgets.KEUR_FORMAT),
    "profit_eur": None,  # the cost beside it is minus the profit, in kEUR; exports keep profit_eur
    "solve_s": st.column_config.NumberColumn("Solve [s]", format="%.2f"),
    "sold_mwh": st.column_config.NumberColumn("Sold [MWh]", format="%.1f"),
    "bought_mwh": st.column_config.NumberColumn("Bought [MWh]", format="%.1f"),
    "heat_bought_mwh": st.column_config.NumberColumn("Heat bought [MWh_th]", format="%.1f"),
    "sr_up_mwh": st.column_config.NumberColumn("SR up [MWh]", format="%.1f"),
    "sr_dn_mwh": st.column_config.NumberColumn("SR down [MWh]", format="%.1f"),
}


def cost_table(table) -> tuple[pd.DataFrame, dict]:
    """Cost [kEUR] to one decimal with thousands separators and a true minus, ``n/a`` where a configuration
    has no plan, right-aligned, with its column settings: as text, since the grid draws a missing number as
    "None" whatever a Styler says."""
    shown = table.map(lambda value: NOT_AVAILABLE if pd.isna(value) else f"{value:,.1f}".replace("-", "−"))
    shown = shown.rename(columns=lambda c: f"{c:g}" if isinstance(c, float) else str(c))
    return shown, {c: st.column_config.TextColumn(c, alignment="right") for c in shown.columns}


st.title("Market sets and HPA prices")
run = state.run_case()
st.markdown(f"What each market costs or saves on **{run.delivery_date:%d %B %Y}**: every strategy's plan under each "
            "market set, the same portfolio without its CSP, and flat HPA tariffs against the time-of-use tariff "
            "(paper Case 3, Tables 10-12). Cost = −profit [kEUR]; lower is better.")
if not run.csp:
    st.info("The CSP is switched off on Portfolio, so every table is without the CSP.", icon=":material/info:")

with st.form("market_sets_form"):
    strategies = st.multiselect("Strategies (rows)", STRATEGIES, default=list(STRATEGIES),
                                key="market_sets_strategies", persist_state="session")
    left, middle, right = st.columns(3)
    market_sets = left.multiselect("Market sets (Table 10)", MARKET_SETS, default=list(MARKET_SETS),
                                   key="market_sets_sets", persist_state="session")
    without_csp = middle.multiselect("Market sets without the CSP (Table 11)", MARKET_SETS_WITHOUT_CSP,
                                     default=list(MARKET_SETS_WITHOUT_CSP), key="market_sets_without_csp",
                                     persist_state="session",
                                     help="Without CSP and HPA nothing can serve the thermal demands, so only "
                                          "market sets with the HPA are offered.")
    prices_text = right.text_input("Flat HPA tariffs [EUR/MWh_th] (Table 12)", value=studies.listed(HPA_FLAT_PRICES),
                                   key="market_sets_prices", persist_state="session",
                                   help="Numbers separated by commas; each is compared with the time-of-use "
                                        "tariff of the case under DAM+SRM+HPA.")
    submitted = st.form_submit_button("Run", type="primary", key="market_sets_run", icon=":material/play_arrow:")

try:
    settings = StudySettings(strategies=tuple(strategies), market_sets=tuple(market_sets),
                             market_sets_without_csp=tuple(without_csp),
                             hpa_flat_prices=studies.numbers(prices_text, "Flat HPA tariffs"))
except RvppError as err:
    widgets.refusal(err, "Settings refused", note="Fix them and press Run.")
    st.stop()
st.caption(f"{len(markets.configurations(settings))} configurations (identical ones are solved once), one after "
           "the other in a study process; the progress shows below once you press Run.")

outputs = studies.run({"markets": "Market sets and HPA prices"}, run, settings, "market_sets", submitted)
if outputs is None:
    st.stop()
out = outputs["markets"]
if out.notes:
    st.warning("**Configurations without an optimal plan** (`n/a` in the tables when there is no plan at all):\n\n"
               + "\n".join(f"- {note}" for note in out.notes), icon=":material/warning:")

for name, figure, heading, columns in TABLES:
    table = out.tables[name]
    if table.columns.empty:
        continue
    st.header(heading)
    shown, config = cost_table(table.rename_axis(index="Strategy", columns=columns))
    st.dataframe(shown, column_config=config)
    st.plotly_chart(out.figures[figure], key=f"market_sets_{figure}")

with st.expander("Every plan: trades and reserve", icon=":material/table_rows:"):
    st.dataframe(out.tables["market_plans"], hide_index=True, column_config=PLAN_COLUMNS)
st.caption(f"Computed in {out.seconds:.1f} s.")
st.header("Downloads")
studies.downloads([out], f"{run.name}_{run.delivery_date:%Y%m%d}_market_sets", key="market_sets_download")
