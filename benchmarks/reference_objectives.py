"""Record the optimal objectives of a fixed list of (day, strategy, period length) cases.

The list is the one ``tests/test_equivalence.py`` checks: every speed-up of the
formulation or of the solver strategy must reach the same optimum within the MIP gap.
The numbers in ``tests/data/reference_objectives.json`` were produced once with this
script on the formulation before those speed-ups (its git commit is recorded in the
file); rerun it only to add cases, never to make a failing comparison pass.

Usage: ``python benchmarks/reference_objectives.py [--out tests/data/reference_objectives.json]``
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import subprocess
import sys
import time
from importlib import metadata
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from rvpp import load_case, solve, with_options  # noqa: E402

CASE = ROOT / "data" / "cases" / "paper"
STRATEGIES = ("deterministic", "optimistic", "balanced", "pessimistic")
HOURLY_DAYS = tuple(f"2025-{month:02d}-15" for month in range(1, 13)) + ("2025-05-05",)
QUARTER_HOUR_DAYS = ("2025-02-15", "2025-05-05", "2025-08-15")
REL_GAP = 1e-4


def cases() -> list[dict]:
    """The fixed list: 13 hourly days and 3 quarter-hour days, every strategy."""
    hourly = [{"date": d, "strategy": s, "dt_h": 1.0} for d in HOURLY_DAYS for s in STRATEGIES]
    quarter = [{"date": d, "strategy": s, "dt_h": 0.25} for d in QUARTER_HOUR_DAYS for s in STRATEGIES]
    return hourly + quarter


def git_commit() -> str:
    try:
        return subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True,
                              check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(ROOT / "tests" / "data" / "reference_objectives.json"))
    args = parser.parse_args()
    base = load_case(CASE)
    rows = []
    for spec in cases():
        started = time.perf_counter()
        result = solve(with_options(base, date=spec["date"], strategy=spec["strategy"], dt_h=spec["dt_h"],
                                    rel_gap=REL_GAP, time_limit_s=600))
        rows.append({**spec, "status": str(result.status), "objective_eur": result.objective_eur,
                     "bound_eur": result.bound_eur, "seconds": round(time.perf_counter() - started, 2)})
        print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
    document = {
        "produced_by": "benchmarks/reference_objectives.py",
        "git_commit": git_commit(),
        "date": dt.date.today().isoformat(),
        "highspy": metadata.version("highspy"),
        "rel_gap": REL_GAP,
        "case": "data/cases/paper",
        "cases": rows,
    }
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_suffix(".tmp")
    tmp.write_text(json.dumps(document, indent=1) + "\n")
    os.replace(tmp, out)


if __name__ == "__main__":
    main()
