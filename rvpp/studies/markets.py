"""Cost by market set, without the CSP and by HPA price (paper Case 3, Tables 10-12)."""

from __future__ import annotations

import time
from concurrent.futures import Executor

import pandas as pd

from ..data.case import Case
from ..solving.outcome import Outcome
from . import figures
from .runner import Config, Progress, StudyOutput, plan_table, solve_configs
from .settings import StudySettings

TITLE = "Market participation and HPA prices (paper Case 3, Tables 10-12)"
ALL_MARKETS = "DAM+SRM+HPA"
TIME_OF_USE = "time-of-use"


def configurations(settings: StudySettings) -> list[Config]:
    """Table 10 (with CSP), Table 11 (without CSP) and Table 12 (HPA tariff) solves."""
    configs = []
    for strategy in settings.strategies:
        for markets in settings.market_sets:
            configs.append(Config.of({"table": "markets", "strategy": strategy, "column": markets},
                                     strategy=strategy, markets=markets))
        for markets in settings.market_sets_without_csp:
            configs.append(Config.of({"table": "without_csp", "strategy": strategy, "column": markets},
                                     strategy=strategy, markets=markets, csp=False))
        configs.append(Config.of({"table": "hpa_price", "strategy": strategy, "column": TIME_OF_USE},
                                 strategy=strategy, markets=ALL_MARKETS))
        for price in settings.hpa_flat_prices:
            configs.append(Config.of({"table": "hpa_price", "strategy": strategy, "column": f"{price:g}"},
                                     strategy=strategy, markets=ALL_MARKETS, hpa_flat=price))
    return configs


def wide(plans: pd.DataFrame, table: str) -> pd.DataFrame:
    """Cost [kEUR] with strategies as rows and the table's columns (paper layout)."""
    part = plans[plans["table"] == table]
    return part.pivot(index="strategy", columns="column", values="cost_keur").reindex(
        index=list(dict.fromkeys(part["strategy"])), columns=list(dict.fromkeys(part["column"])))


def note(row, result) -> str:
    """Why a configuration is not an optimal plan: no plan (n/a in its table), or stopped early."""
    where = f"{row.strategy}, {row.column} ({row.table.replace('_', ' ')})"
    gap = "" if result.mip_gap is None else f", gap {result.mip_gap:.2%}"
    what = (f"no plan, {result.status}" if not result.has_plan
            else f"{result.status}{gap}: the cost in the table is of a plan that may not be optimal")
    return f"{where}: {what}" + (f" ({result.message})" if result.message else "")


def run(case: Case, settings: StudySettings, executor: Executor | None = None,
        progress: Progress | None = None) -> StudyOutput:
    """Solve every market set, the portfolio without CSP and every HPA price."""
    started = time.perf_counter()
    configs = configurations(settings)
    results = solve_configs(case, configs, settings, executor, progress, "markets")
    plans = plan_table(configs, results)
    tables = {name: wide(plans, name) for name in ("markets", "without_csp", "hpa_price")}
    out = StudyOutput("markets", TITLE)
    out.tables = {"market_plans": plans, "table10_markets": tables["markets"],
                  "table11_without_csp": tables["without_csp"], "table12_hpa_price": tables["hpa_price"]}
    out.figures["markets_cost"] = figures.cost_bars_figure(tables["markets"], "Cost by market set", "markets")
    out.figures["markets_without_csp"] = figures.cost_bars_figure(
        tables["without_csp"], "Cost without the CSP", "markets")
    out.figures["hpa_price_cost"] = figures.cost_bars_figure(
        tables["hpa_price"], "Cost by HPA tariff [EUR/MWh_th]", "HPA tariff")
    out.notes += [note(row, result) for row, result in zip(plans.itertuples(), results) if result.status is not Outcome.OPTIMAL]
    out.facts.update(plans=plans, **tables)
    out.seconds = time.perf_counter() - started
    return out
