"""How solve time grows with the number of periods, of wind and PV units, and of CSPs.

The default day, balanced strategy, build + solve + extract: periods 24/48/96
(dt = 1, 0.5, 0.25 h), wind+PV units 5/20/50 (copies of the case's two wind farms and
three PV plants following the same history columns), CSPs 1/2/4 (copies of the
case's CSP). For each axis a least-squares fit of log(time) on log(size) gives the
exponent b of time ~ size^b. Writes ``benchmarks/results/scaling.json``.

Usage: ``python benchmarks/scaling.py [--quick]`` (quick: the two smaller sizes of each axis).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.common import CASE, header, write_result  # noqa: E402
from rvpp import load_case, solve, with_options  # noqa: E402

AXES = {"periods": (24, 48, 96), "ndres_units": (5, 20, 50), "csp_units": (1, 2, 4)}


def copies(units, n: int) -> list:
    """``n`` units cycling through ``units``; copies follow the original's history column."""
    out = []
    for i in range(n):
        unit = units[i % len(units)]
        if i < len(units):
            out.append(unit)
        elif hasattr(unit, "solar_field"):
            out.append(unit.model_copy(update={"name": f"{unit.name}_{i}", "solar_field": unit.solar_field.model_copy(
                update={"series": unit.column})}))
        else:
            out.append(unit.model_copy(update={"name": f"{unit.name}_{i}", "series": unit.column}))
    return out


def variant(base, axis: str, size: int):
    if axis == "periods":
        return with_options(base, dt_h=24 / size)
    if axis == "ndres_units":
        units = copies(list(base.ndres), size)
        return base.replace(wind=[u for u in units if u.kind == "wind"], pv=[u for u in units if u.kind == "pv"])
    return base.replace(csp=copies(list(base.csp), size))


def exponent(sizes, seconds) -> float | None:
    if len(sizes) < 2:
        return None
    return round(float(np.polyfit(np.log(sizes), np.log(seconds), 1)[0]), 2)


def run(quick: bool) -> dict:
    base = with_options(load_case(CASE), strategy="balanced")
    solve(base)
    document = header("scaling", "quick" if quick else "full")
    document.update(case=base.name, date=base.delivery_date.isoformat(), strategy="balanced", axes={})
    for axis, sizes in AXES.items():
        sizes = sizes[:2] if quick else sizes
        rows = []
        for size in sizes:
            case = variant(base, axis, size)
            started = time.perf_counter()
            result = solve(case)
            rows.append({"size": size, "status": str(result.status), "total_s": round(time.perf_counter() - started, 3),
                         "solve_s": round(result.solve_s, 3), "nodes": result.nodes,
                         "lp_iterations": result.lp_iterations, "objective_eur": result.objective_eur})
            print(f"{axis} {size}: {rows[-1]['total_s']} s", file=sys.stderr, flush=True)
        document["axes"][axis] = {"runs": rows, "exponent": exponent([r["size"] for r in rows],
                                                                     [r["total_s"] for r in rows])}
    return document


def print_table(document: dict) -> None:
    print(f"scaling (balanced, default day), time ~ size^b; load average {document['load_average_before']}")
    for axis, block in document["axes"].items():
        cells = ", ".join(f"{r['size']}: {r['total_s']:.2f} s" for r in block["runs"])
        print(f"  {axis:12s} {cells}; b = {block['exponent']}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    document = run(args.quick)
    write_result(document)
    print_table(document)


if __name__ == "__main__":
    main()
