"""The paper's qualitative findings, each checked against the numbers of our own run.

Every check reads the tables of the studies that ran and returns a :class:`Finding`
with a verdict and the numbers behind it, or ``None`` when its study did not run.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ..data.kinds import UnitKind
from ..solving.outcome import Outcome
from .runner import StudyOutput
from .stress import GREEDY, PAPER

COST_TOLERANCE_KEUR = 1e-3  # differences below 1 EUR count as ties (solver gap 1e-4)
MAJORITY = 0.5


@dataclass(frozen=True)
class Finding:
    """A claim of the paper, where it is made, whether it holds here and why."""

    claim: str
    paper: str
    holds: bool
    evidence: str


Outputs = dict[str, StudyOutput]


def _fact(outputs: Outputs, study: str, name: str):
    output = outputs.get(study)
    return None if output is None else output.facts.get(name)


def _costs(values) -> str:
    """``name value`` pairs [kEUR]; a configuration without a plan reads "no plan"."""
    return ", ".join(f"{k} {v:.1f}" if np.isfinite(v) else f"{k} no plan" for k, v in values.items())


def cost_rises_with_gamma(outputs: Outputs) -> Finding | None:
    table = _fact(outputs, "sensitivity", "sensitivity")
    if table is None:
        return None
    part = table[table["sources"] == table["sources"].iloc[0]].sort_values("gamma")
    steps = np.diff(part["cost_keur"].to_numpy(float))
    drops = int((steps < -COST_TOLERANCE_KEUR).sum())
    first, last = part.iloc[0], part.iloc[-1]
    return Finding("Cost rises with the uncertainty budget Γ", "Case 2, Figure 15", drops == 0,
                   f"cost {first['cost_keur']:.1f} kEUR at Γ={first['gamma']} and {last['cost_keur']:.1f} kEUR at "
                   f"Γ={last['gamma']} (sources: {first['sources']}); {drops} of {len(steps)} steps lower the cost")


def cost_rises_with_strategy(outputs: Outputs) -> Finding | None:
    plans = _fact(outputs, "strategies", "plans")
    if plans is None:
        return None
    costs = plans.set_index("strategy")["cost_keur"]
    holds = bool((np.diff(costs.to_numpy(float)) >= -COST_TOLERANCE_KEUR).all())
    return Finding("More conservative strategies cost more", "Case 3, Table 10", holds,
                   f"cost [kEUR]: {_costs(costs)}")


def _cheapest(table: pd.DataFrame, column: str, dearest: bool = False) -> tuple[bool, str]:
    target = table[column]
    other = table.drop(columns=column)
    if dearest:  # a market set without a plan counts as the most expensive
        ok = target.isna() | (target >= other.max(axis=1) - COST_TOLERANCE_KEUR)
    else:
        ok = (target <= other.min(axis=1) + COST_TOLERANCE_KEUR)
    rows = "; ".join(f"{s}: {_costs(table.loc[s])}" for s in table.index)
    return bool(ok.all()), f"cost [kEUR] by market set: {rows}"


def all_markets_cheapest(outputs: Outputs) -> Finding | None:
    table = _fact(outputs, "markets", "markets")
    if table is None or "DAM+SRM+HPA" not in table:
        return None
    holds, evidence = _cheapest(table, "DAM+SRM+HPA")
    return Finding("DAM+SRM+HPA is the cheapest market set for every strategy", "Case 3, Table 10", holds, evidence)


def dam_only_dearest(outputs: Outputs) -> Finding | None:
    table = _fact(outputs, "markets", "markets")
    if table is None or "DAM" not in table:
        return None
    holds, evidence = _cheapest(table, "DAM", dearest=True)
    return Finding("DAM-only participation is the most expensive", "Case 3, Table 10", holds, evidence)


def csp_lowers_cost(outputs: Outputs) -> Finding | None:
    with_csp, without = _fact(outputs, "markets", "markets"), _fact(outputs, "markets", "without_csp")
    if with_csp is None or without is None:
        return None
    shared = [c for c in without.columns if c in with_csp.columns]
    diff = without[shared] - with_csp.loc[without.index, shared]
    holds = bool((diff > COST_TOLERANCE_KEUR).all().all())
    return Finding("The RVPP without its CSP costs more", "Case 3, Table 11", holds,
                   "extra cost without CSP [kEUR]: " + "; ".join(
                       f"{s}: {_costs(diff.loc[s])}" for s in diff.index))


def hpa_price_lowers_cost(outputs: Outputs) -> Finding | None:
    table = _fact(outputs, "markets", "hpa_price")
    if table is None or table.shape[1] < 2:
        return None
    flat = table.drop(columns="time-of-use", errors="ignore")
    prices = [float(c) for c in flat.columns]
    ordered = flat[[c for _, c in sorted(zip(prices, flat.columns), reverse=True)]]
    holds = bool((np.diff(ordered.to_numpy(float), axis=1) <= COST_TOLERANCE_KEUR).all())
    if "time-of-use" in table:
        holds = holds and bool((ordered.iloc[:, 0] <= table["time-of-use"] + COST_TOLERANCE_KEUR).all())
    return Finding("A lower HPA price lowers the cost", "Case 3, Table 12", holds,
                   "cost [kEUR] by HPA tariff: " + "; ".join(f"{s}: {_costs(table.loc[s])}" for s in table.index))


TENS_OF_PERCENT = 0.10  # "tens of percent": the paper's Table 12 reductions at 50 EUR/MWh_th are 20.7-48.9 %
RELATIVE_TIE = 1e-3  # costs closer than 0.1 % are a tie: ten times the default MIP gap (1e-4)


def _spans(clock: pd.Series, chosen: np.ndarray) -> str:
    """The chosen periods as runs of consecutive start times, e.g. ``00:00-05:00, 18:00``."""
    runs, start = [], None
    for k, on in enumerate([*chosen, False]):
        if on and start is None:
            start = k
        elif not on and start is not None:
            runs.append(clock.iloc[start] if k - 1 == start else f"{clock.iloc[start]}-{clock.iloc[k - 1]}")
            start = None
    return ", ".join(runs) or "none"


def hpa_heat_bought_at_night(outputs: Outputs) -> Finding | None:
    """Case 1: the deterministic plan buys most of its HPA heat in the periods of the cheapest tariff."""
    result = _fact(outputs, "case1", "result")
    if result is None or not result.has_plan or not result.case.markets.hpa:
        return None
    market = result.market
    heat = market["h_hpa_mw"].to_numpy(float) * result.problem.dt_h
    tariff = market["tariff_hpa"].to_numpy(float)
    cheapest = tariff <= tariff.min() + 1e-9
    total, at_night = heat.sum(), heat[cheapest].sum()
    share = at_night / total if total > 0 else 0.0
    return Finding("HPA heat is bought in the night hours of the cheapest tariff", "Case 1, Figure 10",
                   bool(total > 0 and share >= MAJORITY),
                   f"heat bought {total:.1f} MWh_th, of which {at_night:.1f} MWh_th ({share:.0%}) in the periods at "
                   f"{tariff.min():g} EUR/MWh_th ({_spans(market['clock'], cheapest)}); periods with purchases: "
                   f"{_spans(market['clock'], heat > 1e-6)}")


def hpa_lowers_dam_cost(outputs: Outputs) -> Finding | None:
    """Table 10: adding the HPA to DAM-only participation lowers the cost (by more than a tie) for a strategy
    at least, and raises it for none."""
    table = _fact(outputs, "markets", "markets")
    if table is None or "DAM" not in table or "DAM+HPA" not in table:
        return None
    dam, with_hpa = table["DAM"], table["DAM+HPA"]
    both = dam.notna() & with_hpa.notna()
    tie = np.maximum(COST_TOLERANCE_KEUR, RELATIVE_TIE * dam.abs())
    holds = bool(both.all() and (with_hpa <= dam + tie).all() and (with_hpa < dam - tie).any())

    def reduction(s: str) -> str:
        if not both[s]:
            return f"{s} n/a (no {'DAM' if np.isnan(dam[s]) else 'DAM+HPA'} plan)"
        relative = f" ({(dam[s] - with_hpa[s]) / abs(dam[s]):.2%})" if abs(dam[s]) > COST_TOLERANCE_KEUR else ""
        return f"{s} {dam[s] - with_hpa[s]:.3f} kEUR{relative}"

    return Finding("DAM+HPA costs less than DAM alone", "Case 3, Table 10 (0-2.0 % less)", holds,
                   "cost reduction of DAM+HPA against DAM: " + ", ".join(reduction(s) for s in table.index))


def flat_hpa_tariff_cuts_cost(outputs: Outputs) -> Finding | None:
    """Table 12: the lowest flat tariff lowers the cost by tens of percent against the time-of-use tariff."""
    table = _fact(outputs, "markets", "hpa_price")
    if table is None or "time-of-use" not in table or table.shape[1] < 2:
        return None
    flat = table.drop(columns="time-of-use")
    lowest = min(flat.columns, key=float)
    base = table["time-of-use"].abs().where(lambda c: c > COST_TOLERANCE_KEUR)
    cut = flat.rsub(table["time-of-use"], axis=0).div(base, axis=0)
    holds = bool((cut[lowest] >= TENS_OF_PERCENT).all())
    shown = cut.round(3) + 0.0  # the shown precision (0.1 %): no "-0.0%" for a tie
    rows = "; ".join(f"{s}: " + ", ".join(f"{c} {shown.loc[s, c]:.1%}" if np.isfinite(shown.loc[s, c]) else f"{c} n/a"
                                          for c in cut.columns) for s in cut.index)
    return Finding(f"A flat HPA tariff of {lowest} EUR/MWh_th lowers the cost by tens of percent (at least "
                   f"{TENS_OF_PERCENT:.0%}) for every strategy", "Case 3, Table 12 (50 EUR/MWh_th: 20.7-48.9 %)",
                   holds, f"cost reduction against the time-of-use tariff by flat tariff [EUR/MWh_th]: {rows}")


def _up_reserve(outputs: Outputs) -> pd.DataFrame | None:
    flexibility = _fact(outputs, "strategies", "flexibility")
    if flexibility is None or UnitKind.CSP not in set(flexibility["kind"]):
        return None
    return flexibility


def csp_supplies_most_up_reserve(outputs: Outputs) -> Finding | None:
    flexibility = _up_reserve(outputs)
    if flexibility is None:
        return None
    total = flexibility.groupby("strategy", sort=False)["r_up_mwh"].sum()
    csp = flexibility[flexibility["kind"] == UnitKind.CSP].set_index("strategy")["r_up_mwh"]
    share = (csp / total.replace(0.0, np.nan)).fillna(0.0)
    holds = bool((share > MAJORITY).all())
    return Finding("The CSP supplies most of the up reserve", "Case 2, Figure 13; Conclusion", holds,
                   "CSP share of the up reserve: " + ", ".join(
                       f"{s} {share[s]:.0%} of {total[s]:.1f} MWh" for s in share.index))


def csp_highest_up_ratio(outputs: Outputs) -> Finding | None:
    flexibility = _up_reserve(outputs)
    if flexibility is None:
        return None
    best = flexibility.loc[flexibility.groupby("strategy", sort=False)["r_up_h"].idxmax()]
    holds = bool(((best["kind"] == UnitKind.CSP) & (best["r_up_h"] > 0)).all())
    return Finding("The CSP has the highest up-reserve-to-capacity ratio", "Case 2, Table 9", holds,
                   "highest ratio [h]: " + ", ".join(
                       f"{r.strategy} {r.kind} {r.r_up_h:.2f}" for r in best.itertuples()))


def _oos(outputs: Outputs, baseline: bool = True) -> pd.DataFrame | None:
    """Table 13 by method; with ``baseline``, only if it has the deterministic plan and another."""
    summary = _fact(outputs, "out_of_sample", "summary")
    if summary is None or summary.empty:
        return None
    if baseline and ("deterministic" not in set(summary["method"]) or len(summary) < 2):
        return None
    return summary.set_index("method")


def _versus_deterministic(outputs: Outputs, column: str, claim: str, label: str,
                          holds: Callable[[pd.Series, float], bool]) -> Finding | None:
    """A Table 13 finding comparing the robust strategies with the deterministic plan."""
    summary = _oos(outputs)
    if summary is None:
        return None
    base = summary.loc["deterministic", column]
    robust = summary.drop(index="deterministic")[column]
    return Finding(claim, "Case 4, Table 13", bool(holds(robust, base)),
                   f"{label} [kEUR]: deterministic {base:.1f}, {_costs(robust)}")


def robust_cuts_penalty(outputs: Outputs) -> Finding | None:
    return _versus_deterministic(outputs, "avg_penalty_keur", "Robust strategies cut penalties out-of-sample",
                                 "average penalty", lambda robust, base: (robust < base).all())


def robust_raise_market_cost(outputs: Outputs) -> Finding | None:
    return _versus_deterministic(outputs, "avg_market_cost_keur", "Robust strategies pay a higher average market cost",
                                 "average market cost", lambda robust, base: (robust > base).all())


def robust_lowers_net_cost(outputs: Outputs) -> Finding | None:
    return _versus_deterministic(outputs, "avg_net_cost_keur",
                                 "A robust strategy has a lower net cost than the deterministic plan",
                                 "average net cost", lambda robust, base: robust.min() < base)


def _sp(outputs: Outputs) -> pd.DataFrame | None:
    summary = _fact(outputs, "stochastic", "summary")
    if summary is None or summary["avg_net_cost_keur"].isna().all():
        return None
    return summary.dropna(subset=["avg_net_cost_keur"]).set_index("method")


def ro_beats_sp(outputs: Outputs) -> Finding | None:
    ro, sp = _oos(outputs, baseline=False), _sp(outputs)
    if ro is None or sp is None:
        return None
    best_ro, best_sp = ro["avg_net_cost_keur"].idxmin(), sp["avg_net_cost_keur"].idxmin()
    holds = bool(ro.loc[best_ro, "avg_net_cost_keur"] < sp.loc[best_sp, "avg_net_cost_keur"])
    return Finding("The best robust strategy has a lower out-of-sample net cost than the stochastic benchmark",
                   "Case 4, Tables 13-14", holds,
                   f"best RO {best_ro} {ro.loc[best_ro, 'avg_net_cost_keur']:.1f} kEUR, best SP {best_sp} "
                   f"{sp.loc[best_sp, 'avg_net_cost_keur']:.1f} kEUR")


def sp_penalty_falls_with_scenarios(outputs: Outputs) -> Finding | None:
    sp = _sp(outputs)
    if sp is None or len(sp) < 2:
        return None
    ordered = sp.sort_values("n_scenarios")
    first, last = ordered.iloc[0], ordered.iloc[-1]
    return Finding("More scenarios lower the stochastic benchmark's penalty", "Case 4, Table 14",
                   bool(last["avg_penalty_keur"] < first["avg_penalty_keur"]),
                   "average penalty [kEUR]: " + ", ".join(
                       f"N={int(r.n_scenarios)} {r.avg_penalty_keur:.1f}" for r in ordered.itertuples()))


def ro_solves_faster(outputs: Outputs) -> Finding | None:
    ro, sp = _oos(outputs, baseline=False), _fact(outputs, "stochastic", "summary")
    if ro is None or sp is None:
        return None
    largest = sp.loc[sp["n_scenarios"].idxmax()]
    slowest_ro = ro["solve_s"].max()
    status = "" if Outcome(largest["status"]) is Outcome.OPTIMAL else f", stopped by {largest['status']}"
    return Finding(f"RO solves faster than SP with {int(largest['n_scenarios'])} scenarios", "Case 4, Tables 13-14",
                   bool(slowest_ro < largest["solve_s"]),
                   f"slowest RO plan {slowest_ro:.2f} s; SP N={int(largest['n_scenarios'])} {largest['solve_s']:.1f} s"
                   f"{status} (gap {largest['mip_gap'] if largest['mip_gap'] is not None else float('nan'):.2%})")


def paper_pattern_is_not_the_worst(outputs: Outputs) -> Finding | None:
    table = _fact(outputs, "stress", "stress")
    if table is None or table.empty:
        return None
    net = table.pivot(index="strategy", columns="pattern", values="net_cost_keur")
    paper, greedy = net[PAPER], net[GREEDY]
    return Finding("Inside the same budget set, a pattern worse than the paper-mode deviations exists "
                   "(greedy search: a lower bound on the worst case)", "beyond the paper (MODEL_SPEC §10)",
                   bool((greedy > paper + COST_TOLERANCE_KEUR).all()),
                   "net cost [kEUR], paper-mode vs greedy pattern: " + ", ".join(
                       f"{s} {paper[s]:.1f} vs {greedy[s]:.1f}" for s in net.index))


CHECKS: tuple[Callable[[Outputs], Finding | None], ...] = (
    cost_rises_with_gamma, cost_rises_with_strategy, all_markets_cheapest, dam_only_dearest, csp_lowers_cost,
    hpa_price_lowers_cost, csp_supplies_most_up_reserve, csp_highest_up_ratio, robust_cuts_penalty,
    robust_raise_market_cost, robust_lowers_net_cost, ro_beats_sp, sp_penalty_falls_with_scenarios,
    ro_solves_faster, paper_pattern_is_not_the_worst,
    hpa_heat_bought_at_night, hpa_lowers_dam_cost, flat_hpa_tariff_cuts_cost,
)


def findings(outputs: Outputs) -> list[Finding]:
    """Every finding whose studies ran."""
    return [f for check in CHECKS if (f := check(outputs)) is not None]
