"""Plotly figures of plans and forecast bands.

Every builder is a pure function of a :class:`~rvpp.solving.results.Result` or a
:class:`~rvpp.uncertainty.problem.Problem` and returns a :class:`plotly.graph_objects.Figure`:
the x axis shows the clock time of each period's start on the delivery day (local
time), every axis title carries its unit, every trace has a legend entry and a hover
value. Backgrounds are transparent and the colours come from :mod:`rvpp.outputs.style`
(Okabe & Ito's colour-blind safe set), which reads on light and dark themes alike, so
the same figure serves the dashboard and static exports (``fig.write_image``).

Builders collect their traces and layout as plain dicts and make one ``go.Figure`` of
them at the end, so Plotly checks every property once; adding traces and updating axes
one call at a time checks them again on each call, several times the work for a page of
figures.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd
import plotly.graph_objects as go

from ..settle.audit import price_exposures, protection_exact
from ..uncertainty.problem import Problem, SourceKind
from ..data.kinds import ELECTRIC_KINDS, FLEX_KINDS, KINDS, UnitKind
from ..solving.results import Result
from .money import IN_KEUR, MONEY_TICKS
from .style import (BLUE, CHI_SHADE, FIGURE_HEIGHT, FIGURE_MARGIN, GREEN, GREY, GRID_COLOR, KIND_COLORS, KIND_LABELS,
                    MARKET_COLORS, ORANGE, PURPLE, SERIES_COLORS, SKY, TRANSPARENT, VERMILION, rgba, run_style)
from ..errors import CaseError
from ..uncertainty.bands import realized_values
from ..uncertainty.forecast import band_specs, case_bands, has_forecast

CLOCK_TITLE = "Delivery day, period start (local time)"
HOURS_PER_TICK = 1  # one x tick per clock hour

SOURCE_UNITS = {"price_da": "EUR/MWh", "price_sr_up": "EUR/MW per h", "price_sr_dn": "EUR/MW per h",
                **{kind: info.power_unit for kind, info in KINDS.items()}}
COMPARE_ROWS = (("p_da_mw", "DAM [MW]", "MW"), ("r_sr_up_mw", "SR up [MW]", "MW"),
                ("r_sr_dn_mw", "SR down [MW]", "MW"), ("h_hpa_mw", "HPA heat [MW_th]", "MW_th"))
TRADE_NAMES = {"p_da_mw": "day-ahead energy", "r_sr_up_mw": "up reserve", "r_sr_dn_mw": "down reserve",
               "h_hpa_mw": "heat"}
SOURCE_TITLES = {"price_da": "Day-ahead price", "price_sr_up": "Up-reserve price",
                 "price_sr_dn": "Down-reserve price"}
TOTALS_MARGIN_R = 80  # [px] the reserve figure's day totals: their tilted unit-kind labels reach past the plot
SUBPLOT_TITLE_SIZE = 16  # [px] as make_subplots sets it


# ----------------------------------------------------------------------------- plan figures


def trades_figure(result: Result) -> go.Figure:
    """DAM energy per period (+ sell, − buy) with the SR up and down bands around it [MW]."""
    market = _plan(result).market
    x = _labels(result)
    p, up, dn = (market[c].to_numpy(float) for c in ("p_da_mw", "r_sr_up_mw", "r_sr_dn_mw"))
    band = dict(type="bar", x=x, opacity=0.75, width=0.35, hovertemplate="%{customdata:.2f} MW")
    traces = [
        _bar(x, p, "DAM energy (+ sell, − buy)", MARKET_COLORS["dam"], "%{y:.2f} MW"),
        {**band, "y": up, "base": p, "customdata": up, "name": "SR up band",
         "marker": dict(color=MARKET_COLORS["sr_up"], pattern=dict(shape="/"))},
        {**band, "y": dn, "base": p - dn, "customdata": dn, "name": "SR down band",
         "marker": dict(color=MARKET_COLORS["sr_dn"], pattern=dict(shape="\\"))},
    ]
    layout = _plan_layout(result, "Day-ahead energy and secondary-reserve bands", "Power [MW]")
    return go.Figure(data=traces, layout={**layout, "barmode": "overlay"})


def heat_figure(result: Result) -> go.Figure:
    """Heat supply by CSP plant and HPA purchase, stacked, against the thermal demand [MW_th]."""
    result = _plan(result)
    x = _labels(result)
    plants = _by_unit(result.csp)
    traces = [_bar(x, part["heat_to_td_mw"].to_numpy(float), f"{name} heat", _shade(VERMILION, i, len(plants)),
                   "%{y:.2f} MW_th") for i, (name, part) in enumerate(plants)]
    traces.append(_bar(x, result.market["h_hpa_mw"].to_numpy(float), "HPA purchase", MARKET_COLORS["hpa"],
                       "%{y:.2f} MW_th"))
    traces.append(dict(type="scatter", x=x, y=_kind_sum(result, UnitKind.TD, "p_mw"), name="Thermal demand",
                       mode="lines+markers", line=dict(color=GREEN, width=3), hovertemplate="%{y:.2f} MW_th"))
    layout = _plan_layout(result, "Heat supply against thermal demand", "Heat [MW_th]")
    return go.Figure(data=traces, layout={**layout, "barmode": "stack"})


def dispatch_figure(result: Result) -> go.Figure:
    """Electrical output of every unit (stacked, demands negative) and the DAM position [MW]."""
    result = _plan(result)
    x = _labels(result)
    units = result.units
    traces = []
    for kind in ELECTRIC_KINDS:
        parts = _by_unit(units[units["kind"] == kind])
        sign = float(KINDS[kind].electric_sign)
        color = KIND_COLORS.get(kind, GREY)
        traces += [{**_bar(x, sign * part["p_mw"].to_numpy(float), name, _shade(color, i, len(parts)),
                           "%{y:.2f} MW"), "legendgroup": kind} for i, (name, part) in enumerate(parts)]
    traces.append(dict(type="scatter", x=x, y=result.market["p_da_mw"].to_numpy(float), name="DAM position",
                       mode="lines+markers", line=dict(color=BLUE, width=3), hovertemplate="%{y:.2f} MW"))
    layout = _plan_layout(result, "Electrical dispatch by unit (consumption negative)", "Power [MW]")
    return go.Figure(data=traces, layout={**layout, "barmode": "relative"})


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
    energy = dict(type="scatter", x=x, mode="lines", hovertemplate="%{y:.1f} MWh_th", **cell_axes(1, 1))
    limit = {**energy, "line": dict(color=GREY, dash="dash")}
    power = cell_axes(2, 1)
    traces = [
        {**limit, "y": np.full(n, storage.e_min_mwh_th), "name": "Minimum energy"},
        {**energy, "y": rows["ts_energy_floor_mwh"].to_numpy(float), "name": "Margin kept for up reserve (σ↑)",
         "fill": "tonexty", "fillcolor": rgba(PURPLE, 0.25), "line": dict(color=PURPLE, dash="dot")},
        {**limit, "y": np.full(n, storage.e_max_mwh_th), "name": "Maximum energy"},
        {**energy, "y": rows["ts_energy_ceiling_mwh"].to_numpy(float), "name": "Margin kept for down reserve (σ↓)",
         "fill": "tonexty", "fillcolor": rgba(SKY, 0.25), "line": dict(color=SKY, dash="dot")},
        {**energy, "y": rows["ts_energy_mwh"].to_numpy(float), "name": "Stored energy (end of period)",
         "mode": "lines+markers", "line": dict(color=VERMILION, width=3)},
        {**_bar(x, rows["ts_charge_mw"].to_numpy(float), "Charge", GREEN, "%{y:.2f} MW_th"), **power},
        {**_bar(x, -rows["ts_discharge_mw"].to_numpy(float), "Discharge (negative)", ORANGE, "%{y:.2f} MW_th"),
         **power},
    ]
    grid = subplots_layout(2, 1, shared_xaxes=True, row_heights=(0.68, 0.32), vertical_spacing=0.05)
    layout = _plan_layout(result, f"{name}: thermal storage", None, height=FIGURE_HEIGHT + 120, grid=grid,
                          x_title=False)
    _titled(layout, yaxis="Stored energy [MWh_th]", yaxis2="Power [MW_th]", xaxis2=CLOCK_TITLE)
    return go.Figure(data=traces, layout={**layout, "barmode": "relative"})


def battery_figure(result: Result, battery: str) -> go.Figure:
    """State of charge of one battery: stored energy [MWh] between its limits, the σ margins kept
    for reserve (MODEL_SPEC §13, as TS11), and charge/discharge power [MW] below."""
    result = _plan(result)
    units = {u.name: u for k, u in result.case.units() if k == UnitKind.BATTERY}
    if battery not in units:
        raise ValueError(f"unknown battery {battery!r}; the plan has {', '.join(units) or 'none'}")
    bat = units[battery]
    rows = result.dispatch[result.dispatch["unit"] == battery].sort_values("t")
    x = _labels(result)
    n = len(x)
    energy = dict(type="scatter", x=x, mode="lines", hovertemplate="%{y:.2f} MWh", **cell_axes(1, 1))
    limit = {**energy, "line": dict(color=GREY, dash="dash")}
    power = cell_axes(2, 1)
    traces = [
        {**limit, "y": np.full(n, bat.e_min_mwh), "name": "Minimum energy"},
        {**energy, "y": rows["energy_floor_mwh"].to_numpy(float), "name": "Margin kept for up reserve (σ↑)",
         "fill": "tonexty", "fillcolor": rgba(PURPLE, 0.25), "line": dict(color=PURPLE, dash="dot")},
        {**limit, "y": np.full(n, bat.e_max_mwh), "name": "Maximum energy"},
        {**energy, "y": rows["energy_ceiling_mwh"].to_numpy(float), "name": "Margin kept for down reserve (σ↓)",
         "fill": "tonexty", "fillcolor": rgba(SKY, 0.25), "line": dict(color=SKY, dash="dot")},
        {**energy, "y": rows["energy_mwh"].to_numpy(float), "name": "State of charge (end of period)",
         "mode": "lines+markers", "line": dict(color=VERMILION, width=3)},
        {**_bar(x, rows["charge_mw"].to_numpy(float), "Charge", GREEN, "%{y:.2f} MW"), **power},
        {**_bar(x, -rows["discharge_mw"].to_numpy(float), "Discharge (negative)", ORANGE, "%{y:.2f} MW"), **power},
    ]
    grid = subplots_layout(2, 1, shared_xaxes=True, row_heights=(0.68, 0.32), vertical_spacing=0.05)
    layout = _plan_layout(result, f"{battery}: state of charge", None, height=FIGURE_HEIGHT + 120, grid=grid,
                          x_title=False)
    _titled(layout, yaxis="Stored energy [MWh]", yaxis2="Power [MW]", xaxis2=CLOCK_TITLE)
    return go.Figure(data=traces, layout={**layout, "barmode": "relative"})


def reserve_share_figure(result: Result) -> go.Figure:
    """Up and down reserve by unit kind per period [MW] and in total over the day [MWh]."""
    result = _plan(result)
    x = _labels(result)
    dt_h = result.problem.dt_h
    units = result.units
    kinds = [kind for kind in FLEX_KINDS if (units["kind"] == kind).any()]
    traces = []  # on a 2 × 2 grid: up above down, per period on the left, day totals on the right
    for row, (column, band) in enumerate((("r_up_mw", "r_sr_up_mw"), ("r_dn_mw", "r_sr_dn_mw")), start=1):
        direction = "up" if row == 1 else "down"
        per_period, totals = cell_axes(row, 1, cols=2), cell_axes(row, 2, cols=2)
        sums = {kind: _kind_sum(result, kind, column) for kind in kinds}
        for kind, values in sums.items():
            traces.append({**_bar(x, values, KIND_LABELS[kind], KIND_COLORS[kind],
                                  f"{KIND_LABELS[kind]} {direction}: %{{y:.2f}} MW<extra></extra>"),
                           "legendgroup": kind, "showlegend": row == 1, **per_period})
        traces.append(dict(type="scatter", x=x, y=result.market[band].to_numpy(float), name="SR band offered",
                           mode="lines", legendgroup="band", showlegend=row == 1,
                           line=dict(color=BLUE, width=2, shape="hvh"),
                           hovertemplate=f"offered {direction}: %{{y:.2f}} MW<extra></extra>", **per_period))
        traces.append(dict(type="bar", x=[KIND_LABELS[k] for k in kinds],
                           y=[float(values.sum() * dt_h) for values in sums.values()],
                           marker=dict(color=[KIND_COLORS[k] for k in kinds]), showlegend=False,
                           name=f"{direction} total", hovertemplate="%{x}: %{y:.1f} MWh<extra></extra>", **totals))
    grid = subplots_layout(2, 2, column_widths=(0.78, 0.22), shared_xaxes="columns", horizontal_spacing=0.09,
                           vertical_spacing=0.08)
    layout = _plan_layout(result, "Reserve by unit kind", None, height=FIGURE_HEIGHT + 160, grid=grid,
                          clock_axes=("xaxis", "xaxis3"), x_title=False)
    _titled(layout, yaxis="Up reserve [MW]", yaxis2="Up, day total [MWh]", yaxis3="Down reserve [MW]",
            yaxis4="Down, day total [MWh]", xaxis3=CLOCK_TITLE)
    layout.update(barmode="stack", hovermode="closest", margin={**layout["margin"], "r": TOTALS_MARGIN_R})
    figure = go.Figure(data=traces, layout=layout)
    for direction, band, axes in (("up", "r_sr_up_mw", ("x", "y", "x2", "y2", "yaxis", "yaxis2")),
                                  ("down", "r_sr_dn_mw", ("x3", "y3", "x4", "y4", "yaxis3", "yaxis4"))):
        if not result.market[band].to_numpy(float).any():  # both empty panels say so, from 0, not −1 to 1
            figure.add_annotation(text=f"No {direction} reserve in this plan", xref=f"{axes[0]} domain",
                                  yref=f"{axes[1]} domain", x=0.5, y=0.5, showarrow=False)
            figure.add_annotation(text="0 MWh", xref=f"{axes[2]} domain", yref=f"{axes[3]} domain", x=0.5, y=0.5,
                                  showarrow=False)
            figure.update_layout({axes[4]: {"range": [0, 1]}, axes[5]: {"range": [0, 1]}})
    return figure


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
    line = dict(type="scatter", x=x, mode="lines", hovertemplate=f"%{{y:.2f}} {unit}")
    traces = [
        {**line, "y": hi, "name": f"{names[0]} ({_percent(q.q_hi)})", "line": dict(color=color, width=1)},
        {**line, "y": lo, "name": f"{names[1]} ({_percent(q.q_lo)})", "line": dict(color=color, width=1),
         "fill": "tonexty", "fillcolor": rgba(color, 0.22)},
        {**line, "y": mid, "name": names[2], "line": dict(color=color, width=3, dash="dash")},
    ]
    if compare is not None:
        label, other_lo, other_hi = compare
        traces += [{**line, "y": np.asarray(values, float), "name": name, "line": dict(color=GREY, width=2, dash="dot")}
                   for name, values in ((f"{label}: upper", other_hi), (f"{label}: lower", other_lo))]
    if realized is not None:
        traces.append({**line, "y": np.asarray(realized, float), "name": "Realized", "mode": "lines+markers",
                       "line": dict(color=PURPLE if color == ORANGE else ORANGE, width=2), "marker": dict(size=5),
                       "hovertemplate": f"realized %{{y:.2f}} {unit}"})
    shapes = []
    if chi is not None:
        chi = np.asarray(chi, dtype=float)
        if len(chi) != problem.nt:
            raise ValueError(f"chi has {len(chi)} values for {problem.nt} periods")
        adverse = np.where(chi < 0, hi, hi if src.kind is SourceKind.CONSUMPTION else lo)
        marked = np.flatnonzero(chi != 0)
        shapes = [dict(type="rect", xref="x", yref="y domain", x0=t - 0.5, x1=t + 0.5, y0=0, y1=1,
                       fillcolor=CHI_SHADE, line=dict(width=0), layer="below") for t in marked]
        if not src.is_price:
            traces.append({**line, "y": np.where(chi != 0, adverse, src.nominal), "name": "Bound the plan respects",
                           "line": dict(color=VERMILION, width=2, shape="hvh")})
        traces.append(dict(type="scatter", x=[x[t] for t in marked], y=adverse[marked],
                           name=f"Deviates (χ = 1) in {len(marked)} periods", mode="markers",
                           marker=dict(color=VERMILION, size=11, symbol="x"),
                           hovertemplate=f"deviates to %{{y:.2f}} {unit}"))
    title = SOURCE_TITLES[source] if src.is_price else f"{source} ({KIND_LABELS[src.unit_kind].lower()})"
    kind_of_band = "forecast band" if method == "climatology" else "forecast-error band"
    layout = _clock_layout(problem.labels, problem.dt_h, f"{title}: {kind_of_band}", _source_axis(source, src, unit))
    return go.Figure(data=traces, layout={**layout, "shapes": shapes} if shapes else layout)


def band_overlays(problem: Problem, source: str) -> dict:
    """What :func:`bands_figure` can draw beside a source's band: the other method's band
    (``compare``, where that method applies) and the delivery day's observed values
    (``realized``, where the history covers the day)."""

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
                                   case.timezone, {source: (spec.low, spec.high)})
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
    table = result.csp if src.unit_kind == UnitKind.CSP else result.units
    rows = table[table["unit"] == source].sort_values("t")
    return rows["chi"].to_numpy(dtype=float, na_value=0.0)


# ----------------------------------------------------------------------------- teaching and comparison


def exposure_figure(result: Result, source: str, gamma: int) -> go.Figure:
    """Per-period loss if ``source``'s price moves adversely [kEUR]; the Γ worst periods highlighted.

    Their sum is the price protection (Bertsimas & Sim 2004; MODEL_SPEC §4).
    """
    result = _plan(result)
    exposure = IN_KEUR.of(price_exposures(result.problem, result.market)[source])
    worst = _top_periods(exposure, gamma)
    protection = protection_exact(exposure, gamma)
    x = _labels(result)
    hover = f"%{{y:{IN_KEUR.hover}}} kEUR"
    traces = [_bar(x, np.where(worst, 0.0, exposure), "Possible loss", GREY, hover),
              _bar(x, np.where(worst, exposure, 0.0), f"Picked by the adversary (Γ = {gamma})", VERMILION, hover)]
    title = f"{SOURCE_TITLES[source]}: loss per period, protection {protection:,.1f} kEUR"
    layout = _plan_layout(result, title, "Loss if the price moves adversely [kEUR]")
    layout["yaxis"].update(MONEY_TICKS)
    return go.Figure(data=traces, layout={**layout, "barmode": "stack"})


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
    traces = []
    for i, (label, result) in enumerate(plans.items()):
        look = run_style(label, i)
        traces += [dict(type="scatter", x=_labels(result), y=result.market[column].to_numpy(float), name=label,
                        legendgroup=label, showlegend=row == 1, mode="lines+markers",
                        line=dict(color=look["color"], width=2, shape="hvh", dash=look["dash"]),
                        marker=dict(size=6, symbol=look["symbol"]),
                        hovertemplate=f"{label}: %{{y:.2f}} {unit}<extra></extra>", **cell_axes(row, 1))
                   for row, (column, _, unit) in enumerate(rows, start=1)]
    grid = subplots_layout(len(rows), 1, shared_xaxes=True, vertical_spacing=0.06)
    layout = _plan_layout(first, "Trades of each plan", None, height=FIGURE_HEIGHT + 95 * len(rows), grid=grid,
                          x_title=False)
    _titled(layout, **{_axis_name(cell_axes(row, 1)["yaxis"]): axis for row, (_, axis, _) in enumerate(rows, start=1)})
    _titled(layout, **{_axis_name(cell_axes(len(rows), 1)["xaxis"]): CLOCK_TITLE})
    return go.Figure(data=traces, layout=layout)


def idle_trades(results: Mapping[str, Result]) -> list[str]:
    """Columns of :data:`COMPARE_ROWS` that are zero in every period of every plan."""
    return [column for column, _, _ in COMPARE_ROWS
            if all(np.allclose(r.market[column].to_numpy(float), 0.0) for r in results.values() if r.has_plan)]


def robustness_figure(points: pd.DataFrame) -> go.Figure:
    """Price of robustness: cost [kEUR] and price protection [kEUR] against the budget Γ.

    ``points`` has columns ``gamma``, ``cost_keur`` and ``protection_keur``.
    """
    line = dict(type="scatter", x=points["gamma"], mode="lines+markers", hovertemplate="Γ = %{x}: %{y:.1f} kEUR")
    traces = [{**line, "y": points["cost_keur"], "name": "Cost (−profit)", "line": dict(color=VERMILION, width=3)},
              {**line, "y": points["protection_keur"], "name": "Price protection in the cost",
               "line": dict(color=BLUE, width=2, dash="dash")}]
    layout = dict(title=dict(text="Price of robustness"), height=FIGURE_HEIGHT, paper_bgcolor=TRANSPARENT,
                  plot_bgcolor=TRANSPARENT, hovermode="x unified", legend=_legend(),
                  xaxis=dict(title=dict(text="Budget Γ of every source [periods]"), gridcolor=GRID_COLOR, dtick=2),
                  yaxis=dict(title=dict(text="Cost [kEUR]"), gridcolor=GRID_COLOR, zerolinecolor=GRID_COLOR))
    return go.Figure(data=traces, layout=layout)


def curve_figure(breakpoints: Sequence[Sequence[float]], p_el_max_mw: float) -> go.Figure:
    """Power-block conversion: electrical output [MW] against thermal input [MW_th]."""
    inputs = np.array([p for p, _ in breakpoints], dtype=float)
    output = np.array([p * eta for p, eta in breakpoints], dtype=float)
    traces = [dict(type="scatter", x=inputs, y=output, name="Output at the breakpoints", mode="lines+markers",
                   line=dict(color=VERMILION, width=3), hovertemplate="%{x:.2f} MW_th → %{y:.2f} MW<extra></extra>"),
              dict(type="scatter", x=[inputs[0], inputs[-1]], y=[p_el_max_mw, p_el_max_mw], name="Turbine nameplate",
                   mode="lines", line=dict(color=GREY, dash="dash"), hovertemplate="%{y:.1f} MW<extra></extra>")]
    layout = dict(title=dict(text="Power-block conversion curve"), height=FIGURE_HEIGHT - 80, legend=_legend(),
                  paper_bgcolor=TRANSPARENT, plot_bgcolor=TRANSPARENT,
                  xaxis=dict(title=dict(text="Thermal input [MW_th]"), gridcolor=GRID_COLOR),
                  yaxis=dict(title=dict(text="Electrical output [MW]"), gridcolor=GRID_COLOR, zerolinecolor=GRID_COLOR))
    return go.Figure(data=traces, layout=layout)


def tariff_figure(problem: Problem) -> go.Figure:
    """HPA tariff per period [EUR/MWh_th]."""
    tariff = dict(type="scatter", x=problem.labels, y=problem.tariff_hpa, name="HPA tariff", mode="lines+markers",
                  line=dict(color=GREEN, width=3, shape="hvh"), hovertemplate="%{y:.1f} EUR/MWh_th")
    layout = _clock_layout(problem.labels, problem.dt_h, "Heat purchase agreement tariff", "Tariff [EUR/MWh_th]")
    return go.Figure(data=[tariff], layout=layout)


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
    """Each unit's rows in period order, the units in the table's order (none for an empty
    table, which may lack the columns: a case without CSP plants)."""
    if table.empty:
        return []
    return [(name, part.sort_values("t")) for name, part in table.groupby("unit", sort=False)]


def _kind_sum(result: Result, kind: str, column: str) -> np.ndarray:
    """``column`` summed over the units of ``kind``, per period (zero without such units)."""
    units = result.units
    part = units[units["kind"] == kind]
    return np.bincount(part["t"].to_numpy(int) - 1, weights=part[column].to_numpy(float), minlength=result.problem.nt)


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
    if src.kind is SourceKind.PRICE_DA:
        return src.nominal - src.deviation, mid, src.nominal + src.deviation_up
    if src.kind is SourceKind.CONSUMPTION:
        return src.nominal, mid, src.nominal + src.deviation
    return src.nominal - src.deviation, np.minimum(mid, src.nominal), src.nominal


def _source_unit(problem: Problem, source: str) -> str:
    src = problem.sources[source]
    return SOURCE_UNITS[source] if src.is_price else SOURCE_UNITS[src.unit_kind]


def _source_axis(source: str, src, unit: str) -> str:
    if src.is_price:
        return f"Price [{unit}]"
    if src.unit_kind == UnitKind.CSP:
        return f"Solar-field heat available [{unit}]"
    if src.kind is SourceKind.CONSUMPTION:
        return f"Consumption [{unit}]"
    return f"Available power [{unit}]"


def _percent(q: float) -> str:
    return f"{q * 100:g}th"


def _legend() -> dict:
    return dict(orientation="h", yanchor="bottom", y=1.02, xanchor="left", x=0, title=dict(text=""),
                traceorder="normal")


def _bar(x, y, name: str, color: str, hover: str) -> dict:
    """A bar trace of one colour."""
    return dict(type="bar", x=x, y=y, name=name, marker=dict(color=color), hovertemplate=hover)


def _plan_layout(result: Result, title: str, y_title: str | None, **options) -> dict:
    """:func:`_clock_layout` on the delivery day of ``result``."""
    return _clock_layout(_labels(result), result.problem.dt_h, title, y_title, **options)


def _clock_layout(labels: list[str], dt_h: float, title: str, y_title: str | None, height: int = FIGURE_HEIGHT,
                  grid: dict | None = None, clock_axes: Sequence[str] | None = None, x_title: bool = True) -> dict:
    """Shared look, as a layout: clock-hour categories on x, unit-labelled y, transparent
    background; on one plot, or on the subplots of ``grid`` (:func:`subplots_layout`),
    which is filled in and returned (pass a fresh one).

    ``clock_axes`` limits the clock to some x axes (``"xaxis3"``; all by default);
    ``x_title=False`` leaves the x titles to the caller (subplots title only their bottom axis).
    """
    step = max(1, int(round(HOURS_PER_TICK / dt_h)))
    ticks = labels[::step]
    clock = dict(type="category", categoryorder="array", categoryarray=labels, tickmode="array", tickvals=ticks,
                 ticktext=ticks, tickangle=-45)
    layout = grid if grid is not None else {"xaxis": {}, "yaxis": {}}
    for name, axis in layout.items():
        if name.startswith("xaxis"):
            axis.update(clock if clock_axes is None or name in clock_axes else {}, gridcolor=GRID_COLOR)
            if x_title:
                axis["title"] = {"text": CLOCK_TITLE}
        elif name.startswith("yaxis"):
            axis.update(gridcolor=GRID_COLOR, zerolinecolor=GRID_COLOR)
            if y_title:
                axis["title"] = {"text": y_title}
    layout.update(title=dict(text=title, y=0.98, yanchor="top"), height=height, hovermode="x unified",
                  paper_bgcolor=TRANSPARENT, plot_bgcolor=TRANSPARENT, legend=_legend(), margin=dict(FIGURE_MARGIN))
    return layout


def subplots_layout(rows: int, cols: int, *, horizontal_spacing: float = 0.0, vertical_spacing: float = 0.0,
                    column_widths: Sequence[float] | None = None, row_heights: Sequence[float] | None = None,
                    shared_xaxes: bool | str = False, shared_yaxes: bool = False,
                    subplot_titles: Sequence[str] | None = None) -> dict:
    """The layout of a grid of subplots, as plain data for a figure built from dicts: the
    axis domains and anchors, shared axes and subplot titles that Plotly's ``make_subplots``
    gives for the same arguments (its arithmetic; ``tests/test_plots.py`` checks they agree).

    ``make_subplots`` builds and checks a whole figure for it, 40 ms a grid the first time.
    Shared x axes follow the bottom plot of their column and lose their tick labels
    (``shared_xaxes`` is ``True`` or ``"columns"``); shared y axes follow the first plot of
    their row.
    """
    widths = _spans(cols, horizontal_spacing, column_widths)
    heights = _spans(rows, vertical_spacing, row_heights)[::-1]  # from the bottom row up
    layout: dict = {}
    titles = []
    for row in range(rows):
        from_bottom = rows - 1 - row
        y = sum(heights[:from_bottom]) + from_bottom * vertical_spacing
        y_domain = [y, min(y + heights[from_bottom], 1.0)]
        for col in range(cols):
            x = sum(widths[:col]) + col * horizontal_spacing
            x_domain = [x, x + widths[col]]
            axes = cell_axes(row + 1, col + 1, cols)
            layout[_axis_name(axes["xaxis"])] = {"anchor": axes["yaxis"], "domain": x_domain}
            layout[_axis_name(axes["yaxis"])] = {"anchor": axes["xaxis"], "domain": list(y_domain)}
            title = subplot_titles[row * cols + col] if subplot_titles else None
            if title:
                titles.append({"font": {"size": SUBPLOT_TITLE_SIZE}, "showarrow": False, "text": title,
                               "x": sum(x_domain) / 2.0, "xanchor": "center", "xref": "paper",
                               "y": y_domain[1], "yanchor": "bottom", "yref": "paper"})
    for row in range(1, rows if shared_xaxes else 1):
        for col in range(1, cols + 1):
            _share(layout[_axis_name(cell_axes(row, col, cols)["xaxis"])], cell_axes(rows, col, cols)["xaxis"])
    for row in range(1, rows + 1 if shared_yaxes else 1):
        for col in range(2, cols + 1):
            _share(layout[_axis_name(cell_axes(row, col, cols)["yaxis"])], cell_axes(row, 1, cols)["yaxis"])
    if titles:
        layout["annotations"] = titles
    return layout


def _spans(count: int, spacing: float, weights: Sequence[float] | None) -> list[float]:
    """Widths (or heights) of ``count`` subplots between ``spacing`` gaps, in proportion to
    ``weights`` (equal without), as ``make_subplots`` computes them."""
    if weights is None:
        return [(1.0 - spacing * (count - 1)) / count] * count
    total = float(sum(weights))
    return [(1.0 - spacing * (count - 1)) * (w / total) for w in weights]


def _share(axis: dict, leader: str) -> None:
    """Make ``axis`` follow the axis ``leader`` (``"x3"``), without tick labels of its own."""
    axis.update(matches=leader, showticklabels=False)


def cell_axes(row: int, col: int, cols: int = 1) -> dict:
    """The axes of a trace in the subplot at ``row``, ``col`` of a grid ``cols`` wide (as
    ``make_subplots`` numbers them: row by row, ``x`` and ``y`` first)."""
    n = (row - 1) * cols + col
    suffix = "" if n == 1 else str(n)
    return {"xaxis": f"x{suffix}", "yaxis": f"y{suffix}"}


def _axis_name(reference: str) -> str:
    """The layout's name of the axis a trace refers to: ``"y2"`` → ``"yaxis2"``."""
    return f"{reference[0]}axis{reference[1:]}"


def _titled(layout: dict, **titles: str) -> None:
    """Title the axes of ``layout`` named in ``titles`` (``yaxis2="Power [MW_th]"``)."""
    for axis, text in titles.items():
        layout[axis]["title"] = {"text": text}


def _shade(color: str, i: int, n: int) -> str:
    """``color`` made darker or lighter so ``n`` units of one kind stay distinguishable."""
    if n <= 1:
        return color
    amount = -0.35 + 0.7 * i / (n - 1)  # −: towards black, +: towards white
    rgb = np.array([int(color[k:k + 2], 16) for k in (1, 3, 5)], dtype=float)
    target = 255.0 if amount > 0 else 0.0
    mixed = rgb + (target - rgb) * abs(amount)
    return "#" + "".join(f"{int(round(v)):02X}" for v in mixed)
