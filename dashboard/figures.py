"""Figures of a plan, built once per plan and shared by every page and session.

A plan's figures are pure functions of its result, so they are kept
(``st.cache_resource``) by the result's identity: the case's content and the solve's
outcome and timings. Pages draw them and must not change them. The plans of a Γ sweep
are plans like any other; their figures carry the Γ in their title
(:func:`titled_figure`) and the sweep's cost curve marks the Γ shown (:func:`sweep_curve`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd
import plotly.graph_objects as go
import streamlit as st

from rvpp import Result
from rvpp.service import GREY, plots, waterfall_figure

from .state import case_key

KEPT = 64  # plans whose figures are kept (a sweep of the default day has 25)
KEUR = 1000.0


def result_key(result: Result) -> str:
    """What makes two results the same plan: the case's content and the solve's outcome."""
    return f"{case_key(result.case)}|{result.status}|{result.objective_eur!r}|{result.build_s!r}|{result.solve_s!r}"


@st.cache_resource(show_spinner=False, max_entries=KEPT, hash_funcs={Result: result_key})
def plan_figures(result: Result) -> dict[str, go.Figure | None]:
    """Every figure of the Results page: economics, trades, heat (``None`` without thermal
    demand), dispatch, storage of each CSP (``"storage NAME"``), state of charge of each battery
    (``"battery NAME"``) and reserve."""
    figures = {
        "economics": waterfall_figure({result.case.budgets.strategy: result}),
        "trades": plots.trades_figure(result),
        "heat": plots.heat_figure(result) if result.case.td else None,
        "dispatch": plots.dispatch_figure(result),
        "reserve": plots.reserve_share_figure(result),
    }
    for csp in result.case.csp:
        figures[f"storage {csp.name}"] = plots.storage_figure(result, csp.name)
    for battery in result.case.battery:
        if battery.enabled:
            figures[f"battery {battery.name}"] = plots.battery_figure(result, battery.name)
    return figures


@st.cache_resource(show_spinner=False, max_entries=2 * KEPT, hash_funcs={Result: result_key})
def titled_figure(result: Result, name: str, title: str) -> go.Figure:
    """The figure ``name`` of :func:`plan_figures` under another title (one copy per title)."""
    figure = go.Figure(plan_figures(result)[name])
    figure.update_layout(title_text=title)
    return figure


@st.cache_resource(show_spinner=False, max_entries=2 * KEPT)
def sweep_curve(sweep: str, gamma: int, _gammas: Sequence[int], _points: Sequence[Result]) -> go.Figure:
    """Cost and price protection against Γ of the plans of the sweep ``sweep`` (its key), with
    the plan at ``gamma`` marked; plans without a plan are left out."""
    frame = pd.DataFrame([{"gamma": g, "cost_keur": r.cost_keur,
                           "protection_keur": sum(r.protection_eur.values()) / KEUR}
                          for g, r in zip(_gammas, _points) if r.has_plan])
    figure = plots.robustness_figure(frame)
    figure.add_vline(x=gamma, line_dash="dot", line_color=GREY)
    figure.update_layout(title_text=f"Price of robustness · plan shown: Γ = {gamma}")
    return figure


def heat_bought(result: Result) -> bool:
    """Whether the plan buys any heat through the HPA."""
    return bool(np.any(result.market["h_hpa_mw"].to_numpy(float) > 0))
