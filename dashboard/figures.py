"""Figures of a plan, built once per plan and shared by every page and session.

A plan's figures are pure functions of its result, so they are kept
(``st.cache_resource``) by the result's identity: the case's content and the solve's
outcome and timings. Pages draw them and must not change them.
"""

from __future__ import annotations

import numpy as np
import plotly.graph_objects as go
import streamlit as st

from rvpp import Result
from rvpp.outputs import plots
from rvpp.outputs.economics import waterfall_figure

from .state import case_key

KEPT = 32  # plans whose figures are kept


def result_key(result: Result) -> str:
    """What makes two results the same plan: the case's content and the solve's outcome."""
    return f"{case_key(result.case)}|{result.status}|{result.objective_eur!r}|{result.build_s!r}|{result.solve_s!r}"


@st.cache_resource(show_spinner=False, max_entries=KEPT, hash_funcs={Result: result_key})
def plan_figures(result: Result) -> dict[str, go.Figure | None]:
    """Every figure of the Results page: economics, trades, heat (``None`` without thermal
    demand), dispatch, storage of each CSP (``"storage NAME"``) and reserve."""
    figures = {
        "economics": waterfall_figure({result.case.budgets.strategy: result}),
        "trades": plots.trades_figure(result),
        "heat": plots.heat_figure(result) if result.case.td else None,
        "dispatch": plots.dispatch_figure(result),
        "reserve": plots.reserve_share_figure(result),
    }
    for csp in result.case.csp:
        figures[f"storage {csp.name}"] = plots.storage_figure(result, csp.name)
    return figures


def heat_bought(result: Result) -> bool:
    """Whether the plan buys any heat through the HPA."""
    return bool(np.any(result.market["h_hpa_mw"].to_numpy(float) > 0))
