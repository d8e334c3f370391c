"""The day's economics of a plan: where the objective comes from, and why its sign.

The objective (MODEL_SPEC §3) is

    net = DAM revenue + SR revenue − HPA cost − operating cost − price protection  [EUR]

and it is often negative: the VPP is not only a seller. It serves its own electrical
demands and thermal demands first, pays the O&M of everything it runs and buys heat
through the HPA, so a day can be a net cost even when the markets pay well. A plan's
:class:`DayEconomics` holds the parts with the energy served, :func:`explanation`
says it in one line, and :func:`waterfall_figure` draws it (one panel per plan).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import plotly.graph_objects as go

from ..data.kinds import UnitKind
from ..solving.results import Result
from .plots import cell_axes, subplots_layout
from .style import FIGURE_HEIGHT, FIGURE_MARGIN, GAIN_COLOR, GRID_COLOR, LOSS_COLOR, NET_COLOR, TRANSPARENT

KILO = 1000.0
NAMES_MARGIN_B = {"full": 110, "short": 92}  # [px] below a waterfall for its tilted part names
SHORT = {"DAM revenue": "DAM", "SR revenue": "SR", "HPA cost": "HPA", "Operating cost": "O&M",
         "Robust protection": "Protection", "Net cost": "Net cost"}  # step names in narrow panels


@dataclass(frozen=True)
class DayEconomics:
    """The parts of a plan's objective [EUR] and what the VPP serves and trades over the day."""

    revenue_dam_eur: float
    revenue_sr_eur: float
    cost_hpa_eur: float
    cost_opex_eur: float
    protection_eur: float
    demand_mwh: float        # electricity consumed by the VPP's own demands [MWh]
    heat_mwh_th: float       # heat delivered to its thermal demands [MWh_th]
    sold_mwh: float          # DAM energy sold [MWh]
    bought_mwh: float        # DAM energy bought [MWh]
    heat_bought_mwh_th: float  # heat bought through the HPA [MWh_th]
    heat_kept_eur: float = 0.0  # value of the heat kept in the tank past midnight (case's end value)

    @property
    def net_eur(self) -> float:
        """The objective: revenues minus costs minus the price protection, plus the heat kept [EUR]."""
        return (self.revenue_dam_eur + self.revenue_sr_eur - self.cost_hpa_eur - self.cost_opex_eur
                - self.protection_eur + self.heat_kept_eur)

    @property
    def served_mwh(self) -> float:
        """Electricity and heat served to the VPP's own demands [MWh + MWh_th]."""
        return self.demand_mwh + self.heat_mwh_th

    @property
    def net_cost_per_mwh(self) -> float | None:
        """−net per MWh served [EUR/MWh]; ``None`` when nothing is served."""
        return -self.net_eur / self.served_mwh if self.served_mwh > 0 else None

    def steps(self) -> dict[str, float]:
        """Signed contributions to the objective [EUR], in the order of the waterfall, then the net."""
        return {"DAM revenue": self.revenue_dam_eur, "SR revenue": self.revenue_sr_eur,
                "HPA cost": -self.cost_hpa_eur, "Operating cost": -self.cost_opex_eur,
                "Robust protection": -self.protection_eur,
                **({"Heat kept": self.heat_kept_eur} if self.heat_kept_eur else {}), "Net": self.net_eur}


def economics(result: Result) -> DayEconomics:
    """The day's economics of a solved plan."""
    if not result.has_plan:
        raise ValueError(f"the result has no plan (status {result.status}: {result.message})")
    dt_h = result.problem.dt_h
    units, market = result.units, result.market
    p_da = market["p_da_mw"].to_numpy(float)
    parts = result.parts
    return DayEconomics(
        revenue_dam_eur=parts.get("revenue_dam_eur", 0.0), revenue_sr_eur=parts.get("revenue_sr_eur", 0.0),
        cost_hpa_eur=parts.get("cost_hpa_eur", 0.0), cost_opex_eur=parts.get("cost_opex_eur", 0.0),
        protection_eur=sum(result.protection_eur.values()),
        demand_mwh=float(units.loc[units["kind"] == UnitKind.ED, "p_mw"].sum() * dt_h),
        heat_mwh_th=float(units.loc[units["kind"] == UnitKind.TD, "p_mw"].sum() * dt_h),
        sold_mwh=float(p_da.clip(min=0).sum() * dt_h), bought_mwh=float(-p_da.clip(max=0).sum() * dt_h),
        heat_bought_mwh_th=float(market["h_hpa_mw"].sum() * dt_h),
        heat_kept_eur=parts.get("value_heat_kept_eur", 0.0))


def explanation(day: DayEconomics) -> str:
    """One line on the sign of the objective, e.g. ``"A net cost of 43.7 kEUR: the VPP serves
    2,000 MWh of its own demand and 1,400 MWh_th of heat; the net cost per MWh served is
    12.8 EUR."``"""
    net = day.net_eur
    served = (f"the VPP serves {day.demand_mwh:,.0f} MWh of its own demand and {day.heat_mwh_th:,.0f} MWh_th "
              "of heat")
    if day.heat_bought_mwh_th > 0:
        served += f" ({day.heat_bought_mwh_th:,.0f} MWh_th of it bought through the HPA)"
    earned = day.revenue_dam_eur + day.revenue_sr_eur
    paid = day.cost_hpa_eur + day.cost_opex_eur + day.protection_eur
    if net < 0 and earned < 0:  # the markets cost money too: no "revenues of −5.8 kEUR"
        head = (f"A net cost of {-net / KILO:,.1f} kEUR: the markets cost {-earned / KILO:,.1f} kEUR (the plant buys "
                f"more than it sells) on top of {paid / KILO:,.1f} kEUR of operating cost, heat and protection, "
                f"because {served}")
    elif net < 0:
        head = (f"A net cost of {-net / KILO:,.1f} kEUR: market revenues of {earned / KILO:,.1f} kEUR do not cover "
                f"{paid / KILO:,.1f} kEUR of operating cost, heat and protection, because {served}")
    else:
        head = (f"A net profit of {net / KILO:,.1f} kEUR: market revenues of {earned / KILO:,.1f} kEUR cover "
                f"{paid / KILO:,.1f} kEUR of operating cost, heat and protection while {served}")
    per = day.net_cost_per_mwh
    if per is None:
        return head + "."
    word = "net cost" if per >= 0 else "net profit"
    return f"{head}; the {word} per MWh served is {abs(per):,.1f} EUR.".replace("-", "−")


def waterfall_figure(results: Mapping[str, Result]) -> go.Figure:
    """The parts of each plan's net cost as a waterfall [kEUR], one panel per plan, in the
    dashboard's one money convention: a cost is positive when the plant pays.

    Revenues go down (they lower the cost), costs and the robust protection go up, the
    last bar is the net cost (minus the objective); every bar carries its signed value, so
    colour is not needed to read it.
    """
    if not results:
        raise ValueError("no plans to draw")
    labels = list(results)
    naming = "full" if len(labels) == 1 else "short"
    traces = []
    for col, label in enumerate(labels, start=1):
        steps = {("Net cost" if name == "Net" else name): -value
                 for name, value in economics(results[label]).steps().items()}
        values = [v / KILO for v in steps.values()]
        traces.append(dict(
            type="waterfall", x=list(steps) if naming == "full" else [SHORT[k] for k in steps], y=values,
            measure=["relative"] * (len(steps) - 1) + ["total"], name=label,
            text=[f"{v:+,.1f}".replace("-", "−") for v in values], textposition="outside", cliponaxis=False,
            increasing={"marker": {"color": LOSS_COLOR}}, decreasing={"marker": {"color": GAIN_COLOR}},
            totals={"marker": {"color": NET_COLOR}}, connector={"line": {"color": GRID_COLOR}},
            hovertemplate="%{x}: %{y:+,.1f} kEUR<extra>" + label + "</extra>", showlegend=False,
            **cell_axes(1, col, cols=len(labels))))
    layout = subplots_layout(1, len(labels), shared_yaxes=True, horizontal_spacing=0.03,
                             subplot_titles=labels if len(labels) > 1 else None)
    for name, axis in layout.items():
        if name.startswith("xaxis"):
            axis.update(title={"text": "Part of the net cost"}, gridcolor=GRID_COLOR, tickangle=-30)
        elif name.startswith("yaxis"):
            axis.update(gridcolor=GRID_COLOR, zerolinecolor=GRID_COLOR)
    layout["yaxis"]["title"] = {"text": "Cost [kEUR], positive: the plant pays"}
    title = "The day's economics, part by part" + (
        f" ({labels[0]})" if len(labels) == 1 else "")
    layout.update(title=dict(text=title, y=0.98, yanchor="top"), height=FIGURE_HEIGHT + 40,
                  paper_bgcolor=TRANSPARENT, plot_bgcolor=TRANSPARENT,
                  margin={**FIGURE_MARGIN, "b": NAMES_MARGIN_B[naming]})
    return go.Figure(data=traces, layout=layout)
