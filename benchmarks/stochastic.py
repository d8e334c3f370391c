"""The stochastic benchmark (paper Table 14): N sampled days solved to a 0.5 % gap.

For every N, the N whole days the study samples from the training window of the
default day (same seed as ``rvpp.studies.stochastic``) are solved by
``rvpp.settle.stochastic.solve_stochastic`` with a relative gap of 0.5 % and a time limit
of 120 s; the JSON holds each N's status, gap, bound, wall time, HiGHS's node and
LP-iteration counts, next to the paper's CPLEX times. Writes
``benchmarks/results/stochastic.json``.

Usage: ``python benchmarks/stochastic.py [--quick] [--scenarios 5,10,15,20,25]``
(quick: N = 5 and 10).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.common import CASE, header, write_result  # noqa: E402
from rvpp import load_case, with_options  # noqa: E402
from rvpp.settle.recourse import Penalties
from rvpp.settle.stochastic import solve_stochastic
from rvpp.studies.evaluation import realizations, sample_days, training_days  # noqa: E402
from rvpp.studies.settings import SCENARIO_COUNTS, StudySettings  # noqa: E402

GAP = 0.005
TIME_LIMIT_S = 120.0
PAPER_SP_S = {5: 73.9, 10: 547.2, 15: 836.0, 20: 1447.2, 25: 6900.1}  # Table 14, CPLEX on a laptop


def run(counts: tuple[int, ...], quick: bool) -> dict:
    base = load_case(CASE)
    case = with_options(base, rel_gap=GAP, time_limit_s=TIME_LIMIT_S)
    pool = training_days(base)
    seed = StudySettings().seed
    document = header("stochastic", "quick" if quick else "full")
    document.update(case=base.name, date=base.delivery_date.isoformat(), rel_gap=GAP, time_limit_s=TIME_LIMIT_S,
                    seed=seed, runs={})
    for n in counts:
        days = sample_days(pool, n, seed)
        started = time.perf_counter()
        plan = solve_stochastic(case, realizations(base, days), Penalties())
        wall = time.perf_counter() - started
        document["runs"][str(n)] = {
            "status": str(plan.status), "mip_gap": plan.mip_gap, "expected_profit_eur": plan.expected_profit_eur,
            "bound_eur": plan.bound_eur, "total_s": round(wall, 2), "solve_s": round(plan.solve_s, 2),
            "build_s": round(plan.build_s, 2), "start_s": round(plan.start_s, 2), "nodes": plan.nodes, "lp_iterations": plan.lp_iterations,
            "within_target": plan.mip_gap is not None and plan.mip_gap <= GAP and wall <= TIME_LIMIT_S,
            "paper_cplex_s": PAPER_SP_S.get(n), "days": [d.isoformat() for d in days]}
        row = document["runs"][str(n)]
        print(f"N={n:2d}: {row['status']} gap {row['mip_gap']} in {row['total_s']} s", file=sys.stderr, flush=True)
    return document


def print_table(document: dict) -> None:
    print(f"stochastic benchmark: gap target {document['rel_gap']:.1%}, time limit {document['time_limit_s']:g} s; "
          f"load average {document['load_average_before']}")
    print(f"{'N':>3s} {'status':>10s} {'gap':>8s} {'total s':>8s} {'nodes':>7s} {'paper s':>8s}")
    for n, row in document["runs"].items():
        gap = "-" if row["mip_gap"] is None else f"{row['mip_gap']:.3%}"
        print(f"{n:>3s} {row['status']:>10s} {gap:>8s} {row['total_s']:8.1f} {str(row['nodes']):>7s} "
              f"{row['paper_cplex_s']!s:>8s}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="N = 5 and 10 only")
    parser.add_argument("--scenarios", help="comma-separated N (default: the paper's 5..25)")
    args = parser.parse_args()
    counts = (5, 10) if args.quick else SCENARIO_COUNTS
    if args.scenarios:
        counts = tuple(int(n) for n in args.scenarios.split(",") if n.strip())
    document = run(counts, args.quick)
    write_result(document)
    print_table(document)


if __name__ == "__main__":
    main()
