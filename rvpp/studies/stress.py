"""Stress test of the robust plans (MODEL_SPEC §10, beyond the paper).

Paper mode lets each source deviate in its Γ largest-deviation periods (MODEL_SPEC §5),
which need not be the periods that hurt the *profit* most. This study searches, for each
strategy's plan, a deviation pattern inside the same budget set (every source at its
adverse bound in at most Γ periods) that raises the settled net cost:

1. screening: from the plan's nominal values, each source deviates alone in one period,
   and the recourse model settles it (one solve per source and period) with the plan's
   CSP commitment kept, which makes each screening solve several times faster; it only
   ranks the periods;
2. pattern: each source deviates in the Γ periods whose screening raised the net cost
   most; the combined pattern is settled once with the study's settings (commitment
   free unless ``fix_commitment``), next to the paper-mode pattern for comparison: each
   price in the Γ periods of the plan's largest exposure (price deviation times the
   quantity at stake, the periods the price protection of MODEL_SPEC §4 guards), each
   availability and consumption in its Γ largest-deviation periods (MODEL_SPEC §5).

The pattern is found greedily, so its net cost is a **lower bound** on the worst case
within the budget set, not the worst case itself. Only settlements that ended optimal
give numbers: a screening solve that did not is left out of the ranking, a pattern
settlement that did not shows ``n/a``, and the study's warning names them.
"""

from __future__ import annotations

import time
from concurrent.futures import Executor

import numpy as np
import pandas as pd

from ..solving.batch import run_many
from ..data.case import Case
from ..data.variants import with_options
from ..data.variants import describe
from ..solving.outcome import Outcome
from ..uncertainty.problem import Problem, SourceKind, top_gamma_deviation
from ..settle.audit import price_exposures
from ..settle.recourse import FirstStage, Realization, first_stage, nominal_realization
from .evaluation import EUR_PER_KEUR, evaluate_task
from .runner import Config, Progress, StudyOutput, solve_configs, stage
from .settings import StudySettings

TITLE = "Stress test: a bad deviation pattern inside each plan's budget set (lower bound on the worst case)"
NOMINAL, PAPER, GREEDY = "nominal", "paper-mode pattern", "greedy pattern (lower bound on the worst case)"


def adverse_values(problem: Problem, p_da: np.ndarray) -> dict[str, np.ndarray]:
    """Each source at its adverse bound in every period.

    Availabilities and SR prices at their lower bound, consumptions at their upper
    bound, the DAM price against the plan's position (low where it sells, high where
    it buys).
    """
    values = {}
    for name, src in problem.sources.items():
        if src.kind is SourceKind.PRICE_DA:
            values[name] = np.where(p_da >= 0, src.nominal - src.deviation, src.nominal + src.deviation_up)
        elif src.kind is SourceKind.CONSUMPTION:
            values[name] = src.nominal + src.deviation
        else:
            values[name] = src.nominal - src.deviation
    return values


def deviating(base: Realization, adverse: dict[str, np.ndarray], pattern: dict[str, list[int]]) -> Realization:
    """``base`` with each source at its adverse value in the periods of ``pattern``."""
    values = base.values.copy()
    for name, periods in pattern.items():
        for t in periods:
            values.loc[t, name] = adverse[name][t - 1]
    return Realization(day=base.day, values=values)


def candidates(problem: Problem) -> list[tuple[str, int]]:
    """``(source, period)`` pairs that can deviate: Γ > 0 and a non-zero deviation."""
    pairs = []
    for name, src in problem.sources.items():
        size = np.maximum(src.deviation, src.deviation_up if src.deviation_up is not None else 0.0)
        if src.gamma > 0:
            pairs += [(name, t) for t in range(1, problem.nt + 1) if size[t - 1] > 0]
    return pairs


def greedy_pattern(problem: Problem, impacts: pd.DataFrame) -> dict[str, list[int]]:
    """Per source, the Γ periods whose single deviation raised the net cost most."""
    pattern = {}
    for name, part in impacts[impacts["impact_eur"] > 0].groupby("source"):
        chosen = part.nlargest(problem.sources[name].gamma, "impact_eur")
        pattern[name] = sorted(int(t) for t in chosen["t"])
    return pattern


def paper_pattern(problem: Problem, bids: FirstStage) -> dict[str, list[int]]:
    """Per source, the Γ periods where paper mode lets it deviate against ``bids``.

    A price deviates in the Γ periods of largest exposure (the worst case its protection
    prices, MODEL_SPEC §4; periods without exposure never), an availability or a
    consumption in its Γ largest-deviation periods (MODEL_SPEC §5). Ties go to the
    earlier periods.
    """
    market = pd.DataFrame({"p_da_mw": bids.p_da, "r_sr_up_mw": bids.r_sr_up, "r_sr_dn_mw": bids.r_sr_dn})
    exposures = price_exposures(problem, market)
    pattern = {}
    for name, src in problem.sources.items():
        size = exposures[name] if src.is_price else src.deviation
        chosen = np.flatnonzero(top_gamma_deviation(size, src.gamma)) + 1
        if len(chosen):
            pattern[name] = [int(t) for t in chosen]
    return pattern


def optimal_value(record: dict, key: str) -> float:
    """A settlement figure [EUR] if the settlement ended optimal, else NaN."""
    return float(record[key]) if Outcome(record["status"]) is Outcome.OPTIMAL else float("nan")


def run(case: Case, settings: StudySettings, executor: Executor | None = None,
        progress: Progress | None = None) -> StudyOutput:
    """Screen every plan's single deviations, then settle the greedy and paper-mode patterns."""
    started = time.perf_counter()
    robust = [s for s in settings.strategies if s != "deterministic"]
    configs = [Config.of({"strategy": s}, strategy=s) for s in robust]
    results = {dict(c.labels)["strategy"]: r
               for c, r in zip(configs, solve_configs(case, configs, settings, executor, progress, "stress plans"))}
    plans = {s: r for s, r in results.items() if r.has_plan}
    out = StudyOutput("stress", TITLE)
    out.notes.append("The greedy pattern is a lower bound on the worst-case net cost within each budget set.")
    out.notes += [f"{s}: no plan to stress ({r.status}: {r.message})" for s, r in results.items() if not r.has_plan]
    if not plans:
        out.facts.update(stress=pd.DataFrame())
        out.seconds = time.perf_counter() - started
        return out
    settle_case = with_options(case, threads=settings.threads)
    bids = {s: first_stage(r, settings.fix_commitment) for s, r in plans.items()}
    screening_bids = {s: first_stage(r, fix_commitment=True) for s, r in plans.items()}
    bases = {s: nominal_realization(r.problem) for s, r in plans.items()}
    adverse = {s: adverse_values(r.problem, bids[s].p_da) for s, r in plans.items()}
    screens = [(s, name, t) for s, r in plans.items() for name, t in [("", 0)] + candidates(r.problem)]
    tasks = [(f"{s}|{name}|{t}", settle_case, screening_bids[s],
              deviating(bases[s], adverse[s], {name: [t]} if name else {}), settings.penalties)
             for s, name, t in screens]
    records = run_many(evaluate_task, tasks, executor, stage(progress, "stress screening"))
    screening = pd.DataFrame([{"strategy": s, "source": name, "t": t, "status": rec["status"],
                               "net_cost_eur": optimal_value(rec, "net_cost_eur")}
                              for (s, name, t), rec in zip(screens, records)])
    base_net = screening[screening["source"] == ""].set_index("strategy")["net_cost_eur"]
    screening = screening[screening["source"] != ""].reset_index(drop=True)
    screening["impact_eur"] = screening["net_cost_eur"] - screening["strategy"].map(base_net)
    patterns = {s: {NOMINAL: {}, PAPER: paper_pattern(r.problem, bids[s]),
                    GREEDY: greedy_pattern(r.problem, screening[screening["strategy"] == s])}
                for s, r in plans.items()}
    final = [(s, label, pattern) for s, by_label in patterns.items() for label, pattern in by_label.items()]
    outcomes = run_many(evaluate_task, [(s, settle_case, bids[s], deviating(bases[s], adverse[s], pattern),
                                         settings.penalties) for s, _, pattern in final],
                        executor, stage(progress, "stress patterns"))
    table = pd.DataFrame([{
        "strategy": s, "variant": describe(plans[s].case), "pattern": label, "status": rec["status"],
        "deviations": sum(map(len, pattern.values())),
        "market_cost_keur": optimal_value(rec, "market_cost_eur") / EUR_PER_KEUR,
        "penalty_keur": optimal_value(rec, "penalty_eur") / EUR_PER_KEUR,
        "net_cost_keur": optimal_value(rec, "net_cost_eur") / EUR_PER_KEUR, "plan_cost_keur": plans[s].cost_keur,
        "periods": "; ".join(f"{name}: {','.join(map(str, ts))}" for name, ts in pattern.items()),
    } for (s, label, pattern), rec in zip(final, outcomes)])
    out.tables = {"stress": table, "stress_screening": screening}
    failed = [f"{row.strategy} {row.pattern}: {row.status}" for row in table.itertuples()
              if Outcome(row.status) is not Outcome.OPTIMAL]
    failed_screens = sum(Outcome(rec["status"]) is not Outcome.OPTIMAL for rec in records)
    if failed or failed_screens:
        out.warnings.append(f"{len(failed)} of {len(table)} pattern settlements and {failed_screens} of "
                            f"{len(records)} screening settlements did not end optimal; their numbers are left "
                            "out" + (f" ({'; '.join(failed)})" if failed else ""))
    out.facts.update(stress=table)
    out.seconds = time.perf_counter() - started
    return out
