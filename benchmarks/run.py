"""Run every solver benchmark and print their tables: ``make bench`` (``make bench BENCH=quick``).

Each benchmark writes its JSON to ``benchmarks/results/`` (see ``benchmarks/common.py``):
``solve_times`` (days through the year, hourly and at 15 minutes), ``gamma_sweep``,
``new_units`` (the paper case with a battery, a hydro and a biomass unit), ``stochastic`` (paper
Table 14) and ``scaling``. Quick mode (a few minutes) uses four
days, N = 5 and 10 and the two smaller sizes of each scaling axis; the full run takes
about half an hour on two cores.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks import gamma_sweep, new_units, scaling, solve_times, stochastic  # noqa: E402
from benchmarks.common import DAYS, QUICK_DAYS, write_result  # noqa: E402
from rvpp.studies.settings import SCENARIO_COUNTS  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mode", choices=("full", "quick"), default="full")
    args = parser.parse_args()
    quick = args.mode == "quick"
    steps = [
        (solve_times, lambda: solve_times.run(QUICK_DAYS if quick else DAYS, quick)),
        (new_units, lambda: new_units.run(QUICK_DAYS if quick else DAYS, quick)),
        (gamma_sweep, lambda: gamma_sweep.run(quick)),
        (stochastic, lambda: stochastic.run((5, 10) if quick else SCENARIO_COUNTS, quick)),
        (scaling, lambda: scaling.run(quick)),
    ]
    documents = []
    for module, run in steps:
        document = run()
        write_result(document)
        documents.append((module, document))
    print()
    for module, document in documents:
        module.print_table(document)
        print()


if __name__ == "__main__":
    main()
