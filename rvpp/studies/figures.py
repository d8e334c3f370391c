"""Figures of the sensitivity, market and out-of-sample studies (Plotly).

Each function takes a study table and returns a ``plotly.graph_objects.Figure``; the
same figure is drawn on a dashboard page, saved as interactive HTML and as PNG.
"""

from __future__ import annotations

import pandas as pd
import plotly.graph_objects as go
from plotly.subplots import make_subplots

from ..results import FLEX_KINDS

KIND_LABELS = {"wind": "Wind farms", "pv": "PV plants", "csp": "CSP", "ed": "Electrical demands"}
KIND_COLORS = {"wind": "#4C78A8", "pv": "#F2B701", "csp": "#E45756", "ed": "#54A24B"}
STRATEGY_COLORS = {"deterministic": "#7F7F7F", "optimistic": "#54A24B", "balanced": "#4C78A8",
                   "pessimistic": "#E45756"}
LAYOUT = {"template": "plotly_white", "legend": {"orientation": "h", "y": -0.18}, "margin": {"t": 60}}


def sensitivity_trade_figure(table: pd.DataFrame) -> go.Figure:
    """Cost, traded electricity and bought heat against Γ (paper Figure 15)."""
    fig = make_subplots(rows=1, cols=2, subplot_titles=("Cost [kEUR]", "Energy traded [MWh]"))
    for group, part in table.groupby("sources", sort=False):
        suffix = "" if group == "all" else f" ({group})"
        fig.add_trace(go.Scatter(x=part["gamma"], y=part["cost_keur"], mode="lines+markers",
                                 name=f"cost{suffix}"), row=1, col=1)
        for column, label in (("sold_mwh", "sold (DAM)"), ("bought_mwh", "bought (DAM)"),
                              ("heat_bought_mwh", "heat bought (HPA) [MWh_th]")):
            fig.add_trace(go.Scatter(x=part["gamma"], y=part[column], mode="lines+markers",
                                     name=f"{label}{suffix}"), row=1, col=2)
    fig.update_xaxes(title_text="uncertainty budget Γ [periods]")
    fig.update_layout(title="Sensitivity to the uncertainty budget: cost and traded energy", **LAYOUT)
    return fig


def sensitivity_reserve_figure(table: pd.DataFrame) -> go.Figure:
    """Up and down reserve by unit kind against Γ (paper Figure 16)."""
    fig = make_subplots(rows=1, cols=2, subplot_titles=("Up reserve [MWh]", "Down reserve [MWh]"))
    part = table[table["sources"] == table["sources"].iloc[0]]
    for col, direction in enumerate(("up", "dn"), start=1):
        for kind in FLEX_KINDS:
            column = f"{kind}_{direction}_mwh"
            if column in part:
                fig.add_trace(go.Bar(x=part["gamma"], y=part[column], name=KIND_LABELS[kind],
                                     marker_color=KIND_COLORS[kind], showlegend=col == 1,
                                     legendgroup=kind), row=1, col=col)
    fig.update_layout(barmode="stack", title=f"Reserve by unit kind against Γ (sources: {part['sources'].iloc[0]})",
                      **LAYOUT)
    fig.update_xaxes(title_text="uncertainty budget Γ [periods]")
    return fig


def reserve_by_kind_figure(flexibility: pd.DataFrame) -> go.Figure:
    """Reserve energy by unit kind per strategy (paper Table 9 as bars)."""
    fig = make_subplots(rows=1, cols=2, subplot_titles=("Up reserve [MWh]", "Down reserve [MWh]"))
    for col, column in enumerate(("r_up_mwh", "r_dn_mwh"), start=1):
        for kind in flexibility["kind"].unique():
            part = flexibility[flexibility["kind"] == kind]
            fig.add_trace(go.Bar(x=part["strategy"], y=part[column], name=KIND_LABELS.get(kind, kind),
                                 marker_color=KIND_COLORS.get(kind), showlegend=col == 1, legendgroup=kind),
                          row=1, col=col)
    fig.update_layout(barmode="group", title="Reserve provided by unit kind and strategy", **LAYOUT)
    return fig


def cost_bars_figure(wide: pd.DataFrame, title: str, column_title: str) -> go.Figure:
    """Grouped bars of cost [kEUR]: one group per strategy, one bar per column of ``wide``."""
    fig = go.Figure()
    for column in wide.columns:
        fig.add_trace(go.Bar(x=list(wide.index), y=wide[column], name=str(column),
                             text=[f"{v:.1f}" for v in wide[column]], textposition="outside"))
    fig.update_layout(barmode="group", title=title, yaxis_title="cost [kEUR]", legend_title=column_title,
                      **LAYOUT)
    return fig


def out_of_sample_figure(summary: pd.DataFrame) -> go.Figure:
    """Average market cost and penalty per method, net cost marked (paper Tables 13-14)."""
    fig = go.Figure()
    fig.add_trace(go.Bar(x=summary["method"], y=summary["avg_market_cost_keur"], name="market cost"))
    fig.add_trace(go.Bar(x=summary["method"], y=summary["avg_penalty_keur"], name="penalty"))
    fig.add_trace(go.Scatter(x=summary["method"], y=summary["avg_net_cost_keur"], mode="markers+text",
                             name="net cost", marker={"symbol": "diamond", "size": 12, "color": "black"},
                             text=[f"{v:.1f}" for v in summary["avg_net_cost_keur"]], textposition="top center"))
    fig.update_layout(barmode="relative", title="Out-of-sample: average cost per test day", yaxis_title="kEUR",
                      **LAYOUT)
    return fig


def solve_time_figure(summary: pd.DataFrame) -> go.Figure:
    """First-stage solve time per method [s], log scale."""
    fig = go.Figure(go.Bar(x=summary["method"], y=summary["solve_s"],
                           text=[f"{v:.1f} s" for v in summary["solve_s"]], textposition="outside"))
    fig.update_layout(title="Solve time of the first-stage plan", yaxis_title="seconds", yaxis_type="log",
                      **LAYOUT)
    return fig
