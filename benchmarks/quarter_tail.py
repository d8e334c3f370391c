"""The 15-minute tail: which days of 2025 tie at the Γ boundary, and how long they take.

With hourly data brought to quarter-hours by a mean-keeping interpolation (MODEL_SPEC §6)
instead of repeating each hour, four quarter-hours no longer share one deviation, so
fewer budgets fall among tied deviations. This scans every (day, strategy) pair of 2025
at 15 minutes for such ties (from the bands, no model built), then times ``rvpp.solve``
(default, exact tie semantics) on every tie pair and on ``--sample`` further days of the
year spread evenly (every strategy), against the 5 s worst-day target, by wall time and by
the process's CPU time (on a shared machine the closer measure of a quiet one). With ``--all`` it
times every pair of the year (long); ``--part K/N`` times every N-th of those pairs from the
K-th on, so N processes share the year, each with its own result file. Each timed pair is
appended to a ``.jsonl`` beside the result as it finishes, and a run started again with the
same options continues from there. Prints the JSON it writes to
``benchmarks/results/quarter_tail[-partKofN].json``.

A year timed by processes sharing two cores with other work is slower than a quiet machine,
so ``--retime-over S`` reads the progress files of every ``--all`` run (all parts) and times
again, one after the other, each pair that took over ``S`` s of CPU time there (wall time
there says more about the other work than about the pair),
writing ``quarter_tail-retimed.json``: the pairs still over the target, each with its cause
(tied deviations or not; closed at the root or after how many nodes).

Usage: ``python benchmarks/quarter_tail.py [--sample 12] [--all] [--part K/N] [--retime-over S]``
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.common import CASE, RESULTS, STRATEGIES, header, load_average, summary, write_result  # noqa: E402
from benchmarks.solve_times import TARGETS, say, tie_days, timed_solve, year_pairs  # noqa: E402
from rvpp import load_case, solve, with_options  # noqa: E402
from rvpp.uncertainty.problem import prepare, tied_budgets  # noqa: E402

DT_H = 0.25


def spread_days(year: int, count: int) -> list[str]:
    """``count`` days of ``year`` at equal steps, starting on 3 January."""
    first = dt.date(year, 1, 3)
    step = 365 // max(count, 1)
    return [(first + dt.timedelta(days=i * step)).isoformat() for i in range(count)]


def part(text: str) -> tuple[int, int]:
    """``"K/N"`` as (K, N), 1 <= K <= N."""
    try:
        k, n = (int(field) for field in text.split("/"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"--part {text!r}: expected K/N, e.g. 1/2") from None
    if not 1 <= k <= n:
        raise argparse.ArgumentTypeError(f"--part {text!r}: K must lie between 1 and N")
    return k, n


def done_rows(progress: Path) -> dict:
    """The pairs already timed by an earlier run with the same options, from its progress file
    (a line cut short by a crash is dropped)."""
    rows = {}
    if progress.exists():
        for line in progress.read_text(encoding="utf-8").splitlines():
            try:
                record = json.loads(line)
            except json.JSONDecodeError:
                continue
            rows[record.pop("pair")] = record
    return rows


def time_pair(base, day: str, strategy: str) -> dict:
    """``rvpp.solve`` of ``base`` on ``day`` with ``strategy`` at 15 minutes, timed, with the
    tied sources (if any) and the load average just after."""
    case = with_options(base, strategy=strategy, dt_h=DT_H, date=day)
    row = timed_solve(case)
    row["tied"] = tied_budgets(prepare(case))
    row["load_average"] = load_average()
    say(f"15 min {day} {strategy:13s}", row)
    return row


def run(sample: int, every: bool, share: tuple[int, int] = (1, 1), progress: Path | None = None) -> dict:
    base = load_case(CASE)
    solve(with_options(base, dt_h=DT_H))  # imports and first-call costs are not part of any measurement
    document = header("quarter_tail", ("all" if every else f"ties+{sample}")
                      + (f" part {share[0]}/{share[1]}" if share[1] > 1 else ""))
    target = TARGETS[DT_H]["max"]
    scanned = year_pairs()
    ties = tie_days(base, DT_H, scanned)
    print(f"{len(ties)} tie pairs of {len(scanned)}", file=sys.stderr, flush=True)
    if every:
        timed = scanned
    else:
        extra = [(day, strategy) for day in spread_days(2025, sample) for strategy in STRATEGIES]
        timed = list(dict.fromkeys([*ties, *extra]))
    timed = timed[share[0] - 1::share[1]]
    ties = [pair for pair in ties if pair in timed]
    earlier = done_rows(progress) if progress is not None else {}
    rows = {}
    for day, strategy in timed:
        key = f"{day} {strategy}"
        if key in earlier:
            rows[key] = earlier[key]
            continue
        row = rows[key] = time_pair(base, day, strategy)
        if progress is not None:
            with progress.open("a", encoding="utf-8") as log:
                log.write(json.dumps({"pair": key, **row}) + "\n")
    over = {key: row for key, row in rows.items() if max(row["total_s"], row["cpu_s"]) > target}
    document.update(case=base.name, dt_h=DT_H, target_max_s=target, pairs_scanned=len(scanned),
                    tie_pairs=[f"{d} {s}" for d, s in ties], timed_pairs=len(rows),
                    over_timed_s=summary([row["total_s"] for row in rows.values()]),
                    over_timed_cpu_s=summary([row["cpu_s"] for row in rows.values()]),
                    over_tie_pairs_s=summary([rows[f"{d} {s}"]["total_s"] for d, s in ties]) if ties else None,
                    over_tie_pairs_cpu_s=summary([rows[f"{d} {s}"]["cpu_s"] for d, s in ties]) if ties else None,
                    over_target={key: {"total_s": row["total_s"], "cpu_s": row["cpu_s"], "nodes": row["nodes"],
                                       "tied": row["tied"]} for key, row in over.items()},
                    load_average_after=load_average(), days=rows)
    return document


def cause(row: dict) -> str:
    """Why a pair took long, in a phrase: tied deviations, then the search's size."""
    where = "closed at the root" if (row["nodes"] or 0) <= 1 else f"{row['nodes']} nodes"
    if row["status"] != "optimal":
        where = f"{row['status']} after {row['nodes']} nodes"
    ties = f"tied deviations ({'; '.join(row['tied'])})" if row["tied"] else "no ties"
    return f"{ties}; {where}; {row['lp_iterations'] or 0:,} LP iterations"


def retime(over_s: float) -> dict:
    """Time again, alone, the pairs of the ``--all`` runs' progress files over ``over_s``."""
    earlier = {}
    for progress in sorted(RESULTS.glob("quarter_tail*-all.jsonl")):
        earlier.update(done_rows(progress))
    if not earlier:
        sys.exit("no year scan to re-time: run with --all first (benchmarks/results/quarter_tail*-all.jsonl)")
    slow = sorted(key for key, row in earlier.items() if row["cpu_s"] > over_s)
    print(f"{len(slow)} of {len(earlier)} pairs over {over_s:g} s of CPU time in the scan", file=sys.stderr, flush=True)
    base = load_case(CASE)
    solve(with_options(base, dt_h=DT_H))
    document = header("quarter_tail-retimed", f"over {over_s:g} s")
    target = TARGETS[DT_H]["max"]
    rows = {}
    for key in slow:
        day, strategy = key.split()
        row = rows[key] = time_pair(base, day, strategy)
        row["scan_total_s"], row["scan_cpu_s"] = earlier[key]["total_s"], earlier[key]["cpu_s"]
    still = {key: row for key, row in rows.items() if max(row["total_s"], row["cpu_s"]) > target}
    document.update(case=base.name, dt_h=DT_H, target_max_s=target, pairs_scanned=len(earlier), retime_over_s=over_s,
                    pairs_retimed=len(rows), pairs_over_target=len(still),
                    tied_over_target=sum(1 for row in still.values() if row["tied"]),
                    over_target={key: {"total_s": row["total_s"], "cpu_s": row["cpu_s"], "cause": cause(row)}
                                 for key, row in still.items()},
                    days=rows)
    return document


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sample", type=int, default=12, help="days of 2025 timed besides the tie pairs")
    parser.add_argument("--all", action="store_true", help="time every (day, strategy) pair of 2025")
    parser.add_argument("--part", type=part, default=(1, 1), metavar="K/N",
                        help="time only every N-th pair from the K-th on (N processes share the year)")
    parser.add_argument("--retime-over", type=float, metavar="S",
                        help="time again, one at a time, the pairs of the year scans that took over S seconds of CPU time")
    args = parser.parse_args()
    if args.retime_over is not None:
        if not args.retime_over > 0:
            parser.error(f"--retime-over {args.retime_over:g}: expected a number of seconds above 0")
        document = retime(args.retime_over)
        write_result(document, RESULTS / "quarter_tail-retimed.json")
        print(json.dumps({key: value for key, value in document.items() if key not in ("days", "machine")}, indent=1))
        return
    suffix = f"-part{args.part[0]}of{args.part[1]}" if args.part[1] > 1 else ""
    name = f"quarter_tail{suffix}"
    progress = RESULTS / f"{name}-{'all' if args.all else f'ties+{args.sample}'}.jsonl"
    RESULTS.mkdir(parents=True, exist_ok=True)
    document = run(args.sample, args.all, args.part, progress)
    write_result(document, RESULTS / f"{name}.json")
    print(json.dumps({key: value for key, value in document.items() if key != "days"}, indent=1))


if __name__ == "__main__":
    main()
