"""The rolling backtest (beyond the paper; MODEL_SPEC §10) and the recommended Γ.

Every day of a period is planned from what was known before it, settled against what
happened that day, and hands its storage and turbine state to the next day
(:mod:`.engine`, :mod:`.state`). Records go to the store as each day finishes
(:class:`rvpp.store.BacktestStore`), so a backtest resumes where it stopped.
:mod:`.metrics` aggregates them, :mod:`.recommend` chooses Γ on a training period and
checks it on a test period, :mod:`.export` writes records and inputs to a folder and
:mod:`.launch` runs a backtest in a detached process for the dashboard.
"""

from ..lazy import lazy_names

_EXPORTS = {
    "run_backtest": ".engine", "run_day": ".engine",
    "aggregates": ".metrics", "cvar": ".metrics", "daily": ".metrics", "monthly": ".metrics", "reconcile": ".metrics",
    "worst_days": ".metrics",
    "Recommendation": ".recommend", "recommend": ".recommend", "recommendation_from": ".recommend",
    "BacktestError": ".settings", "BacktestSettings": ".settings", "BacktestVariant": ".settings",
    "variants_of": ".settings",
}

__all__ = sorted(_EXPORTS)


# Names are imported on first use (as in rvpp): the settings, which the command line reads to build
# its options, load without the engine and its solver stack.
__getattr__, __dir__ = lazy_names(__name__, _EXPORTS)
