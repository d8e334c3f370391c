"""Solve times of the paper case over days spread through the year, hourly and at 15 minutes.

For every period length and strategy: the wall time of ``rvpp.solve`` (forecast bands,
model build, HiGHS, plan tables) on each day, its median, 90th percentile and maximum
over the days, and the case's default day alone, next to the targets. The process CPU
time of each solve is recorded next to its wall time (on a machine shared with other
work it is the closer measure of what a quiet machine gives), and so are HiGHS's node
and LP-iteration counts, which do not depend on the load at all. Writes ``benchmarks/results/solve_times.json``.

In full mode it also times the days of the year where the solver itself places some
budgeted deviations (deviations tied at the Γ boundary: on the bundled case the solar
field's band reaching zero at noon in early April), the slowest days rvpp has, which the
twelve days miss: ``tie_days`` per period length, each (day, strategy) with its time;
and the same pairs under the option ``budgets.ties: earliest`` (``tie_days.earliest``),
with how far each optimum falls below the default's.

Usage: ``python benchmarks/solve_times.py [--quick] [--periods 60 15]`` (quick: four days,
no tie days; periods: the period lengths in minutes to time, both by default).
"""

from __future__ import annotations

import argparse
import datetime as dt
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.common import CASE, DAYS, QUICK_DAYS, STRATEGIES, header, summary, write_result  # noqa: E402
from rvpp import load_case, solve, with_options  # noqa: E402
from rvpp.uncertainty.problem import prepare, tied_budgets  # noqa: E402

# Targets [s] of build + solve + extract per strategy: median and worst day.
TARGETS = {1.0: {"median": 0.3, "max": 1.0}, 0.25: {"median": 2.0, "max": 5.0}}
TIE_YEAR = 2025  # the year of the bundled history whose tie days are timed
PERIOD_MINUTES = {60: 1.0, 15: 0.25}


def timed_solve(case) -> dict:
    started, cpu_started = time.perf_counter(), time.process_time()
    result = solve(case)
    total, cpu = time.perf_counter() - started, time.process_time() - cpu_started
    return {"status": str(result.status), "objective_eur": result.objective_eur, "mip_gap": result.mip_gap,
            "total_s": round(total, 3), "cpu_s": round(cpu, 3), "build_s": round(result.build_s, 3),
            "solve_s": round(result.solve_s, 3), "extract_s": round(result.extract_s, 3), "nodes": result.nodes, "lp_iterations": result.lp_iterations}


def say(label: str, row: dict) -> None:
    print(f"{label}: {row['total_s']:7.3f} s ({row['cpu_s']:7.3f} s CPU) {row['nodes']} nodes {row['status']}",
          file=sys.stderr, flush=True)


def year_pairs(year: int = TIE_YEAR) -> list[tuple[str, str]]:
    """Every (day, strategy) pair of ``year``."""
    first = dt.date(year, 1, 1)
    days = (first + dt.timedelta(days=i) for i in range((dt.date(year + 1, 1, 1) - first).days))
    return [(day.isoformat(), strategy) for day in days for strategy in STRATEGIES]


def tie_days(base, dt_h: float, pairs: list[tuple[str, str]]) -> list[tuple[str, str]]:
    """The ``pairs`` where the case's budgets leave the solver to place some deviations: tied
    deviations straddle the Γ boundary of a source (paper mode, top-Γ). Read from the bands,
    as :func:`rvpp.model.robust.budget_choices` reads it from a built model, without building
    a model for each of the year's pairs."""
    return [(day, strategy) for day, strategy in pairs
            if tied_budgets(prepare(with_options(base, strategy=strategy, dt_h=dt_h, date=day)))]


def optimum_below(row: dict, default: dict) -> float | None:
    """How far ``row``'s optimum lies below ``default``'s [% of the default's], if both solved."""
    if row["objective_eur"] is None or default["objective_eur"] is None:
        return None
    return round(100 * (default["objective_eur"] - row["objective_eur"]) / max(1.0, abs(default["objective_eur"])), 3)


def over_pairs(rows: dict, target: dict) -> dict:
    """Median, p90 and maximum of the pairs' times, and whether each is within the worst-day target."""
    return {"over_pairs_s": summary([r["total_s"] for r in rows.values()]) if rows else None,
            "within_max_target": all(r["total_s"] <= target["max"] for r in rows.values())}


def run(days: tuple[str, ...], quick: bool, period_lengths_h: tuple[float, ...] = tuple(TARGETS)) -> dict:
    base = load_case(CASE)
    solve(base)  # imports and first-call costs are not part of any measurement
    document = header("solve_times", "quick" if quick else "full")
    document.update(case=base.name, default_day=base.delivery_date.isoformat(), days=list(days), results={})
    for dt_h in period_lengths_h:
        target = TARGETS[dt_h]
        per_strategy = {}
        for strategy in STRATEGIES:
            rows = {}
            for day in (*days, base.delivery_date.isoformat()):
                rows[day] = timed_solve(with_options(base, strategy=strategy, dt_h=dt_h, date=day))
                say(f"dt={dt_h:g} h {strategy:13s} {day}", rows[day])
            over_days = summary([rows[d]["total_s"] for d in days])
            default = rows[base.delivery_date.isoformat()]
            per_strategy[strategy] = {"over_days_s": over_days,
                                      "over_days_cpu_s": summary([rows[d]["cpu_s"] for d in days]),
                                      "default_day_s": default["total_s"], "default_day_cpu_s": default["cpu_s"],
                                      "within_target": over_days["median"] <= target["median"]
                                      and over_days["max"] <= target["max"],
                                      "days": rows}
        block = {"target_s": target, "strategies": per_strategy}
        if not quick:
            scanned = year_pairs()
            pairs = tie_days(base, dt_h, scanned)
            rows, earliest = {}, {}
            for day, strategy in pairs:
                key, case = f"{day} {strategy}", with_options(base, strategy=strategy, dt_h=dt_h, date=day)
                rows[key] = timed_solve(case)
                say(f"dt={dt_h:g} h tie day {day} {strategy:13s}", rows[key])
                earliest[key] = timed_solve(with_options(case, ties="earliest"))
                say(f"dt={dt_h:g} h tie day {day} {strategy:13s} earliest", earliest[key])
                earliest[key]["optimum_below_default_pct"] = optimum_below(earliest[key], rows[key])
            block["tie_days"] = {"year": TIE_YEAR, "pairs": len(pairs), "pairs_scanned": len(scanned),
                                 **over_pairs(rows, target), "days": rows,
                                 "earliest": {**over_pairs(earliest, target), "days": earliest}}
        document["results"][f"dt_{dt_h:g}h"] = block
    return document


def print_table(document: dict) -> None:
    print(f"solve times [s], build + solve + extract, over {len(document['days'])} days "
          f"(default day {document['default_day']}); load average {document['load_average_before']}")
    print(f"{'period':>7s} {'strategy':13s} {'median':>7s} {'p90':>7s} {'max':>7s} {'default':>8s}  "
          f"{'CPU med':>7s} {'CPU max':>7s}  target")
    for key, block in document["results"].items():
        target = block["target_s"]
        for strategy, row in block["strategies"].items():
            s, cpu = row["over_days_s"], row["over_days_cpu_s"]
            print(f"{key[3:]:>7s} {strategy:13s} {s['median']:7.3f} {s['p90']:7.3f} {s['max']:7.3f} "
                  f"{row['default_day_s']:8.3f}  {cpu['median']:7.3f} {cpu['max']:7.3f}  median<={target['median']:g} max<={target['max']:g}"
                  f"{'' if row['within_target'] else '  (missed)'}")
        ties = block.get("tie_days")
        if ties and ties["pairs"]:
            t = ties["over_pairs_s"]
            slowest = max(ties["days"], key=lambda k: ties["days"][k]["total_s"])
            verdict = "" if ties["within_max_target"] else f"  (over {target['max']:g} s)"
            print(f"{key[3:]:>7s} tie days: {ties['pairs']} of {ties['pairs_scanned']} day-strategy pairs of "
                  f"{ties['year']}, median {t['median']:.3f} s, p90 {t['p90']:.3f} s, max {t['max']:.3f} s "
                  f"({slowest}){verdict}")
            fixed = ties["earliest"]
            t = fixed["over_pairs_s"]
            below = [r["optimum_below_default_pct"] for r in fixed["days"].values()
                     if r["optimum_below_default_pct"] is not None]
            verdict = "" if fixed["within_max_target"] else f"  (over {target['max']:g} s)"
            print(f"{'':>7s}   with ties: earliest: median {t['median']:.3f} s, p90 {t['p90']:.3f} s, "
                  f"max {t['max']:.3f} s, optimum lower by {statistics.median(below):.2f} % (median) to "
                  f"{max(below):.2f} %{verdict}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="four days instead of twelve")
    parser.add_argument("--periods", type=int, nargs="+", choices=sorted(PERIOD_MINUTES, reverse=True),
                        default=sorted(PERIOD_MINUTES, reverse=True), metavar="MINUTES",
                        help="period lengths to time, in minutes (60, 15 or both; default both)")
    args = parser.parse_args()
    lengths = tuple(PERIOD_MINUTES[minutes] for minutes in dict.fromkeys(args.periods))
    document = run(QUICK_DAYS if args.quick else DAYS, args.quick, lengths)
    write_result(document)
    print_table(document)


if __name__ == "__main__":
    main()
