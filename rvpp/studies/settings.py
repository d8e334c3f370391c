"""Settings shared by every study: one frozen object, filled from the command line or a page."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from ..case import STRATEGIES
from ..recourse import Penalties

MARKET_SETS = ("DAM", "DAM+HPA", "DAM+SRM", "DAM+SRM+HPA")  # paper Table 10
MARKET_SETS_WITHOUT_CSP = ("DAM+HPA", "DAM+SRM+HPA")  # paper Table 11 (heat needs the HPA)
HPA_FLAT_PRICES = (70.0, 60.0, 50.0)  # paper Table 12 [EUR/MWh_th]
SCENARIO_COUNTS = (5, 10, 15, 20, 25)  # paper Table 14
TEST_DAYS = 30
SEED = 20250318
SP_TIME_LIMIT_S = 600.0


@dataclass(frozen=True)
class StudySettings:
    """What the studies compute and how.

    ``gammas``: the Γ grid of the sensitivity [periods] (``None``: every hour from 0 to
    the day's length); ``sources``: the sources swept one at a time (empty: all at
    once); ``test_days``: out-of-sample days from the delivery date on;
    ``scenario_counts``: N of the stochastic benchmark; ``sp_time_limit_s``: time limit
    of each stochastic solve [s]; ``threads``: HiGHS threads per solve (1 keeps serial
    and parallel runs identical); ``png``: also write static figures.
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

    def with_changes(self, **changes) -> "StudySettings":
        return replace(self, **changes)
