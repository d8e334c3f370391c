"""Store: saved runs of the dashboard and backtest records, in one database.

SQLite in WAL mode by default (``RVPP_DATA_DIR``, default ``./rvpp-data``), any
SQLAlchemy URL (e.g. PostgreSQL) through ``RVPP_STORE_URL``; see :mod:`.engine`.
"""

from .backtests import BacktestInfo, BacktestStore, RecordKey, StoredRecommendation, backtest_id, pending
from .engine import STORE_ERRORS, StoreError, connect, default_url
from .runs import RunInfo, RunLibrary, SavedRun

__all__ = ["STORE_ERRORS", "BacktestInfo", "BacktestStore", "RecordKey", "RunInfo", "RunLibrary", "SavedRun", "StoreError",
           "StoredRecommendation", "backtest_id", "connect", "default_url", "pending"]
