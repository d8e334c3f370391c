"""``python -m rvpp study NAME``: run a study (or ``reproduce``: all of them) into ``--out``."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..data.case import MAX_QUANTITY, MAX_THREADS, STRATEGIES
from ..data.case_yaml import load_case
from ..data.periods import ALLOWED_DT_H
from ..data.variants import with_options
from ..settle.penalties import Penalties
from ..studies.settings import (BACKTEST_CRITERIA, BACKTEST_FRACTIONS, HPA_FLAT_PRICES, MARKET_SETS, REPRODUCE,
                                SCENARIO_COUNTS, SEED, SP_TIME_LIMIT_S, STUDY_NAMES, TEST_DAYS, StudySettings)
from .options import (DEFAULT_CASE, Number, add_settlement_options, choice, choice_of, date_option, listed, market_set,
                      path_option, period_option, scheduler_option)


def add_study_commands(commands) -> None:
    """Add the ``study`` subcommand to the command line's subparsers."""
    study = commands.add_parser(
        "study", help="run a case study of the paper (or reproduce all of them)",
        description="Run one of the paper's case studies on a case and write its tables (CSV, Markdown, "
                    "tables.xlsx), figures (HTML, PNG) and report.md to --out.")
    study.add_argument("name", choices=[*STUDY_NAMES, REPRODUCE],
                       help="the study; reproduce runs those of the paper and the backtest (all but stress)")
    study.add_argument("--case", type=path_option, default=DEFAULT_CASE,
                       help="case folder (default: the paper case)")
    study.add_argument("--date", type=date_option, help="delivery date YYYY-MM-DD (default: the case's)")
    study.add_argument("--dt", type=choice_of(ALLOWED_DT_H, "h"), help="period length in hours: 1, 0.5 or 0.25")
    study.add_argument("--out", type=path_option, help="output folder (default: out/study-NAME)")
    study.add_argument("--scheduler", type=scheduler_option, default="processes",
                       help="processes (default: local process pool), serial, local (a local Dask cluster) "
                            "or the address of a Dask scheduler, e.g. tcp://10.0.0.5:8786")
    study.add_argument("--workers", type=Number(1, MAX_THREADS, whole=True),
                       help="worker processes of a local pool or cluster (default: cores; a local pool uses "
                            "at most one per core)")
    study.add_argument("--strategies", type=listed(choice(STRATEGIES), "a comma-separated subset of "
                                                   + ",".join(STRATEGIES)),
                       help="comma-separated subset of " + ",".join(STRATEGIES))
    study.add_argument("--gammas", type=listed(Number(0, whole=True), "whole numbers >= 0 such as 0,6,12"),
                       help="Γ grid of the sensitivity, e.g. 0,6,12 (default: every hour of the day)")
    study.add_argument("--sources", type=listed(str, "source names or kinds such as PV1,wind,price"), default=(),
                       help="sensitivity: sweep these sources or kinds one at a time, e.g. PV1,wind,price "
                            "(default: all sources at once)")
    study.add_argument("--market-sets", type=listed(market_set, "market sets such as DAM,DAM+SRM+HPA"),
                       help=f"market sets of Table 10, e.g. DAM,DAM+SRM+HPA (default {','.join(MARKET_SETS)})")
    tariff = Number(0, MAX_QUANTITY, unit="EUR/MWh_th")
    study.add_argument("--hpa-prices", type=listed(tariff, "tariffs >= 0 such as 70,60,50"),
                       help=f"flat HPA tariffs [EUR/MWh_th] (default {','.join(f'{p:g}' for p in HPA_FLAT_PRICES)})")
    study.add_argument("--test-days", type=Number(1, whole=True), default=TEST_DAYS,
                       help=f"out-of-sample days (default {TEST_DAYS})")
    study.add_argument("--scenarios", type=listed(Number(1, whole=True), "whole numbers >= 1 such as 5,10"),
                       help=f"scenario counts N of the stochastic benchmark (default "
                            f"{','.join(map(str, SCENARIO_COUNTS))})")
    study.add_argument("--seed", type=Number(0, whole=True), default=SEED,
                       help=f"seed of the scenario sampling, >= 0 (default {SEED})")
    seconds = Number(0, MAX_QUANTITY, low_open=True, unit="s")
    study.add_argument("--sp-time-limit", type=seconds, default=SP_TIME_LIMIT_S, metavar="S",
                       help=f"time limit of each stochastic solve [s] (default {SP_TIME_LIMIT_S:g})")
    study.add_argument("--time-limit", type=seconds, metavar="S",
                       help="time limit of every other solve [s]")
    add_settlement_options(study)
    study.add_argument("--backtest-train", type=period_option, metavar="D1:D2",
                       help="backtest: training period of the recommended Γ (default: April 2025 on the paper case)")
    study.add_argument("--backtest-test", type=period_option, metavar="D3:D4",
                       help="backtest: test period, after the training period (default: May 2025)")
    study.add_argument("--backtest-fractions", type=listed(Number(0, 1), "fractions of the day such as 0,0.125,0.25"),
                       help="backtest: the Γ grid as fractions of the day (default "
                            f"{','.join(f'{f:g}' for f in BACKTEST_FRACTIONS)})")
    study.add_argument("--backtest-criterion", choices=BACKTEST_CRITERIA, default="mean",
                       help="backtest: choose Γ by the mean daily net cost or its CVaR 95 %% (default: mean)")
    study.add_argument("--no-png", action="store_true", help="write interactive HTML figures only")
    study.add_argument("--quiet", action="store_true", help="no progress bars")
    study.set_defaults(run=run_study_command)



def settings_from(args: argparse.Namespace) -> StudySettings:
    """The study settings of the command line's options."""
    changes = {"strategies": args.strategies, "gammas": args.gammas, "hpa_flat_prices": args.hpa_prices,
               "market_sets": args.market_sets,
               "scenario_counts": args.scenarios, "backtest_train": args.backtest_train,
               "backtest_test": args.backtest_test, "backtest_fractions": args.backtest_fractions}
    settings = StudySettings(
        sources=args.sources, test_days=args.test_days, seed=args.seed, sp_time_limit_s=args.sp_time_limit,
        penalties=Penalties(m_def=args.m_def, m_sur=args.m_sur, m_sr=args.m_sr, c_heat_eur_per_mwh=args.c_heat),
        fix_commitment=args.fix_commitment, png=not args.no_png, backtest_criterion=args.backtest_criterion)
    return settings.with_changes(**{k: v for k, v in changes.items() if v is not None})


class ProgressBars:
    """One tqdm bar per stage on standard error."""

    def __init__(self, enabled: bool):
        self.enabled = enabled
        self.bars: dict[str, object] = {}

    def __call__(self, stage: str, done: int, total: int) -> None:
        if not self.enabled:
            return
        # heavy (the solver stack, the store or pvlib): loaded only when this command runs
        from tqdm import tqdm

        bar = self.bars.get(stage)
        if bar is None:
            bar = self.bars[stage] = tqdm(total=total, desc=f"{stage:>27}", unit="solve", file=sys.stderr,
                                          dynamic_ncols=True)
        bar.update(done - bar.n)
        if done >= total:
            bar.close()


def run_study_command(args: argparse.Namespace) -> int:
    # heavy (the solver stack, the store or pvlib): loaded only when this command runs
    from ..solving.parallel import open_executor
    from ..studies import run_studies

    settings = settings_from(args)  # checks every setting before the case is read
    case = with_options(load_case(args.case), date=args.date, dt_h=args.dt, time_limit_s=args.time_limit)
    out = args.out or Path("out") / f"study-{args.name}"
    if not args.quiet:
        print(f"rvpp study {args.name}: case {case.name}, {case.delivery_date}, scheduler {args.scheduler}",
              file=sys.stderr)
    with open_executor(args.scheduler, args.workers) as executor:
        outputs = run_studies(case, [args.name], settings, out, executor, ProgressBars(not args.quiet),
                              scheduler=args.scheduler)
    if not args.quiet:
        for output in outputs:
            print(f"{output.name}: {output.seconds:.1f} s" + "".join(f"\n  note: {n}" for n in output.notes),
                  file=sys.stderr)
        print(f"wrote {out}/report.md, tables/ and figures/", file=sys.stderr)
    return 0
