"""``python -m rvpp backtest``: the rolling backtest, the recommended Γ and exports of stored backtests.

* ``backtest --from D1 --to D2 [--strategies ...] [--fractions ...]``: run or resume;
* ``backtest recommend --train D1:D2 --test D3:D4 [--criterion cvar95]``: choose Γ;
* ``backtest export ID --out FOLDER`` and ``backtest list``: what the store holds;
* ``backtest intraday-compare --from D1 --to D2 --out FOLDER``: the same days with and without the
  intraday sessions, per strategy.
"""

from __future__ import annotations

import argparse
import signal
import sys
from pathlib import Path

from ..backtest.settings import CARRY, BacktestError, BacktestSettings, parse_day, parse_period, variants_of
from ..data.case import MAX_THREADS, STRATEGIES
from ..data.case_yaml import load_case
from ..data.files import excerpt
from ..settle.penalties import Penalties
from .options import DEFAULT_CASE, Number, add_settlement_options, listed, path_option, scheduler_option

CRITERIA = ("mean", "cvar95")


def add_backtest_commands(commands) -> None:
    """Add the ``backtest`` subcommand (and its ``recommend``, ``export``, ``list``) to the command line."""
    backtest = commands.add_parser(
        "backtest", help="settle every day's plan against its own realized day, over a period",
        description="Rolling backtest: for every day of --from..--to and every strategy or Γ fraction, plan from "
                    "the history before the day, settle against the day's observations, carry the storage and "
                    "turbine state to the next day. Records go to the store as each day finishes; running the "
                    "same command again resumes where it stopped.")
    _add_run_options(backtest)
    backtest.add_argument("--from", dest="first", metavar="D1", help="first delivery day YYYY-MM-DD")
    backtest.add_argument("--to", dest="last", metavar="D2", help="last delivery day YYYY-MM-DD (included)")
    backtest.add_argument("--strategies", type=listed(_strategy, "a comma-separated subset of " + ",".join(STRATEGIES)),
                          help="comma-separated presets among " + ",".join(STRATEGIES)
                          + " (default: all four, unless --fractions is given)")
    backtest.add_argument("--fractions", "--gammas", dest="fractions", type=FRACTIONS,
                          help="Γ as fractions of the day applied to every source, e.g. 0,0.125,0.25 "
                               "(Γ = round(f·periods))")
    backtest.set_defaults(run=run_backtest_command)
    actions = backtest.add_subparsers(title="other actions", dest="action")

    recommend = actions.add_parser(
        "recommend", help="choose Γ on a training period, check it on a later test period",
        description="Backtest a grid of Γ fractions and the four presets over --train and --test, pick the "
                    "fraction that minimises the criterion on the training days, and report how it does on the "
                    "test days against the presets.")
    _add_run_options(recommend)
    recommend.add_argument("--train", required=True, metavar="D1:D2", help="training period, both days included")
    recommend.add_argument("--test", required=True, metavar="D3:D4", help="test period, after the training period")
    recommend.add_argument("--criterion", choices=CRITERIA, default="mean",
                           help="mean daily net cost or CVaR 95 %% of it (default: mean)")
    recommend.add_argument("--fractions", "--gammas", dest="fractions", type=FRACTIONS,
                           default=(0.0, 0.0625, 0.125, 0.1875, 0.25, 0.3125, 0.375, 0.5),
                           help="the Γ grid as fractions of the day (default 0,0.0625,...,0.375,0.5)")
    recommend.set_defaults(run=run_recommend_command)

    compare = actions.add_parser(
        "intraday-compare", help="the same backtest without and with the intraday sessions, per strategy",
        description="Run (or resume) the backtest of --from..--to twice, on the day-ahead bids alone and with the "
                    "case's intraday sessions (IDA1-IDA3 unless the case lists others), and report the mean daily "
                    "net cost, penalty and market (trading) cost of each strategy; docs/intraday.md.")
    _add_run_options(compare)
    compare.add_argument("--from", dest="first", required=True, metavar="D1", help="first delivery day YYYY-MM-DD")
    compare.add_argument("--to", dest="last", required=True, metavar="D2", help="last delivery day (included)")
    compare.add_argument("--strategies", type=listed(_strategy, "a comma-separated subset of " + ",".join(STRATEGIES)),
                         default=STRATEGIES, help="comma-separated presets (default: all four)")
    compare.set_defaults(run=run_intraday_compare_command, fractions=None)

    export = actions.add_parser("export", help="write a stored backtest's records and inputs to a folder")
    export.add_argument("ident", metavar="ID", help="the backtest id (see backtest list)")
    export.add_argument("--out", type=path_option, required=True,
                        help="folder to write: a new or empty folder, or an earlier export (replaced as a whole)")
    export.add_argument("--store", help="store URL (default: RVPP_STORE_URL or the local rvpp-data folder)")
    export.set_defaults(run=run_export_command)

    listing = actions.add_parser("list", help="the backtests of the store and their progress")
    listing.add_argument("--store", help="store URL (default: RVPP_STORE_URL or the local rvpp-data folder)")
    listing.set_defaults(run=run_list_command)


def _add_run_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--case", type=path_option, default=DEFAULT_CASE, help="case folder (default: the paper case)")
    parser.add_argument("--no-perfect", action="store_true",
                        help="skip the perfect-information plan (no regret figures; one chain less)")
    parser.add_argument("--storage-end", type=_storage_end, default=CARRY, metavar="carry|F",
                        help="end-of-day storage rule: carry (default: end at or above the day's start) or a "
                             "fraction F of the storage range (may run down to that level)")
    add_settlement_options(parser)
    parser.add_argument("--no-audit", action="store_true", help="do not audit the plans")
    parser.add_argument("--intraday", action="store_true",
                        help="after the day-ahead market, trade the case's intraday sessions (IDA1-IDA3 unless the "
                             "case lists others) and settle against the final position; docs/intraday.md")
    parser.add_argument("--scheduler", type=scheduler_option, default="processes",
                        help="processes (default: local process pool), serial, local (a local Dask cluster) or "
                             "the address of a Dask scheduler, e.g. tcp://10.0.0.5:8786")
    parser.add_argument("--workers", type=Number(1, MAX_THREADS, whole=True),
                        help="worker processes of a local pool or cluster (default: cores; a local pool uses "
                            "at most one per core)")
    parser.add_argument("--store", help="store URL (default: RVPP_STORE_URL or the local rvpp-data folder)")
    parser.add_argument("--label", type=_label, default="",
                        help="a name for the backtest in the store (no control characters)")
    parser.add_argument("--out", type=path_option,
                        help="also export records, aggregates and inputs to this folder (a new or empty folder, "
                             "or an earlier export, which is replaced)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


FRACTIONS = listed(Number(0, 1, unit="fraction of the day"), "Γ as fractions of the day such as 0,0.125,0.25")


def _strategy(name: str) -> str:
    if name not in STRATEGIES:
        raise argparse.ArgumentTypeError(f"unknown strategy {excerpt(name)!r}; choose from {', '.join(STRATEGIES)}")
    return name


def _label(text: str) -> str:
    from ..backtest.launch import check_label  # heavy: the launch imports the store; only when a label is given

    try:
        return check_label(text)
    except BacktestError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _storage_end(text: str) -> str | float:
    if text.strip() == CARRY:
        return CARRY
    try:
        return Number(0, 1, unit="fraction of the storage range")(text)
    except argparse.ArgumentTypeError as exc:
        raise argparse.ArgumentTypeError(f"{exc}, or {CARRY}") from None


def settings_from(args: argparse.Namespace, first, last, strategies, fractions) -> BacktestSettings:
    """Backtest settings from the command line's options."""
    penalties = Penalties(m_def=args.m_def, m_sur=args.m_sur, m_sr=args.m_sr, c_heat_eur_per_mwh=args.c_heat)
    return BacktestSettings(first_day=first, last_day=last,
                            variants=variants_of(strategies, fractions, perfect=not args.no_perfect),
                            penalties=penalties, storage_end=args.storage_end, fix_commitment=args.fix_commitment,
                            audit=not args.no_audit, intraday=bool(getattr(args, "intraday", False)))


def check_out(out: Path | None) -> None:
    """Refuse an ``--out`` the export may not replace (:func:`.export.check_replaceable_export`),
    before any backtest runs; the message names the option and the folder as given."""
    # heavy (the solver stack, the store or pvlib): loaded only when this command runs
    from ..backtest.export import check_replaceable_export

    if out is None:
        return
    try:
        check_replaceable_export(out)
    except OSError as exc:
        raise BacktestError(f"--out {out}: {exc.strerror or exc}") from None


def stop_on_terminate() -> None:
    """End on SIGTERM as on Ctrl-C: the store then records the backtest as interrupted."""
    def terminate(_signum, _frame):
        raise KeyboardInterrupt

    signal.signal(signal.SIGTERM, terminate)


class ProgressBar:
    """A tqdm bar on standard error with the records done and the time left."""

    def __init__(self, enabled: bool, title: str):
        self.enabled, self.title, self.bar = enabled, title, None

    def __call__(self, done: int, total: int, _eta_s: float | None) -> None:
        if not self.enabled:
            return
        if self.bar is None:
            from tqdm import tqdm  # heavy: only when a progress bar is drawn

            self.bar = tqdm(total=total, initial=done, desc=self.title, unit="day", file=sys.stderr,
                            dynamic_ncols=True)
        self.bar.update(done - self.bar.n)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def run_backtest_command(args: argparse.Namespace) -> int:
    # heavy (the solver stack, the store or pvlib): loaded only when this command runs
    from ..backtest.engine import run_backtest
    from ..solving.parallel import open_executor
    from ..store import BacktestStore

    if not args.first or not args.last:
        raise BacktestError("backtest needs --from D1 and --to D2 (delivery days, YYYY-MM-DD)")
    strategies = args.strategies if args.strategies is not None else (() if args.fractions else STRATEGIES)
    settings = settings_from(args, parse_day(args.first, "--from"), parse_day(args.last, "--to"), strategies,
                             args.fractions or ())
    check_out(args.out)
    case = load_case(args.case)
    settings.check_case(case)
    store = BacktestStore(args.store)
    say = (lambda _m: None) if args.quiet else (lambda m: print(m, file=sys.stderr))
    say(f"rvpp backtest: case {case.name}, {settings.first_day} to {settings.last_day}, "
        f"{len(settings.variants)} variant(s) ({', '.join(v.label for v in settings.variants)}), "
        f"scheduler {args.scheduler}")
    if settings.intraday or case.intraday.enabled:
        say(case.intraday_summary())
    bar = ProgressBar(not args.quiet, "backtest")
    stop_on_terminate()
    try:
        with open_executor(args.scheduler, args.workers) as executor:
            ident = run_backtest(case, settings, store, executor, bar, label=args.label)
    except KeyboardInterrupt:
        bar.close()
        print("interrupted: the finished days are stored; run the same command again to resume", file=sys.stderr)
        return 130
    bar.close()
    return _report(store, ident, args.out, say)


def _report(store, ident: str, out: Path | None, say) -> int:
    # heavy (the solver stack, the store or pvlib): loaded only when this command runs
    from ..backtest import metrics
    from ..backtest.export import export

    records = store.records(ident)
    problems = metrics.reconcile(records)
    say(f"backtest {ident}: {len(records)} records")
    table = metrics.aggregates(records)
    columns = ["label", "days_settled", "mean_net_cost_eur", "cvar95_net_cost_eur", "mean_penalty_eur",
               "mean_regret_eur"]
    say(table[columns].to_string(index=False, float_format=lambda v: f"{v:,.0f}"))
    if len(problems):
        say(f"warning: {len(problems)} day(s) do not reconcile or were not settled, e.g. "
            f"{problems.iloc[0].to_dict()}")
    if out is not None:
        export(store, ident, out)
        say(f"wrote {out}")
    return 0 if problems.empty else 1


def run_recommend_command(args: argparse.Namespace) -> int:
    # heavy (the solver stack, the store or pvlib): loaded only when this command runs
    from ..backtest.recommend import check_periods, recommend, write_recommendation
    from ..solving.parallel import open_executor
    from ..store import BacktestStore

    train = parse_period(args.train, "--train")
    test = parse_period(args.test, "--test")
    check_periods(train, test)  # before the settings of train[0]..test[1], whose rules name --from and --to
    check_out(args.out)
    case = load_case(args.case)
    template = settings_from(args, train[0], test[1], STRATEGIES, ())
    template.check_case(case, first_option="--train", last_option="--test")
    store = BacktestStore(args.store)
    bar = ProgressBar(not args.quiet, "backtest")
    stop_on_terminate()
    try:
        with open_executor(args.scheduler, args.workers) as executor:
            result = recommend(case, train, test, args.fractions, args.criterion, template=template, store=store,
                               executor=executor, progress=bar, label=args.label)
    except KeyboardInterrupt:
        bar.close()
        print("interrupted: the finished days are stored; run the same command again to resume", file=sys.stderr)
        return 130
    bar.close()
    print(result.verdict)
    print(result.comparison.to_string(index=False, float_format=lambda v: f"{v:,.0f}"))
    if args.out is not None:
        write_recommendation(result, store, args.out)
        print(f"wrote {args.out}", file=sys.stderr)
    return 0


def run_export_command(args: argparse.Namespace) -> int:
    # heavy (the solver stack, the store or pvlib): loaded only when this command runs
    from ..backtest.export import export
    from ..store import BacktestStore

    check_out(args.out)
    export(BacktestStore(args.store, existing=args.store is not None), args.ident, args.out)
    print(f"wrote {args.out}", file=sys.stderr)
    return 0


def run_list_command(args: argparse.Namespace) -> int:
    # heavy (the solver stack, the store or pvlib): loaded only when this command runs
    from ..store import BacktestStore
    from ..data.edits import LABEL_LENGTH

    store = BacktestStore(args.store, existing=args.store is not None)  # a typed path must hold a store
    for info in store.list():
        progress = store.progress(info.id)
        state = progress.state if progress else "not run"
        print(f"{info.id}  {info.keys_done}/{info.keys_total}  {state:<11}  {info.created_at[:19]}  "
              f"{excerpt(info.label, LABEL_LENGTH)}")  # a label stored before the rule: shown, never obeyed
    return 0


def run_intraday_compare_command(args: argparse.Namespace) -> int:
    # heavy (the solver stack, the store or pvlib): loaded only when this command runs
    from ..data.files import replacing
    from ..solving.parallel import open_executor
    from ..store import BacktestStore
    from ..studies.intraday import compare_intraday
    from ..studies.report import markdown_table

    settings = settings_from(args, parse_day(args.first, "--from"), parse_day(args.last, "--to"), args.strategies, ())
    settings = settings.with_changes(variants=tuple(v for v in settings.variants if not v.is_perfect))
    case = load_case(args.case)
    settings.check_case(case)
    store = BacktestStore(args.store)
    bar = ProgressBar(not args.quiet, "intraday comparison")
    stop_on_terminate()
    with open_executor(args.scheduler, args.workers) as executor:
        table = compare_intraday(case, settings, store, executor, bar)
    bar.close()
    print(table.to_string(index=False, float_format=lambda v: f"{v:,.1f}"))
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        for name, text in (("intraday_comparison.csv", table.to_csv(index=False)),
                           ("intraday_comparison.md", markdown_table(table, digits=1) + "\n")):
            with replacing(args.out / name) as temporary:
                temporary.write_text(text, encoding="utf-8")
    unreconciled = int((table["days_settled"] - table["days_reconciled"]).sum())
    return 0 if unreconciled == 0 else 1
