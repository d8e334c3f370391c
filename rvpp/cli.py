"""Command line: ``python -m rvpp solve|data|study ...``.

Bad input ends with a one-line message and exit code 2, never a traceback; a solve
without a plan (infeasible, solver error) exits with 1.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .data.case import STRATEGIES, load_case, with_options
from .data.variants import describe
from .errors import RvppError

DEFAULT_CASE = Path(__file__).resolve().parent.parent / "data" / "cases" / "paper"


def main(argv: list[str] | None = None) -> int:
    parser = _parser()
    args = parser.parse_args(argv)
    if not hasattr(args, "run"):
        parser.print_help()
        return 2
    try:
        return args.run(args)
    except RvppError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"error: {exc.strerror or exc}: {exc.filename or ''}".rstrip(": "), file=sys.stderr)
        return 2


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m rvpp", description=(
        "Robust day-ahead bids for a renewable-only virtual power plant (DAM, aFRR reserve, heat purchase)."))
    commands = parser.add_subparsers(title="commands")

    solve = commands.add_parser("solve", help="compute the plan of one delivery day and export it",
                                description="Compute the robust plan of one delivery day and write it to --out.")
    solve.add_argument("--case", type=Path, default=DEFAULT_CASE, help="case folder (default: the paper case)")
    solve.add_argument("--date", help="delivery date YYYY-MM-DD (default: the case's)")
    solve.add_argument("--strategy", choices=STRATEGIES, help="budget preset (default: the case's)")
    solve.add_argument("--gamma", action="append", default=[], metavar="SOURCE=N",
                       help="budget of one source in periods: price_da, price_sr_up, price_sr_dn or a unit "
                            "name (repeatable)")
    solve.add_argument("--budget-mode", choices=("paper", "planner_chosen"),
                       help="paper (default): deviations in the largest-deviation periods; planner_chosen: "
                            "the variant as printed, for teaching")
    solve.add_argument("--markets", help="comma-separated subset of DAM,SRM,HPA (DAM always)")
    solve.add_argument("--no-csp", action="store_true", help="remove every CSP from the portfolio")
    solve.add_argument("--hpa-flat", type=float, metavar="EUR_PER_MWH", help="flat HPA tariff for every hour")
    solve.add_argument("--dt", type=float, choices=(1.0, 0.5, 0.25), help="period length in hours")
    solve.add_argument("--time-limit", type=float, metavar="S", help="solver time limit in seconds")
    solve.add_argument("--gap", type=float, help="relative MIP gap (default 1e-4)")
    solve.add_argument("--threads", type=int, help="HiGHS threads (0 = HiGHS default)")
    solve.add_argument("--out", type=Path, default=Path("out"), help="output folder (default: ./out)")
    solve.add_argument("--write-mps", type=Path, metavar="FILE", help="also write the MILP as an MPS file")
    solve.add_argument("--quiet", action="store_true", help="print only errors")
    solve.set_defaults(run=_run_solve)

    data = commands.add_parser("data", help="build the default dataset")
    data_commands = data.add_subparsers(title="data commands")
    build = data_commands.add_parser("build", help="regenerate the synthetic history of the paper case")
    build.add_argument("--seed", type=int, help="random seed (default: the published one)")
    build.add_argument("--out", type=Path, default=DEFAULT_CASE / "history.csv", help="CSV to write")
    build.set_defaults(run=_run_data_build)

    from .studies.cli import add_study_commands

    add_study_commands(commands)
    return parser


def _parse_gammas(items: list[str]) -> dict[str, int]:
    gammas = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise RvppError(f"--gamma {item!r} must look like SOURCE=N, e.g. price_da=6 or WF1=3")
        try:
            gamma = int(value)
        except ValueError:
            raise RvppError(f"--gamma {item!r}: N={value!r} must be a whole number of periods") from None
        if gamma < 0:
            raise RvppError(f"--gamma {item!r}: N={gamma} must be >= 0")
        gammas[name.strip()] = gamma
    return gammas


def _run_solve(args: argparse.Namespace) -> int:
    from .outputs.export import write_plan
    from .solving.plan import solve, write_mps

    say = (lambda _m: None) if args.quiet else (lambda m: print(f"  {m}", file=sys.stderr))
    case = load_case(args.case)
    case = with_options(case, date=args.date, strategy=args.strategy, gammas=_parse_gammas(args.gamma),
                        markets=args.markets, csp=not args.no_csp, hpa_flat=args.hpa_flat, dt_h=args.dt,
                        budget_mode=args.budget_mode, time_limit_s=args.time_limit, rel_gap=args.gap,
                        threads=args.threads)
    if not args.quiet:
        print(f"rvpp: case {case.name}, {case.delivery_date}, {describe(case)}", file=sys.stderr)
    if args.write_mps:
        write_mps(case, args.write_mps)
        say(f"wrote {args.write_mps}")
    result = solve(case, progress=say)
    written = write_plan(result, args.out)
    if not args.quiet:
        print(_describe(result), file=sys.stderr)
        print(f"wrote {', '.join(p.name for p in written)} to {args.out}", file=sys.stderr)
    if not result.has_plan:
        if args.quiet:
            print(f"error: {result.status}: {result.message}", file=sys.stderr)
        return 1
    return 0


def _describe(result) -> str:
    if not result.has_plan:
        return f"status {result.status}: {result.message}"
    gap = f"{result.mip_gap:.2e}" if result.mip_gap is not None else "n/a"
    return (f"status {result.status}; profit {result.objective_eur:,.0f} EUR (cost {result.cost_keur:.1f} kEUR); "
            f"MIP gap {gap}; build {result.build_s:.2f} s, solve {result.solve_s:.2f} s")


def _run_data_build(args: argparse.Namespace) -> int:
    from .data import synth

    seed = synth.DEFAULT_SEED if args.seed is None else args.seed
    frame = synth.write_history(args.out, seed=seed)
    print(f"wrote {len(frame)} hours to {args.out} (seed {seed})", file=sys.stderr)
    return 0
