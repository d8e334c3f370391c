"""Uncertainty: delivery day, history window and percentiles, budgets Γ, and where each
source deviates in the plan."""

import datetime as dt

import pandas as pd
import streamlit as st

from dashboard import solving, state, widgets
from rvpp import Case, CaseError
from rvpp.service import (PERIOD_NAMES, PRICE_COLUMNS, PRICE_MODELS, STRATEGIES, STRATEGY_BUDGETS_H, band_overlays,
                          band_specs, bands_figure, delivery_periods, deviating_periods, excerpt, has_forecast,
                          strategy_budgets, thin_clock_ticks)

state.through_app("pages/uncertainty.py")

BUDGETS_KEY = "uncertainty_budgets"
WINDOW_DAYS = (7, 90)
Q_LO, Q_HI = (0.05, 0.45), (0.55, 0.95)
Q_STEP = 0.05
BAND_COLUMNS = 2
DATE_PX, SLIDER_PX = 170, 190  # the day, the window and the percentiles in one row from 790 px, two rows when narrower
CHOICE_PX = 230  # the price point forecast: "same hour last week" whole
BUDGET_TABLE_PX, VARIANT_PX = 490, 300  # the budget table beside the variant's choices from 806 px
TABLE_ROW_PX, TABLE_BORDER_PX = 35, 3  # st.data_editor row height and frame
PRICE_LABELS = {"price_da": "DAM price", "price_sr_up": "SR up price", "price_sr_dn": "SR down price"}
GROUPS = {"Prices": ("price",), "Wind": ("wind",), "PV": ("pv",), "CSP": ("csp",), "Demands": ("ed", "td")}
MODES = {"paper": "Paper: each source deviates in its Γ largest-deviation periods",
         "planner_chosen": "Planner-chosen periods (teaching only; see Learn)"}
TIES = {"choose": "The model chooses among them (as the binary formulation)",
        "earliest": "The earliest of them deviate"}


def apply(**changes) -> None:
    try:
        state.set_case(state.case().replace(**changes))
        st.session_state["uncertainty_problems"] = []
    except CaseError as err:
        st.session_state["uncertainty_problems"] = err.problems


def from_widget(section: str | None, field: str, key: str) -> None:
    value = st.session_state[key]
    apply(**({section: {field: value}} if section else {field: value}))


def set_forecast_bands(key: str) -> None:
    apply(uncertainty={"bands": {"default": "climatology", **{s: "forecast" for s in st.session_state[key]}}})


def set_mode(key: str) -> None:
    mode = st.session_state[key]
    apply(budgets={"mode": mode} if mode == "paper" else {"mode": mode, "ties": "choose"})


def set_strategy(key: str) -> None:
    apply(budgets={"strategy": st.session_state[key], "overrides": {}})
    widgets.reset_editor(BUDGETS_KEY)


def period_count(case: Case) -> int:
    return len(delivery_periods(case.delivery_date, case.timezone, case.dt_h))


def budget_table(case: Case) -> pd.DataFrame:
    nt = period_count(case)
    preset = strategy_budgets(case.replace(budgets={"overrides": {}}), nt)
    gammas = {**preset, **case.budgets.override_map}
    kinds = {unit.name: widgets.KIND_TITLES[kind] for kind, unit in case.units()}
    return pd.DataFrame({"source": list(gammas),
                         "kind": [PRICE_LABELS.get(s) or kinds[s] for s in gammas],
                         "preset": [preset[s] for s in gammas],
                         "gamma": [float(gammas[s]) for s in gammas],
                         "hours": [gammas[s] * case.dt_h for s in gammas]})


def with_budgets(case: Case, table: pd.DataFrame) -> Case:
    """Γ that differ from the strategy preset become overrides; an empty cell means the preset.

    A Γ outside 0 to the day's number of periods, or not a whole number, is refused by
    name, value and range (never clipped). The table has one row per source; a row that
    names no source of the case, or a source twice (a crafted request can add rows), is
    refused by name.
    """
    sources, rows = case.sources(), list(table["source"])
    unknown = ["Budgets Γ: a row without a source; the table has one row per source" if pd.isna(source) else
               f"Budgets Γ: {excerpt(source)!r} is not a source of this case (sources: {', '.join(sources)})"
               for source in rows if pd.isna(source) or source not in sources]
    unknown += [f"Budgets Γ: {source} has more than one row" for source in sources if rows.count(source) > 1]
    if unknown:
        raise CaseError(list(dict.fromkeys(unknown)))
    nt = period_count(case)
    name = f"Γ [{PERIOD_NAMES[case.dt_h]}]"
    wrong = [f"{name} of {row.source}: {row.gamma:g} is outside the allowed range 0 to {nt} (the day's {nt} "
             f"{PERIOD_NAMES[case.dt_h]})" if not 0 <= row.gamma <= nt else
             f"{name} of {row.source}: {row.gamma:g} must be a whole number of {PERIOD_NAMES[case.dt_h]} (0 to {nt})"
             for row in table.itertuples() if pd.notna(row.gamma) and not (0 <= row.gamma <= nt
                                                                           and float(row.gamma).is_integer())]
    if wrong:
        raise CaseError(wrong)
    preset = strategy_budgets(case.replace(budgets={"overrides": {}}), nt)
    overrides = {row.source: int(row.gamma) for row in table.itertuples()
                 if pd.notna(row.gamma) and int(row.gamma) != preset[row.source]}
    edited = case.replace(budgets={"overrides": overrides})
    strategy_budgets(edited, period_count(edited))
    return edited


st.title("Uncertainty")
case = state.case()
nt = period_count(case)

st.header("Delivery day and forecast bands")
days = case.history.local_days(case.timezone)
if not days:
    widgets.problems([f"{case.history.source}: the history does not cover one whole day"], "No delivery day",
                     note="Load a case with a longer history.")
    st.stop()
window, q = case.uncertainty.window_days, case.uncertainty
row = st.container(horizontal=True)  # a row that wraps in a narrow window, each label whole
earliest = days[0] + dt.timedelta(days=window)
row.date_input("Delivery day", value=case.delivery_date, min_value=min(earliest, case.delivery_date),
               max_value=max(days[-1], case.delivery_date),
               key="uncertainty_date", on_change=from_widget, args=(None, "delivery_date", "uncertainty_date"),
               width=DATE_PX, help=f"Any day from {earliest:%d %b %Y} (the history must cover the {window}-day "
                                   f"window before it) to {days[-1]:%d %b %Y}.")
row.slider("History window [days]", min(WINDOW_DAYS[0], window), max(WINDOW_DAYS[1], window), value=window,
           key="uncertainty_window", width=SLIDER_PX,
           on_change=from_widget, args=("uncertainty", "window_days", "uncertainty_window"),
           help="Days before the delivery day whose observations give the bands (paper: 30).")
row.slider("Lower percentile", min(Q_LO[0], q.q_lo), max(Q_LO[1], q.q_lo), value=q.q_lo, step=Q_STEP,
           key="uncertainty_q_lo", width=SLIDER_PX,
           on_change=from_widget, args=("uncertainty", "q_lo", "uncertainty_q_lo"),
           help="Bad bound of production and prices, nominal of consumption (paper: 0.2).")
row.slider("Upper percentile", min(Q_HI[0], q.q_hi), max(Q_HI[1], q.q_hi), value=q.q_hi, step=Q_STEP,
           key="uncertainty_q_hi", width=SLIDER_PX,
           on_change=from_widget, args=("uncertainty", "q_hi", "uncertainty_q_hi"),
           help="Nominal of production, bad bound of consumption (paper: 0.8).")
specs = band_specs(case)
eligible = [name for name, spec in specs.items() if has_forecast(spec)]
row = st.container(horizontal=True)
row.multiselect("Sources on forecast-based bands", eligible,
                default=[n for n in eligible if specs[n].method == "forecast"],
                key="uncertainty_forecast_bands", on_change=set_forecast_bands, args=("uncertainty_forecast_bands",),
                help="Forecast band: the day-ahead point forecast plus percentiles of its past errors (units with a "
                     "forecast column; prices from a naive model). Others keep the paper's climatology.")
row.selectbox("Price point forecast", PRICE_MODELS, index=PRICE_MODELS.index(q.price_forecast),
              format_func=lambda m: m.replace("_", " "), key="uncertainty_price_forecast",
              on_change=from_widget, args=("uncertainty", "price_forecast", "uncertainty_price_forecast"),
              width=CHOICE_PX)
if case.provenance_summary():
    st.caption(case.provenance_summary())
if st.session_state.get("uncertainty_problems"):
    widgets.problems(st.session_state["uncertainty_problems"])

st.header("Budgets Γ")
st.markdown(f"A budget Γ is the number of **periods** in which a source may deviate to its bad bound. "
            f"This day has **{nt} periods of {case.dt_h * 60:g} minutes**"
            + (f", so Γ = {round(1 / case.dt_h)} is one hour" if case.dt_h < 1 else "") + ". "
            "The strategy presets are the paper's Table 7, given in hours and scaled to periods.")
st.segmented_control("Strategy preset", STRATEGIES, default=case.budgets.strategy, key="uncertainty_strategy",
                     required=True, format_func=str.capitalize, on_change=set_strategy,
                     args=("uncertainty_strategy",),
                     help="One click sets every Γ to the preset and drops the individual edits.")
st.caption("Presets in hours — " + "; ".join(
    f"{s}: prices {b['price']}, wind {b['wind']}, PV {b['pv']}, CSP {b['csp']}, demands {b['ed']}"
    for s, b in STRATEGY_BUDGETS_H.items()))
budgets = st.container(horizontal=True)  # the variant goes below the table in a narrow window
with budgets.container(width=BUDGET_TABLE_PX):
    widgets.table_editor(
        BUDGETS_KEY,
        build=lambda: budget_table(state.case()),
        apply=lambda table: with_budgets(state.case(), table),
        column_config={
            "source": st.column_config.TextColumn("Source", disabled=True),
            "kind": st.column_config.TextColumn("Kind", disabled=True),
            "preset": st.column_config.NumberColumn(f"Preset Γ [{PERIOD_NAMES[case.dt_h]}]", disabled=True),
            "gamma": st.column_config.NumberColumn(f"Γ [{PERIOD_NAMES[case.dt_h]}]", step=1,
                                                   help=f"Whole number from 0 to {nt} (the day's periods). Edit to "
                                                        "override the preset; empty: the preset"),
            "hours": st.column_config.NumberColumn("Γ [h]", disabled=True, format="%.2f"),
        },
        column_order=["source", "kind", "preset", "gamma"] + (["hours"] if case.dt_h < 1 else []),
        hide_index=True, height=TABLE_ROW_PX * (len(case.sources()) + 1) + TABLE_BORDER_PX,
    )
with budgets.container(width=VARIANT_PX):
    st.radio("Budget variant", list(MODES), format_func=MODES.get, index=list(MODES).index(case.budgets.mode),
             key="uncertainty_mode", on_change=set_mode, args=("uncertainty_mode",))
    st.caption("Paper mode is the published method and the default. In the planner-chosen variant the "
               "optimiser may pick the Γ periods where a deviation hurts least: useful to show why the "
               "published constraints matter, not for bidding.")
    st.caption("Prices deviate in the periods where that costs the plan's trades most (found exactly); units "
               "deviate in their periods of largest deviation in MW (paper mode), which need not be the periods "
               "that cost the plan most.")
    paper_fast_path = case.budgets.mode == "paper" and case.solver.budget_encoding == "top_gamma"
    st.radio("Equal deviations at the Γ boundary", list(TIES), format_func=TIES.get,
             index=list(TIES).index(case.budgets.ties), key="uncertainty_ties", disabled=not paper_fast_path,
             on_change=from_widget, args=("budgets", "ties", "uncertainty_ties"),
             help="When more periods share the Γ-th largest deviation than the budget has left (a solar "
                  "field at its ceiling with a band down to zero, for instance), the model either chooses which "
                  "of them deviate, in the plan's favour, or takes the earliest. The earliest is one fixed "
                  "pattern: faster on such days, and a plan protected against other periods. Paper mode only.")

st.header("Where each source deviates")
run = state.run_case()
problem = solving.prepare(run)
if problem is not None:
    result = None
    if state.is_requested(run) or st.button("Solve to mark the deviating periods χ", key="uncertainty_solve",
                                            icon=":material/play_arrow:"):
        state.mark_requested(run)
        result = solving.solve(run, "Solving the current case")
    if result is None or not result.has_plan:
        st.caption("Bands of the delivery day; solve to mark the periods where each source deviates.")
    else:
        st.caption("Shaded, with a cross on the bad bound: the periods where the plan assumes the source "
                   "deviates (χ = 1). Prices: the Γ periods of largest loss for this plan.")
    st.caption("Dotted grey: the band of the other method; solid line with dots: what the day brought, where "
               "the history covers it.")
    sources = list(PRICE_COLUMNS) + [u.name for _, u in run.units()]
    kinds = {u.name: k for k, u in run.units()}
    groups = {g: [s for s in sources if (kinds.get(s) or "price") in members] for g, members in GROUPS.items()}
    groups = {g: members for g, members in groups.items() if members}
    for tab, (group, members) in zip(st.tabs(list(groups)), groups.items()):
        with tab:
            for i, source in enumerate(members):
                if i % BAND_COLUMNS == 0:  # a row of charts, one below the other in a narrow window
                    row = st.container(horizontal=True)
                chi = deviating_periods(result, source) if result is not None and result.has_plan else None
                figure = bands_figure(problem, source, chi, **band_overlays(problem, source))
                row.plotly_chart(thin_clock_ticks(figure, widgets.NARROW_TICK_HOURS), key=f"uncertainty_band_{source}")
