"""Backtest: every day of a period planned from what was known before it and settled against what
happened that day, in a background process (``rvpp.backtest.launch``); the store's backtests with
their cost, spread, worst days and export; the price of robustness and the recommended Γ."""

import datetime as dt

import streamlit as st

from dashboard import backtests as bt
from dashboard import solving, state, widgets
from rvpp import RvppError
from rvpp.service import (BacktestInfo, BacktestSettings, BacktestVariant, CARRY, CRITERION_NAMES, MIN_TEST_DAYS,
                          MIN_TRAIN_DAYS, IN_KEUR, PERFECT, RecordKey, STORE_ERRORS, STRATEGIES, Verdict,
                          beats_presets_on_training, cumulative_figure, day_summary, distribution_figure, export_zip,
                          intraday_days, launch, metrics, parse_numbers, recommendation_from, reopen_case,
                          robustness_figure, session_table, shortfalls, trading_day_figure, variants_of, verdict_words)

state.through_app("pages/backtest.py")

DEFAULT_DAYS = 14     # a first backtest small enough to watch: 14 days × 5 variants, a minute or two
POLL_S = 1.0          # how often the progress of a running backtest is read again [s]
PENDING_POLL_S = 0.5  # how often the store is read for a backtest started but not yet listed [s]
PENDING = "backtest_pending"  # the id of the backtest this session started, until the store lists it
WORST_DAYS = 10
PERCENT = 100.0
CHOSEN = "backtest_chosen"
KEUR = widgets.KEUR_FORMAT  # money in kEUR, shown from the records' EUR by widgets.in_keur
AGGREGATE_COLUMNS = {
    "label": st.column_config.TextColumn("Strategy", pinned=True),
    "days_settled": st.column_config.NumberColumn("Days settled"),
    "mean_net_cost_keur": st.column_config.NumberColumn("Mean net cost [kEUR/day]", format=KEUR),
    "median_net_cost_keur": st.column_config.NumberColumn("Median net cost [kEUR/day]", format=KEUR),
    "cvar95_net_cost_keur": st.column_config.NumberColumn(
        "CVaR 95 % [kEUR/day]", format=KEUR, help="Mean of the worst 5 % of days (at least the worst day)"),
    "total_net_cost_keur": st.column_config.NumberColumn("Total net cost [kEUR]", format=KEUR),
    "mean_market_cost_keur": st.column_config.NumberColumn("Mean market cost [kEUR/day]", format=KEUR),
    "mean_penalty_keur": st.column_config.NumberColumn("Mean penalty [kEUR/day]", format=KEUR),
    "penalty_share_pct": st.column_config.NumberColumn(
        "Penalty share [%]", format="%.1f", help="Total penalty / total net cost; empty when the total is not a cost"),
    "mean_regret_keur": st.column_config.NumberColumn(
        "Mean regret [kEUR/day]", format=KEUR, help="Net cost minus the perfect-information plan's, same day"),
    "days_without_plan": st.column_config.NumberColumn("Days without plan"),
    "audit_violations": st.column_config.NumberColumn("Audit violations"),
}
# The aggregates in three tables of a few columns each, every one whole at 1280 px: one wider than the page hid
# the regret and the days without a plan past its right edge.
AGGREGATE_TABLES = (("label", "days_settled", "days_without_plan", "mean_net_cost_keur", "cvar95_net_cost_keur"),
                    ("label", "mean_regret_keur", "median_net_cost_keur", "total_net_cost_keur"),
                    ("label", "mean_market_cost_keur", "mean_penalty_keur", "penalty_share_pct", "audit_violations"))
MONTHLY_COLUMNS = {
    "label": st.column_config.TextColumn("Strategy", pinned=True),
    "month": st.column_config.TextColumn("Month"),
    "days": st.column_config.NumberColumn("Days settled"),
    "market_cost_keur": st.column_config.NumberColumn("Market cost [kEUR]", format=KEUR),
    "penalty_keur": st.column_config.NumberColumn("Penalty [kEUR]", format=KEUR),
    "net_cost_keur": st.column_config.NumberColumn("Net cost [kEUR]", format=KEUR),
    "mean_net_cost_keur": st.column_config.NumberColumn("Mean net cost [kEUR/day]", format=KEUR),
    "regret_keur": st.column_config.NumberColumn("Regret [kEUR]", format=KEUR),
}
WORST_COLUMNS = {  # records' column -> header; a text table, whose headers wrap, so every column is in view at 1280 px
    "day": "Delivery day", "plan_status": "Plan", "net_cost_keur": "Net cost [kEUR]",
    "market_cost_keur": "Market cost [kEUR]", "penalty_keur": "Penalty [kEUR]", "regret_keur": "Regret [kEUR]",
    "deficit_mwh": "Energy short [MWh]", "surplus_mwh": "Energy surplus [MWh]",
    "unserved_heat_mwh": "Heat not served [MWh_th]",
}
COST_HELP = "Cost: positive when the plant pays, negative when it earns"
TRADING_COLUMNS = {
    "Session": st.column_config.TextColumn("Session", pinned=True),
    "Gate closure": st.column_config.TextColumn("Gate closure (local time)"),
    "Status": st.column_config.TextColumn("Solve"),
    "Sold [MWh]": st.column_config.NumberColumn("Sold [MWh]", format="%,.1f"),
    "Bought [MWh]": st.column_config.NumberColumn("Bought [MWh]", format="%,.1f"),
    "Trading cost [kEUR]": st.column_config.NumberColumn(
        "Trading cost [kEUR]", format=KEUR, help="Minus the session's trading revenue: positive when the plant "
                                                "buys more than it sells"),
    "Expected imbalance before [MWh]": st.column_config.NumberColumn(
        "Expected imbalance before [MWh]", format="%,.1f",
        help="The imbalance the position would leave on the forecasts of the session's gate closure"),
    "Expected imbalance after [MWh]": st.column_config.NumberColumn("Expected imbalance after [MWh]", format="%,.1f"),
}
COMPARISON_COLUMNS = {
    "variant": st.column_config.TextColumn("Bidding rule", pinned=True),
    "train_mean_net_cost_keur": st.column_config.NumberColumn("Training: mean net cost [kEUR/day]", format=KEUR),
    "train_cvar95_net_cost_keur": st.column_config.NumberColumn("Training: CVaR 95 % [kEUR/day]", format=KEUR),
    "test_mean_net_cost_keur": st.column_config.NumberColumn("Test: mean net cost [kEUR/day]", format=KEUR),
    "test_cvar95_net_cost_keur": st.column_config.NumberColumn("Test: CVaR 95 % [kEUR/day]", format=KEUR),
    "test_mean_regret_keur": st.column_config.NumberColumn("Test: mean regret [kEUR/day]", format=KEUR),
}


def refuse(err: RvppError, title: str, note: str) -> None:
    widgets.problems([bt.in_form_words(str(err))], title, note=note)


def launch_backtest(run, first, last, strategies, fractions_text, perfect, end_target, label) -> None:
    """Start the backtest in its own process; remember its id so the page shows it."""
    try:
        fractions = parse_numbers(fractions_text or "")
    except ValueError as err:
        st.session_state["backtest_problem"] = f"--fractions: {err}"
        return
    try:
        settings = BacktestSettings(first, last, variants_of(strategies, fractions, perfect),
                                    storage_end=CARRY if end_target is None else float(end_target))
        stored = {info.id: info for info in bt.store().list()}
        launched = launch.start(run, settings, bt.store(), label=label.strip())
    except launch.AlreadyRunning as err:
        already_running(err)
        return
    except RvppError as err:
        st.session_state["backtest_problem"] = str(err)
        return
    st.session_state["backtest_problem"] = None
    st.session_state[CHOSEN] = launched.backtest_id
    title = label.strip() or f"{run.name} backtest"
    st.session_state[PENDING] = (launched.backtest_id, f"{title} · {first} .. {last}")
    st.session_state["backtest_notice"] = started_notice(launched, stored.get(launched.backtest_id), label.strip())


def started_notice(launched: launch.Launched, before: BacktestInfo | None, label: str) -> str:
    """What starting a backtest did: a new one, or one the store already held with the same case, days and
    strategies (``before``), which keeps its label and its settled days."""
    if before is None:
        return (f"Started in the background (process {launched.pid}). It shows below with its progress; you may "
                "leave this page meanwhile.")
    same = (f"The store already holds this backtest (the same case, days and strategies) as "
            f"“{widgets.literal(before.label, widgets.LABEL_CHARS)}”")
    kept = "" if label in ("", before.label) else " It keeps that label."
    if before.keys_done >= before.keys_total:
        return (f"{same}, all {before.keys_total:,} days × strategies settled: nothing is computed again; it is "
                f"shown below.{kept}")
    return (f"{same}, with {before.keys_done:,} of {before.keys_total:,} days × strategies settled: it goes on "
            f"from there in the background (process {launched.pid}) and shows below with its progress.{kept}")


def already_running(err: launch.AlreadyRunning) -> None:
    """A second start of a running backtest (a double click, another tab): show the running one."""
    st.session_state["backtest_problem"] = None
    st.session_state[CHOSEN] = err.backtest_id
    st.session_state["backtest_notice"] = (
        f"This backtest is already running (process {err.pid}); it was not started a second time. It shows "
        "below with its progress.")


def stop(ident: str) -> None:
    if not launch.stop(ident, bt.store()):
        st.session_state["backtest_notice"] = "The backtest was not running on this server; nothing to stop."


def resume(ident: str) -> None:
    store = bt.store()
    try:
        case, stored = store.load(ident)
        launch.start(case, BacktestSettings.from_stored(stored), store)  # the stored backtest keeps its label
    except launch.AlreadyRunning as err:
        already_running(err)
    except RvppError as err:
        st.session_state["backtest_problem"] = str(err)


def open_day(ident: str, key: RecordKey, source: str) -> None:
    """The day's case (its date, budgets and recorded start state) becomes the current case, solved on
    Results in the dashboard's solver processes: the same plan the backtest settled."""
    try:
        case = reopen_case(bt.store(), ident, key)
    except RvppError as err:
        st.session_state["backtest_problem"] = str(err)
        return
    state.load(case, source=source)
    state.mark_requested(state.run_case())
    st.session_state["backtest_open"] = True


def remember(ident: str, rec) -> None:
    stored = bt.store().remember_recommendation(ident, rec.fraction, rec.criterion, rec.train, rec.test, rec.verdict)
    st.session_state["backtest_notice"] = (f"Remembered Γ = {stored.fraction:g} of the day: Results and Compare "
                                           "strategies now offer it as the recommended strategy.")


def pending_panel(ident: str, title: str) -> None:
    """A backtest this session started whose process has not registered it in the store yet: read
    the store again every PENDING_POLL_S and draw the whole page once it is listed."""

    @st.fragment(run_every=PENDING_POLL_S)
    def panel() -> None:
        if ident in listed_ids():
            st.rerun()
        st.progress(0.0, text=f"{widgets.literal(title, widgets.LABEL_CHARS)}: starting, its process is reading "
                              "the case and the history…")

    panel()


def listed_ids() -> set[str]:
    return {b.id for b in bt.store().list()}


def progress_panel(ident: str, drawn: int) -> None:
    """Where the backtest's process stands, read from the store again every POLL_S while it runs
    (or has not written its progress yet); the page is drawn with ``drawn`` settled records, and drawn
    again when the first ones arrive (it said the figures appear with them)."""
    first = bt.progress(ident)
    was_running = first is not None and first.running
    watch = first is None or first.running

    @st.fragment(run_every=POLL_S if watch else None)
    def panel() -> None:
        info = bt.progress(ident)
        if info is not None and (info.running != was_running or first is None or (not drawn and info.done)):
            st.rerun()  # it started, ended or settled its first days: draw the whole page again with its records
        if info is None:
            st.progress(0.0, text="Starting: its process has not written any progress yet…")
            return
        share = info.done / info.total if info.total else 0.0
        text = f"{info.done} of {info.total} days × strategies settled · {info.state}"
        if info.running:
            text += f" · {bt.eta(info.eta_s)}"
        left, right = st.columns([6, 1], vertical_alignment="bottom")
        left.progress(min(1.0, share), text=text)
        if info.running:
            right.button("Stop", key="backtest_stop", on_click=stop, args=(ident,), icon=":material/stop_circle:",
                         help="Ends the process; the days already settled stay, and Resume goes on from there.")
        elif info.done < info.total:
            right.button("Resume", key="backtest_resume", on_click=resume, args=(ident,),
                         icon=":material/play_arrow:", help="Starts the process again; settled days are skipped.")
        if info.message:
            st.caption(info.message)

    panel()


st.title("Backtest: what each strategy would have cost, day after day")
if st.session_state.pop("backtest_open", False):
    st.switch_page("pages/results.py")
st.markdown(
    "A **rolling backtest** bids every day of a period as the operator would have: the plan of day *D* uses only "
    "the history before *D*, and is then **settled against what really happened on D** (realized prices, "
    "production and demand) by the recourse model, which pays penalties for energy short or in surplus, reserve "
    "not delivered and heat not served. The storage level and the turbine state at the end of each settled day "
    "are the start of the next, as in operation. **Net cost** = market cost + penalty, in kEUR, positive when the "
    "plant pays; lower is better. The **CVaR 95 %** is the mean of the worst 5 % of days: what a bad day costs. "
    "The **regret** is what a day cost beyond the plan made with perfect knowledge of that day.")

run = state.run_case()
covered = run.history.local_days(run.timezone)
earliest = covered[0] + dt.timedelta(days=run.uncertainty.window_days)
latest = covered[-1]
default_last = min(latest, max(earliest, run.delivery_date))
default_first = max(earliest, default_last - dt.timedelta(days=DEFAULT_DAYS - 1))

expected = solving.solver().expected_s(run)  # measured by this server, or nothing
pace = (f"two solves of about {expected[0]:.1f} s each ({expected[1]})" if expected
        else "two solves, each about as long as a plan of this case on Results")
with st.expander(f"Start a backtest of the current case ({widgets.literal(run.name)})", icon=":material/play_circle:",
                 expanded=False):
    st.caption(f"The days can run from {earliest} (the first day with the {run.uncertainty.window_days} days of "
               f"history its bands need) to {latest} (the last day with observations to settle against). It runs "
               "in a process of its own on the server: you may leave this page or close the tab, and come back to "
               f"follow it. Each day of each strategy takes {pace}.")
    with st.form("backtest_form"):
        first_col, last_col = st.columns(2)
        first_day = first_col.date_input("First day", value=default_first, min_value=earliest, max_value=latest,
                                         key="backtest_first")
        last_day = last_col.date_input("Last day", value=default_last, min_value=earliest, max_value=latest,
                                       key="backtest_last")
        strategies = st.multiselect("Strategies", STRATEGIES, default=list(STRATEGIES), key="backtest_strategies",
                                    help="Presets of the paper's Table 7, as published (the case's own Γ edits "
                                         "are set aside)")
        fractions_text = st.text_input(
            "Γ fractions", value="", key="backtest_fractions", placeholder="e.g. 0.125, 0.25, 0.375 (optional)",
            help="Γ of every source as a share of the day: 0.25 → 6 of 24 hours. A grid of fractions (with the "
                 "deterministic preset as Γ = 0) draws the price of robustness and gives a recommended Γ.")
        left, right = st.columns(2)
        perfect = left.checkbox("Perfect-information plan (for the regret)", value=True, key="backtest_perfect",
                                help="The plan made on the realized day: the benchmark every strategy is "
                                     "measured against. One more chain of days.")
        end_target = right.number_input(
            "Storage end target [fraction of the storage range], from 0 to 1", min_value=0.0, max_value=1.0,
            value=None, step=0.05, key="backtest_end", placeholder="empty: carry (never end below the start)",
            help="Empty: each day ends with at least the energy it started with, in every tank and battery. A "
                 "fraction: the day may run each storage down to e_min + fraction × (e_max − e_min), never below it.")
        label = st.text_input("Label", value="", key="backtest_label", max_chars=190,
                              placeholder=f"{run.name} backtest")
        submitted = st.form_submit_button("Start the backtest", type="primary", icon=":material/play_arrow:",
                                          key="backtest_start")
    if submitted:
        launch_backtest(run, first_day, last_day, strategies, fractions_text, perfect, end_target, label)
    if st.session_state.get("backtest_problem"):
        refuse(RvppError(st.session_state["backtest_problem"]), "Not started", "Nothing was started.")

if notice := st.session_state.pop("backtest_notice", None):
    st.info(notice, icon=":material/info:")

st.header("Backtests in the store")
try:
    listed = bt.store().list()
except (RvppError, *STORE_ERRORS) as err:
    widgets.problems([f"the store cannot be read: {err}"], "Backtests unavailable", note="Nothing was changed.")
    st.stop()
pending = st.session_state.get(PENDING)
if pending is not None and pending[0] in {b.id for b in listed}:
    st.session_state[CHOSEN] = st.session_state.pop(PENDING)[0]  # shown below once listed
elif pending is not None:
    pending_panel(*pending)
if not listed:
    if pending is None:
        st.info("No backtest in the store yet. Start one above: it appears here with its progress.",
                icon=":material/history:")
    st.stop()

progresses = {b.id: bt.progress(b.id) for b in listed}
st.dataframe(
    [{"Label": b.label,  # where it stands next to the label: in view at 1280 px, the rest may scroll
      "State": progresses[b.id].state if progresses[b.id] else "not started",
      "Progress": b.keys_done / b.keys_total if b.keys_total else 0.0,
      "Days × strategies": f"{b.keys_done} of {b.keys_total}",
      "Period": f"{b.settings['from']} .. {b.settings['to']}", "Strategies": bt.variant_labels(b.settings),
      "Case": b.case_name, "Created (UTC)": b.created_at[:16].replace("T", " ")}
     for b in listed],
    hide_index=True, width="stretch",
    column_config={"Progress": st.column_config.ProgressColumn("Progress", min_value=0.0, max_value=1.0,
                                                               format="percent"),
                   "Strategies": st.column_config.TextColumn("Strategies", width="medium")})
ids = [b.id for b in listed]
if st.session_state.get(CHOSEN) not in ids:
    st.session_state[CHOSEN] = ids[0]
info_of = {b.id: b for b in listed}
ident = st.selectbox("Backtest shown below", ids, key=CHOSEN,
                     format_func=lambda i: f"{info_of[i].label} · {info_of[i].settings['from']} .. "
                                           f"{info_of[i].settings['to']}")
chosen = info_of[ident]
settings = chosen.settings
progress_panel(ident, chosen.keys_done)

records = bt.records(ident, chosen.keys_done)
if records.empty:
    st.info("No day settled yet; the figures appear with the first days.", icon=":material/hourglass_top:")
    st.stop()
if progresses[ident] is not None and progresses[ident].running:
    st.button("Redraw with the days settled so far", key="backtest_redraw", icon=":material/refresh:")

st.header("Cost over the period")
st.plotly_chart(cumulative_figure(records, IN_KEUR), key="backtest_cumulative")
st.caption("Each line adds up the net cost of the days settled so far: a steeper line is a costlier strategy; a "
           "jump is a bad day. The boxes below show how the daily net cost spreads.")
st.plotly_chart(distribution_figure(records, IN_KEUR), key="backtest_distribution")

st.header("Per strategy")
table = widgets.in_keur(metrics.aggregates(records))
table["penalty_share_pct"] = table["penalty_share"].astype(float) * PERCENT
for columns in AGGREGATE_TABLES:
    st.dataframe(table[[c for c in columns if c in table]], hide_index=True, width="stretch",
                 column_config=AGGREGATE_COLUMNS)
with st.expander("Per month", icon=":material/calendar_month:"):
    monthly = widgets.in_keur(metrics.monthly(records))
    st.dataframe(monthly[[c for c in MONTHLY_COLUMNS if c in monthly]], hide_index=True, width="stretch",
                 column_config=MONTHLY_COLUMNS)

st.header("Worst days")
st.caption("The costliest settled days of one strategy. Open one to see its plan on Results: the day's case "
           "(its date, its budgets, the storage and turbine state it started from) becomes the current case and "
           "is solved again, giving the plan that was settled.")
variants = [BacktestVariant(*v) for v in settings["variants"] if v[0] != PERFECT]
if variants:
    labels = {v.label: v for v in variants}
    shown = st.selectbox("Strategy", list(labels), key="backtest_worst_variant")
    variant = labels[shown]
    worst = metrics.worst_days(records, variant.strategy, variant.gamma, WORST_DAYS)
    if worst.empty:
        st.caption("No settled day for this strategy yet.")
    else:
        shown_worst = widgets.in_keur(worst)
        table = shown_worst[[c for c in WORST_COLUMNS if c in shown_worst]].rename(columns=WORST_COLUMNS)
        # The day on one line: its hyphens are non-breaking (the table draws no style that would keep it whole)
        table = table.assign(**{"Delivery day": [str(d).replace("-", "\u2011") for d in table["Delivery day"]]})
        numbers = [c for c in table.columns if c not in ("Delivery day", "Plan")]
        st.table(table.style.hide(axis="index").format(widgets.tenths, subset=numbers, na_rep="–"))
        days = [str(d) for d in worst["day"]]
        costs = dict(zip(days, worst["net_cost_eur"]))
        left, right = st.columns([3, 2], vertical_alignment="bottom")
        day = left.selectbox("Day", days, key="backtest_worst_day",
                             format_func=lambda d: f"{d} · net cost {widgets.keur(costs[d])} kEUR")
        right.button("Open this day's plan on Results", key="backtest_open_day", type="primary",
                     icon=":material/open_in_browser:", on_click=open_day,
                     args=(ident, RecordKey(day, variant.strategy, variant.gamma),
                           f'backtest "{chosen.label}": {day}, {variant.label}'))
else:
    st.caption("This backtest ran only the perfect-information plan.")
if st.session_state.get("backtest_problem"):
    refuse(RvppError(st.session_state.pop("backtest_problem")), "Not done", "Nothing was changed.")


def trading_day(ident: str, records) -> None:
    """One day traded in intraday sessions: the position after each session, the trades, the forecast
    change behind them and the imbalance the settlement left (only for records with sessions)."""
    traded = intraday_days(records)
    if traded.empty:
        return
    st.header("Trading day: the intraday sessions of one day")
    st.caption("After the day-ahead market each intraday session corrects the position as the forecasts change: "
               "the lines show the position after each session, the bars what each session sold (+) or bought "
               "(−), the bottom panel the forecast change seen at its gate closure. The settlement measures the "
               "imbalance against the final position.")
    left, right = st.columns(2)
    label = left.selectbox("Strategy", list(dict.fromkeys(traded["label"])), key="backtest_trading_variant")
    day = right.selectbox("Day", list(traded.loc[traded["label"] == label, "day"]), key="backtest_trading_day")
    record = bt.record_of(records, day, label)
    try:
        figure = trading_day_figure(record, bt.timezone_of(ident))
        table, summary = session_table(record, IN_KEUR), day_summary(record)
    except RvppError as err:
        refuse(err, "This day cannot be shown", "The record is kept as it is.")
        return
    cards = st.columns(4)
    for card, (label, key) in zip(cards, (("Net cost [kEUR]", "net_cost_eur"),
                                          ("Intraday trading cost [kEUR]", "intraday_cost_eur"),
                                          ("Penalty [kEUR]", "penalty_eur"))):
        card.metric(label, widgets.keur(summary[key]), help=f"{COST_HELP}. Exact: {widgets.eur(summary[key])}.")
    short, surplus = summary["deficit_mwh"], summary["surplus_mwh"]
    cards[3].metric("Imbalance left [MWh]", "–" if short is None or surplus is None else
                    f"{short:,.1f} short · {surplus:,.1f} surplus", help="Energy short and in surplus against the "
                    "final position, from the settlement")
    st.plotly_chart(figure, key="backtest_trading_figure")
    st.dataframe(table, hide_index=True, width="stretch", column_config=TRADING_COLUMNS)


trading_day(ident, records)

st.download_button("Export records and inputs (zip)", lambda: export_zip(bt.store(), ident),
                   file_name=f"backtest-{ident[:12]}.zip", mime="application/zip", on_click="ignore",
                   key="backtest_export", icon=":material/folder_zip:",
                   help="records, bids, settled dispatch, aggregates and months as CSV (opens in Excel) and "
                        "Parquet; the case with its exact history; manifest.json with the settings")

st.header("Price of robustness and the recommended Γ")
grid = bt.fractions_of(settings)
days = [dt.date.fromisoformat(settings["from"]) + dt.timedelta(days=k)
        for k in range((dt.date.fromisoformat(settings["to"]) - dt.date.fromisoformat(settings["from"])).days + 1)]
if len(grid) < 2 or len(days) < 2:
    st.caption("This backtest has no Γ grid over two days or more. Start one with **Γ fractions** such as "
               "0.125, 0.25, 0.375 and the deterministic preset (Γ = 0) over a few weeks to see what protection "
               "costs and which Γ did best.")
    st.stop()
st.markdown("The more periods Γ protects, the more the plan holds back: its market cost rises while the "
            "penalties of bad surprises fall. The Γ with the lowest cost on the **training days** is the "
            "recommendation; the **test days**, later and unseen by the choice, show whether it holds up against "
            f"the presets. A recommendation needs at least {MIN_TRAIN_DAYS} training days (every weekday "
            f"twice: demand and prices follow the week) and {MIN_TEST_DAYS} test days (every weekday "
            "once), and must beat every preset on the training days to be offered.")
split = max(1, round(len(days) * 2 / 3))
t1, t2, t3 = st.columns(3)
train = t1.date_input("Training days", value=(days[0], days[split - 1]), min_value=days[0], max_value=days[-1],
                      key=f"backtest_train_{ident}")
test = t2.date_input("Test days", value=(days[split], days[-1]), min_value=days[0], max_value=days[-1],
                     key=f"backtest_test_{ident}")
criterion = t3.radio("Criterion", list(CRITERION_NAMES), format_func=CRITERION_NAMES.get, key="backtest_criterion",
                     help="What the recommendation minimises over the training days")
if len(train) != 2 or len(test) != 2:
    st.info("Choose the first and the last day of both periods.", icon=":material/date_range:")
    st.stop()
try:
    rec = recommendation_from(records, tuple(train), tuple(test), grid, criterion, ident)
except RvppError as err:
    refuse(err, "No recommendation", "Change the training or test days.")
    st.stop()
left, right = st.columns(2)
left.plotly_chart(robustness_figure(rec.curve, rec.fraction, "train", IN_KEUR), key="backtest_robustness_train")
right.plotly_chart(robustness_figure(rec.curve, rec.fraction, "test", IN_KEUR), key="backtest_robustness_test")
if rec.outcome is Verdict.LOSES:
    st.warning(verdict_words(rec, IN_KEUR), icon=":material/trending_down:")
else:
    st.success(verdict_words(rec, IN_KEUR), icon=":material/verified:")
comparison = widgets.in_keur(rec.comparison)
for period in ("train_", "test_"):  # one table per period: together they were wider than the page at 1280 px
    columns = [c for c in COMPARISON_COLUMNS if c == "variant" or c.startswith(period)]
    st.dataframe(comparison[[c for c in columns if c in comparison]], hide_index=True, width="stretch",
                 column_config=COMPARISON_COLUMNS)
remembered = bt.recommended()
if remembered is not None:
    st.caption("Now remembered: " + bt.recommendation_note(remembered))
thin = shortfalls(rec)
if thin:
    st.warning("**Small sample: read this as an example, not a recommendation.** "
               + "; ".join(thin) + f". Give the backtest at least {MIN_TRAIN_DAYS} training and "
               f"{MIN_TEST_DAYS} test days to be offered a Γ to remember.", icon=":material/warning:")
elif not beats_presets_on_training(rec):
    st.info(f"Γ = {rec.fraction:g} of the day does not beat every preset on the training days, so there is "
            "nothing to remember: bid with the best preset.", icon=":material/info:")
else:
    st.button(f"Remember this Γ ({rec.fraction:g} of the day) for Results and Compare", key="backtest_remember",
              on_click=remember, args=(ident, rec), icon=":material/bookmark_add:",
              help="Kept in the store: every session and every restart offers it as the recommended strategy.")
