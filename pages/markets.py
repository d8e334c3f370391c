"""Markets & tariffs: market switches, κ, the period length, the HPA tariff and the price bands."""

import pandas as pd
import streamlit as st

from dashboard import solving, state, widgets
from rvpp import CaseError
from rvpp.service import (
    bands_figure,
    tariff_figure,
    thin_clock_ticks,
    with_period_length,
)

state.through_app("pages/markets.py")

HOURS = range(24)
FLAT_PRESETS = (70.0, 60.0, 50.0)  # EUR/MWh_th, the flat tariffs of the paper's Table 12
PERIOD_MINUTES = {60: 1.0, 30: 0.5, 15: 0.25}
TARIFF_KEY = "markets_tariff"
SETTING_PX = 220        # a number field's width: its label on two lines
TARIFF_TABLE_PX = 320   # the tariff table's two columns whole (Clock hour, Tariff [EUR/MWh_th])


def apply(**changes) -> None:
    """Change the case through the case model; refusals are shown on the next run."""
    try:
        state.set_case(state.case().replace(**changes))
        st.session_state["markets_problems"] = []
        st.session_state["markets_notes"] = []
    except CaseError as err:
        st.session_state["markets_problems"] = err.problems


def set_period_length(key: str) -> None:
    """A new market time unit; Γ overrides are converted so they keep their hours, and the page says so."""
    try:
        case, converted = with_period_length(state.case(), PERIOD_MINUTES.get(st.session_state[key]))
    except CaseError as err:
        st.session_state["markets_problems"] = err.problems
        return
    state.set_case(case)
    st.session_state["markets_problems"] = []
    st.session_state["markets_notes"] = ["Γ overrides kept their hours: " + "; ".join(converted)] if converted else []


def set_tariff(values: list[float]) -> None:
    apply(markets={"hpa_tariff_eur_per_mwh": values})
    widgets.reset_editor(TARIFF_KEY)


def from_widget(field: str, key: str, section: str | None = None) -> None:
    value = st.session_state[key]
    apply(**({section: {field: value}} if section else {field: value}))


def tariff_table(case) -> pd.DataFrame:
    return pd.DataFrame({"hour": [f"{h:02d}:00–{h + 1:02d}:00" for h in HOURS],
                         "tariff_eur_per_mwh": list(case.markets.hpa_tariff_eur_per_mwh)})


st.title("Markets & tariffs")
case = state.case()
markets = case.markets

st.header("Markets")
switches = st.container(horizontal=True)  # a row that wraps: each label whole in a narrow window
switches.toggle("Day-ahead market (DAM)", value=True, disabled=True, key="markets_dam",
                help="The DAM is always on: it balances the plan.")
switches.toggle("Secondary reserve (SRM)", value=markets.srm, key="markets_srm", on_change=from_widget,
                args=("srm", "markets_srm", "markets"), help="Off: no up or down reserve band is offered.")
switches.toggle("Heat purchase (HPA)", value=markets.hpa, key="markets_hpa", on_change=from_widget,
                args=("hpa", "markets_hpa", "markets"),
                help="Heat purchase agreement. Off: thermal demands are served by the CSP alone.")
minutes = {v: k for k, v in PERIOD_MINUTES.items()}[case.dt_h]
settings = st.container(horizontal=True)
settings.number_input("κ: reserve band cap [-], from 0 to 1", min_value=0.0, max_value=1.0, step=0.05,
                      value=markets.kappa, key="markets_kappa", on_change=from_widget,
                      args=("kappa", "markets_kappa", "markets"), width=SETTING_PX,
                      help="Each SR band is at most κ × (generation capacity − demand capacity); paper: 0.3.")
settings.number_input("Reserve delivery time [min], at least 1", min_value=1.0, step=1.0,
                      value=markets.reserve_duration_min,
                      key="markets_duration", on_change=from_widget,
                      args=("reserve_duration_min", "markets_duration", "markets"), width=SETTING_PX,
                      help="A reserve band must be deliverable for this long: ramp [MW/min] × time caps each band.")
settings.segmented_control("Market time unit [min]", list(PERIOD_MINUTES), default=minutes, key="markets_dt",
                           required=True, on_change=set_period_length, args=("markets_dt",),
                           help="Period length; 15 minutes is the EU day-ahead market time unit (96 periods). Γ "
                                "overrides keep their duration in hours (rounded to whole periods).")
if st.session_state.get("markets_problems"):
    widgets.problems(st.session_state["markets_problems"])
for note in st.session_state.get("markets_notes", []):
    st.caption(note)

st.header("Heat purchase agreement tariff")
st.caption("One price per clock hour [EUR/MWh_th]; with 15-minute periods each quarter-hour takes its hour's "
           "price. Presets: the time-of-use tariff of the loaded case and the flat prices of the paper's "
           "Table 12.")
presets = st.container(horizontal=True)
presets.button("Time of use (case file)", key="markets_tou", on_click=set_tariff,
               args=(list(state.origin().markets.hpa_tariff_eur_per_mwh),))
for price in FLAT_PRESETS:
    presets.button(f"Flat {price:g}", key=f"markets_flat_{price:g}", on_click=set_tariff, args=([price] * 24,))
with presets.popover("Flat price…"):
    flat = st.number_input("Price [EUR/MWh_th]", min_value=0.0, value=70.0, step=5.0, key="markets_flat_price")
    st.button("Apply", key="markets_flat_apply", on_click=set_tariff, args=([flat] * 24,))
tariff = st.container(horizontal=True)  # the chart goes below the table in a narrow window
with tariff.container(width=TARIFF_TABLE_PX):
    widgets.table_editor(
        TARIFF_KEY,
        build=lambda: tariff_table(state.case()),
        apply=lambda table: state.case().replace(
            markets={"hpa_tariff_eur_per_mwh": [v for v in table["tariff_eur_per_mwh"]]}),
        column_config={"hour": st.column_config.TextColumn("Clock hour", disabled=True),
                       "tariff_eur_per_mwh": st.column_config.NumberColumn(
                           "Tariff [EUR/MWh_th]", format="%.2f", help="At least 0 EUR/MWh_th")},
        hide_index=True, height=400,
    )
problem = solving.prepare(state.run_case())
if problem is not None:
    tariff.plotly_chart(thin_clock_ticks(tariff_figure(problem), widgets.NARROW_TICK_HOURS), key="markets_tariff_chart")
    st.header("Price bands")
    st.caption("The DAM price may fall to its lower percentile when the plan sells and rise to its upper "
               "percentile when it buys; reserve prices are planned at their upper percentile and may fall to "
               "the lower one.")
    for source in ("price_da", "price_sr_up", "price_sr_dn"):
        st.plotly_chart(bands_figure(problem, source), key=f"markets_band_{source}")
