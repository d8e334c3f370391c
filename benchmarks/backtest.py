"""Wall time of the rolling backtest on the paper case, hourly, on local worker processes.

Two measurements against their targets, each in a fresh SQLite store:

* ``strategies``: the four presets (plan + settlement + audit), ``--days`` days
  (default 365): target 10 min on 2 cores;
* ``gamma_grid``: 8 Γ fractions of the day, the same days: target 20 min on 2 cores;

and the cost of resuming: rerunning a finished backtest (every day skipped). Writes one
JSON document to ``benchmarks/results/backtest.json`` (and prints it): wall times,
seconds per record, the CPU seconds the workers spent per record (and the wall time
they imply on otherwise idle cores: total CPU / workers), the load average before and
after, the mean plan and settlement solve times and the plans' LP iterations and nodes (which
do not depend on the load) from the records, and whether each
target was met by the measured wall time. ``--days 28`` gives a quick look; the targets are for a
year. Timings on a shared machine are noisy: repeat and compare.
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from rvpp import load_case  # noqa: E402
from rvpp.backtest import BacktestSettings, metrics, run_backtest, variants_of  # noqa: E402
from rvpp.data.case import STRATEGIES  # noqa: E402
from rvpp.solving.parallel import default_workers, open_executor  # noqa: E402
from rvpp.store import BacktestStore  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
CASE = ROOT / "data" / "cases" / "paper"
RESULTS = ROOT / "benchmarks" / "results" / "backtest.json"
FIRST_DAY = dt.date(2024, 12, 31)  # the first day with 30 days of history before it
GRID = (0.0, 0.0625, 0.125, 0.1875, 0.25, 0.3125, 0.375, 0.5)
TARGETS_S = {"strategies": 600.0, "gamma_grid": 1200.0}  # for 365 days on 2 cores


def measure(name: str, case, settings: BacktestSettings, workers: int, folder: Path) -> dict:
    store = BacktestStore(f"sqlite:///{folder / f'{name}.sqlite3'}")
    load_before = round(os.getloadavg()[0], 2)
    started = time.perf_counter()
    with open_executor("processes", workers) as executor:
        ident = run_backtest(case, settings, store, executor,
                             progress=lambda done, total, eta: print(f"\r{name}: {done}/{total}, "
                                                                     f"{eta or 0:,.0f} s left   ", end="",
                                                                     file=sys.stderr, flush=True))
    wall = time.perf_counter() - started
    print(file=sys.stderr)
    records = store.records(ident)
    resume_started = time.perf_counter()
    run_backtest(case, settings, store)  # everything recorded: opens, restores the chains, skips
    resume_s = time.perf_counter() - resume_started
    target = TARGETS_S[name] * len(settings.days) / 365
    cpu = float(records["cpu_s"].sum())
    return {"days": len(settings.days), "variants": len(settings.variants), "records": len(records),
            "workers": workers, "wall_s": round(wall, 1), "s_per_record": round(wall / max(1, len(records)), 3),
            "worker_cpu_s": round(cpu, 1), "worker_cpu_s_per_record": round(cpu / max(1, len(records)), 3),
            "wall_on_idle_cores_estimate_s": round(cpu / workers, 1),
            "load_average_before_after": [load_before, round(os.getloadavg()[0], 2)],
            "mean_plan_solve_s": round(float(records["plan_solve_s"].mean()), 3),
            "mean_settle_solve_s": round(float(records["settle_solve_s"].mean()), 3),
            "plan_lp_iterations": int(records["plan_lp_iterations"].fillna(0).sum()),
            "plan_nodes": int(records["plan_nodes"].fillna(0).sum()),
            "mean_record_wall_s": round(float(records["wall_s"].mean()), 3),
            "days_not_settled": int((~metrics.daily(records)["settled"]).sum()),
            "reconcile_problems": int(len(metrics.reconcile(records))),
            "resume_of_finished_s": round(resume_s, 2),
            "target_s": round(target, 1), "within_target": wall <= target}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--days", type=int, default=365, help="days from 2024-12-31 (default 365)")
    parser.add_argument("--workers", type=int, default=default_workers(), help="worker processes (default: cores)")
    parser.add_argument("--only", choices=tuple(TARGETS_S), help="run one of the two measurements")
    parser.add_argument("--out", type=Path, default=RESULTS, help="JSON file to write")
    args = parser.parse_args()
    case = load_case(CASE)
    last = FIRST_DAY + dt.timedelta(days=args.days - 1)
    runs = {"strategies": variants_of(STRATEGIES, [], perfect=False),
            "gamma_grid": variants_of([], GRID, perfect=False)}
    report = {"benchmark": "backtest", "case": case.name, "from": FIRST_DAY.isoformat(), "to": last.isoformat(),
              "dt_h": case.dt_h, "python": platform.python_version(), "machine": platform.machine(),
              "cores": os.cpu_count(), "created": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
              "results": {}}
    with tempfile.TemporaryDirectory() as folder:
        for name, variants in runs.items():
            if args.only and name != args.only:
                continue
            settings = BacktestSettings(FIRST_DAY, last, variants)
            report["results"][name] = measure(name, case, settings, args.workers, Path(folder))
            print(json.dumps({name: report["results"][name]}), file=sys.stderr)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(report, indent=2) + "\n", encoding="utf-8")
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
