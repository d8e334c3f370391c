"""Wall time of the rolling backtest on the paper case, hourly, on local worker processes.

Two measurements against their targets, each in a fresh SQLite store:

* ``strategies``: the four presets (plan + settlement + audit), ``--days`` days
  (default 365): target 10 min on 2 cores;
* ``gamma_grid``: 8 Γ fractions of the day, the same days: target 20 min on 2 cores;

and the cost of resuming: rerunning a finished backtest (every day skipped). Writes one
JSON document to ``benchmarks/results/backtest.json``: wall times,
seconds per record, the CPU seconds the workers spent per record (and the wall time
they imply on otherwise idle cores: total CPU / workers), the load average before and
after, the mean plan and settlement solve times and the plans' LP iterations and nodes (which
do not depend on the load) from the records, and whether each
target was met by the measured wall time, next to the machine, package versions, date and git
commit every benchmark records (``benchmarks/common.py``); prints a short table. ``--days 28``
gives a quick look; the targets are for a year. Timings on a shared machine are noisy: repeat
and compare.
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.common import header, write_result  # noqa: E402
from rvpp import load_case  # noqa: E402
from rvpp.backtest import BacktestSettings, metrics, run_backtest, variants_of  # noqa: E402
from rvpp.cli.options import Number  # noqa: E402
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
        ident = run_backtest(case, settings, store, executor, progress=Progress(name))
    wall = time.perf_counter() - started
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


class Progress:
    """Records done and the time left on standard error: one line redrawn on a terminal, a line
    per tenth of the work in a log file."""

    def __init__(self, name: str):
        self.name, self.tty, self.shown = name, sys.stderr.isatty(), -1

    def __call__(self, done: int, total: int, eta_s: float | None) -> None:
        line = f"{self.name}: {done:,}/{total:,} records, {eta_s or 0:,.0f} s left"
        if self.tty:
            print(f"\r{line}   ", end="" if done < total else "\n", file=sys.stderr, flush=True)
        elif done * 10 // max(1, total) > self.shown:
            self.shown = done * 10 // max(1, total)
            print(line, file=sys.stderr, flush=True)


def print_table(report: dict) -> None:
    print(f"backtest, {report['from']} to {report['to']}, hourly, workers on local processes")
    print(f"{'run':12s} {'records':>8s} {'wall s':>8s} {'s/record':>9s} {'plan s':>7s} {'settle s':>8s}  target")
    for name, row in report["results"].items():
        print(f"{name:12s} {row['records']:8,d} {row['wall_s']:8.1f} {row['s_per_record']:9.3f} "
              f"{row['mean_plan_solve_s']:7.3f} {row['mean_settle_solve_s']:8.3f}  <= {row['target_s']:g} s"
              f"{'' if row['within_target'] else '  (missed)'}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--days", type=Number(1, 365, whole=True), default=365,
                        help="days from 2024-12-31, 1 to 365 (default 365)")
    parser.add_argument("--workers", type=Number(1, 64, whole=True), default=default_workers(),
                        help="worker processes, 1 to 64 (default: one per core)")
    parser.add_argument("--only", choices=tuple(TARGETS_S), help="run one of the two measurements")
    parser.add_argument("--out", type=Path, default=RESULTS, help="JSON file to write")
    args = parser.parse_args()
    case = load_case(CASE)
    last = FIRST_DAY + dt.timedelta(days=args.days - 1)
    runs = {"strategies": variants_of(STRATEGIES, [], perfect=False),
            "gamma_grid": variants_of([], GRID, perfect=False)}
    report = header("backtest", "full" if args.days == 365 else f"{args.days} days")
    report.update(case=case.name, dt_h=case.dt_h, results={})
    report["from"], report["to"] = FIRST_DAY.isoformat(), last.isoformat()
    with tempfile.TemporaryDirectory() as folder:
        for name, variants in runs.items():
            if args.only and name != args.only:
                continue
            settings = BacktestSettings(FIRST_DAY, last, variants)
            report["results"][name] = measure(name, case, settings, args.workers, Path(folder))
            print(json.dumps({name: report["results"][name]}), file=sys.stderr)
    write_result(report, args.out)
    print_table(report)


if __name__ == "__main__":
    main()
