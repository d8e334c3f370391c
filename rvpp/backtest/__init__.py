"""The rolling backtest (beyond the paper; MODEL_SPEC §10) and the recommended Γ.

Every day of a period is planned from what was known before it, settled against what
happened that day, and hands its storage and turbine state to the next day
(:mod:`.engine`, :mod:`.state`). Records go to the store as each day finishes
(:class:`rvpp.store.BacktestStore`), so a backtest resumes where it stopped.
:mod:`.metrics` aggregates them, :mod:`.recommend` chooses Γ on a training period and
checks it on a test period, :mod:`.export` writes records and inputs to a folder and
:mod:`.launch` runs a backtest in a detached process for the dashboard.
"""

from .engine import run_backtest, run_day
from .metrics import aggregates, cvar, daily, monthly, reconcile, worst_days
from .recommend import Recommendation, recommend, recommendation_from
from .settings import BacktestError, BacktestSettings, BacktestVariant, variants_of

__all__ = ["BacktestError", "BacktestSettings", "Recommendation", "BacktestVariant", "aggregates", "cvar", "daily",
           "monthly", "recommend", "recommendation_from", "reconcile", "run_backtest", "run_day", "variants_of",
           "worst_days"]
