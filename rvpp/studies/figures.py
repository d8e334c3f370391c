"""Figures of the sensitivity, market and out-of-sample studies (Plotly).

Each function takes a study table and returns a ``plotly.graph_objects.Figure``; the
same figure is drawn on a dashboard page, saved as interactive HTML and as PNG. As in
:mod:`rvpp.outputs.plots`: every axis title carries its unit, every trace has a legend entry and
a hover value with its unit, backgrounds are transparent and the colours, dashes and
markers come from :mod:`rvpp.outputs.style`, so a strategy looks the same on every page.
"""

from __future__ import annotations

import math

import pandas as pd
import plotly.graph_objects as go
from plotly.subplots import make_subplots

from ..outputs.money import MONEY_TICKS
from ..outputs.style import (BLUE, DASHES, FIGURE_HEIGHT, GREY, GRID_COLOR, KIND_COLORS, KIND_GROUP_LABELS,
                             MARKET_COLORS, ORANGE, PURPLE, SERIES_COLORS, SKY, TRANSPARENT, VERMILION, run_style)
from ..data.kinds import FLEX_KINDS

KIND_LABELS = {kind: KIND_GROUP_LABELS[kind] for kind in FLEX_KINDS}
GAMMA_TITLE = "Uncertainty budget Γ [periods]"
TRADES = (("sold_mwh", "Sold (DAM) [MWh]", "MWh", MARKET_COLORS["dam"]),
          ("bought_mwh", "Bought (DAM) [MWh]", "MWh", VERMILION),
          ("heat_bought_mwh", "Heat bought (HPA) [MWh_th]", "MWh_th", MARKET_COLORS["hpa"]))
PENALTY_CAUSES = (("penalty_deficit_eur", "Energy short of the DAM bid", VERMILION, ""),
                  ("penalty_surplus_eur", "Energy beyond the DAM bid", SKY, "/"),
                  ("penalty_reserve_eur", "Reserve not delivered", ORANGE, "x"),
                  ("penalty_heat_eur", "Heat not served", PURPLE, "."))
NOT_AVAILABLE = "n/a"


def sensitivity_trade_figure(table: pd.DataFrame) -> go.Figure:
    """Cost, traded electricity and bought heat against Γ (paper Figure 15)."""
    fig = make_subplots(rows=1, cols=2, subplot_titles=("Cost", "Energy traded over the day"),
                        horizontal_spacing=0.1)
    groups = list(table.groupby("sources", sort=False))
    for i, (group, part) in enumerate(groups):
        suffix = "" if group == "all" else f" ({group})"
        dash = _dash(i)
        fig.add_trace(go.Scatter(x=part["gamma"], y=part["cost_keur"], mode="lines+markers",
                                 name=f"Cost [kEUR]{suffix}", line=dict(color=SERIES_COLORS[i % len(SERIES_COLORS)]
                                                                        if len(groups) > 1 else PURPLE, dash=dash),
                                 hovertemplate=f"Γ = %{{x}}: %{{y:.1f}} kEUR{suffix}<extra></extra>"), row=1, col=1)
        for column, label, unit, color in TRADES:
            fig.add_trace(go.Scatter(x=part["gamma"], y=part[column], mode="lines+markers", name=f"{label}{suffix}",
                                     line=dict(color=color, dash=dash),
                                     hovertemplate=f"Γ = %{{x}}: %{{y:.1f}} {unit}<extra>{label}{suffix}</extra>"),
                          row=1, col=2)
    _style(fig, "Sensitivity to the uncertainty budget: cost and traded energy")
    fig.update_xaxes(title_text=GAMMA_TITLE)
    fig.update_yaxes(title_text="Cost (−profit) [kEUR]", row=1, col=1)
    fig.update_yaxes(title_text="Energy [MWh] / heat [MWh_th]", row=1, col=2)
    return fig


def sensitivity_reserve_figure(table: pd.DataFrame, sources: str | None = None) -> go.Figure:
    """Up and down reserve by unit kind against Γ (paper Figure 16).

    ``sources``: which sweep to draw (a value of the table's ``sources`` column; default
    the first).
    """
    fig = make_subplots(rows=1, cols=2, subplot_titles=("Up reserve over the day", "Down reserve over the day"),
                        horizontal_spacing=0.1)
    sources = table["sources"].iloc[0] if sources is None else sources
    part = table[table["sources"] == sources]
    for col, (direction, word) in enumerate((("up", "up"), ("dn", "down")), start=1):
        for kind in FLEX_KINDS:
            column = f"{kind}_{direction}_mwh"
            if column in part:
                fig.add_trace(go.Bar(x=part["gamma"], y=part[column], name=KIND_LABELS[kind],
                                     marker_color=KIND_COLORS[kind], showlegend=col == 1, legendgroup=kind,
                                     hovertemplate=f"Γ = %{{x}}: %{{y:.1f}} MWh<extra>{KIND_LABELS[kind]} {word}"
                                                   "</extra>"), row=1, col=col)
    _style(fig, f"Reserve by unit kind against Γ (sources: {sources})")
    fig.update_layout(barmode="stack")
    fig.update_xaxes(title_text=GAMMA_TITLE)
    fig.update_yaxes(title_text="Reserve energy [MWh]")
    return fig


def reserve_by_kind_figure(flexibility: pd.DataFrame) -> go.Figure:
    """Reserve energy by unit kind per strategy (paper Table 9 as bars)."""
    fig = make_subplots(rows=1, cols=2, subplot_titles=("Up reserve over the day", "Down reserve over the day"),
                        horizontal_spacing=0.1)
    for col, column in enumerate(("r_up_mwh", "r_dn_mwh"), start=1):
        for kind in flexibility["kind"].unique():
            part = flexibility[flexibility["kind"] == kind]
            label = KIND_LABELS.get(kind, kind)
            fig.add_trace(go.Bar(x=part["strategy"], y=part[column], name=label, marker_color=KIND_COLORS.get(kind),
                                 showlegend=col == 1, legendgroup=kind,
                                 hovertemplate=f"%{{x}}: %{{y:.1f}} MWh<extra>{label}</extra>"), row=1, col=col)
    _style(fig, "Reserve provided by unit kind and strategy")
    fig.update_layout(barmode="group")
    fig.update_xaxes(title_text="Strategy")
    fig.update_yaxes(title_text="Reserve energy [MWh]")
    return fig


def cost_bars_figure(wide: pd.DataFrame, title: str, column_title: str) -> go.Figure:
    """Grouped bars of cost [kEUR]: one group per strategy, one bar per column of ``wide``.

    A configuration without a plan (NaN) has no bar and is labelled ``n/a``.
    """
    fig = go.Figure()
    for i, column in enumerate(wide.columns):
        values = [None if _missing(v) else float(v) for v in wide[column]]
        fig.add_trace(go.Bar(x=list(wide.index), y=values, name=str(column),
                             marker_color=SERIES_COLORS[i % len(SERIES_COLORS)],
                             text=[NOT_AVAILABLE if v is None else f"{v:.1f}" for v in values],
                             textposition="outside", cliponaxis=False,
                             hovertemplate=f"%{{x}}, {column}: %{{y:.1f}} kEUR<extra></extra>"))
    _style(fig, title)
    fig.update_layout(barmode="group", legend_title_text=column_title)
    fig.update_xaxes(title_text="Strategy")
    fig.update_yaxes(title_text="Cost (−profit) [kEUR]")
    return fig


def out_of_sample_figure(summary: pd.DataFrame) -> go.Figure:
    """Average market cost and penalty per method, net cost marked (paper Tables 13-14)."""
    fig = go.Figure()
    fig.add_trace(go.Bar(x=summary["method"], y=summary["avg_market_cost_keur"], name="Market cost [kEUR]",
                         marker_color=BLUE, hovertemplate="%{x}: %{y:,.1f} kEUR<extra>market cost</extra>"))
    fig.add_trace(go.Bar(x=summary["method"], y=summary["avg_penalty_keur"], name="Penalty [kEUR]",
                         marker_color=ORANGE, marker_pattern_shape="/",
                         hovertemplate="%{x}: %{y:,.1f} kEUR<extra>penalty</extra>"))
    fig.add_trace(go.Scatter(x=summary["method"], y=summary["avg_net_cost_keur"], mode="markers+text",
                             name="Net cost [kEUR]", marker={"symbol": "diamond", "size": 13, "color": VERMILION,
                                                             "line": {"width": 1, "color": GREY}},
                             text=[NOT_AVAILABLE if _missing(v) else f"{v:,.1f}" for v in summary["avg_net_cost_keur"]],
                             textposition="top center", cliponaxis=False,
                             hovertemplate="%{x}: %{y:,.1f} kEUR<extra>net cost</extra>"))
    _style(fig, "Out-of-sample: average cost per test day")
    fig.update_layout(barmode="relative")
    fig.update_xaxes(title_text="Method")
    fig.update_yaxes(title_text="Average per test day [kEUR]", **MONEY_TICKS, range=_headroom(
        [*summary["avg_market_cost_keur"], *summary["avg_net_cost_keur"],
         *(summary["avg_market_cost_keur"] + summary["avg_penalty_keur"].clip(lower=0))]))
    return fig


def penalty_causes_figure(evaluations: pd.DataFrame) -> go.Figure:
    """Average penalty per test day [kEUR] of each method, split by its cause.

    The settlement prices each deviation from the plan: energy short of the DAM bid at
    m_def × the realized DAM price, energy beyond it at m_sur × that price (a credit,
    so negative), reserve not delivered at m_sr × its price, heat not served at the
    unserved-heat price. The causes add up to the method's average penalty.
    """
    methods = list(dict.fromkeys(evaluations["method"]))
    means = evaluations.groupby("method", sort=False)[[c for c, *_ in PENALTY_CAUSES]].mean() / 1000.0
    fig = go.Figure()
    for column, label, color, pattern in PENALTY_CAUSES:
        fig.add_trace(go.Bar(x=methods, y=[float(means.loc[m, column]) for m in methods], name=label,
                             marker_color=color, marker_pattern_shape=pattern,
                             hovertemplate=f"%{{x}}: %{{y:,.1f}} kEUR<extra>{label}</extra>"))
    _style(fig, "Penalty per test day by cause")
    fig.update_layout(barmode="relative")
    fig.update_xaxes(title_text="Method")
    fig.update_yaxes(title_text="Average penalty per test day [kEUR]", **MONEY_TICKS)
    return fig


def net_cost_by_day_figure(evaluations: pd.DataFrame) -> go.Figure:
    """Net cost [kEUR] of every method on every test day (one line style per method)."""
    fig = go.Figure()
    for i, (method, part) in enumerate(evaluations.groupby("method", sort=False)):
        look = run_style(str(method), i)
        fig.add_trace(go.Scatter(x=part["day"], y=part["net_cost_eur"] / 1000.0, mode="lines+markers", name=method,
                                 line=dict(color=look["color"], dash=look["dash"]),
                                 marker=dict(symbol=look["symbol"], size=8),
                                 hovertemplate=f"%{{x}}: %{{y:,.1f}} kEUR<extra>{method}</extra>"))
    _style(fig, "Net cost on each test day")
    fig.update_xaxes(title_text="Test day (realization)", type="category")
    fig.update_yaxes(title_text="Net cost (market cost + penalty) [kEUR]", **MONEY_TICKS)
    return fig


def solve_time_figure(summary: pd.DataFrame) -> go.Figure:
    """First-stage solve time per method [s]."""
    fig = go.Figure(go.Bar(x=summary["method"], y=summary["solve_s"], name="Solve time [s]", marker_color=GREY,
                           text=[f"{v:.1f} s" for v in summary["solve_s"]], textposition="outside", cliponaxis=False,
                           hovertemplate="%{x}: %{y:.2f} s<extra></extra>", showlegend=True))
    _style(fig, "Solve time of the first-stage plan")
    fig.update_xaxes(title_text="Method")
    fig.update_yaxes(title_text="Solve time [s]", range=_headroom([0.0, *summary["solve_s"]]))
    return fig


def _headroom(values, share: float = 0.15) -> list[float]:
    """An axis range over ``values`` with room above (and below, for negatives) for text labels."""
    finite = [float(v) for v in values if not _missing(v)] or [0.0]
    low, high = min(0.0, *finite), max(0.0, *finite)
    span = (high - low) or 1.0
    return [low - (share * span if low < 0 else 0.0), high + share * span]


def _style(fig: go.Figure, title: str) -> None:
    """The look of :mod:`rvpp.outputs.plots`: transparent background, grey grid, legend on top."""
    fig.update_layout(title=dict(text=title, y=0.98, yanchor="top"), height=FIGURE_HEIGHT,
                      paper_bgcolor=TRANSPARENT, plot_bgcolor=TRANSPARENT, margin=dict(t=110, b=60, l=70, r=30),
                      legend=dict(orientation="h", yanchor="bottom", y=1.08, xanchor="left", x=0))
    fig.update_xaxes(gridcolor=GRID_COLOR)
    fig.update_yaxes(gridcolor=GRID_COLOR, zerolinecolor=GRID_COLOR)


def _dash(i: int) -> str:
    return DASHES[i % len(DASHES)]


def _missing(value) -> bool:
    return value is None or (isinstance(value, float) and math.isnan(value))
