"""Plotly figures of plans and forecast bands.

Every builder is a pure function of a :class:`~rvpp.solving.results.Result` or a
:class:`~rvpp.solving.problem.Problem` and returns a :class:`plotly.graph_objects.Figure`:
the x axis shows the clock time of each period's start on the delivery day (local
time), every axis title carries its unit, every trace has a legend entry and a hover
value. Backgrounds are transparent and the colours come from :mod:`rvpp.outputs.style`
(Okabe & Ito's colour-blind safe set), which reads on light and dark themes alike, so
the same figure serves the dashboard and static exports (``fig.write_image``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd
import plotly.graph_objects as go
from plotly.subplots import make_subplots

from ..settle.audit import price_exposures, protection_exact
from ..solving.problem import Problem
from ..solving.results import FLEX_KINDS, Result
from .style import (BLUE, CHI_SHADE, FIGURE_HEIGHT, FIGURE_MARGIN, GREEN, GREY, GRID_COLOR, KIND_COLORS, KIND_LABELS,
                    MARKET_COLORS, ORANGE, PURPLE, SERIES_COLORS, SKY, TRANSPARENT, VERMILION, rgba, run_style)

CLOCK_TITLE = "Delivery day, period start (local time)"
HOURS_PER_TICK = 1  # one x tick per clock hour

SOURCE_UNITS = {"price_da": "EUR/MWh", "price_sr_up": "EUR/MW per h", "price_sr_dn": "EUR/MW per h",
                "wind": "MW", "pv": "MW", "csp": "MW_th", "ed": "MW", "td": "MW_th"}
COMPARE_ROWS = (("p_da_mw", "DAM [MW]", "MW"), ("r_sr_up_mw", "SR up [MW]", "MW"),
                ("r_sr_dn_mw", "SR down [MW]", "MW"), ("h_hpa_mw", "HPA heat [MW_th]", "MW_th"))
TRADE_NAMES = {"p_da_mw": "day-ahead energy", "r_sr_up_mw": "up reserve", "r_sr_dn_mw": "down reserve",
               "h_hpa_mw": "heat"}
SOURCE_TITLES = {"price_da": "Day-ahead price", "price_sr_up": "Up-reserve price",
                 "price_sr_dn": "Down-reserve price"}
TOTALS_MARGIN_R = 80  # [px] the reserve figure's day totals: their tilted unit-kind labels reach past the plot


# ----------------------------------------------------------------------------- plan figures


def trades_figure(result: Result) -> go.Figure:
    """DAM energy per period (+ sell, − buy) with the SR up and down bands around it [MW]."""
    market = _plan(result).market
    x = _labels(result)
    p, up, dn = (market[c].to_numpy(float) for c in ("p_da_mw", "r_sr_up_mw", "r_sr_dn_mw"))
    fig = go.Figure()
    fig.add_bar(x=x, y=p, name="DAM energy (+ sell, − buy)", marker_color=MARKET_COLORS["dam"],
                hovertemplate="%{y:.2f} MW")
    fig.add_bar(x=x, y=up, base=p, name="SR up band", marker_color=MARKET_COLORS["sr_up"], opacity=0.75,
                width=0.35, customdata=up, hovertemplate="%{customdata:.2f} MW", marker_pattern_shape="/")
    fig.add_bar(x=x, y=dn, base=p - dn, name="SR down band", marker_color=MARKET_COLORS["sr_dn"], opacity=0.75,
                width=0.35, customdata=dn, hovertemplate="%{customdata:.2f} MW", marker_pattern_shape="\\")
    _style(fig, result, "Day-ahead energy and secondary-reserve bands", "Power [MW]")
    fig.update_layout(barmode="overlay")
    return fig


def heat_figure(result: Result) -> go.Figure:
    """Heat supply by CSP plant and HPA purchase, stacked, against the thermal demand [MW_th]."""
    result = _plan(result)
    x = _labels(result)
    fig = go.Figure()
    for i, (name, part) in enumerate(_by_unit(result.csp)):
        fig.add_bar(x=x, y=part["heat_to_td_mw"].to_numpy(float), name=f"{name} heat",
                    marker_color=_shade(VERMILION, i, result.csp["unit"].nunique()),
                    hovertemplate="%{y:.2f} MW_th")
    fig.add_bar(x=x, y=result.market["h_hpa_mw"].to_numpy(float), name="HPA purchase",
                marker_color=MARKET_COLORS["hpa"], hovertemplate="%{y:.2f} MW_th")
    demand = _kind_sum(result, "td", "p_mw")
    fig.add_scatter(x=x, y=demand, name="Thermal demand", mode="lines+markers",
                    line=dict(color=GREEN, width=3), hovertemplate="%{y:.2f} MW_th")
    _style(fig, result, "Heat supply against thermal demand", "Heat [MW_th]")
    fig.update_layout(barmode="stack")
    return fig


def dispatch_figure(result: Result) -> go.Figure:
    """Electrical output of every unit (stacked, demands negative) and the DAM position [MW]."""
    result = _plan(result)
    x = _labels(result)
    units = result.units
    fig = go.Figure()
    for kind in ("wind", "pv", "csp", "ed"):
        parts = _by_unit(units[units["kind"] == kind])
        for i, (name, part) in enumerate(parts):
            sign = -1.0 if kind == "ed" else 1.0
            fig.add_bar(x=x, y=sign * part["p_mw"].to_numpy(float), name=name, legendgroup=kind,
                        marker_color=_shade(KIND_COLORS[kind], i, len(parts)),
                        hovertemplate="%{y:.2f} MW")
    fig.add_scatter(x=x, y=result.market["p_da_mw"].to_numpy(float), name="DAM position",
                    mode="lines+markers", line=dict(color=BLUE, width=3), hovertemplate="%{y:.2f} MW")
    _style(fig, result, "Electrical dispatch by unit (consumption negative)", "Power [MW]")
    fig.update_layout(barmode="relative")
    return fig


def storage_figure(result: Result, csp: str | None = None) -> go.Figure:
    """Thermal storage of one CSP: stored energy [MWh_th] between its limits, the σ margins
    kept for reserve (MODEL_SPEC §8, TS11), and charge/discharge power [MW_th] below."""
    result = _plan(result)
    names = [c.name for c in result.case.csp]
    if not names:
        raise ValueError("the case has no CSP plant, so there is no thermal storage to show")
    name = csp or names[0]
    if name not in names:
        raise ValueError(f"unknown CSP {name!r}; the case has {', '.join(names)}")
    storage = next(c for c in result.case.csp if c.name == name).storage
    rows = result.csp[result.csp["unit"] == name].sort_values("t")
    x = _labels(result)
    n = len(x)
    e_min, e_max = np.full(n, storage.e_min_mwh_th), np.full(n, storage.e_max_mwh_th)
    floor = rows["ts_energy_floor_mwh"].to_numpy(float)
    ceiling = rows["ts_energy_ceiling_mwh"].to_numpy(float)
    fig = make_subplots(rows=2, cols=1, shared_xaxes=True, row_heights=[0.68, 0.32], vertical_spacing=0.05)
    energy = "%{y:.1f} MWh_th"
    fig.add_scatter(x=x, y=e_min, name="Minimum energy", mode="lines", line=dict(color=GREY, dash="dash"),
                    hovertemplate=energy, row=1, col=1)
    fig.add_scatter(x=x, y=floor, name="Margin kept for up reserve (σ↑)", mode="lines", fill="tonexty",
                    fillcolor=rgba(PURPLE, 0.25), line=dict(color=PURPLE, dash="dot"), hovertemplate=energy,
                    row=1, col=1)
    fig.add_scatter(x=x, y=e_max, name="Maximum energy", mode="lines", line=dict(color=GREY, dash="dash"),
                    hovertemplate=energy, row=1, col=1)
    fig.add_scatter(x=x, y=ceiling, name="Margin kept for down reserve (σ↓)", mode="lines", fill="tonexty",
                    fillcolor=rgba(SKY, 0.25), line=dict(color=SKY, dash="dot"), hovertemplate=energy,
                    row=1, col=1)
    fig.add_scatter(x=x, y=rows["ts_energy_mwh"].to_numpy(float), name="Stored energy (end of period)",
                    mode="lines+markers", line=dict(color=VERMILION, width=3), hovertemplate=energy, row=1, col=1)
    fig.add_bar(x=x, y=rows["ts_charge_mw"].to_numpy(float), name="Charge", marker_color=GREEN,
                hovertemplate="%{y:.2f} MW_th", row=2, col=1)
    fig.add_bar(x=x, y=-rows["ts_discharge_mw"].to_numpy(float), name="Discharge (negative)",
                marker_color=ORANGE, hovertemplate="%{y:.2f} MW_th", row=2, col=1)
    _style(fig, result, f"{name}: thermal storage", None, height=FIGURE_HEIGHT + 120, x_title=False)
    fig.update_yaxes(title_text="Stored energy [MWh_th]", row=1, col=1)
    fig.update_yaxes(title_text="Power [MW_th]", row=2, col=1)
    fig.update_xaxes(title_text=CLOCK_TITLE, row=2, col=1)
    fig.update_layout(barmode="relative")
    return fig


def reserve_share_figure(result: Result) -> go.Figure:
    """Up and down reserve by unit kind per period [MW] and in total over the day [MWh]."""
    result = _plan(result)
    x = _labels(result)
    dt_h = result.problem.dt_h
    units = result.units
    fig = make_subplots(rows=2, cols=2, column_widths=[0.78, 0.22], shared_xaxes="columns",
                        horizontal_spacing=0.09, vertical_spacing=0.08)
    for row, (column, band) in enumerate((("r_up_mw", "r_sr_up_mw"), ("r_dn_mw", "r_sr_dn_mw")), start=1):
        direction = "up" if row == 1 else "down"
        totals = []
        for kind in FLEX_KINDS:
            if not (units["kind"] == kind).any():
                continue
            per_period = _kind_sum(result, kind, column)
            totals.append((kind, float(per_period.sum() * dt_h)))
            fig.add_bar(x=x, y=per_period, name=KIND_LABELS[kind], legendgroup=kind, showlegend=row == 1,
                        marker_color=KIND_COLORS[kind], row=row, col=1,
                        hovertemplate=f"{KIND_LABELS[kind]} {direction}: %{{y:.2f}} MW<extra></extra>")
        fig.add_scatter(x=x, y=result.market[band].to_numpy(float), name="SR band offered", mode="lines",
                        legendgroup="band", showlegend=row == 1, line=dict(color=BLUE, width=2, shape="hvh"),
                        row=row, col=1, hovertemplate=f"offered {direction}: %{{y:.2f}} MW<extra></extra>")
        fig.add_bar(x=[KIND_LABELS[k] for k, _ in totals], y=[v for _, v in totals],
                    marker_color=[KIND_COLORS[k] for k, _ in totals], showlegend=False, row=row, col=2,
                    name=f"{direction} total", hovertemplate="%{x}: %{y:.1f} MWh<extra></extra>")
        fig.update_yaxes(title_text=f"{direction.capitalize()} reserve [MW]", row=row, col=1)
        fig.update_yaxes(title_text=f"{direction.capitalize()}, day total [MWh]", row=row, col=2)
    _style(fig, result, "Reserve by unit kind", None, height=FIGURE_HEIGHT + 160, clock_col=1, x_title=False)
    fig.update_layout(barmode="stack", hovermode="closest", margin_r=TOTALS_MARGIN_R)
    fig.update_xaxes(title_text=CLOCK_TITLE, row=2, col=1)
    return fig


# ----------------------------------------------------------------------------- forecast bands


def bands_figure(problem: Problem, source: str, chi: Sequence[float] | np.ndarray | None = None,
                 compare: tuple[str, np.ndarray, np.ndarray] | None = None,
                 realized: Sequence[float] | np.ndarray | None = None) -> go.Figure:
    """Forecast band of one uncertain source: lower bound, middle and upper bound.

    The band is the one the model uses, by the source's method (MODEL_SPEC §6): the
    window's percentiles per clock hour (climatology, the paper's) or the point forecast
    plus percentiles of its past errors (forecast). ``compare`` = ``(label, lo, hi)``
    outlines another band (e.g. the other method's); ``realized`` draws what the day then
    brought. Price axes follow the data, below zero included.

    ``chi`` (one value per period) marks the periods where the source deviates: the
    marker sits on the adverse bound (lower for production and prices, upper for
    consumption). For the DAM price, ``chi = -1`` marks a period whose adverse price is
    the upper one (the plan buys there). For units, ``chi`` also draws the bound the plan
    must respect: the nominal value, moved to the adverse bound where ``chi = 1``. The
    bounds are those the model uses (clipped to the nameplate for production).
    """
    if source not in problem.sources:
        raise ValueError(f"unknown source {source!r}; sources are {', '.join(problem.sources)}")
    src = problem.sources[source]
    lo, mid, hi = _model_band(problem, source)
    unit = _source_unit(problem, source)
    q = problem.case.uncertainty
    method = q.band_method(source, src.unit_kind)
    x = problem.labels
    color = SERIES_COLORS[0] if src.is_price else KIND_COLORS[src.unit_kind]
    names = (("Upper percentile", "Lower percentile", "Median") if method == "climatology" else
             ("Upper bound: forecast + error", "Lower bound: forecast + error", "Forecast + median error"))
    fig = go.Figure()
    fig.add_scatter(x=x, y=hi, name=f"{names[0]} ({_percent(q.q_hi)})", mode="lines",
                    line=dict(color=color, width=1), hovertemplate=f"%{{y:.2f}} {unit}")
    fig.add_scatter(x=x, y=lo, name=f"{names[1]} ({_percent(q.q_lo)})", mode="lines",
                    line=dict(color=color, width=1), fill="tonexty", fillcolor=rgba(color, 0.22),
                    hovertemplate=f"%{{y:.2f}} {unit}")
    fig.add_scatter(x=x, y=mid, name=names[2], mode="lines", line=dict(color=color, width=3, dash="dash"),
                    hovertemplate=f"%{{y:.2f}} {unit}")
    if compare is not None:
        label, other_lo, other_hi = compare
        for name, values in ((f"{label}: upper", other_hi), (f"{label}: lower", other_lo)):
            fig.add_scatter(x=x, y=np.asarray(values, float), name=name, mode="lines",
                            line=dict(color=GREY, width=2, dash="dot"), hovertemplate=f"%{{y:.2f}} {unit}")
    if realized is not None:
        fig.add_scatter(x=x, y=np.asarray(realized, float), name="Realized", mode="lines+markers",
                        line=dict(color=PURPLE if color == ORANGE else ORANGE, width=2), marker=dict(size=5),
                        hovertemplate=f"realized %{{y:.2f}} {unit}")
    if chi is not None:
        chi = np.asarray(chi, dtype=float)
        if len(chi) != problem.nt:
            raise ValueError(f"chi has {len(chi)} values for {problem.nt} periods")
        adverse = np.where(chi < 0, hi, hi if src.kind == "consumption" else lo)
        marked = np.flatnonzero(chi != 0)
        for t in marked:
            fig.add_vrect(x0=t - 0.5, x1=t + 0.5, fillcolor=CHI_SHADE, line_width=0, layer="below")
        if not src.is_price:
            bound = np.where(chi != 0, adverse, src.nominal)
            fig.add_scatter(x=x, y=bound, name="Bound the plan respects", mode="lines",
                            line=dict(color=VERMILION, width=2, shape="hvh"), hovertemplate=f"%{{y:.2f}} {unit}")
        fig.add_scatter(x=[x[t] for t in marked], y=adverse[marked], name=f"Deviates (χ = 1) in {len(marked)} periods",
                        mode="markers", marker=dict(color=VERMILION, size=11, symbol="x"),
                        hovertemplate=f"deviates to %{{y:.2f}} {unit}")
    title = SOURCE_TITLES[source] if src.is_price else f"{source} ({KIND_LABELS[src.unit_kind].lower()})"
    kind_of_band = "forecast band" if method == "climatology" else "forecast-error band"
    _style_axes(fig, problem.labels, problem.dt_h, f"{title}: {kind_of_band}", _source_axis(source, src, unit))
    return fig


def band_overlays(problem: Problem, source: str) -> dict:
    """What :func:`bands_figure` can draw beside a source's band: the other method's band
    (``compare``, where that method applies) and the delivery day's observed values
    (``realized``, where the history covers the day)."""
    from ..errors import CaseError
    from ..uncertainty.bands import realized_values
    from ..uncertainty.forecast import band_specs, case_bands, has_forecast

    case = problem.case
    spec = band_specs(case)[source]
    out: dict = {}
    other = "forecast" if spec.method == "climatology" else "climatology"
    if other == "climatology" or has_forecast(spec):
        try:
            bands = case_bands(case, problem.periods, {source: other})
            lo, hi = bands[(source, "lo")].to_numpy(float), bands[(source, "hi")].to_numpy(float)
            if spec.high is not None:  # output is clipped to [0, nameplate], as the model's band
                lo, hi = np.clip(lo, spec.low, spec.high), np.clip(hi, spec.low, spec.high)
            out["compare"] = (other.capitalize(), lo, hi)
        except CaseError:
            pass
    try:
        observed = realized_values(case.history, problem.day, problem.periods, {source: (spec.column, spec.scale)},
                                   case.timezone)
        out["realized"] = observed[source].to_numpy(float)
    except CaseError:
        pass
    return out


def deviating_periods(result: Result, source: str) -> np.ndarray:
    """χ per period for ``source`` in a solved plan.

    Units and CSP solar fields: the model's χ. Prices: the Γ periods of largest loss
    (the adversary of the price protection, MODEL_SPEC §4); for the DAM price −1 where
    the plan buys (the adverse price is the upper one), +1 where it sells.
    """
    result = _plan(result)
    problem = result.problem
    src = problem.sources[source]
    if src.is_price:
        exposure = price_exposures(problem, result.market)[source]
        chi = np.zeros(problem.nt)
        worst = _top_periods(exposure, src.gamma)
        chi[worst] = 1.0
        if source == "price_da":
            buying = result.market["p_da_mw"].to_numpy(float) < 0
            chi[worst & buying] = -1.0
        return chi
    table = result.csp if src.unit_kind == "csp" else result.units
    rows = table[table["unit"] == source].sort_values("t")
    return rows["chi"].to_numpy(dtype=float, na_value=0.0)


# ----------------------------------------------------------------------------- teaching and comparison


def exposure_figure(result: Result, source: str, gamma: int) -> go.Figure:
    """Per-period loss if ``source``'s price moves adversely [EUR]; the Γ worst periods highlighted.

    Their sum is the price protection (Bertsimas & Sim 2004; MODEL_SPEC §4).
    """
    result = _plan(result)
    exposure = price_exposures(result.problem, result.market)[source]
    worst = _top_periods(exposure, gamma)
    protection = protection_exact(exposure, gamma)
    x = _labels(result)
    fig = go.Figure()
    fig.add_bar(x=x, y=np.where(worst, 0.0, exposure), name="Possible loss", marker_color=GREY,
                hovertemplate="%{y:.1f} EUR")
    fig.add_bar(x=x, y=np.where(worst, exposure, 0.0), name=f"Picked by the adversary (Γ = {gamma})",
                marker_color=VERMILION, hovertemplate="%{y:.1f} EUR")
    title = f"{SOURCE_TITLES[source]}: loss per period, protection {protection:,.0f} EUR"
    _style(fig, result, title, "Loss if the price moves adversely [EUR]")
    fig.update_layout(barmode="stack")
    return fig


def compare_trades_figure(results: Mapping[str, Result]) -> go.Figure:
    """DAM energy, SR bands and HPA heat of several plans overlaid, one line style per plan.

    A panel in which every plan is zero all day (e.g. no heat bought, no reserve offered)
    carries no information and is left out; :func:`idle_trades` names what was left out.
    """
    plans = {label: _plan(r) for label, r in results.items()}
    if not plans:
        raise ValueError("no plans to compare")
    first = next(iter(plans.values()))
    rows = [row for row in COMPARE_ROWS if row[0] not in idle_trades(plans)]
    fig = make_subplots(rows=len(rows), cols=1, shared_xaxes=True, vertical_spacing=0.06)
    for i, (label, result) in enumerate(plans.items()):
        look = run_style(label, i)
        for row, (column, axis, unit) in enumerate(rows, start=1):
            fig.add_scatter(x=_labels(result), y=result.market[column].to_numpy(float), name=label,
                            legendgroup=label, showlegend=row == 1, mode="lines+markers",
                            line=dict(color=look["color"], width=2, shape="hvh", dash=look["dash"]),
                            marker=dict(size=6, symbol=look["symbol"]),
                            hovertemplate=f"{label}: %{{y:.2f}} {unit}<extra></extra>", row=row, col=1)
            fig.update_yaxes(title_text=axis, row=row, col=1)
    _style(fig, first, "Trades of each plan", None, height=FIGURE_HEIGHT + 95 * len(rows), x_title=False)
    fig.update_xaxes(title_text=CLOCK_TITLE, row=len(rows), col=1)
    return fig


def idle_trades(results: Mapping[str, Result]) -> list[str]:
    """Columns of :data:`COMPARE_ROWS` that are zero in every period of every plan."""
    return [column for column, _, _ in COMPARE_ROWS
            if all(np.allclose(r.market[column].to_numpy(float), 0.0) for r in results.values() if r.has_plan)]


def robustness_figure(points: pd.DataFrame) -> go.Figure:
    """Price of robustness: cost [kEUR] and price protection [kEUR] against the budget Γ.

    ``points`` has columns ``gamma``, ``cost_keur`` and ``protection_keur``.
    """
    fig = go.Figure()
    fig.add_scatter(x=points["gamma"], y=points["cost_keur"], name="Cost (−profit)", mode="lines+markers",
                    line=dict(color=VERMILION, width=3), hovertemplate="Γ = %{x}: %{y:.1f} kEUR")
    fig.add_scatter(x=points["gamma"], y=points["protection_keur"], name="Price protection in the cost",
                    mode="lines+markers", line=dict(color=BLUE, width=2, dash="dash"),
                    hovertemplate="Γ = %{x}: %{y:.1f} kEUR")
    fig.update_layout(title="Price of robustness", height=FIGURE_HEIGHT, paper_bgcolor=TRANSPARENT,
                      plot_bgcolor=TRANSPARENT, hovermode="x unified", legend=_legend())
    fig.update_xaxes(title_text="Budget Γ of every source [periods]", gridcolor=GRID_COLOR, dtick=2)
    fig.update_yaxes(title_text="Cost [kEUR]", gridcolor=GRID_COLOR, zerolinecolor=GRID_COLOR)
    return fig


def curve_figure(breakpoints: Sequence[Sequence[float]], p_el_max_mw: float) -> go.Figure:
    """Power-block conversion: electrical output [MW] against thermal input [MW_th]."""
    inputs = np.array([p for p, _ in breakpoints], dtype=float)
    output = np.array([p * eta for p, eta in breakpoints], dtype=float)
    fig = go.Figure()
    fig.add_scatter(x=inputs, y=output, name="Output at the breakpoints", mode="lines+markers",
                    line=dict(color=VERMILION, width=3),
                    hovertemplate="%{x:.2f} MW_th → %{y:.2f} MW<extra></extra>")
    fig.add_scatter(x=[inputs[0], inputs[-1]], y=[p_el_max_mw, p_el_max_mw], name="Turbine nameplate",
                    mode="lines", line=dict(color=GREY, dash="dash"),
                    hovertemplate="%{y:.1f} MW<extra></extra>")
    fig.update_layout(title="Power-block conversion curve", height=FIGURE_HEIGHT - 80, legend=_legend(),
                      paper_bgcolor=TRANSPARENT, plot_bgcolor=TRANSPARENT)
    fig.update_xaxes(title_text="Thermal input [MW_th]", gridcolor=GRID_COLOR)
    fig.update_yaxes(title_text="Electrical output [MW]", gridcolor=GRID_COLOR, zerolinecolor=GRID_COLOR)
    return fig


def tariff_figure(problem: Problem) -> go.Figure:
    """HPA tariff per period [EUR/MWh_th]."""
    fig = go.Figure()
    fig.add_scatter(x=problem.labels, y=problem.tariff_hpa, name="HPA tariff", mode="lines+markers",
                    line=dict(color=GREEN, width=3, shape="hvh"), hovertemplate="%{y:.1f} EUR/MWh_th")
    _style_axes(fig, problem.labels, problem.dt_h, "Heat purchase agreement tariff", "Tariff [EUR/MWh_th]")
    return fig


def thin_clock_ticks(fig: go.Figure, hours: int) -> go.Figure:
    """Label only every ``hours``-th clock hour of ``fig``'s time axes (for narrow figures)."""
    for name in fig.layout.to_plotly_json():
        axis = fig.layout[name]
        if name.startswith("xaxis") and axis.type == "category":
            hourly = [label for label in axis.categoryarray if label[3:5] == "00"]
            axis.update(tickvals=hourly[::hours], ticktext=hourly[::hours])
    return fig


# ----------------------------------------------------------------------------- helpers


def _plan(result: Result) -> Result:
    if not result.has_plan:
        raise ValueError(f"the result has no plan to draw (status {result.status}: {result.message})")
    return result


def _labels(result: Result) -> list[str]:
    return list(result.problem.labels)


def _by_unit(table: pd.DataFrame) -> list[tuple[str, pd.DataFrame]]:
    if table.empty:
        return []
    return [(name, table[table["unit"] == name].sort_values("t")) for name in dict.fromkeys(table["unit"])]


def _kind_sum(result: Result, kind: str, column: str) -> np.ndarray:
    units = result.units
    part = units[units["kind"] == kind]
    if part.empty:
        return np.zeros(result.problem.nt)
    return part.groupby("t")[column].sum().reindex(range(1, result.problem.nt + 1), fill_value=0.0).to_numpy(float)


def _top_periods(exposure: np.ndarray, gamma: int) -> np.ndarray:
    """Mask of the Γ largest positive exposures (earlier periods win ties)."""
    mask = np.zeros(len(exposure), dtype=bool)
    if gamma > 0:
        order = np.argsort(-np.asarray(exposure, float), kind="stable")[:gamma]
        mask[order] = True
    return mask & (np.asarray(exposure) > 0)


def _model_band(problem: Problem, source: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lower bound, median and upper bound the model uses for ``source``."""
    src = problem.sources[source]
    mid = problem.bands[(source, "mid")].to_numpy(float)
    if src.kind == "price_da":
        return src.nominal - src.deviation, mid, src.nominal + src.deviation_up
    if src.kind == "consumption":
        return src.nominal, mid, src.nominal + src.deviation
    return src.nominal - src.deviation, np.minimum(mid, src.nominal), src.nominal


def _source_unit(problem: Problem, source: str) -> str:
    src = problem.sources[source]
    return SOURCE_UNITS[source] if src.is_price else SOURCE_UNITS[src.unit_kind]


def _source_axis(source: str, src, unit: str) -> str:
    if src.is_price:
        return f"Price [{unit}]"
    if src.unit_kind == "csp":
        return f"Solar-field heat available [{unit}]"
    if src.kind == "consumption":
        return f"Consumption [{unit}]"
    return f"Available power [{unit}]"


def _percent(q: float) -> str:
    return f"{q * 100:g}th"


def _legend() -> dict:
    return dict(orientation="h", yanchor="bottom", y=1.02, xanchor="left", x=0, title_text="", traceorder="normal")


def _style(fig: go.Figure, result: Result, title: str, y_title: str | None, height: int = FIGURE_HEIGHT,
           **axes) -> None:
    _style_axes(fig, _labels(result), result.problem.dt_h, title, y_title, height, **axes)


def _style_axes(fig: go.Figure, labels: list[str], dt_h: float, title: str, y_title: str | None,
                height: int = FIGURE_HEIGHT, clock_col: int | None = None, x_title: bool = True) -> None:
    """Shared look: clock-hour categories on x, unit-labelled y, transparent background.

    ``clock_col`` limits the clock axis to one subplot column; ``x_title=False`` leaves
    the x titles to the caller (subplots title only their bottom axis).
    """
    step = max(1, int(round(HOURS_PER_TICK / dt_h)))
    ticks = labels[::step]
    fig.update_layout(title=dict(text=title, y=0.98, yanchor="top"), height=height, hovermode="x unified",
                      paper_bgcolor=TRANSPARENT, plot_bgcolor=TRANSPARENT, legend=_legend(),
                      margin=FIGURE_MARGIN)
    fig.update_xaxes(type="category", categoryorder="array", categoryarray=labels, tickmode="array",
                     tickvals=ticks, ticktext=ticks, tickangle=-45, col=clock_col)
    fig.update_xaxes(gridcolor=GRID_COLOR)
    if x_title:
        fig.update_xaxes(title_text=CLOCK_TITLE)
    fig.update_yaxes(gridcolor=GRID_COLOR, zerolinecolor=GRID_COLOR)
    if y_title:
        fig.update_yaxes(title_text=y_title)


def _shade(color: str, i: int, n: int) -> str:
    """``color`` made darker or lighter so ``n`` units of one kind stay distinguishable."""
    if n <= 1:
        return color
    amount = -0.35 + 0.7 * i / (n - 1)  # −: towards black, +: towards white
    rgb = np.array([int(color[k:k + 2], 16) for k in (1, 3, 5)], dtype=float)
    target = 255.0 if amount > 0 else 0.0
    mixed = rgb + (target - rgb) * abs(amount)
    return "#" + "".join(f"{int(round(v)):02X}" for v in mixed)
