"""Compare: the four strategies of the current case in one click (the paper's cost and
flexibility tables), or any two to four runs of the library side by side."""

import streamlit as st

from dashboard import backtests, library, solving, state, sweeps, widgets
from rvpp import RvppError
from rvpp.service import (MARKET_SETS, Outcome, STRATEGIES, TRADE_NAMES, Variant, compare_trades_figure, cost_table,
                          flexibility_table, idle_trades, kpi_table, waterfall_figure)

state.through_app("pages/compare.py")

KEUR = st.column_config.NumberColumn(format="%,.1f")
MODES = ("Strategies of the current case", "Saved runs")
RUNS_MAX = 4
# The flexibility table's headers as Results names them (the full name is each one's help), so it fits too.
FLEXIBILITY_HEADERS = {"Upward reserve [MWh]": "Up reserve [MWh]", "Downward reserve [MWh]": "Down reserve [MWh]",
                       "Upward reserve to capacity [h]": "Up / capacity [h]",
                       "Downward reserve to capacity [h]": "Down / capacity [h]"}


def save_all(cases: dict, results: dict) -> None:
    saved = []
    try:
        for strategy, result in results.items():
            saved.append(library.save(state.default_label(cases[strategy]), cases[strategy], result).label)
    except RvppError as err:
        st.session_state["compare_notice"] = ("error", str(err))
        return
    st.session_state["compare_notice"] = ("saved", "Saved " + ", ".join(f'"{s}"' for s in saved) + ".")


def side_by_side(results: dict, baseline: str | None) -> None:
    """Economics, KPI table, trades and flexibility of labelled plans."""
    st.header("The day's economics")
    st.plotly_chart(waterfall_figure(results), key=f"compare_economics_{len(results)}")
    st.header("Net cost and its parts")
    st.caption(widgets.MONEY + " DAM and SR are the revenues; HPA, O&M and protection the costs.")
    if baseline:
        st.caption(f"What being safer costs: each plan's extra cost over **{widgets.literal(baseline)}**, the least "
                   "safe plan; a positive number is more cost. A percentage is given only when that plan's net cost "
                   "is at least 5 % of the day's money flows; otherwise the absolute difference says more.")
    kpis = kpi_table(results, baseline=baseline)
    hidden = ["Solve time [s]"] + (["Status"] if (kpis["Status"] == "optimal").all() else [])
    # A table that wraps: a run's whole label and every part of the net cost in view at 1280 px (a grid cut the
    # labels short or hid the last part), the amounts written as the cards write them.
    # A text table draws its cells and headers as markdown: the labels (the user's words) are escaped to show as typed
    shown = kpis.drop(columns=hidden).rename(index=lambda label: widgets.literal(label, widgets.LABEL_CHARS),
                                             columns=lambda column: widgets.literal(column, limit=None))
    money = [c for c in shown.columns if c != "Status"]
    st.table(shown.style.format(widgets.tenths, subset=money, na_rep="–"))
    st.caption("Solve times: " + ", ".join(f"{widgets.literal(run)} {seconds:.1f} s"
                                           for run, seconds in kpis["Solve time [s]"].items())
               + (" (every plan optimal)." if "Status" in hidden else "."))
    st.header("Trades")
    idle = idle_trades(results)
    if idle:
        st.caption("Not drawn, zero all day in every plan: " + ", ".join(TRADE_NAMES[c] for c in idle)
                   + (" (no heat bought)" if "h_hpa_mw" in idle else "") + ".")
    st.plotly_chart(compare_trades_figure(results), key=f"compare_trades_{len(results)}")
    st.header("Flexibility")
    st.caption("Paper Table 9 layout: reserve energy over the day and the same divided by installed capacity [h].")
    flexibility = flexibility_table(results)
    config = widgets.number_formats(flexibility)
    for column, short in FLEXIBILITY_HEADERS.items():
        if column in config:
            config[column] = st.column_config.NumberColumn(short, format=config[column]["type_config"].get("format"),
                                                           help=column)
    st.dataframe(flexibility, column_config=config)


def least_safe(results: dict) -> str:
    """The label of the least safe plan: the smallest total budget Γ over its sources (the cheaper of
    equal ones), against which the others' extra cost reads forwards."""
    return min(results, key=lambda label: (sum(s.gamma for s in results[label].problem.sources.values()),
                                           results[label].cost_keur))


st.title("Compare strategies")
if "compare_mode" not in st.session_state:
    st.session_state["compare_mode"] = MODES[0]
mode = st.segmented_control("Compare", MODES, key="compare_mode", required=True)

if mode == MODES[1]:
    runs = library.runs()
    if len(runs) < 2:
        st.info("Save at least two runs (on **Results**, or below with the strategies) to compare them here.",
                icon=":material/bookmarks:")
        st.stop()
    labels = {r.id: r.label for r in runs}
    wanted = [i for i in st.session_state.get("compare_runs", []) if i in labels] or [r.id for r in runs[:2]]
    st.session_state["compare_runs"] = wanted
    chosen = st.multiselect(f"Saved runs (two, three or {RUNS_MAX})", list(labels), format_func=labels.get,
                            key="compare_runs", max_selections=RUNS_MAX,
                            help="Any runs of the library, of any case, strategy or market set.")
    if len(chosen) < 2:
        st.info("Choose at least two runs.", icon=":material/info:")
        st.stop()
    try:
        opened = {labels[i]: library.load(i) for i in chosen}
    except RvppError as err:
        widgets.refusal(err, "A run cannot be opened", note="Choose other runs.")
        st.stop()
    with_plan = {label: saved.result for label, saved in opened.items()
                 if saved.result is not None and saved.result.has_plan}
    missing = [label for label in opened if label not in with_plan]
    if missing:
        st.warning("Without a plan, left out: " + ", ".join(widgets.literal(label) for label in missing),
                   icon=":material/warning:")
    if len(with_plan) >= 2:
        side_by_side(with_plan, baseline=least_safe(with_plan))
    st.stop()

run = state.run_case()
st.markdown("Solve the deterministic, optimistic, balanced and pessimistic strategies of the current case "
            "(budgets of the paper's Table 7; individual Γ edits are set aside) and see what being safer costs.")
market_sets = st.segmented_control(
    "Market sets (columns of the cost table)", MARKET_SETS, selection_mode="multi", default=[run.markets.label],
    key="compare_sets",
    help="Each market set adds four solves. The paper's Table 10 has all four; Table 11 is the same without "
         "the CSP (switch it off on Portfolio).")
market_sets = [m for m in MARKET_SETS if m in (market_sets or [])]
recommendation = backtests.recommended()
variants = {s: (lambda case, m, s=s: Variant(strategy=s, markets=m).apply(case)) for s in STRATEGIES}
if recommendation is None:
    st.caption(":material/lightbulb: " + backtests.HOW_TO_RECOMMEND)
elif st.checkbox(f"Add the {backtests.recommended_label(recommendation)} as a fifth strategy", value=True,
                 key="compare_recommended", help=backtests.recommendation_note(recommendation)):
    variants[backtests.recommended_label(recommendation)] = \
        lambda case, m: backtests.recommended_case(case, recommendation, markets=m)
cases = {(s, m): make(run, m) for m in market_sets for s, make in variants.items()}
ready = bool(cases) and all(state.is_requested(c) for c in cases.values())
clicked = st.button(f"Solve {len(cases)} plans", type="primary", key="compare_solve", disabled=not cases,
                    icon=":material/play_arrow:")
if solving.cancelled():
    st.info("The solves were cancelled. Press the button to start again.", icon=":material/cancel:")

if cases and (clicked or ready):
    for case in cases.values():
        state.mark_requested(case)
    solved = solving.solve_all(list(cases.values()), "Solving the strategies", again=clicked, stoppable=True)
    if solved is None:
        st.stop()
    results = dict(zip(cases, solved))
    failed = [f"{s} / {m}: {r.status} {r.message}" for (s, m), r in results.items() if not r.has_plan]
    if failed:
        st.warning("Some plans could not be made:\n\n" + "\n".join(f"- {f}" for f in failed))
    unproven = [f"{s} / {m}: {widgets.unproven(r)}" for (s, m), r in results.items()
                if r.has_plan and r.status is not Outcome.OPTIMAL]
    if unproven:
        st.warning("Not proven optimal, so compare them with care; press the button above to search on:\n\n"
                   + "\n".join(f"- {u}" for u in unproven), icon=":material/done_all:")

    st.header("Net cost [kEUR]")
    st.caption("Net cost, positive when the plant pays, as in the paper's Tables 10 and 11; lower is better.")
    st.dataframe(cost_table(results), column_config={m: KEUR for m in market_sets})

    shown = market_sets[0] if len(market_sets) == 1 else st.segmented_control(
        "Market set shown below", market_sets, default=market_sets[0], required=True, key="compare_shown")
    by_strategy = {s: results[(s, shown)] for s in variants if results[(s, shown)].has_plan}
    if by_strategy:
        side_by_side(by_strategy, baseline="deterministic" if "deterministic" in by_strategy else None)
        edited = {s: variants[s](state.case(), shown) for s in by_strategy}
        st.button("Save these plans to the library", key="compare_save", on_click=save_all,
                  args=(edited, by_strategy), icon=":material/bookmark_add:")
        notice = st.session_state.pop("compare_notice", None)
        if notice and notice[0] == "saved":
            st.success(notice[1], icon=":material/check:")
        elif notice:
            widgets.problems([notice[1]], "Not saved", note="Nothing was changed.")

st.header("One Γ for every source")
st.markdown("Between the strategies: give every source the same budget Γ, from 0 (the forecast) to every period "
            "going wrong, and see the plan and its economics for each. The plans are solved once for every Γ; "
            "then moving Γ shows them at once.")
problem = solving.prepare(run)
if problem is not None:
    sweeps.gamma_slider(run, problem.nt, round(problem.nt / 2), page="compare", charts=("economics", "trades"))
