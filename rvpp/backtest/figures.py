"""Figures of a backtest: the price-of-robustness curve, the cumulative net cost, the spread of
the daily net cost per variant and one day's intraday trading. Colours, dashes and markers come
from :mod:`rvpp.outputs.style`."""

from __future__ import annotations

import html
from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd
import plotly.graph_objects as go
from plotly.subplots import make_subplots

from ..data.periods import delivery_periods, period_labels
from ..errors import RvppError
from ..outputs.money import IN_EUR, MONEY_TICKS, MoneyUnit
from ..outputs.style import (DASHES, FIGURE_HEIGHT, GREY, GRID_COLOR, NET_COLOR, ORANGE, SERIES_COLORS, SKY,
                             TRANSPARENT, VERMILION, run_style)
from . import metrics
from .trading_day import day_summary, sessions

PARTS = (("mean_market_cost_eur", "market cost", SKY, "dash"), ("mean_penalty_eur", "penalty", VERMILION, "dot"),
         ("mean_net_cost_eur", "net cost", NET_COLOR, "solid"))
RECOMMENDED_COLOR = ORANGE


def robustness_figure(curve: pd.DataFrame, fraction: float | None = None, period: str = "train",
                      money: MoneyUnit = IN_EUR) -> go.Figure:
    """Mean daily market cost, penalty and net cost against Γ (fraction of the day), with the
    recommended fraction marked. ``curve`` in EUR/day; drawn in ``money`` per day."""
    part = curve[curve["period"] == period].sort_values("fraction")
    per_day = f"{money.symbol}/day"
    fig = go.Figure()
    for column, name, color, dash in PARTS:
        fig.add_trace(go.Scatter(x=part["fraction"], y=money.of(part[column]), mode="lines+markers", name=name,
                                 line={"color": color, "dash": dash,
                                       "width": 3 if column == "mean_net_cost_eur" else 2},
                                 hovertemplate=f"Γ %{{x:.3g}} of the day<br>%{{y:{money.hover}}} {per_day}<extra>"
                                 + name + "</extra>"))
    if fraction is not None and (part["fraction"] == fraction).any():
        point = part[part["fraction"] == fraction].iloc[0]
        fig.add_trace(go.Scatter(x=[fraction], y=[money.of(point["mean_net_cost_eur"])], mode="markers",
                                 name="recommended", marker={"symbol": "star", "size": 16, "color": RECOMMENDED_COLOR},
                                 hovertemplate=f"recommended Γ %{{x:.3g}}<br>%{{y:{money.hover}}} {per_day}"
                                 "<extra></extra>"))
    fig.update_layout(title=f"Price of robustness ({period} period): mean daily cost against Γ",
                      xaxis_title="Γ [fraction of the day, every source]", yaxis_title=f"cost [{per_day}]",
                      **_money_layout())
    return fig


def cumulative_figure(records: pd.DataFrame, money: MoneyUnit = IN_EUR) -> go.Figure:
    """Cumulative settled net cost per variant over the days, in ``money`` (the records in EUR)."""
    table = metrics.daily(records)
    fig = go.Figure()
    for index, (label, part) in enumerate(table[table["settled"]].groupby("label", sort=False)):
        part = part.sort_values("day")
        look = run_style(str(label), index)
        fig.add_trace(go.Scatter(x=part["day"], y=money.of(part["net_cost_eur"].cumsum()), mode="lines+markers",
                                 name=label, line={"color": look["color"], "dash": look["dash"]},
                                 marker={"symbol": look["symbol"], "size": 6},
                                 hovertemplate=f"%{{x}}<br>%{{y:{money.hover}}} {money.symbol}<extra>" + str(label)
                                 + "</extra>"))
    fig.update_layout(title="Cumulative net cost of the settled days", xaxis_title="delivery day",
                      yaxis_title=f"cumulative net cost [{money.symbol}]", **_money_layout())
    return fig


def distribution_figure(records: pd.DataFrame, money: MoneyUnit = IN_EUR) -> go.Figure:
    """The daily net cost of the settled days, one box per variant, in ``money`` per day (the records
    in EUR; every day drawn as a point)."""
    table = metrics.daily(records)
    fig = go.Figure()
    for index, (label, part) in enumerate(table[table["settled"]].groupby("label", sort=False)):
        look = run_style(str(label), index)
        fig.add_trace(go.Box(y=money.of(part["net_cost_eur"]), x=[label] * len(part), name=label, boxpoints="all",
                             jitter=0.3, pointpos=0, marker={"color": look["color"], "symbol": look["symbol"]},
                             text=[str(d) for d in part["day"]],
                             hovertemplate=f"%{{text}}: %{{y:{money.hover}}} {money.symbol}<extra>" + str(label)
                             + "</extra>"))
    fig.update_layout(title="Daily net cost per strategy (box: quartiles and median; points: days)",
                      xaxis_title="strategy", yaxis_title=f"daily net cost [{money.symbol}/day]", showlegend=False,
                      **{k: v for k, v in _money_layout().items() if k != "legend"})
    return fig


def trading_day_figure(record: Mapping[str, Any], timezone: str) -> go.Figure:
    """One day of intraday trading (MODEL_SPEC §14) from its backtest record: the position after each
    session [MW] (day-ahead, after each session, final), what each session traded [MW] (+ sell,
    − buy), the forecast change per source seen at each session's gate closure [MW], and in the
    title the imbalance the settlement left [MWh]. ``timezone``: the case's, for the clock labels."""
    day = sessions(record)
    labels = period_labels(delivery_periods(day.day, timezone, day.dt_h))
    if len(labels) != day.periods:
        raise RvppError(f"the record of {day.day} has {day.periods} periods, but the day has {len(labels)} of "
                        f"{day.dt_h:g} h in {timezone}")
    colors = [SERIES_COLORS[(i + 1) % len(SERIES_COLORS)] for i in range(len(day.sessions))]
    fig = make_subplots(rows=3, cols=1, shared_xaxes=True, vertical_spacing=0.08, row_heights=[0.45, 0.3, 0.25],
                        subplot_titles=("Position after each session [MW]",
                                        "Traded in each session [MW] (+ sell, − buy)",
                                        "Forecast change seen at each gate closure [MW]"))
    step = {"shape": "hv"}
    fig.add_trace(go.Scatter(x=labels, y=day.p_da_mw, name="day-ahead", mode="lines",
                             line={**step, "color": GREY, "dash": "dot", "width": 2},
                             hovertemplate="%{x}: %{y:,.2f} MW<extra>day-ahead</extra>"), row=1, col=1)
    for s, color in zip(day.sessions, colors):
        fig.add_trace(go.Scatter(x=labels, y=s.position_mw, name=f"after {s.session}", mode="lines",
                                 line={**step, "color": color, "width": 1.5},
                                 hovertemplate="%{x}: %{y:,.2f} MW<extra>after " + s.session + "</extra>"),
                      row=1, col=1)
    fig.add_trace(go.Scatter(x=labels, y=day.final_position_mw, name="final", mode="lines",
                             line={**step, "color": NET_COLOR, "width": 3},
                             hovertemplate="%{x}: %{y:,.2f} MW<extra>final position</extra>"), row=1, col=1)
    for s, color in zip(day.sessions, colors):
        fig.add_trace(go.Bar(x=labels, y=s.traded_mw, name=f"{s.session} traded", marker={"color": color},
                             customdata=s.price_eur_per_mwh,
                             hovertemplate="%{x}: %{y:+,.2f} MW at %{customdata:,.2f} EUR/MWh<extra>"
                             + s.session + "</extra>"), row=2, col=1)
    for s, color in zip(day.sessions, colors):
        for index, (source, change) in enumerate(s.forecast_change_mw.items()):
            if not np.any(change):
                continue
            fig.add_trace(go.Scatter(x=labels, y=change, name=f"{s.session}: {source}", mode="lines",
                                     line={**step, "color": color, "dash": DASHES[index % len(DASHES)]},
                                     hovertemplate="%{x}: %{y:+,.2f} MW<extra>" + f"{s.session}: {source}"
                                     + "</extra>"), row=3, col=1)
    summary = day_summary(record)
    left = ", ".join(f"{summary[key]:,.2f} MWh {word}" for key, word in (("deficit_mwh", "short"),
                                                                        ("surplus_mwh", "in surplus"))
                     if summary[key] is not None) or "not settled"
    layout = _layout()
    fig.update_layout(title=f"Trading day {day.day} · {html.escape(day.label)}<br><sup>imbalance left by the settlement: "
                            f"{left}</sup>", barmode="group", **{**layout, "height": 2 * FIGURE_HEIGHT})
    for row in (1, 2, 3):
        fig.update_xaxes(type="category", gridcolor=GRID_COLOR, row=row, col=1)
        fig.update_yaxes(gridcolor=GRID_COLOR, zerolinecolor=GRID_COLOR, row=row, col=1)
    fig.update_xaxes(title_text="period start (local clock)", row=3, col=1)
    return fig


def _layout() -> dict:
    return {"height": FIGURE_HEIGHT, "paper_bgcolor": TRANSPARENT, "plot_bgcolor": TRANSPARENT,
            "xaxis": {"gridcolor": GRID_COLOR}, "yaxis": {"gridcolor": GRID_COLOR, "zerolinecolor": GRID_COLOR},
            "legend": {"orientation": "h", "y": -0.3}, "margin": {"b": 120}}


def _money_layout() -> dict:
    layout = _layout()
    return {**layout, "yaxis": {**layout["yaxis"], **MONEY_TICKS}}
