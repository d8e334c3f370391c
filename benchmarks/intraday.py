"""Intraday sessions: session solve times and the backtest with three sessions against day-ahead only.

On the paper case, hourly, one process (serial), ``--days`` days from ``--from`` (2025-04-01) for the balanced
preset, each backtest in a fresh SQLite store:

* ``day_ahead``: plan, settle and audit every day (no session);
* ``intraday``: the same, with IDA1, IDA2 and IDA3 between the plan and the settlement.

Prints one JSON document (and writes it to ``benchmarks/results/intraday.json``): the wall time
of each backtest and their ratio (target: at most 3), the median, 90th percentile and maximum of
the day-ahead plan solve and of the session solves (target for a session: hourly median at most
0.3 s, as for the day-ahead plan), next to the machine, date and git commit. Timings on a shared
machine are noisy: repeat and compare.
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.common import header, summary, write_result  # noqa: E402
from rvpp import load_case, with_options  # noqa: E402
from rvpp.backtest import BacktestSettings, run_backtest, variants_of  # noqa: E402
from rvpp.cli.options import Number  # noqa: E402
from rvpp.store import BacktestStore  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
CASE = ROOT / "data" / "cases" / "paper"
RESULTS = ROOT / "benchmarks" / "results" / "intraday.json"
FIRST_DAY = dt.date(2025, 4, 1)
TARGET_SESSION_MEDIAN_S, TARGET_RATIO = 0.3, 3.0


def measure(case, first: dt.date, days: int, intraday: bool, folder: Path) -> tuple[float, list[dict]]:
    store = BacktestStore(f"sqlite:///{folder / ('intraday' if intraday else 'day_ahead')}.sqlite3")
    settings = BacktestSettings(first, first + dt.timedelta(days=days - 1),
                                variants_of(["balanced"], perfect=False), intraday=intraday)
    started = time.perf_counter()
    ident = run_backtest(case, settings, store)
    return time.perf_counter() - started, store.records(ident).to_dict("records")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--days", type=Number(1, 365, whole=True), default=7, help="days (default 7)")
    parser.add_argument("--from", dest="first", type=dt.date.fromisoformat, default=FIRST_DAY,
                        help=f"first day, YYYY-MM-DD (default {FIRST_DAY})")
    parser.add_argument("--out", type=Path, default=RESULTS, help="JSON file to write")
    args = parser.parse_args()
    case = with_options(load_case(CASE), threads=1)
    report = header("intraday", f"{args.days} days from {args.first}")
    report.update(case=case.name, dt_h=case.dt_h, strategy="balanced", sessions=["IDA1", "IDA2", "IDA3"])
    with tempfile.TemporaryDirectory() as folder:
        wall_da, records_da = measure(case, args.first, args.days, False, Path(folder))
        wall_id, records_id = measure(case, args.first, args.days, True, Path(folder))
    sessions = [s for r in records_id for s in (r.get("intraday") or []) if s.get("solve_s") is not None]
    session_solve = [float(s["solve_s"]) for s in sessions]
    report["results"] = {
        "day_ahead_wall_s": round(wall_da, 3), "intraday_wall_s": round(wall_id, 3),
        "ratio": round(wall_id / wall_da, 3), "ratio_target": TARGET_RATIO,
        "within_ratio_target": wall_id / wall_da <= TARGET_RATIO,
        "plan_solve_s": summary([float(r["plan_solve_s"]) for r in records_da if r.get("plan_solve_s") is not None]),
        "session_solve_s": summary(session_solve), "sessions_solved": len(session_solve),
        "session_statuses": {status: sum(s["status"] == status for s in sessions)
                             for status in sorted({s["status"] for s in sessions})},
        "session_median_target_s": TARGET_SESSION_MEDIAN_S,
        "within_session_target": summary(session_solve)["median"] <= TARGET_SESSION_MEDIAN_S,
    }
    write_result(report, args.out)
    print(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
