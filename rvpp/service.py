"""The dashboard's face of rvpp: everything its pages and its support modules call, in one place.

The pages (``pages/``) and ``dashboard/`` import this module and rvpp's public names (``rvpp.solve``,
``rvpp.Case``, ...), never the layers below directly, so the library can move its modules without
touching the dashboard and a reader sees at once what the dashboard uses. Grouped by job:

* cases: the case model's constants and edits in the forms' words, uploads and downloads;
* solving: preparing a day, its bands, budgets and ties, Γ sweeps;
* results: figures, economics, comparison tables, exports;
* studies: the paper's studies and their tables;
* backtests: starting and following backtests, their metrics, figures and recommended Γ;
* the run library and the backtest store, with the errors reading them may raise.
"""

from __future__ import annotations

from .lazy import lazy_names
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # what a reader and the import contracts see; at run time a name loads on first use
    from .backtest import launch, metrics
    from .backtest.engine import reopen_case
    from .backtest.export import export_zip
    from .backtest.figures import cumulative_figure, distribution_figure, robustness_figure, trading_day_figure
    from .backtest.recommend import (CRITERION_NAMES, MIN_TEST_DAYS, MIN_TRAIN_DAYS, Verdict, beats_presets_on_training,
                                     recommendation_from, shortfalls, verdict_words)
    from .backtest.trading_day import day_summary, intraday_days, session_table
    from .backtest.settings import CARRY, FRACTION, PERFECT, PRESET, BacktestSettings, BacktestVariant, variants_of
    from .data.case import PRICE_MODELS, STRATEGIES, parse_case
    from .data.edits import (FIELDS, LABEL_LENGTH, PERIOD_NAMES, describe_edits, field_words, follow_capacity, label,
                             plain_message, run_label, table_message, with_period_length)
    from .data.files import EXCERPT_CHARS, excerpt
    from .data.history import PRICE_COLUMNS
    from .data.kinds import KINDS, UNIT_KINDS, UnitKind, power_unit
    from .data.periods import delivery_periods
    from .data.variants import Variant
    from .errors import CasePathError
    from .outputs import plots, workbook
    from .outputs.bundle import case_zip_bytes, read_case_files
    from .outputs.compare import MARKET_SETS, cost_table, flexibility_table, kpi_table
    from .outputs.economics import economics, explanation, waterfall_figure
    from .outputs.export import plan_workbook_bytes
    from .outputs.money import IN_KEUR, amount
    from .outputs.plots import (SOURCE_TITLES, TRADE_NAMES, band_overlays, bands_figure, compare_trades_figure,
                                curve_figure, deviating_periods, exposure_figure, idle_trades, tariff_figure,
                                thin_clock_ticks, trades_figure)
    from .outputs.style import GREY, KIND_LABELS, SERIES_COLORS
    from .outputs.workbook import SERIES_FIELDS, case_workbook_bytes, new_unit_row, unit_columns
    from .settle.audit import price_exposures, protection_exact
    from .settle.penalties import Penalties
    from .solving.outcome import Outcome
    from .solving.plan import solve, solve_problem
    from .solving.sweep import sweep_gamma
    from .store import (STORE_ERRORS, BacktestStore, RecordKey, RunInfo, RunLibrary, SavedRun, StoredRecommendation,
                        default_url)
    from .store.backtests import BacktestInfo, BacktestProgress
    from .store.codec import case_data
    from .studies import STUDIES, StudyOutput, StudySettings, figures, markets, sensitivity
    from .studies.evaluation import evaluation_days, realizations_used, training_days
    from .studies.report import table_csv, tables_workbook_bytes
    from .studies.settings import HPA_FLAT_PRICES, MARKET_SETS_WITHOUT_CSP, parse_numbers
    from .uncertainty.forecast import band_specs, has_forecast
    from .uncertainty.problem import (STRATEGY_BUDGETS_H, SourceKind, prepare, strategy_budgets, tied_budgets,
                                      top_gamma_deviation)

# Where each name lives. Names load on first use (as rvpp's own public names do), so a page that only
# edits a case does not load the optimisation stack, the store or the studies.
_WHERE = {
    "launch": ".backtest",
    "metrics": ".backtest",
    "reopen_case": ".backtest.engine",
    "export_zip": ".backtest.export",
    "cumulative_figure": ".backtest.figures",
    "distribution_figure": ".backtest.figures",
    "robustness_figure": ".backtest.figures",
    "trading_day_figure": ".backtest.figures",
    "day_summary": ".backtest.trading_day",
    "intraday_days": ".backtest.trading_day",
    "session_table": ".backtest.trading_day",
    "CRITERION_NAMES": ".backtest.recommend",
    "MIN_TEST_DAYS": ".backtest.recommend",
    "MIN_TRAIN_DAYS": ".backtest.recommend",
    "beats_presets_on_training": ".backtest.recommend",
    "shortfalls": ".backtest.recommend",
    "Verdict": ".backtest.recommend",
    "recommendation_from": ".backtest.recommend",
    "verdict_words": ".backtest.recommend",
    "BacktestSettings": ".backtest.settings",
    "BacktestVariant": ".backtest.settings",
    "CARRY": ".backtest.settings",
    "FRACTION": ".backtest.settings",
    "PERFECT": ".backtest.settings",
    "PRESET": ".backtest.settings",
    "variants_of": ".backtest.settings",
    "PRICE_MODELS": ".data.case",
    "STRATEGIES": ".data.case",
    "parse_case": ".data.case",
    "FIELDS": ".data.edits",
    "describe_edits": ".data.edits",
    "field_words": ".data.edits",
    "PERIOD_NAMES": ".data.edits",
    "follow_capacity": ".data.edits",
    "label": ".data.edits",
    "plain_message": ".data.edits",
    "run_label": ".data.edits",
    "table_message": ".data.edits",
    "with_period_length": ".data.edits",
    "EXCERPT_CHARS": ".data.files",
    "excerpt": ".data.files",
    "PRICE_COLUMNS": ".data.history",
    "KINDS": ".data.kinds",
    "UNIT_KINDS": ".data.kinds",
    "UnitKind": ".data.kinds",
    "power_unit": ".data.kinds",
    "delivery_periods": ".data.periods",
    "Variant": ".data.variants",
    "CasePathError": ".errors",
    "plots": ".outputs",
    "workbook": ".outputs",
    "case_zip_bytes": ".outputs.bundle",
    "read_case_files": ".outputs.bundle",
    "MARKET_SETS": ".outputs.compare",
    "cost_table": ".outputs.compare",
    "flexibility_table": ".outputs.compare",
    "kpi_table": ".outputs.compare",
    "economics": ".outputs.economics",
    "explanation": ".outputs.economics",
    "waterfall_figure": ".outputs.economics",
    "plan_workbook_bytes": ".outputs.export",
    "IN_KEUR": ".outputs.money",
    "amount": ".outputs.money",
    "SOURCE_TITLES": ".outputs.plots",
    "TRADE_NAMES": ".outputs.plots",
    "band_overlays": ".outputs.plots",
    "bands_figure": ".outputs.plots",
    "compare_trades_figure": ".outputs.plots",
    "curve_figure": ".outputs.plots",
    "deviating_periods": ".outputs.plots",
    "exposure_figure": ".outputs.plots",
    "idle_trades": ".outputs.plots",
    "tariff_figure": ".outputs.plots",
    "thin_clock_ticks": ".outputs.plots",
    "trades_figure": ".outputs.plots",
    "GREY": ".outputs.style",
    "KIND_LABELS": ".outputs.style",
    "SERIES_COLORS": ".outputs.style",
    "SERIES_FIELDS": ".outputs.workbook",
    "case_workbook_bytes": ".outputs.workbook",
    "new_unit_row": ".outputs.workbook",
    "unit_columns": ".outputs.workbook",
    "price_exposures": ".settle.audit",
    "protection_exact": ".settle.audit",
    "Penalties": ".settle.recourse",
    "Outcome": ".solving.outcome",
    "solve": ".solving.plan",
    "solve_problem": ".solving.plan",
    "sweep_gamma": ".solving.sweep",
    "BacktestStore": ".store",
    "RecordKey": ".store",
    "RunInfo": ".store",
    "RunLibrary": ".store",
    "SavedRun": ".store",
    "STORE_ERRORS": ".store",
    "StoredRecommendation": ".store",
    "default_url": ".store",
    "BacktestInfo": ".store.backtests",
    "BacktestProgress": ".store.backtests",
    "case_data": ".store.codec",
    "LABEL_LENGTH": ".data.edits",
    "STUDIES": ".studies",
    "StudyOutput": ".studies",
    "StudySettings": ".studies",
    "figures": ".studies",
    "markets": ".studies",
    "sensitivity": ".studies",
    "evaluation_days": ".studies.evaluation",
    "realizations_used": ".studies.evaluation",
    "training_days": ".studies.evaluation",
    "table_csv": ".studies.report",
    "tables_workbook_bytes": ".studies.report",
    "HPA_FLAT_PRICES": ".studies.settings",
    "MARKET_SETS_WITHOUT_CSP": ".studies.settings",
    "parse_numbers": ".studies.settings",
    "band_specs": ".uncertainty.forecast",
    "has_forecast": ".uncertainty.forecast",
    "SourceKind": ".uncertainty.problem",
    "STRATEGY_BUDGETS_H": ".uncertainty.problem",
    "prepare": ".uncertainty.problem",
    "strategy_budgets": ".uncertainty.problem",
    "tied_budgets": ".uncertainty.problem",
    "top_gamma_deviation": ".uncertainty.problem",
}

__all__ = [
    "BacktestInfo", "BacktestProgress", "BacktestSettings", "BacktestStore", "BacktestVariant", "CARRY", "CasePathError",
    "CRITERION_NAMES", "EXCERPT_CHARS", "FIELDS", "FRACTION", "GREY", "HPA_FLAT_PRICES", "IN_KEUR", "KIND_LABELS",
    "KINDS",
    "LABEL_LENGTH", "MARKET_SETS", "MARKET_SETS_WITHOUT_CSP", "MIN_TEST_DAYS", "MIN_TRAIN_DAYS", "Outcome", "Penalties",
    "PERFECT", "PERIOD_NAMES", "PRESET", "PRICE_COLUMNS", "PRICE_MODELS", "RecordKey", "RunInfo", "RunLibrary",
    "SavedRun", "SERIES_COLORS", "SERIES_FIELDS", "SOURCE_TITLES", "SourceKind", "STORE_ERRORS", "StoredRecommendation", "STRATEGIES",
    "STRATEGY_BUDGETS_H", "STUDIES", "StudyOutput", "StudySettings", "TRADE_NAMES", "UNIT_KINDS", "UnitKind", "Variant",
    "Verdict", "amount", "band_overlays", "band_specs", "bands_figure", "beats_presets_on_training", "case_data",
    "case_workbook_bytes", "case_zip_bytes", "compare_trades_figure", "cost_table", "cumulative_figure", "curve_figure",
    "day_summary", "default_url", "delivery_periods", "describe_edits", "deviating_periods", "distribution_figure", "economics",
    "evaluation_days", "excerpt", "explanation", "export_zip", "exposure_figure", "field_words", "figures",
    "flexibility_table", "follow_capacity", "has_forecast", "idle_trades", "intraday_days", "kpi_table", "label", "launch", "markets",
    "metrics", "new_unit_row", "parse_case", "parse_numbers", "plain_message", "plan_workbook_bytes", "plots",
    "power_unit", "prepare", "price_exposures", "protection_exact", "read_case_files", "realizations_used",
    "recommendation_from", "reopen_case", "robustness_figure", "run_label", "sensitivity", "session_table", "shortfalls",
    "solve",
    "solve_problem", "strategy_budgets", "sweep_gamma", "table_csv", "table_message", "tables_workbook_bytes",
    "tariff_figure", "thin_clock_ticks", "tied_budgets", "top_gamma_deviation", "trades_figure", "trading_day_figure",
    "training_days",
    "unit_columns", "variants_of", "verdict_words", "waterfall_figure", "with_period_length", "workbook",
]


__getattr__, __dir__ = lazy_names(__name__, _WHERE, anchor=__name__.rpartition(".")[0])
