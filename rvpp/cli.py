"""Command line: ``python -m rvpp solve|data|study ...``.

Every failure ends with exit code 1 and one line ``error: ...`` that names the option,
file or field and the rule, never a traceback: a bad option, a case that breaks a rule,
a file that cannot be read or written, and a solve without a plan (infeasible, solver
error). Success exits with 0.

During ``solve``, Ctrl-C ends the solver's search with the best plan found so far, which
is written as usual with status ``stopped`` and its gap (exit code 0); a second Ctrl-C
gives up the solve (exit code 130, nothing written). A long search reports itself every
:data:`SEARCH_REPORT_S` seconds.
"""

from __future__ import annotations

import argparse
import datetime as dt
import math
import re
import signal
import sys
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from .data.case import (FIRST_DATE, ISO_DATE, LAST_DATE, MAX_QUANTITY, MAX_THREADS, STRATEGIES, load_case,
                        parse_markets, with_options)
from .data.files import excerpt
from .data.periods import ALLOWED_DT_H
from .data.variants import describe
from .errors import RvppError

DEFAULT_CASE = Path(__file__).resolve().parent.parent / "data" / "cases" / "paper"
FAILURE = 1
INTERRUPTED = 130  # the shell's code for a command ended by Ctrl-C
SEARCH_REPORT_S = 5.0  # a solve's search reports itself this often [s]


class Parser(argparse.ArgumentParser):
    """argparse with one-line errors (``error: --gap: ...``) and exit code 1."""

    def error(self, message: str) -> None:
        message = re.sub(r"^argument ([^:]+): ", r"\1: ", message)
        self.exit(FAILURE, f"error: {message} (see {self.prog} --help)\n")


@dataclass(frozen=True)
class Number:
    """An option's value: a finite number within bounds (``whole``: an integer), as an argparse ``type``.

    Anything else raises :class:`argparse.ArgumentTypeError` naming the value and the
    allowed range, e.g. ``'nan' is not allowed; give a number > 0 [s]``.
    """

    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False
    whole: bool = False
    unit: str = ""

    def __call__(self, text: str) -> float | int:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{excerpt(text)!r} is not a number; give {self.rule}") from None
        if not math.isfinite(value) or (self.whole and not value.is_integer()) or not self._within(value):
            raise argparse.ArgumentTypeError(f"{excerpt(text)!r} is not allowed; give {self.rule}")
        return int(value) if self.whole else value

    def _within(self, value: float) -> bool:
        above = self.low is None or (value > self.low if self.low_open else value >= self.low)
        below = self.high is None or (value < self.high if self.high_open else value <= self.high)
        return above and below

    @property
    def rule(self) -> str:
        kind = "a whole number" if self.whole else "a number"
        unit = f" [{self.unit}]" if self.unit else ""
        if self.low is not None and self.high is not None:
            return (f"{kind} in {'(' if self.low_open else '['}{self.low:g}, {self.high:g}"
                    f"{')' if self.high_open else ']'}{unit}")
        if self.low is not None:
            return f"{kind} {'>' if self.low_open else '>='} {self.low:g}{unit}"
        return f"a finite {kind[2:]}{unit}"


def choice_of(values: tuple[float, ...], unit: str):
    """An argparse ``type`` accepting one of ``values`` (numbers), e.g. the period lengths."""
    allowed = ", ".join(f"{v:g}" for v in values)

    def convert(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if value not in values:
            raise argparse.ArgumentTypeError(f"{excerpt(text)!r} is not allowed; give one of {allowed} [{unit}]")
        return value
    return convert


def listed(convert, what: str):
    """An argparse ``type`` for a comma-separated list: every item given, none empty, each through
    ``convert`` (which may raise ``argparse.ArgumentTypeError`` or ``ValueError``)."""
    def parse(text: str) -> tuple:
        items = [part.strip() for part in text.split(",")]
        if not text.strip():
            raise argparse.ArgumentTypeError(f"is empty; give {what}")
        empty = [i for i, item in enumerate(items, start=1) if not item]
        if empty:
            raise argparse.ArgumentTypeError(f"{excerpt(text)!r}: item {empty[0]} is empty; give {what}")
        try:
            return tuple(convert(item) for item in items)
        except (argparse.ArgumentTypeError, ValueError, RvppError) as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
    return parse


def _market_list(text: str) -> str:
    """``--markets``: a comma-separated subset of DAM,SRM,HPA including DAM, checked now."""
    try:
        parse_markets(text)
    except RvppError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text


def date_option(text: str) -> str:
    """An argparse ``type`` for a delivery date: ``YYYY-MM-DD``, a day of the calendar, within the
    dates rvpp plans; refused in the option's words (``--date: '2025-02-30' is not a day ...``)."""
    try:
        day = dt.date.fromisoformat(text) if ISO_DATE.fullmatch(text) else None
    except ValueError:
        day = None
    if day is None:
        raise argparse.ArgumentTypeError(f"{excerpt(text)!r} is not a day of the calendar; give YYYY-MM-DD, "
                                         "e.g. 2025-03-18")
    if not FIRST_DATE <= day <= LAST_DATE:
        raise argparse.ArgumentTypeError(f"{text} is not allowed; give a day from {FIRST_DATE} to {LAST_DATE}")
    return text


def path_option(text: str) -> Path:
    """An argparse ``type`` for a file or folder: an empty value is refused, not read as "."."""
    if not text.strip():
        raise argparse.ArgumentTypeError("is empty; give a file or folder")
    return Path(text)


def main(argv: list[str] | None = None) -> int:
    parser = _parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help (0) or a bad option (1, message already printed)
        return exc.code if isinstance(exc.code, int) else FAILURE
    if not hasattr(args, "run"):
        parser.print_help(sys.stderr)
        return FAILURE
    try:
        return args.run(args)
    except KeyboardInterrupt:
        print("error: interrupted; nothing more was written", file=sys.stderr)
        return INTERRUPTED
    except RvppError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return FAILURE
    except OSError as exc:  # writing the outputs: a full disk, no permission, a file where a folder belongs
        where = f": {exc.filename}" if exc.filename else ""
        print(f"error: cannot write{where} ({exc.strerror or exc})", file=sys.stderr)
        return FAILURE


def _parser() -> argparse.ArgumentParser:
    parser = Parser(prog="python -m rvpp", description=(
        "Robust day-ahead bids for a renewable-only virtual power plant (DAM, aFRR reserve, heat purchase)."))
    commands = parser.add_subparsers(title="commands")

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
    solve.add_argument("--markets", type=_market_list, help="comma-separated subset of DAM,SRM,HPA (DAM always)")
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

    data = commands.add_parser("data", help="build the default dataset, import real data, build a case from it")
    data_commands = data.add_subparsers(title="data commands")
    build = data_commands.add_parser("build", help="regenerate the synthetic history of the paper case")
    build.add_argument("--seed", type=Number(0, whole=True), help="random seed >= 0 (default: the published one)")
    build.add_argument("--out", type=path_option, default=DEFAULT_CASE / "history.csv", help="CSV to write")
    build.set_defaults(run=_run_data_build)
    from .data.cli import add_data_commands

    add_data_commands(data_commands)

    from .studies.cli import add_study_commands
    from .backtest.cli import add_backtest_commands

    add_study_commands(commands)
    add_backtest_commands(commands)
    return parser


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
    from .outputs.export import check_plan_folder, check_replaceable, write_plan
    from .solving.plan import MPS_HEADERS, solve, write_mps
    from .solving.problem import tied_budgets

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
                self.say(f"search {search.seconds:.0f} s: best plan so far, profit {search.objective:,.0f} EUR, "
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
    return (f"status {result.status}; profit {result.objective_eur:,.0f} EUR (cost {result.cost_keur:.1f} kEUR); "
            f"MIP gap {gap}; build {result.build_s:.2f} s, solve {result.solve_s:.2f} s")


def _run_data_build(args: argparse.Namespace) -> int:
    from .data import synth
    from .outputs.export import check_replaceable

    seed = synth.DEFAULT_SEED if args.seed is None else args.seed
    check_replaceable(args.out, (synth.HISTORY_HEADER,), "a history CSV")
    frame = synth.write_history(args.out, seed=seed)
    print(f"wrote {len(frame)} hours to {args.out} (seed {seed})", file=sys.stderr)
    return 0
