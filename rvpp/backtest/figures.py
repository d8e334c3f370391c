"""Figures of a backtest: the price-of-robustness curve and the cumulative net cost per variant."""

from __future__ import annotations

import pandas as pd
import plotly.graph_objects as go

from . import metrics

PARTS = (("mean_market_cost_eur", "market cost", "#4C78A8"), ("mean_penalty_eur", "penalty", "#E45756"),
         ("mean_net_cost_eur", "net cost", "#222222"))


def robustness_figure(curve: pd.DataFrame, fraction: float | None = None, period: str = "train") -> go.Figure:
    """Mean daily market cost, penalty and net cost [EUR/day] against Γ (fraction of the day), with
    the recommended fraction marked."""
    part = curve[curve["period"] == period].sort_values("fraction")
    fig = go.Figure()
    for column, name, color in PARTS:
        fig.add_trace(go.Scatter(x=part["fraction"], y=part[column], mode="lines+markers", name=name,
                                 line={"color": color, "width": 3 if column == "mean_net_cost_eur" else 2},
                                 hovertemplate="Γ %{x:.3g} of the day<br>%{y:,.0f} EUR/day<extra>" + name + "</extra>"))
    if fraction is not None and (part["fraction"] == fraction).any():
        point = part[part["fraction"] == fraction].iloc[0]
        fig.add_trace(go.Scatter(x=[fraction], y=[point["mean_net_cost_eur"]], mode="markers", name="recommended",
                                 marker={"symbol": "star", "size": 16, "color": "#F58518"},
                                 hovertemplate="recommended Γ %{x:.3g}<br>%{y:,.0f} EUR/day<extra></extra>"))
    fig.update_layout(title=f"Price of robustness ({period} period): mean daily cost against Γ",
                      xaxis_title="Γ [fraction of the day, every source]", yaxis_title="cost [EUR/day]",
                      template="plotly_white", legend={"orientation": "h", "y": -0.2})
    return fig


def cumulative_figure(records: pd.DataFrame) -> go.Figure:
    """Cumulative settled net cost per variant over the days [EUR]."""
    table = metrics.daily(records)
    fig = go.Figure()
    for label, part in table[table["settled"]].groupby("label", sort=False):
        part = part.sort_values("day")
        fig.add_trace(go.Scatter(x=part["day"], y=part["net_cost_eur"].cumsum(), mode="lines", name=label,
                                 hovertemplate="%{x}<br>%{y:,.0f} EUR<extra>" + str(label) + "</extra>"))
    fig.update_layout(title="Cumulative net cost of the settled days", xaxis_title="delivery day",
                      yaxis_title="cumulative net cost [EUR]", template="plotly_white",
                      legend={"orientation": "h", "y": -0.2})
    return fig
