"""Time to generate the synthetic history of the paper case (``rvpp.data.synth``).

Writes ``benchmarks/results/history.json`` (with the machine, package versions, date and
git commit of every benchmark): the wall seconds of each of ``--repeat`` runs of
``build_history`` (13 months of hourly data), their median and the target it is measured
against; prints one line. Run with ``make bench``.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.common import header, write_result  # noqa: E402
from rvpp.cli.options import Number  # noqa: E402
from rvpp.data import synth  # noqa: E402

TARGET_S = 15.0  # a fresh machine rebuilds the default history within this


def run(repeat: int) -> dict:
    document = header("history", "full")
    seconds, rows = [], 0
    for _ in range(repeat):
        started = time.perf_counter()
        rows = len(synth.build_history())
        seconds.append(time.perf_counter() - started)
    median = statistics.median(seconds)
    document.update(hours=rows, repeat=repeat, seconds=[round(s, 3) for s in seconds], median_s=round(median, 3),
                    target_s=TARGET_S, within_target=median <= TARGET_S)
    return document


def print_table(document: dict) -> None:
    print(f"synthetic history, {document['hours']:,} hours: median {document['median_s']:.3f} s of "
          f"{document['repeat']} runs; target <= {document['target_s']:g} s"
          f"{'' if document['within_target'] else '  (missed)'}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=Number(1, 100, whole=True), default=3,
                        help="runs, 1 to 100 (the median is reported; default 3)")
    args = parser.parse_args()
    document = run(args.repeat)
    write_result(document)
    print_table(document)


if __name__ == "__main__":
    main()
