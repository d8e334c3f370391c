"""``python -m rvpp solve``: the robust plan of one delivery day, exported to a folder."""

from __future__ import annotations

import argparse
import signal
import sys
from contextlib import contextmanager
from pathlib import Path

from ..data.case import MAX_QUANTITY, MAX_THREADS, STRATEGIES
from ..data.case_yaml import load_case
from ..data.files import check_replaceable, excerpt
from ..data.periods import ALLOWED_DT_H
from ..data.variants import describe, with_options
from ..errors import RvppError
from ..outputs.money import amount
from ..uncertainty.problem import tied_budgets
from .options import DEFAULT_CASE, FAILURE, Number, choice_of, date_option, market_list, path_option

SEARCH_REPORT_S = 5.0  # a solve's search reports itself this often [s]


def add_solve_command(commands) -> None:
    """Add ``solve`` to the commands."""
    solve = commands.add_parser("solve", help="compute the plan of one delivery day and export it",
                                description="Compute the robust plan of one delivery day and write it to --out. "
                                            "Ctrl-C during a long search writes the best plan found so far "
                                            "(status stopped, with its gap); a second Ctrl-C gives up.")
    solve.add_argument("--case", type=path_option, default=DEFAULT_CASE, help="case folder (default: the paper case)")
    solve.add_argument("--date", type=date_option, help="delivery date YYYY-MM-DD (default: the case's)")
    solve.add_argument("--strategy", choices=STRATEGIES, help="budget preset (default: the case's)")
    solve.add_argument("--gamma-fraction", type=Number(0, 1, unit="fraction of the day"), metavar="F",
                       help="Γ of every source as a fraction of the day, Γ = round(F·periods) (replaces the "
                            "strategy preset; e.g. the recommended Γ of python -m rvpp backtest recommend)")
    solve.add_argument("--gamma", action="append", default=[], metavar="SOURCE=N",
                       help="budget of one source in periods: price_da, price_sr_up, price_sr_dn or a unit "
                            "name (repeatable)")
    solve.add_argument("--budget-mode", choices=("paper", "planner_chosen"),
                       help="paper (default): deviations in the largest-deviation periods; planner_chosen: "
                            "the variant as printed, for teaching")
    solve.add_argument("--ties", choices=("choose", "earliest"),
                       help="paper mode, where equal deviations straddle Γ: choose (default): the model picks "
                            "which deviate, as the binary formulation does; earliest: the earliest of them "
                            "deviate (one fixed pattern, faster on such days)")
    solve.add_argument("--markets", type=market_list, help="comma-separated subset of DAM,SRM,HPA (DAM always)")
    solve.add_argument("--no-csp", action="store_true", help="remove every CSP from the portfolio")
    solve.add_argument("--hpa-flat", type=Number(0, MAX_QUANTITY, unit="EUR/MWh_th"), metavar="EUR_PER_MWH",
                       help="flat HPA tariff for every hour")
    solve.add_argument("--dt", type=choice_of(ALLOWED_DT_H, "h"), help="period length in hours: 1, 0.5 or 0.25")
    solve.add_argument("--time-limit", type=Number(0, MAX_QUANTITY, low_open=True, unit="s"), metavar="S",
                       help="solver time limit in seconds")
    solve.add_argument("--gap", type=Number(0, 1, high_open=True),
                       help="relative MIP gap in [0, 1) (default: the case's solver.rel_gap, 1e-4 in the bundled case)")
    solve.add_argument("--threads", type=Number(0, MAX_THREADS, whole=True),
                       help="HiGHS threads (0 = HiGHS default)")
    solve.add_argument("--out", type=path_option, default=Path("out"), help="output folder (default: ./out)")
    solve.add_argument("--write-mps", type=path_option, metavar="FILE", help="also write the MILP as an MPS file")
    solve.add_argument("--quiet", action="store_true", help="print only errors")
    solve.set_defaults(run=_run_solve)


def _parse_gammas(items: list[str]) -> dict[str, int]:
    gammas = {}
    for item in items:
        shown = excerpt(item)
        name, sep, value = item.partition("=")
        name = name.strip()
        if not sep or not name:
            raise RvppError(f"--gamma {shown!r} must look like SOURCE=N, e.g. price_da=6 or WF1=3")
        try:
            gamma = int(value)
        except ValueError:
            raise RvppError(f"--gamma {shown!r}: N={excerpt(value)!r} must be a whole number of periods") from None
        if gamma < 0:
            raise RvppError(f"--gamma {shown!r}: N={gamma} must be >= 0")
        if name in gammas:
            raise RvppError(f"--gamma gives {excerpt(name)!r} twice ({name}={gammas[name]} and {name}={gamma}); "
                            "keep one")
        gammas[name] = gamma
    return gammas


def _run_solve(args: argparse.Namespace) -> int:
    # heavy: the optimisation stack (Pyomo, HiGHS) loads only when a solve runs
    from ..outputs.export import check_plan_folder, write_plan
    from ..solving.plan import MPS_HEADERS, solve, write_mps

    say = (lambda _m: None) if args.quiet else (lambda m: print(f"  {m}", file=sys.stderr))
    case = load_case(args.case)
    case = with_options(case, date=args.date, strategy=args.strategy, gamma_fraction=args.gamma_fraction,
                        gammas=_parse_gammas(args.gamma),
                        markets=args.markets, csp=not args.no_csp, hpa_flat=args.hpa_flat, dt_h=args.dt,
                        budget_mode=args.budget_mode, ties=args.ties, time_limit_s=args.time_limit, rel_gap=args.gap,
                        threads=args.threads)
    check_plan_folder(args.out)  # before the solve, not after it
    if not args.quiet:
        print(f"rvpp: case {excerpt(case.name)}, {case.delivery_date}, {describe(case)}", file=sys.stderr)
    if args.write_mps:
        check_replaceable(args.write_mps, MPS_HEADERS, "an MPS file")
        write_mps(case, args.write_mps)
        say(f"wrote {args.write_mps}")
    stop = SearchStop(say)
    with stop.on_ctrl_c():
        result = solve(case, progress=say, watch=stop)
    written = write_plan(result, args.out)
    if not args.quiet:
        if result.has_plan:
            print(_describe(result), file=sys.stderr)
            print(_describe_parts(result), file=sys.stderr)
            for phrase in tied_budgets(result.problem):
                print(f"  tied deviations, the model chose: {phrase} (--ties earliest fixes the earliest)",
                      file=sys.stderr)
        print(f"wrote {', '.join(p.name for p in written)} to {args.out}", file=sys.stderr)
    if not result.has_plan:
        print(f"error: {result.status}: {result.message}", file=sys.stderr)
        return FAILURE
    return 0


class SearchStop:
    """The solve's watch (:data:`rvpp.solving.outcome.Watch`): reports the search every
    :data:`SEARCH_REPORT_S` through ``say`` and ends it at the best plan once Ctrl-C was pressed."""

    def __init__(self, say):
        self.say = say
        self.requested = False
        self.reported = 0.0  # the search's clock at its last report [s]

    def __call__(self, search) -> bool:
        if search.seconds - self.reported >= SEARCH_REPORT_S:
            self.reported = search.seconds
            if search.objective is None:
                self.say(f"search {search.seconds:.0f} s: no plan yet")
            else:
                gap = f"{search.gap:.2%}" if search.gap is not None else "n/a"
                self.say(f"search {search.seconds:.0f} s: best plan so far, profit {amount(search.objective, 0)} EUR, "
                         f"gap {gap} ({search.nodes} nodes); Ctrl-C keeps it")
        return self.requested

    @contextmanager
    def on_ctrl_c(self):
        """The first Ctrl-C asks the search to end at its best plan; a second one gives up the solve."""
        def interrupt(_signum, _frame):
            if self.requested:
                raise KeyboardInterrupt
            self.requested = True
            self.say("stopping at the best plan found so far (Ctrl-C again gives up)")

        previous = signal.signal(signal.SIGINT, interrupt)
        try:
            yield self
        finally:
            signal.signal(signal.SIGINT, previous)


def _describe(result) -> str:
    gap = f"{result.mip_gap:.2e}" if result.mip_gap is not None else "n/a"
    return (f"status {result.status}; profit {amount(result.objective_eur, 0)} EUR "
            f"(cost {amount(result.cost_keur, 1)} kEUR); "
            f"MIP gap {gap}; build {result.build_s:.2f} s, solve {result.solve_s:.2f} s")


def _describe_parts(result) -> str:
    """The objective's parts to the cent, as summary.json holds them, e.g. to compare them with another
    tool's accounts: ``objective = DAM revenue + SR revenue − HPA cost − operating cost − protection``."""
    parts, protection = result.parts, result.protection_eur
    kept = parts.get("value_heat_kept_eur", 0.0)
    cents = [("DAM revenue", parts.get("revenue_dam_eur", 0.0)), ("SR revenue", parts.get("revenue_sr_eur", 0.0)),
             ("HPA cost", parts.get("cost_hpa_eur", 0.0)), ("operating cost", parts.get("cost_opex_eur", 0.0)),
             ("price protection DAM", protection.get("price_da", 0.0)), ("SR up", protection.get("price_sr_up", 0.0)),
             ("SR down", protection.get("price_sr_dn", 0.0)), *([("heat kept", kept)] if kept else []),
             ("profit", result.objective_eur)]
    said = [f"{name} {amount(value, 2)}" for name, value in cents]
    return "  parts [EUR]: " + "; ".join(said[:4] + [", ".join(said[4:7])] + said[7:])
