"""The trading-day view of a backtest record with intraday sessions (rvpp.backtest.trading_day and
rvpp.backtest.figures.trading_day_figure), on records written here by hand.

The day (5 May 2025, 24 hourly periods, Europe/Madrid) bids 10 MW day-ahead in every hour.
IDA1 sells 2 MW in periods 8 to 11 at 50 EUR/MWh (8 MWh, revenue 400 EUR); IDA2 buys 5 MW in
periods 14 and 15 at 60 EUR/MWh (10 MWh, revenue -600 EUR); IDA3 (from period 12) buys 1 MW in
period 20 and sells 3 MW in period 21 at 70 EUR/MWh (revenue 140 EUR). The day's intraday
revenue is 400 - 600 + 140 = -60 EUR, a trading cost of 60 EUR.
"""

from __future__ import annotations

import copy

import pytest

from rvpp.backtest.figures import trading_day_figure
from rvpp.backtest.trading_day import has_intraday, intraday_days, period_hours, session_table
from rvpp.errors import RvppError
from rvpp.outputs.money import IN_KEUR

NT = 24


def per_period(values: dict[int, float], nt: int = NT) -> list[float]:
    return [values.get(t, 0.0) for t in range(nt)]


def trading_record() -> dict:
    """The day of the module notes, with the positions added up by hand."""
    da = [10.0] * NT
    ida1 = per_period({8: 2.0, 9: 2.0, 10: 2.0, 11: 2.0})
    ida2 = per_period({14: -5.0, 15: -5.0})
    ida3 = per_period({20: -1.0, 21: 3.0})
    after1 = per_period({t: 12.0 if 8 <= t <= 11 else 10.0 for t in range(NT)})
    after2 = per_period({t: 12.0 if 8 <= t <= 11 else 5.0 if t in (14, 15) else 10.0 for t in range(NT)})
    after3 = [9.0 if t == 20 else 13.0 if t == 21 else v for t, v in enumerate(after2)]
    return {
        "day": "2025-05-05", "strategy": "balanced", "gamma": "preset", "label": "balanced", "status": "optimal",
        "plan_status": "optimal", "net_cost_eur": 1234.5, "market_cost_eur": 924.5, "penalty_eur": 310.0,
        "deficit_mwh": 1.25, "surplus_mwh": 0.75,
        "bids": {"p_da_mw": da, "r_sr_up_mw": [0.0] * NT, "r_sr_dn_mw": [0.0] * NT, "h_hpa_mw": [0.0] * NT},
        "intraday": [
            {"session": "IDA1", "gate_closure": "2025-05-04T15:00:00+02:00", "window_first_period": 0,
             "status": "optimal", "traded_mw": ida1, "price_eur_per_mwh": [50.0] * NT, "position_mw": after1,
             "trading_revenue_eur": 400.0, "expected_imbalance_before_mwh": 8.0,
             "expected_imbalance_after_mwh": 0.0, "forecast_change_mw": {"WF1": ida1, "PV1": [0.0] * NT},
             "solve_s": 0.1},
            {"session": "IDA2", "gate_closure": "2025-05-04T22:00:00+02:00", "window_first_period": 0,
             "status": "optimal", "traded_mw": ida2, "price_eur_per_mwh": [60.0] * NT, "position_mw": after2,
             "trading_revenue_eur": -600.0, "expected_imbalance_before_mwh": 10.0,
             "expected_imbalance_after_mwh": 0.5, "forecast_change_mw": {"WF1": ida2}, "solve_s": 0.1},
            {"session": "IDA3", "gate_closure": "2025-05-05T10:00:00+02:00", "window_first_period": 12,
             "status": "optimal", "traded_mw": ida3, "price_eur_per_mwh": [70.0] * NT, "position_mw": after3,
             "trading_revenue_eur": 140.0, "expected_imbalance_before_mwh": 2.0,
             "expected_imbalance_after_mwh": 0.0, "forecast_change_mw": {"PV1": per_period({20: -1.0, 21: 3.0})},
             "solve_s": 0.1},
        ],
        "intraday_revenue_eur": -60.0, "final_position_mw": after3,
    }


def traces(fig) -> dict:
    return {t.name: t for t in fig.data}


def test_the_figure_draws_each_position_trade_and_forecast_change():
    fig = trading_day_figure(trading_record(), "Europe/Madrid")
    shown = traces(fig)
    assert list(shown) == ["day-ahead", "after IDA1", "after IDA2", "after IDA3", "final", "IDA1 traded",
                           "IDA2 traded", "IDA3 traded", "IDA1: WF1", "IDA2: WF1", "IDA3: PV1"]  # PV1 of IDA1 is 0
    assert list(shown["day-ahead"].x)[:2] == ["00:00", "01:00"] and list(shown["final"].x)[-1] == "23:00"
    assert list(shown["after IDA2"].y)[14] == 5.0 and list(shown["after IDA2"].y)[9] == 12.0
    assert list(shown["final"].y)[20:22] == [9.0, 13.0]
    assert list(shown["IDA3 traded"].y)[20:22] == [-1.0, 3.0] and sum(abs(v) for v in shown["IDA3 traded"].y) == 4.0
    assert list(shown["IDA2 traded"].customdata)[14] == 60.0
    assert fig.layout.title.text.endswith("imbalance left by the settlement: 1.25 MWh short, 0.75 MWh in surplus</sup>")


def test_a_label_is_shown_as_text_in_the_title():
    fig = trading_day_figure({**trading_record(), "label": "<b>bold</b>"}, "Europe/Madrid")
    assert fig.layout.title.text.startswith("Trading day 2025-05-05 · &lt;b&gt;bold&lt;/b&gt;<br>")


def test_the_session_table_in_mwh_and_cost():
    table = session_table(trading_record())
    assert list(table["Session"]) == ["IDA1", "IDA2", "IDA3"]
    assert list(table["Sold [MWh]"]) == [8.0, 0.0, 3.0]
    assert list(table["Bought [MWh]"]) == [0.0, 10.0, 1.0]
    assert list(table["Trading cost [EUR]"]) == [-400.0, 600.0, -140.0]  # cost: positive when the plant pays
    in_keur = session_table(trading_record(), IN_KEUR)
    assert list(in_keur["Trading cost [kEUR]"]) == pytest.approx([-0.4, 0.6, -0.14])
    assert list(in_keur["Sold [MWh]"]) == [8.0, 0.0, 3.0]  # only money changes unit
    assert list(table["Expected imbalance before [MWh]"]) == [8.0, 10.0, 2.0]
    assert list(table["Expected imbalance after [MWh]"]) == [0.0, 0.5, 0.0]


def test_quarter_hours_count_a_quarter_of_an_hour():
    record = trading_record()
    nt = 96
    record["bids"]["p_da_mw"] = [10.0] * nt
    sells = per_period({40: 4.0, 41: 4.0, 42: 4.0, 43: 4.0}, nt)  # 10:00 to 11:00 at 4 MW: 4 MWh
    record["intraday"] = [{**record["intraday"][0], "traded_mw": sells, "price_eur_per_mwh": [50.0] * nt,
                           "position_mw": [10.0 + v for v in sells], "forecast_change_mw": {"WF1": sells}}]
    record["final_position_mw"] = [10.0 + v for v in sells]
    table = session_table(record)
    assert list(table["Sold [MWh]"]) == [4.0]
    fig = trading_day_figure(record, "Europe/Madrid")
    assert list(traces(fig)["final"].x)[41] == "10:15"
    assert [period_hours(n) for n in (23, 24, 25, 46, 50, 92, 100)] == [1.0, 1.0, 1.0, 0.5, 0.5, 0.25, 0.25]


def test_records_without_intraday_have_no_trading_day():
    import pandas as pd

    plain = {k: v for k, v in trading_record().items() if k not in ("intraday", "final_position_mw",
                                                                     "intraday_revenue_eur")}
    assert not has_intraday(plain) and has_intraday(trading_record())
    days = intraday_days(pd.DataFrame([plain, {**trading_record(), "day": "2025-05-06"}]))
    assert list(days["day"]) == ["2025-05-06"]
    assert intraday_days(pd.DataFrame([plain])).empty
    with pytest.raises(RvppError, match="the record of 2025-05-05 has no intraday sessions"):
        session_table(plain)


@pytest.mark.parametrize("edit, message", [
    (lambda r: r["intraday"][1].update(traded_mw=[1.0] * 23), "IDA2: traded_mw has 23 values for the day's 24"),
    (lambda r: r["intraday"][0].update(price_eur_per_mwh=["x"] * NT), "IDA1: price_eur_per_mwh holds a value that "
                                                                      "is not a number"),
    (lambda r: r["intraday"][2].update(trading_revenue_eur=float("nan")), "IDA3: trading_revenue_eur=nan is not"),
    (lambda r: r["intraday"][2].update(window_first_period=24), "window_first_period=24 is not a period of the day"),
    (lambda r: r.update(final_position_mw=None), "final_position_mw is missing"),
    (lambda r: r["bids"].update(p_da_mw=[1.0] * 30), "a day of 30 periods is not a day of hours"),
])
def test_a_damaged_record_is_refused_by_name(edit, message):
    record = copy.deepcopy(trading_record())
    edit(record)
    with pytest.raises(RvppError, match=message):
        session_table(record)


# ----------------------------------------------------------------------------- on the Backtest page


def store_with(paper_case, data_dir, records: list[dict]):
    """A store in the test's data folder holding one backtest of the balanced preset with ``records``."""
    import datetime as dt

    from rvpp.backtest import BacktestSettings, variants_of
    from rvpp.store import BacktestStore, RecordKey

    data_dir.mkdir(parents=True, exist_ok=True)
    store = BacktestStore(f"sqlite:///{data_dir / 'rvpp.sqlite3'}")
    settings = BacktestSettings(dt.date(2025, 5, 4), dt.date(2025, 5, 5), variants_of(["balanced"], [], False))
    ident = store.open(paper_case, settings.stored(), keys_total=len(records), label="intraday days")
    for record in records:
        store.record(ident, RecordKey(record["day"], record["strategy"], record["gamma"]), record)
    store.engine.dispose()
    return ident


def plain_day() -> dict:
    """4 May without intraday sessions."""
    record = {k: v for k, v in trading_record().items() if k not in ("intraday", "final_position_mw",
                                                                     "intraday_revenue_eur")}
    return {**record, "day": "2025-05-04", "net_cost_eur": 1000.0}


@pytest.mark.slow
def test_the_backtest_page_shows_the_trading_day(paper_case, data_dir):
    from tests.factories import open_app
    from tests.test_app import figures, trace, values

    store_with(paper_case, data_dir, [plain_day(), trading_record()])
    at = open_app("backtest")
    assert at.selectbox(key="backtest_trading_day").options == ["2025-05-05"]  # the day without sessions is not offered
    spec = next(s for title, s in figures(at).items() if title.startswith("Trading day 2025-05-05"))
    assert list(values(trace(spec, "after IDA2")["y"]))[14] == 5.0
    assert list(values(trace(spec, "IDA3 traded")["y"]))[21] == 3.0
    (table,) = [t.value for t in at.dataframe if "Session" in t.value.columns]
    assert list(table["Sold [MWh]"]) == [8.0, 0.0, 3.0]
    assert list(table["Trading cost [kEUR]"]) == pytest.approx([-0.4, 0.6, -0.14])  # the record's EUR / 1000
    cards = {m.label: m for m in at.metric}
    assert cards["Intraday trading cost [kEUR]"].value == "0.1"  # 60 EUR
    assert cards["Intraday trading cost [kEUR]"].proto.help.endswith("Exact: 60 EUR.")
    cards = {label: m.value for label, m in cards.items()}
    assert cards["Imbalance left [MWh]"] == "1.2 short · 0.8 surplus"


@pytest.mark.slow
def test_the_backtest_page_without_intraday_shows_no_trading_day(paper_case, data_dir):
    from tests.factories import open_app

    store_with(paper_case, data_dir, [plain_day()])
    at = open_app("backtest")
    assert not [h for h in at.header if h.value.startswith("Trading day")]
    assert not [k for k in ("backtest_trading_day",) if any(s.key == k for s in at.selectbox)]
