"""Solve times of the paper case with one battery, one hydro and one biomass unit (MODEL_SPEC §13).

The bundled case plus the three units of the workbook templates (``rvpp.outputs.workbook.UNIT_TEMPLATES``:
a 20 MW / 40 MWh battery, a 30 MW hydro plant with 300 MWh of water, a 15 MW biomass plant),
solved with the balanced strategy on the benchmark's days, hourly and at 15 minutes: the wall
time of ``rvpp.solve`` and the process CPU time of each solve (on a machine shared with other
work the CPU time is the closer measure of a quiet machine), HiGHS's nodes, the median and the
worst day next to the targets. Writes ``benchmarks/results/new_units.json``.

Usage: ``python benchmarks/new_units.py [--quick]`` (quick: four days).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.common import CASE, DAYS, QUICK_DAYS, header, summary, write_result  # noqa: E402
from benchmarks.solve_times import say, timed_solve  # noqa: E402
from rvpp import load_case, with_options  # noqa: E402
from rvpp.outputs.workbook import UNIT_TEMPLATES  # noqa: E402

TARGETS = {1.0: {"median": 0.3, "max": 1.0}, 0.25: {"median": 2.0}}
NAMES = {"battery": "BAT1", "hydro": "HY1", "biomass": "BIO1"}


def with_new_units(case):
    """The case with one unit of each kind beyond the paper's, from the templates."""
    return case.replace(**{kind: [{"name": name, **UNIT_TEMPLATES[kind]}] for kind, name in NAMES.items()})


def run(days: tuple[str, ...], quick: bool) -> dict:
    base = with_new_units(load_case(CASE))
    document = header("new_units", "quick" if quick else "full")
    document.update(days=list(days), strategy="balanced", units=NAMES, periods={})
    for dt_h in TARGETS:
        rows = {}
        for day in days:
            rows[day] = timed_solve(with_options(base, strategy="balanced", dt_h=dt_h, date=day))
            say(f"dt {dt_h:g} h {day}", rows[day])
        solved = [row for row in rows.values() if row["status"] == "optimal"]
        wall, cpu = summary([r["total_s"] for r in solved]), summary([r["cpu_s"] for r in solved])
        target = TARGETS[dt_h]
        document["periods"][f"{dt_h:g}"] = {
            "days": rows, "optimal": len(solved), "wall_s": wall, "cpu_s": cpu, "target_s": target,
            "within_target_wall": {k: wall[k] <= v for k, v in target.items()},
            "within_target_cpu": {k: cpu[k] <= v for k, v in target.items()},
        }
    return document


def print_table(document: dict) -> None:
    print(f"new units ({', '.join(document['units'].values())}), balanced, {len(document['days'])} days")
    for dt_h, part in document["periods"].items():
        print(f"  dt {dt_h} h: wall median {part['wall_s']['median']:.3f} s max {part['wall_s']['max']:.3f} s; "
              f"CPU median {part['cpu_s']['median']:.3f} s max {part['cpu_s']['max']:.3f} s; "
              f"target {part['target_s']}; optimal {part['optimal']}/{len(part['days'])}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    document = run(QUICK_DAYS if args.quick else DAYS, args.quick)
    write_result(document)
    print_table(document)


if __name__ == "__main__":
    main()
