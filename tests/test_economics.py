"""The day's economics: parts that add up to the objective, energy served, and the waterfall."""

from __future__ import annotations

import numpy as np
import pytest

from rvpp.outputs.economics import economics, explanation, waterfall_figure


@pytest.fixture(scope="module")
def balanced(paper_solve):
    result = paper_solve(strategy="balanced")
    assert result.status == "optimal"
    return result


def test_the_parts_add_up_to_the_objective(balanced):
    day = economics(balanced)
    assert day.net_eur == pytest.approx(balanced.objective_eur, abs=1e-3)
    steps = day.steps()
    assert sum(v for k, v in steps.items() if k != "Net") == pytest.approx(balanced.objective_eur, abs=1e-3)
    assert steps["Robust protection"] == pytest.approx(-sum(balanced.protection_eur.values()))


def test_energy_served_is_the_demands_over_the_day(balanced, paper_case):
    day = economics(balanced)
    units = balanced.units
    # Independent sums: every electrical demand's and thermal demand's power over 24 one-hour periods.
    ed = sum(units[units["unit"] == d.name]["p_mw"].sum() for d in paper_case.ed)
    td = sum(units[units["unit"] == d.name]["p_mw"].sum() for d in paper_case.td)
    assert day.demand_mwh == pytest.approx(ed) and day.heat_mwh_th == pytest.approx(td)
    assert day.demand_mwh >= sum(d.e_min_mwh for d in paper_case.ed) - 1e-6
    p = balanced.market["p_da_mw"].to_numpy()
    assert day.sold_mwh - day.bought_mwh == pytest.approx(p.sum())
    assert day.net_cost_per_mwh == pytest.approx(-balanced.objective_eur / (ed + td))


def test_the_explanation_states_the_sign_and_the_cost_per_mwh(balanced):
    day = economics(balanced)
    line = explanation(day)
    assert balanced.objective_eur < 0
    assert line.startswith(f"A net cost of {-balanced.objective_eur / 1000:,.1f} kEUR")
    assert f"{day.demand_mwh:,.0f} MWh of its own demand" in line
    assert f"net cost per MWh served is {-balanced.objective_eur / day.served_mwh:,.1f} EUR" in line


def test_a_day_whose_markets_cost_money_is_not_said_to_have_negative_revenues(paper_solve):
    # 1 June, pessimistic: the plan buys more than it sells and Results read "market revenues of −5.8 kEUR do
    # not cover 76.7 kEUR of operating cost": a revenue below zero that "does not cover" a cost.
    result = paper_solve(strategy="pessimistic", date="2025-06-01")
    parts = result.parts
    markets = parts["revenue_dam_eur"] + parts["revenue_sr_eur"]
    assert markets < 0  # by hand: this day's DAM and SR revenues sum to a cost
    costs = parts["cost_hpa_eur"] + parts["cost_opex_eur"] + sum(result.protection_eur.values())
    line = explanation(economics(result))
    assert line.startswith(f"A net cost of {-result.objective_eur / 1000:,.1f} kEUR: the markets cost "
                           f"{-markets / 1000:,.1f} kEUR (the plant buys more than it sells) on top of "
                           f"{costs / 1000:,.1f} kEUR of operating cost, heat and protection"), line
    assert "revenues of −" not in line


def test_the_waterfall_ends_at_the_net_cost(balanced, paper_solve):
    fig = waterfall_figure({"balanced": balanced})
    [trace] = fig.data
    assert list(trace.x) == ["DAM revenue", "SR revenue", "HPA cost", "Operating cost", "Robust protection",
                             "Net cost"]
    assert list(trace.measure) == ["relative"] * 5 + ["total"]
    values = np.asarray(trace.y, float)
    parts = balanced.parts
    # A cost is positive when the plant pays: revenues count negative, costs and protection positive.
    assert values[0] == pytest.approx(-parts["revenue_dam_eur"] / 1000)
    assert values[2] == pytest.approx(parts["cost_hpa_eur"] / 1000)
    assert values[:5].sum() == pytest.approx(values[5]) == pytest.approx(-balanced.objective_eur / 1000)
    assert fig.layout.title.text.startswith("The day's economics")
    assert fig.layout.yaxis.title.text.startswith("Cost [kEUR]") and fig.layout.xaxis.title.text
    two = waterfall_figure({"balanced": balanced, "deterministic": paper_solve(strategy="deterministic")})
    assert len(two.data) == 2 and [a.text for a in two.layout.annotations] == ["balanced", "deterministic"]
