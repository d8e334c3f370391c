"""Backtests for the dashboard: the store's backtests, their records and the remembered recommended Γ.

A backtest runs in a process of its own started by :func:`rvpp.backtest.launch.start`
(never in the server), which writes every settled day and a progress row into the store;
this module only reads the store, so a page can be closed, reopened or reloaded while the
backtest goes on. The recommended Γ fraction a user chose to remember on the Backtest page
is kept in the store too (:meth:`rvpp.store.BacktestStore.remember_recommendation`), so
Results and Compare offer it in every session and after a restart.
"""

from __future__ import annotations

import re

import pandas as pd
import streamlit as st

from rvpp import Case, RvppError
from rvpp.service import (BacktestProgress, BacktestStore, BacktestVariant, FRACTION, PRESET, STORE_ERRORS,
                          StoredRecommendation, Variant, default_url)

from .widgets import literal

RECORDS_KEPT = 8  # record tables kept in memory (a year of five variants is a few MB)
# The command line's option names as the Backtest page's fields show them.
FORM_WORDS = {"--from": "First day", "--to": "Last day", "--storage-end": "Storage end target",
              "--fractions": "Γ fractions", "--strategies": "Strategies", "--train": "Training days",
              "--test": "Test days", "--criterion": "Criterion"}
HOW_TO_RECOMMEND = ("No recommended Γ yet: on **Backtest**, run a backtest with Γ fractions, compute the price of "
                    "robustness and press **Remember this Γ**; it is then offered here.")


@st.cache_resource(show_spinner=False)
def _store(url: str) -> BacktestStore:
    return BacktestStore(url)


def store() -> BacktestStore:
    """The backtest store the environment names (one engine per store URL)."""
    return _store(default_url())


def in_form_words(message: str) -> str:
    """A library message with the command line's option names replaced by the page's field labels."""
    return re.sub(r"--[a-z][a-z-]*", lambda m: f"**{FORM_WORDS.get(m.group(0), m.group(0))}**", message)


def progress(ident: str) -> BacktestProgress | None:
    return store().progress(ident)


@st.cache_data(max_entries=RECORDS_KEPT, show_spinner=False)
def _records(url: str, ident: str, done: int) -> pd.DataFrame:
    return BacktestStore(engine=_store(url).engine).records(ident)


def records(ident: str, done: int) -> pd.DataFrame:
    """Every record of ``ident`` (read again when ``done``, the records held, changes)."""
    return _records(default_url(), ident, done)


@st.cache_data(max_entries=RECORDS_KEPT, show_spinner=False)
def _timezone(url: str, ident: str) -> str:
    case, _ = BacktestStore(engine=_store(url).engine).load(ident)
    return case.timezone


def timezone_of(ident: str) -> str:
    """The time zone of the case a backtest ran (the clock of its days)."""
    return _timezone(default_url(), ident)


def record_of(records: pd.DataFrame, day: str, label: str) -> dict:
    """The record of ``day`` and the variant labelled ``label``, as plain data (keys a record
    does not have left out, as the store holds them)."""
    row = records[(records["day"] == day) & (records["label"] == label)].iloc[0]
    return {key: value for key, value in row.items() if isinstance(value, (list, dict)) or not pd.isna(value)}


def fractions_of(settings: dict) -> list[float]:
    """The Γ grid of a backtest's stored settings: its fractions, and 0 when it ran the deterministic plan."""
    grid = {float(gamma) for strategy, gamma in settings["variants"] if strategy == FRACTION}
    if ["deterministic", PRESET] in settings["variants"]:
        grid.add(0.0)
    return sorted(grid)


def variant_labels(settings: dict) -> str:
    """The variants of a backtest in words: ``balanced, Γ 0.25 of the day, perfect information``."""
    return ", ".join(BacktestVariant(*v).label for v in settings["variants"])


def eta(seconds: float | None) -> str:
    """Time left in words: ``about 40 s``, ``about 12 min``, ``about 2.5 h``."""
    if seconds is None:
        return "time left: known after the first day"
    if seconds < 90:
        return f"about {seconds:.0f} s left"
    if seconds < 5400:
        return f"about {seconds / 60:.0f} min left"
    return f"about {seconds / 3600:.1f} h left"


def recommended() -> StoredRecommendation | None:
    """The latest remembered recommendation, ``None`` before the first (or when the store cannot be read:
    the pages then simply do not offer it)."""
    try:
        return store().recommendation()
    except (RvppError, *STORE_ERRORS):
        return None


def recommended_label(rec: StoredRecommendation) -> str:
    return f"recommended (Γ = {rec.fraction:g} of the day)"


def recommended_case(case: Case, rec: StoredRecommendation, markets: str | None = None) -> Case:
    """``case`` bidding with the recommended Γ fraction: the backtest's own way of applying a fraction
    (``Variant(gamma_fraction=f)``, ``budgets.fraction``), on ``markets`` if given."""
    return Variant(gamma_fraction=rec.fraction, markets=markets).apply(case)


def recommendation_note(rec: StoredRecommendation) -> str:
    """Where the recommendation comes from, in one line."""
    criterion = "mean daily net cost" if rec.criterion == "mean" else "CVaR 95 % of the daily net cost"
    return (f"Γ = {rec.fraction:g} of the day for every source, chosen on the Backtest page from case "
            f"**{literal(rec.case_name)}** by the {criterion} over the training days {rec.train[0]}..{rec.train[1]} "
            f"(test days {rec.test[0]}..{rec.test[1]}).")
