"""Figures of a backtest: the price-of-robustness curve, the cumulative net cost and the spread of
the daily net cost per variant. Colours, dashes and markers come from :mod:`rvpp.outputs.style`."""

from __future__ import annotations

import pandas as pd
import plotly.graph_objects as go

from ..outputs.style import FIGURE_HEIGHT, GRID_COLOR, NET_COLOR, ORANGE, SKY, TRANSPARENT, VERMILION, run_style
from . import metrics

PARTS = (("mean_market_cost_eur", "market cost", SKY, "dash"), ("mean_penalty_eur", "penalty", VERMILION, "dot"),
         ("mean_net_cost_eur", "net cost", NET_COLOR, "solid"))
RECOMMENDED_COLOR = ORANGE


def robustness_figure(curve: pd.DataFrame, fraction: float | None = None, period: str = "train") -> go.Figure:
    """Mean daily market cost, penalty and net cost [EUR/day] against Γ (fraction of the day), with
    the recommended fraction marked."""
    part = curve[curve["period"] == period].sort_values("fraction")
    fig = go.Figure()
    for column, name, color, dash in PARTS:
        fig.add_trace(go.Scatter(x=part["fraction"], y=part[column], mode="lines+markers", name=name,
                                 line={"color": color, "dash": dash,
                                       "width": 3 if column == "mean_net_cost_eur" else 2},
                                 hovertemplate="Γ %{x:.3g} of the day<br>%{y:,.0f} EUR/day<extra>" + name
                                 + "</extra>"))
    if fraction is not None and (part["fraction"] == fraction).any():
        point = part[part["fraction"] == fraction].iloc[0]
        fig.add_trace(go.Scatter(x=[fraction], y=[point["mean_net_cost_eur"]], mode="markers", name="recommended",
                                 marker={"symbol": "star", "size": 16, "color": RECOMMENDED_COLOR},
                                 hovertemplate="recommended Γ %{x:.3g}<br>%{y:,.0f} EUR/day<extra></extra>"))
    fig.update_layout(title=f"Price of robustness ({period} period): mean daily cost against Γ",
                      xaxis_title="Γ [fraction of the day, every source]", yaxis_title="cost [EUR/day]",
                      **_layout())
    return fig


def cumulative_figure(records: pd.DataFrame) -> go.Figure:
    """Cumulative settled net cost per variant over the days [EUR]."""
    table = metrics.daily(records)
    fig = go.Figure()
    for index, (label, part) in enumerate(table[table["settled"]].groupby("label", sort=False)):
        part = part.sort_values("day")
        look = run_style(str(label), index)
        fig.add_trace(go.Scatter(x=part["day"], y=part["net_cost_eur"].cumsum(), mode="lines+markers", name=label,
                                 line={"color": look["color"], "dash": look["dash"]},
                                 marker={"symbol": look["symbol"], "size": 6},
                                 hovertemplate="%{x}<br>%{y:,.0f} EUR<extra>" + str(label) + "</extra>"))
    fig.update_layout(title="Cumulative net cost of the settled days", xaxis_title="delivery day",
                      yaxis_title="cumulative net cost [EUR]", **_layout())
    return fig


def distribution_figure(records: pd.DataFrame) -> go.Figure:
    """The daily net cost of the settled days, one box per variant [EUR/day] (every day drawn as a point)."""
    table = metrics.daily(records)
    fig = go.Figure()
    for index, (label, part) in enumerate(table[table["settled"]].groupby("label", sort=False)):
        look = run_style(str(label), index)
        fig.add_trace(go.Box(y=part["net_cost_eur"], x=[label] * len(part), name=label, boxpoints="all",
                             jitter=0.3, pointpos=0, marker={"color": look["color"], "symbol": look["symbol"]},
                             text=[str(d) for d in part["day"]],
                             hovertemplate="%{text}: %{y:,.0f} EUR<extra>" + str(label) + "</extra>"))
    fig.update_layout(title="Daily net cost per strategy (box: quartiles and median; points: days)",
                      xaxis_title="strategy", yaxis_title="daily net cost [EUR/day]", showlegend=False,
                      **{k: v for k, v in _layout().items() if k != "legend"})
    return fig


def _layout() -> dict:
    return {"height": FIGURE_HEIGHT, "paper_bgcolor": TRANSPARENT, "plot_bgcolor": TRANSPARENT,
            "xaxis": {"gridcolor": GRID_COLOR}, "yaxis": {"gridcolor": GRID_COLOR, "zerolinecolor": GRID_COLOR},
            "legend": {"orientation": "h", "y": -0.3}, "margin": {"b": 120}}
