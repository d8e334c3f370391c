"""Wall time of the many-solve studies, serial against a local process pool; RO vs SP solve times.

Writes ``benchmarks/results/studies.json`` (with the machine, package versions, date and git
commit every benchmark records, ``benchmarks/common.py``) and prints it:

* ``sensitivity`` (Γ = 0..NT, every source at once) and ``markets`` (Tables 10-12):
  wall time serial and on the process pool, and the speed-up;
* ``out_of_sample``: test days × strategies, the robust plans' solve times and the
  average costs per strategy;
* ``stochastic``: solve time, status and gap of the stochastic benchmark per N, next
  to the paper's (CPLEX on a laptop).

Usage: ``python benchmarks/studies.py [--scenarios 5,10] [--test-days 30] [--workers 2]``;
``--scenarios ""`` skips the stochastic benchmark (the longest part: up to 600 s per N).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import pandas as pd  # noqa: E402

import rvpp  # noqa: E402
from benchmarks.common import header, write_result  # noqa: E402
from rvpp.cli.options import Number  # noqa: E402
from rvpp.solving.parallel import default_workers, open_executor  # noqa: E402
from rvpp.studies import markets, out_of_sample, sensitivity, stochastic  # noqa: E402
from rvpp.studies.settings import SCENARIO_COUNTS, SP_TIME_LIMIT_S, TEST_DAYS, StudySettings  # noqa: E402

CASE_DIR = Path(__file__).resolve().parent.parent / "data" / "cases" / "paper"
PAPER_RO_S = {"deterministic": 1.5, "optimistic": 1.8, "balanced": 1.0, "pessimistic": 1.4}  # Table 13
PAPER_SP_S = {5: 73.9, 10: 547.2, 15: 836.0, 20: 1447.2, 25: 6900.1}  # Table 14


def timed(study, case, settings, scheduler: str, workers: int) -> tuple[float, object]:
    started = time.perf_counter()
    with open_executor(scheduler, workers) as executor:
        output = study(case, settings, executor)
    return time.perf_counter() - started, output


def serial_vs_pool(study, case, settings, workers: int) -> dict:
    serial_s, output = timed(study, case, settings, "serial", workers)
    pool_s, _ = timed(study, case, settings, "processes", workers)
    plans = next(iter(output.tables.values()))
    return {"configurations": int(len(plans)), "sum_of_solve_s": round(float(plans["solve_s"].sum()), 2),
            "serial_s": round(serial_s, 2), "processes_s": round(pool_s, 2), "workers": workers,
            "speedup": round(serial_s / pool_s, 2)}


def scenario_counts(text: str) -> tuple[int, ...]:
    """``--scenarios``: whole numbers from 1 to 100 separated by commas, or nothing."""
    return tuple(Number(1, 100, whole=True)(item.strip()) for item in text.split(",") if item.strip())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenarios", type=scenario_counts, default=SCENARIO_COUNTS,
                        help="scenario counts of the stochastic benchmark, e.g. 5,10 (\"\" skips it)")
    parser.add_argument("--test-days", type=Number(1, 366, whole=True), default=TEST_DAYS)
    parser.add_argument("--sp-time-limit", type=Number(0, 1e6, low_open=True, unit="s"), default=SP_TIME_LIMIT_S)
    parser.add_argument("--workers", type=Number(1, 64, whole=True), default=default_workers())
    args = parser.parse_args()
    case = rvpp.load_case(CASE_DIR)
    settings = StudySettings(test_days=args.test_days, sp_time_limit_s=args.sp_time_limit, png=False,
                             scenario_counts=args.scenarios)
    report = {**header("studies", "full"), "case": case.name, "delivery_date": case.delivery_date.isoformat(),
              "sensitivity": serial_vs_pool(sensitivity.run, case, settings, args.workers),
              "markets": serial_vs_pool(markets.run, case, settings, args.workers)}
    oos_s, oos = timed(out_of_sample.run, case, settings, "processes", args.workers)
    table = oos.tables["table13_out_of_sample"]
    report["out_of_sample"] = {
        "wall_s": round(oos_s, 2), "test_days": args.test_days, "realization_set": table["realization_set"].iloc[0],
        "strategies": {r.method: {"plan_solve_s": round(r.solve_s, 2), "paper_solve_s": PAPER_RO_S.get(r.method),
                                  "avg_market_cost_keur": round(r.avg_market_cost_keur, 2),
                                  "avg_penalty_keur": round(r.avg_penalty_keur, 2),
                                  "avg_net_cost_keur": round(r.avg_net_cost_keur, 2)} for r in table.itertuples()}}
    if settings.scenario_counts:
        sp_s, sp = timed(stochastic.run, case, settings, "processes", args.workers)
        report["stochastic"] = {"wall_s": round(sp_s, 2), "time_limit_s": args.sp_time_limit, "runs": {
            int(r.n_scenarios): {"solve_s": round(r.solve_s, 1), "status": r.status,
                                 "mip_gap": None if pd.isna(r.mip_gap) else round(r.mip_gap, 5),
                                 "paper_solve_s": PAPER_SP_S.get(int(r.n_scenarios)),
                                 "avg_net_cost_keur": round(r.avg_net_cost_keur, 2)}
            for r in sp.tables["table14_stochastic"].itertuples()}}
    write_result(report)
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
