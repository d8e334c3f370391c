"""Solve times of the default case per strategy, hourly and at 15 minutes.

Prints one JSON document: for every (period length, strategy) the median over
``--repeat`` runs of the build, solve, extract and total wall seconds, the MIP gap and
the objective, with the targets they are measured against. Run with ``make bench``.
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from rvpp import load_case, solve, with_options  # noqa: E402
from rvpp.solving.problem import STRATEGY_BUDGETS_H  # noqa: E402

CASE = Path(__file__).resolve().parent.parent / "data" / "cases" / "paper"
TARGET_S = {1.0: 10.0, 0.25: 60.0}  # every strategy to a 1e-4 gap within these seconds


def measure(case, repeat: int) -> dict:
    runs = []
    for _ in range(repeat):
        started = time.perf_counter()
        result = solve(case)
        total = time.perf_counter() - started
        runs.append((result, total))
    result = runs[-1][0]
    return {
        "status": result.status,
        "objective_eur": round(result.objective_eur, 2) if result.objective_eur is not None else None,
        "mip_gap": result.mip_gap,
        "build_s": round(statistics.median(r.build_s for r, _ in runs), 3),
        "solve_s": round(statistics.median(r.solve_s for r, _ in runs), 3),
        "extract_s": round(statistics.median(r.extract_s for r, _ in runs), 3),
        "total_s": round(statistics.median(t for _, t in runs), 3),
        "periods": result.problem.nt,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=3, help="runs per configuration (median reported)")
    parser.add_argument("--date", help="delivery date (default: the case's)")
    args = parser.parse_args()
    case = load_case(CASE)
    report = {"case": case.name, "date": str(args.date or case.delivery_date), "repeat": args.repeat,
              "python": platform.python_version(), "machine": platform.machine(), "results": {}}
    for dt_h, target in TARGET_S.items():
        rows = {}
        for strategy in STRATEGY_BUDGETS_H:
            rows[strategy] = measure(with_options(case, strategy=strategy, dt_h=dt_h, date=args.date), args.repeat)
            print(f"dt={dt_h:g} h {strategy}: {rows[strategy]['total_s']} s", file=sys.stderr, flush=True)
        slowest = max(row["total_s"] for row in rows.values())
        report["results"][f"dt_{dt_h:g}h"] = {"target_s": target, "slowest_total_s": slowest,
                                              "within_target": slowest <= target, "strategies": rows}
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
