"""The backtest study on a real case and its modelled-sky counterpart, side by side.

Two cases are built here from the formula table of tests/test_build_case.py (one on the
sky of its solar series, one with the field heat and the demands modelled); the study
backtests a training day and a test day of both, and its tables are checked against
numbers recomputed from the stored records by hand.
"""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from rvpp.cli import main
from rvpp.data.build_case import BuildOptions, build_case
from rvpp.errors import RvppError
from rvpp.store import BacktestStore
from rvpp.studies import backtest
from rvpp.studies.settings import StudySettings
from tests.factories import PAPER, SPAIN
from tests.test_build_case import write_table

PRESETS = ("deterministic", "optimistic", "balanced", "pessimistic")
PARTS = ("deficit", "surplus", "reserve", "heat")


@pytest.fixture(scope="module")
def cases(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cases")
    source = write_table(folder / "series.csv")
    frame = pd.read_csv(source)
    hour = pd.DatetimeIndex(pd.to_datetime(frame["time_utc"], utc=True)).tz_convert("Europe/Madrid").hour
    frame["load_actual"] = 30000.0 + 3000.0 * np.sin(np.pi * (np.asarray(hour, float) - 6.0) / 12.0)
    frame["load_forecast"] = frame["load_actual"] * 1.01
    frame.to_csv(source, index=False)
    build_case([source], folder / "real", template=PAPER)
    build_case([source], folder / "modelled", template=PAPER,
               options=BuildOptions(sky="modelled", demands="modelled"))
    return folder / "real", folder / "modelled"


def by_hand(records: pd.DataFrame) -> dict[str, dict[str, float]]:
    """Per preset and the perfect plan: mean daily market cost, penalty parts, net cost and regret."""
    perfect = records[records["strategy"] == "perfect"].set_index("day")["net_cost_eur"]
    out = {}
    for name in (*PRESETS, "perfect"):
        rows = records[(records["strategy"] == name) & (records["gamma"] == "preset")]
        assert (rows["status"] == "optimal").all()
        days = len(rows)
        out[name] = {"days": days, "market": sum(rows["market_cost_eur"]) / days,
                     "penalty": sum(rows["penalty_eur"]) / days, "net": sum(rows["net_cost_eur"]) / days,
                     "regret": sum(n - perfect[d] for d, n in zip(rows["day"], rows["net_cost_eur"])) / days,
                     **{part: sum(rows[f"penalty_{part}_eur"]) / days for part in PARTS}}
    return out


def test_both_skies_side_by_side_with_the_penalty_split_recomputed_from_the_records(cases, tmp_path, monkeypatch):
    real, modelled = cases
    monkeypatch.setenv("RVPP_DATA_DIR", str(tmp_path / "data"))
    monkeypatch.delenv("RVPP_STORE_URL", raising=False)
    monkeypatch.setenv("RVPP_BACKTEST_CASE", str(real))
    monkeypatch.setenv("RVPP_BACKTEST_MODELLED_CASE", str(modelled))
    out = tmp_path / "study"
    code = main(["study", "backtest", "--out", str(out), "--scheduler", "serial", "--no-png", "--quiet",
                 "--backtest-train", "2021-06-10:2021-06-10", "--backtest-test", "2021-06-11:2021-06-11",
                 "--backtest-fractions", "0"])
    assert code == 0
    facts = json.loads((out / "run.json").read_text())["backtest"]
    causes = pd.read_csv(out / "tables" / "backtest_penalty_causes.csv")
    store = BacktestStore()
    numbers = {}
    for sky, checks in (("real sky", facts), ("modelled sky", facts["modelled_sky"])):
        assert checks["records"] == 2 * 5 and checks["reconcile_problems"] == 0 and checks["audit_violations"] == 0
        expected = by_hand(store.records(checks["backtest_id"]))
        rows = causes[causes["case"] == sky].set_index("label")
        assert len(rows) == 5  # the four presets and the perfect-information plan, no Γ fraction
        perfect = rows.drop(list(PRESETS))
        assert len(perfect) == 1 and "perfect" in perfect.index[0]
        assert list(rows.index) == [*PRESETS, perfect.index[0]]
        for name, row in zip((*PRESETS, "perfect"), [rows.loc[p] for p in PRESETS] + [perfect.iloc[0]]):
            mine = expected[name]
            assert row["days_settled"] == mine["days"] == 2
            for column, key in [("mean_market_cost_eur", "market"), ("mean_penalty_eur", "penalty"),
                                ("mean_net_cost_eur", "net"), ("mean_regret_eur", "regret")] + \
                    [(f"mean_penalty_{p}_eur", p) for p in PARTS]:
                assert row[column] == pytest.approx(mine[key], abs=1e-5), (sky, name, column)
            assert sum(mine[p] for p in PARTS) == pytest.approx(mine["penalty"], abs=1e-5)
        assert perfect.iloc[0]["mean_penalty_eur"] == pytest.approx(0.0, abs=1e-3)
        numbers[sky] = expected
    # The skies differ in the field's heat and the demands: so do the settled days.
    assert numbers["real sky"]["balanced"]["net"] != pytest.approx(numbers["modelled sky"]["balanced"]["net"])
    verdicts = pd.read_csv(out / "tables" / "backtest_verdicts.csv")
    assert list(verdicts["case"]) == ["real sky", "modelled sky"] and list(verdicts["fraction"]) == [0.0, 0.0]
    assert verdicts["verdict"].str.startswith("Recommended Γ = 0 of the day").all()
    report = (out / "report.md").read_text()
    assert "**backtest_penalty_causes**" in report and "**backtest_comparison_modelled_sky**" in report
    assert report.count("stored days (day x variant) of backtest") == 2
    assert "`tables/backtest_problems_modelled_sky.csv`" in report


def test_the_modelled_sky_needs_its_real_case(monkeypatch, cases):
    monkeypatch.delenv("RVPP_BACKTEST_CASE", raising=False)
    monkeypatch.setenv("RVPP_BACKTEST_MODELLED_CASE", str(cases[1]))
    with pytest.raises(RvppError, match="RVPP_BACKTEST_MODELLED_CASE names the modelled-sky counterpart of a real "
                                        "case; set RVPP_BACKTEST_CASE"):
        backtest.run(None, StudySettings())


@pytest.mark.slow
@pytest.mark.skipif(not (SPAIN / "entsoe_spain_2015_2018.csv").is_file(), reason="real Spanish data not present")
def test_two_days_of_2018_on_both_skies_of_the_real_files(tmp_path, monkeypatch):
    source = SPAIN / "entsoe_spain_2015_2018.csv"
    for name, options in (("real", {}), ("modelled", {"sky": "modelled", "demands": "modelled"})):
        build_case([source], tmp_path / name, template=PAPER,
                   options=BuildOptions(start="2017-11-20", end="2018-01-03", fill_gaps_h=3, **options))
    monkeypatch.setenv("RVPP_DATA_DIR", str(tmp_path / "data"))
    monkeypatch.delenv("RVPP_STORE_URL", raising=False)
    monkeypatch.setenv("RVPP_BACKTEST_CASE", str(tmp_path / "real"))
    monkeypatch.setenv("RVPP_BACKTEST_MODELLED_CASE", str(tmp_path / "modelled"))
    out = tmp_path / "study"
    assert main(["study", "backtest", "--out", str(out), "--scheduler", "serial", "--no-png", "--quiet",
                 "--backtest-train", "2018-01-02:2018-01-02", "--backtest-test", "2018-01-03:2018-01-03",
                 "--backtest-fractions", "0"]) == 0
    facts = json.loads((out / "run.json").read_text())["backtest"]
    causes = pd.read_csv(out / "tables" / "backtest_penalty_causes.csv")
    store = BacktestStore()
    for sky, checks in (("real sky", facts), ("modelled sky", facts["modelled_sky"])):
        assert checks["reconcile_problems"] == 0 and checks["audit_violations"] == 0
        expected = by_hand(store.records(checks["backtest_id"]))
        rows = causes[causes["case"] == sky].set_index("label")
        for name in PRESETS:
            assert rows.loc[name, "mean_net_cost_eur"] == pytest.approx(expected[name]["net"], abs=1e-5)
            assert rows.loc[name, "mean_penalty_heat_eur"] == pytest.approx(expected[name]["heat"], abs=1e-5)
