"""The CSP builders' implied bounds (rvpp/model/csp.py) on hand-derived numbers, and against
the independent reference model (tests/reference_model.py), which has none of them."""

from __future__ import annotations

import pytest

from rvpp import audit_result, solve, with_options
from rvpp.model.csp import reserve_share_limits
from tests.factories import with_storage
from tests.reference_model import reference_optimum

# The paper case's tank: Emin 110, Emax 1,100 MWh_th (ΔE = 990), P̄ch 140, P̄dis 115 MW_th,
# η_ch = η_dis = 0.95.
SPAN = 990.0


def storage(paper_case, **changes):
    return with_storage(paper_case, **changes).csp[0].storage


def test_an_empty_tank_without_sun_in_its_first_period_holds_no_up_reserve(paper_case):
    # e[1] ≤ 110 + 0.95·0·1 = 110 = Emin, so σ↑ = 0; e[1] ≥ 110 − 115/0.95 leaves σ↓ ≤ 1.
    assert reserve_share_limits(storage(paper_case, e_init_mwh_th=110.0), 0.0, 1.0) == (0.0, 1.0)


def test_sun_in_the_first_period_bounds_the_up_share_by_what_it_can_charge(paper_case):
    ts = storage(paper_case, e_init_mwh_th=110.0)
    # hourly, 100 MW_th of field: e[1] ≤ 110 + 0.95·100 = 205, σ↑ ≤ 95/990.
    assert reserve_share_limits(ts, 100.0, 1.0)[0] == pytest.approx(95.0 / SPAN)
    # 15 minutes, 300 MW_th of field but P̄ch = 140: e[1] ≤ 110 + 0.95·140·0.25 = 143.25.
    assert reserve_share_limits(ts, 300.0, 0.25)[0] == pytest.approx(33.25 / SPAN)


def test_a_full_tank_bounds_the_down_share_by_one_period_of_discharge(paper_case):
    # e[1] ≥ 1100 − 115/0.95 = 978.947..., σ↓ ≤ (1100 − 978.947)/990 = 0.12228; σ↑ ≤ 1.
    up, dn = reserve_share_limits(storage(paper_case, e_init_mwh_th=1100.0), 0.0, 1.0)
    assert up == 1.0
    assert dn == pytest.approx((115.0 / 0.95) / SPAN)
    assert dn == pytest.approx(0.122275, abs=1e-6)


def test_a_cyclic_day_has_no_implied_share_bound(paper_case):
    assert reserve_share_limits(storage(paper_case, e_init_mwh_th=None), 0.0, 1.0) == (1.0, 1.0)


@pytest.mark.parametrize(("e_init", "strategy"), [(110.0, "optimistic"), (160.0, "balanced"), (1100.0, "balanced")])
def test_the_bounds_keep_the_reference_optimum(paper_case, e_init, strategy):
    """Empty (up scenario tied to the nominal one), partly filled (σ↑ ≤ 50/990) and full
    (σ↓ bounded) starts: rvpp's optimum equals the reference's, which has no such bounds.
    (tests/test_reference.py compares an empty start at 15 minutes.)"""
    case = with_options(with_storage(paper_case, e_init_mwh_th=e_init), strategy=strategy, date="2025-05-05",
                        rel_gap=1e-7)
    result = solve(case)
    assert result.status == "optimal", result.message
    reference = reference_optimum(case)
    assert abs(result.objective_eur - reference) <= 1e-6 * max(1.0, abs(reference)), (result.objective_eur, reference)


def _twins(case, n: int = 2):
    """``case`` with ``n`` copies of its CSP, each following the original's solar series."""
    csp = case.csp[0]
    copies = [csp.model_copy(update={"name": f"{csp.name}_{i}", "solar_field": csp.solar_field.model_copy(
        update={"series": csp.column})}) for i in range(1, n)]
    return case.replace(csp=[csp, *copies])


def test_identical_csps_are_paired_and_budgets_that_differ_part_them(paper_case):
    from rvpp.model.csp import identical_csp_pairs
    from rvpp.uncertainty.problem import prepare

    case = _twins(with_options(paper_case, strategy="balanced"), 3)
    names = [c.name for c in case.csp]
    assert identical_csp_pairs(prepare(case)) == [(names[0], names[1]), (names[1], names[2])]
    # A different budget for the last plant's field leaves only the first two interchangeable.
    uneven = with_options(case, gammas={names[2]: 0})
    assert identical_csp_pairs(prepare(uneven)) == [(names[0], names[1])]
    # A different tank parts them as well.
    tanks = case.replace(csp=[case.csp[0], with_storage(case.replace(csp=[case.csp[1]]), e_min_mwh_th=100.0).csp[0]])
    assert identical_csp_pairs(prepare(tanks)) == []


@pytest.mark.slow
@pytest.mark.parametrize("strategy", ["deterministic", "balanced"])
def test_ordering_identical_csps_keeps_the_reference_optimum(paper_case, strategy):
    """Two interchangeable CSPs: rvpp orders them by hours online; the reference model,
    which has no such order, reaches the same optimum, and the plan honours the order."""
    case = _twins(with_options(paper_case, strategy=strategy, date="2025-05-05", rel_gap=1e-7))
    result = solve(case)
    assert result.status == "optimal", result.message
    reference = reference_optimum(case)
    assert abs(result.objective_eur - reference) <= 1e-6 * max(1.0, abs(reference)), (result.objective_eur, reference)
    hours = result.csp.groupby("unit")["online"].sum()
    assert hours[case.csp[0].name] >= hours[case.csp[1].name]


def test_heat_kept_past_midnight_is_worth_its_end_value(paper_case):
    """A value for the heat left in the tank (``end_value_eur_per_mwh_th``) makes the plan carry heat
    past midnight; the objective gains exactly that value, and no more cash than the plan without it."""
    day = dict(strategy="deterministic", date="2025-05-05")
    plain = solve(with_options(with_storage(paper_case, e_init_mwh_th=110.0), **day))
    valued = solve(with_options(with_storage(paper_case, e_init_mwh_th=110.0, end_value_eur_per_mwh_th=66.5), **day))
    assert plain.status == valued.status == "optimal"
    end = {name: r.csp["ts_energy_mwh"].to_numpy()[-1] for name, r in (("plain", plain), ("valued", valued))}
    assert end["plain"] == pytest.approx(110.0, abs=1e-6)  # without a value, every MWh_th is used or sold today
    assert end["valued"] > 110.0 + 100.0
    kept = 66.5 * (end["valued"] - 110.0)
    assert valued.parts["value_heat_kept_eur"] == pytest.approx(kept, rel=1e-9)
    cash = valued.objective_eur - kept
    gap = 1e-4 * abs(plain.objective_eur) + 1.0
    assert cash <= plain.objective_eur + gap  # the plain plan is the best for today's cash alone
    assert valued.objective_eur >= plain.objective_eur - gap  # and it stays feasible with its kept value >= 0
    assert audit_result(valued) == [] and audit_result(plain) == []
