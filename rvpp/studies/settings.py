"""Settings shared by every study: one frozen object, filled from the command line or a page."""

from __future__ import annotations

import datetime as dt
import math
import numbers
from dataclasses import dataclass, field, replace

from ..data.case import STRATEGIES
from ..data.variants import parse_markets
from ..data.history import MAX_QUANTITY
from ..errors import CaseError, RvppError
from ..settle.penalties import Penalties

MARKET_SETS = ("DAM", "DAM+HPA", "DAM+SRM", "DAM+SRM+HPA")  # paper Table 10
MARKET_SETS_WITHOUT_CSP = ("DAM+HPA", "DAM+SRM+HPA")  # paper Table 11 (heat needs the HPA)
HPA_FLAT_PRICES = (70.0, 60.0, 50.0)  # paper Table 12 [EUR/MWh_th]
SCENARIO_COUNTS = (5, 10, 15, 20, 25)  # paper Table 14
MAX_SCENARIOS = 100  # one MILP holds a copy of the day per scenario; 25 take a minute, 100 many hours
MAX_GRID = 100  # values of one list (Γ, tariffs, market sets, fractions): each is at least one solve per day
MAX_TEST_DAYS = 366
TEST_DAYS = 30
SEED = 20250318
SP_TIME_LIMIT_S = 600.0
BACKTEST_FRACTIONS = (0.0, 0.125, 0.25, 0.375)  # Γ grid of the reproduce backtest [fraction of the day]
BACKTEST_CRITERIA = ("mean", "cvar95")
STUDY_NAMES = ("case1", "strategies", "sensitivity", "markets", "out-of-sample", "stochastic", "stress", "backtest")
REPRODUCE = "reproduce"
PAPER_STUDIES = ("case1", "strategies", "sensitivity", "markets", "out-of-sample", "stochastic")
REPRODUCE_STUDIES = (*PAPER_STUDIES, "backtest")  # the paper's, then the rolling backtest beyond it


@dataclass(frozen=True)
class StudySettings:
    """What the studies compute and how.

    ``gammas``: the Γ grid of the sensitivity [periods] (``None``: every hour from 0 to
    the day's length); ``sources``: the sources swept one at a time (empty: all at
    once); ``test_days``: out-of-sample days from the delivery date on;
    ``scenario_counts``: N of the stochastic benchmark; ``sp_time_limit_s``: time limit
    of each stochastic solve [s]; ``threads``: HiGHS threads per solve (1 keeps serial
    and parallel runs identical); ``png``: also write static figures. The backtest study
    (:mod:`.backtest`) trains Γ on ``backtest_train`` and tests it on ``backtest_test``
    (``None``: its documented periods) over the grid ``backtest_fractions`` by the
    criterion ``backtest_criterion`` (``mean`` or ``cvar95``).

    Checked on creation: an :class:`~rvpp.errors.RvppError` names every broken rule, e.g.
    ``study settings: test_days=0 must be at least 1``. Rules that need the case (Γ up
    to the day's periods, test days covered by the history) are checked by the study.
    """

    strategies: tuple[str, ...] = STRATEGIES
    gammas: tuple[int, ...] | None = None
    sources: tuple[str, ...] = ()
    market_sets: tuple[str, ...] = MARKET_SETS
    market_sets_without_csp: tuple[str, ...] = MARKET_SETS_WITHOUT_CSP
    hpa_flat_prices: tuple[float, ...] = HPA_FLAT_PRICES
    test_days: int = TEST_DAYS
    scenario_counts: tuple[int, ...] = SCENARIO_COUNTS
    seed: int = SEED
    sp_time_limit_s: float = SP_TIME_LIMIT_S
    penalties: Penalties = field(default_factory=Penalties)
    fix_commitment: bool = False
    threads: int = 1
    png: bool = True
    backtest_train: tuple[dt.date, dt.date] | None = None
    backtest_test: tuple[dt.date, dt.date] | None = None
    backtest_fractions: tuple[float, ...] = BACKTEST_FRACTIONS
    backtest_criterion: str = "mean"

    def __post_init__(self) -> None:
        problems = self._problems()
        if problems:
            raise RvppError("study settings: " + "; ".join(problems))

    def _problems(self) -> list[str]:
        problems = []
        if not self.strategies:
            problems.append("strategies is empty; choose at least one of " + ", ".join(STRATEGIES))
        problems += [f"strategies: unknown strategy {s!r}; choose from {', '.join(STRATEGIES)}"
                     for s in self.strategies if s not in STRATEGIES]
        problems += [f"gammas: {g} must be a whole number >= 0" for g in self.gammas or ()
                     if isinstance(g, bool) or not isinstance(g, numbers.Integral) or g < 0]
        for name in ("market_sets", "market_sets_without_csp"):
            for markets in getattr(self, name):
                try:
                    parse_markets(markets)
                except CaseError as err:
                    problems.append(f"{name}: {err}")
        problems += [f"hpa_flat_prices: {p} must be a number in [0, {MAX_QUANTITY:g}] [EUR/MWh_th]"
                     for p in self.hpa_flat_prices if not (math.isfinite(p) and 0 <= p <= MAX_QUANTITY)]
        for name in ("gammas", "market_sets", "market_sets_without_csp", "hpa_flat_prices", "backtest_fractions"):
            values = getattr(self, name) or ()
            if len(values) > MAX_GRID:
                problems.append(f"{name} has {len(values)} values; a study takes at most {MAX_GRID}, each solved "
                                "on its own")
        if self.test_days < 1:
            problems.append(f"test_days={self.test_days} must be at least 1")
        elif self.test_days > MAX_TEST_DAYS:
            problems.append(f"test_days={self.test_days} must be at most {MAX_TEST_DAYS} (a year)")
        problems += [f"scenario_counts: N={n} must be at least 1" for n in self.scenario_counts if n < 1]
        problems += [f"scenario_counts: N={n:g} must be at most {MAX_SCENARIOS} (the stochastic benchmark solves "
                     "one model with a copy of the day per scenario)" for n in self.scenario_counts
                     if n > MAX_SCENARIOS]
        if not (math.isfinite(self.sp_time_limit_s) and self.sp_time_limit_s > 0):
            problems.append(f"sp_time_limit_s={self.sp_time_limit_s} must be a number > 0 [s]")
        if self.threads < 1:
            problems.append(f"threads={self.threads} must be at least 1")
        problems += [f"backtest_fractions: {f} must be a fraction of the day in [0, 1]"
                     for f in self.backtest_fractions if not 0.0 <= f <= 1.0]
        if not self.backtest_fractions:
            problems.append("backtest_fractions is empty; give the Γ grid, e.g. 0, 0.125, 0.25")
        if self.backtest_criterion not in BACKTEST_CRITERIA:
            problems.append(f"backtest_criterion={self.backtest_criterion!r} must be one of "
                            f"{', '.join(BACKTEST_CRITERIA)}")
        if self.backtest_train and self.backtest_test and self.backtest_test[0] <= self.backtest_train[1]:
            problems.append(f"backtest_test starts on {self.backtest_test[0]}, before the training period ends "
                            f"({self.backtest_train[1]})")
        return problems

    def with_changes(self, **changes) -> "StudySettings":
        return replace(self, **changes)


def parse_numbers(text: str, whole: bool = False) -> tuple[float, ...] | tuple[int, ...]:
    """``"70, 60, 50"`` → ``(70.0, 60.0, 50.0)``; with ``whole``, ``"0, 6, 12"`` → ``(0, 6, 12)``.

    Empty parts are skipped. A part that is not a number raises ``ValueError`` naming it,
    e.g. ``'six' is not a whole number (write whole numbers separated by commas, e.g. 0, 6, 12)``.
    """
    convert, one, many, example = (int, "a whole number", "whole numbers", "0, 6, 12") if whole else \
        (float, "a number", "numbers", "70, 60, 50")
    values = []
    for part in (p.strip() for p in text.split(",")):
        if not part:
            continue
        try:
            values.append(convert(part))
        except ValueError:
            raise ValueError(f"{part!r} is not {one} (write {many} separated by commas, e.g. {example})") from None
    return tuple(values)
