"""One way to derive a variant of a case, and labels that name what was solved."""

from __future__ import annotations

import pytest

from rvpp import CaseError, with_options
from rvpp.data.variants import Variant, describe


@pytest.fixture(scope="module")
def edited(paper_case):
    """The paper case as a dashboard session may hold it: a preset with Γ edits."""
    return paper_case.replace(budgets={"strategy": "optimistic", "overrides": {"WF1": 12, "CSP1": 5}})


def test_a_strategy_sets_the_cases_own_budget_edits_aside(edited):
    case = Variant(strategy="pessimistic", gammas={"PV1": 7}, markets="DAM+HPA").apply(edited)
    assert case.budgets.strategy == "pessimistic" and case.budgets.override_map == {"PV1": 7}
    assert case.markets.label == "DAM+HPA"
    assert describe(case) == "pessimistic · DAM+HPA · Γ PV1=7"


def test_without_a_strategy_the_edits_are_kept_and_extended(edited):
    case = Variant(gammas={"PV1": 7, "WF1": 2}).apply(edited)
    assert case.budgets.strategy == "optimistic"
    assert case.budgets.override_map == {"CSP1": 5, "PV1": 7, "WF1": 2}
    assert describe(case) == "optimistic · DAM+SRM+HPA · Γ CSP1=5, PV1=7, WF1=2"
    assert Variant().apply(edited) is edited


def test_removing_the_csp_drops_its_budget_edit_and_says_so(edited):
    case = Variant(csp=False, markets="DAM,SRM,HPA").apply(edited)
    assert case.csp == () and case.budgets.override_map == {"WF1": 12}
    assert describe(case) == "optimistic · DAM+SRM+HPA · Γ WF1=12 · no CSP"


def test_flat_tariff_period_length_and_one_budget_for_every_source(paper_case):
    every = {source: 4 for source in paper_case.sources()}
    case = Variant(strategy="deterministic", gammas=every, hpa_flat=60.0, dt_h=0.25).apply(paper_case)
    assert case.markets.hpa_tariff_eur_per_mwh == (60.0,) * 24 and case.dt_h == 0.25
    assert describe(case) == "deterministic · DAM+SRM+HPA · Γ=4 for every source · HPA flat 60 EUR/MWh_th · 15-min periods"
    assert Variant(strategy="deterministic", hpa_flat=60.0, markets="DAM").label(paper_case) == "deterministic · DAM"


def test_with_options_derives_the_same_variant(edited):
    variant = Variant(strategy="balanced", gammas={"WF2": 3}, markets="DAM,SRM", csp=False, hpa_flat=50.0)
    derived = with_options(edited, strategy="balanced", gammas={"WF2": 3}, markets="DAM,SRM", csp=False,
                           hpa_flat=50.0, time_limit_s=30.0)
    assert derived == variant.apply(edited, solver={"time_limit_s": 30.0})
    assert Variant(gammas={"WF2": 3}) == Variant(gammas=(("WF2", 3),))  # a mapping becomes sorted pairs
    assert hash(variant) == hash(Variant(strategy="balanced", gammas={"WF2": 3}, markets="DAM,SRM", csp=False,
                                         hpa_flat=50.0))


def test_a_bad_variant_is_refused_with_the_users_words(paper_case):
    with pytest.raises(CaseError, match="unknown market 'IDM'"):
        Variant(markets="DAM+IDM").apply(paper_case)
    with pytest.raises(CaseError, match="strategy"):
        Variant(strategy="cautious").apply(paper_case)
