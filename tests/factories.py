"""Builders of small hand-solvable cases with bands given explicitly."""

from __future__ import annotations

import datetime as dt
import os
import re
import time
from pathlib import Path

import numpy as np
import pandas as pd

from rvpp.data.case import parse_case
from rvpp.data.history import History
from rvpp.data.periods import delivery_periods
from rvpp.uncertainty.problem import problem_from_bands

ROOT = Path(__file__).resolve().parent.parent
# The real Spanish data (never committed): RVPP_SPAIN_DATA, or shared/data/spain beside the project.
SPAIN = Path(os.environ.get("RVPP_SPAIN_DATA", ROOT.parent / "shared" / "data" / "spain"))
PAPER = ROOT / "data" / "cases" / "paper"
DAY = dt.date(2025, 3, 18)



def tiny_history(columns: list[str], days: int = 2, start: str = "2025-03-17") -> History:
    """A history with the given columns, all zero (bands are supplied directly)."""
    first = pd.Timestamp(start, tz="Europe/Madrid")
    stamps = pd.date_range(first.tz_convert("UTC"), periods=24 * days, freq="1h")
    frame = pd.DataFrame({"timestamp": stamps, **{c: np.zeros(len(stamps)) for c in columns}})
    return History(frame)


def wind(name="W", p_max=50.0, om=10.0, share=0.1, **extra):
    return {"name": name, "p_max_mw": p_max, "om_eur_per_mwh": om, "ramp_up_mw_per_min": 15,
            "ramp_dn_mw_per_min": 25, "reserve_share": share, **extra}


def demand(name="D", p_min=0.0, p_max=100.0, e_min=0.0, flex=0.0, **extra):
    return {"name": name, "p_min_mw": p_min, "p_max_mw": p_max, "e_min_mwh": e_min,
            "ramp_up_mw_per_min": 10, "ramp_dn_mw_per_min": 10, "flex_up": flex, "flex_dn": flex, **extra}


def heat(name="H", h_min=0.0, h_max=100.0, q_min=0.0):
    return {"name": name, "h_min_mw_th": h_min, "h_max_mw_th": h_max, "q_min_mwh_th": q_min}


def tiny_case(wind_units=(), pv_units=(), ed_units=(), td_units=(), csp_units=(), srm=False, hpa=False,
              tariff=80.0, kappa=0.3, strategy="deterministic", overrides=None, mode="paper",
              encoding="top_gamma", dt_h=1.0, day=DAY, battery_units=(), hydro_units=(), biomass_units=()):
    units = {"wind": list(wind_units), "pv": list(pv_units), "ed": list(ed_units), "td": list(td_units),
             "csp": list(csp_units)}
    certain = {"battery": list(battery_units), "hydro": list(hydro_units), "biomass": list(biomass_units)}
    names = [u["name"] for group in units.values() for u in group]
    units.update({kind: group for kind, group in certain.items() if group})
    data = {
        "name": "tiny", "delivery_date": day.isoformat(), "dt_h": dt_h,
        "markets": {"srm": srm, "hpa": hpa, "kappa": kappa,
                    "hpa_tariff_eur_per_mwh": [tariff] * 24 if np.isscalar(tariff) else list(tariff)},
        "budgets": {"strategy": strategy, "overrides": overrides or {}, "mode": mode},
        "solver": {"budget_encoding": encoding, "rel_gap": 1e-9, "time_limit_s": 60},
        "units": units,
    }
    history = tiny_history(["price_da", "price_sr_up", "price_sr_dn", *names])
    return parse_case(data, history)


def bands(nt: int, **series) -> pd.DataFrame:
    """Bands per source from ``(lo, mid, hi)`` tuples of scalars or arrays of length ``nt``."""
    data = {}
    for name, (lo, mid, hi) in series.items():
        for stat, value in zip(("lo", "mid", "hi"), (lo, mid, hi)):
            data[(name, stat)] = np.broadcast_to(np.asarray(value, float), (nt,)).copy()
    frame = pd.DataFrame(data, index=pd.RangeIndex(1, nt + 1, name="t"))
    frame.columns = pd.MultiIndex.from_tuples(frame.columns, names=["source", "stat"])
    return frame


def tiny_problem(case, **series):
    """A problem for ``case`` from explicit bands; unspecified prices are zero."""
    periods = delivery_periods(case.delivery_date, case.timezone, case.dt_h)
    nt = len(periods)
    for price in ("price_da", "price_sr_up", "price_sr_dn"):
        series.setdefault(price, (0.0, 0.0, 0.0))
    return problem_from_bands(case, periods, bands(nt, **series))


def with_storage(case, **changes):
    """``case`` with its first CSP's storage fields changed."""
    csp = case.csp[0]
    return case.replace(csp=[csp.model_copy(update={"storage": csp.storage.model_copy(update=changes)})])


def cyclic_storage(case):
    """The storage day is cyclic (``e[0] = e[NT]``) instead of starting at the case's fixed level.

    The paper case starts the day with an empty tank, so its night heat comes through the HPA;
    with a cyclic day the tank carries the afternoon's heat into the night instead, no heat is
    bought on the default day and every market set has a plan."""
    return with_storage(case, e_init_mwh_th=None)


def wait_for(predicate, timeout_s: float = 600.0, every_s: float = 0.3):
    """The first truthy value of ``predicate()``, polled every ``every_s`` seconds; fails the
    test after ``timeout_s`` (a ceiling for work to finish, never a performance assertion)."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(every_s)
    raise AssertionError("timed out")


APP = str(ROOT / "app.py")
APP_TIMEOUT_S = 180  # a generous ceiling for a page run that may solve (never a performance assertion)


def open_app(page: str | None = None, run: str | None = None):
    """The dashboard run once in AppTest (opened by the link of saved run ``run``), then on ``page``;
    checked to have raised nothing."""
    from streamlit.testing.v1 import AppTest

    at = AppTest.from_file(APP, default_timeout=APP_TIMEOUT_S)
    if run is not None:
        at.query_params["run"] = run
    at.run()
    if page:
        at.switch_page(f"pages/{page}.py").run()
    assert not at.exception, at.exception
    return at


def click(at, key: str):
    """Press the button ``key`` and check the run raised nothing."""
    at.button(key=key).click().run()
    assert not at.exception, at.exception
    return at


def one_day_backtest_form(at, day, label: str):
    """The Backtest page's form filled for one day of the deterministic plan, without the
    perfect-information plan, labelled ``label`` (not yet started)."""
    at.date_input(key="backtest_first").set_value(day)
    at.date_input(key="backtest_last").set_value(day)
    at.multiselect(key="backtest_strategies").set_value(["deterministic"])
    at.checkbox(key="backtest_perfect").uncheck()
    at.text_input(key="backtest_label").input(label)
    return at


def shown(text: str) -> str:
    """What markdown shows of ``text``: its backslash escapes undone."""
    return re.sub(r"\\(.)", r"\1", text)


def shown_table(element) -> pd.DataFrame:
    """A text table (``st.table``) as the page shows it: its index and headers, which the page writes as
    markdown with backslash escapes, read without them."""
    frame = element.value.copy()
    frame.index = [shown(str(label)) for label in frame.index]
    frame.columns = [shown(str(column)) for column in frame.columns]
    return frame
