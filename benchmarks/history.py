"""Time to generate the synthetic history of the paper case (``rvpp.data.synth``).

Prints one JSON document: the median wall seconds over ``--repeat`` runs of
``build_history`` (13 months of hourly data) and the target it is measured against.
Run with ``make bench``.
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

from rvpp.data import synth  # noqa: E402

TARGET_S = 15.0  # a fresh machine rebuilds the default history within this


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=3, help="runs (median reported)")
    args = parser.parse_args()
    seconds, rows = [], 0
    for _ in range(args.repeat):
        started = time.perf_counter()
        rows = len(synth.build_history())
        seconds.append(time.perf_counter() - started)
    median = statistics.median(seconds)
    print(json.dumps({"benchmark": "synthetic history", "hours": rows, "repeat": args.repeat,
                      "seconds": [round(s, 3) for s in seconds], "median_s": round(median, 3),
                      "target_s": TARGET_S, "within_target": median <= TARGET_S,
                      "python": platform.python_version(), "machine": platform.machine()}, indent=2))


if __name__ == "__main__":
    main()
