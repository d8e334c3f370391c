"""The Γ sweep: the default day re-solved for Γ = 0..24 of every source.

Times ``rvpp.solving.sweep.sweep_gamma`` (one model, re-solved in place, each point
started from its neighbour) against the same 25 plans solved one by one, and checks
that both give the same objectives. Writes ``benchmarks/results/gamma_sweep.json``.

Usage: ``python benchmarks/gamma_sweep.py [--quick]`` (quick: no one-by-one comparison).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.common import CASE, header, write_result  # noqa: E402
from rvpp import load_case, solve, with_options  # noqa: E402
from rvpp.solving.sweep import sweep_gamma  # noqa: E402

TARGET_S = 10.0
GAMMAS = tuple(range(25))


def run(quick: bool) -> dict:
    case = with_options(load_case(CASE), strategy="deterministic")
    solve(case)  # imports and first-call costs are not part of any measurement
    document = header("gamma_sweep", "quick" if quick else "full")
    started = time.perf_counter()
    points = sweep_gamma(case, GAMMAS)
    sweep_s = time.perf_counter() - started
    document.update(case=case.name, date=case.delivery_date.isoformat(), gammas=list(GAMMAS), sources="all",
                    sweep_s=round(sweep_s, 2), target_s=TARGET_S, within_target=sweep_s <= TARGET_S,
                    points=[{"gamma": g, "status": str(p.status), "objective_eur": p.objective_eur,
                             "solve_s": round(p.solve_s, 3), "nodes": p.nodes, "lp_iterations": p.lp_iterations}
                            for g, p in zip(GAMMAS, points)])
    if not quick:
        started = time.perf_counter()
        alone = [solve(with_options(case, gammas={s: g for s in case.sources()})) for g in GAMMAS]
        document["one_by_one_s"] = round(time.perf_counter() - started, 2)
        document["largest_objective_difference_eur"] = max(
            abs(a.objective_eur - p.objective_eur) for a, p in zip(alone, points))
        document["one_by_one_lp_iterations"] = sum(a.lp_iterations or 0 for a in alone)
    return document


def print_table(document: dict) -> None:
    its = sum(p["lp_iterations"] or 0 for p in document["points"])
    line = f"Γ sweep, {len(document['gammas'])} values: {document['sweep_s']:.2f} s ({its} LP iterations)"
    if "one_by_one_s" in document:
        line += (f"; one by one {document['one_by_one_s']:.2f} s ({document['one_by_one_lp_iterations']} LP "
                 f"iterations), objectives differ by at most {document['largest_objective_difference_eur']:.2f} EUR")
    print(line + f"; target <= {document['target_s']:g} s; load average {document['load_average_before']}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    document = run(args.quick)
    write_result(document)
    print_table(document)


if __name__ == "__main__":
    main()
