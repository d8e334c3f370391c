"""Saved runs: the store's run library (:class:`rvpp.store.RunLibrary`), shared by every session.

A run is saved with the case as edited, its run switches (``csp``), the case it was
edited from (``origin``, so its edits can be described again) and the plan's tables.
The store is SQLite in WAL mode under ``RVPP_DATA_DIR`` (default ``./rvpp-data``) or
any database named by ``RVPP_STORE_URL`` (e.g. PostgreSQL for a team's server); this
module only speaks through ``RunLibrary``, so nothing here assumes SQLite.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import streamlit as st

from rvpp import service

from . import state

if TYPE_CHECKING:  # the store (and SQLAlchemy) loads on first use, not with the first page
    from rvpp import Case, Result
    from rvpp.service import RunInfo, RunLibrary, SavedRun

LOADED_KEPT = 32  # reopened runs kept in memory (their plan and prepared day)


@st.cache_resource(show_spinner=False)
def _library(url: str) -> RunLibrary:
    return service.RunLibrary(url)


def library() -> RunLibrary:
    """The run library of the store the environment names (one engine per store URL)."""
    return _library(service.default_url())


def runs() -> list[RunInfo]:
    """Every saved run, newest first."""
    return library().list()


def save(label: str, case: Case, result: Result | None) -> RunInfo:
    """Save ``case`` (as edited, CSP parameters kept) with its plan, under ``label`` or
    ``label (2)`` if it is taken; the session's run switches and origin go with it."""
    settings = {"csp": state.csp_on(), "origin": service.case_data(state.origin()), "source": state.source()}
    return library().save(label, case, result, settings=settings)


@st.cache_resource(show_spinner=False, max_entries=LOADED_KEPT)
def _load(url: str, run_id: str) -> SavedRun:
    return service.RunLibrary(engine=_library(url).engine).load(run_id)


def load(run_id: str) -> SavedRun:
    """A saved run with its case and plan (reopened once per server, then kept)."""
    return _load(service.default_url(), run_id)


def forget(run_id: str) -> None:
    """Drop a deleted run from the reopened runs kept in memory."""
    _load.clear(service.default_url(), run_id)


def link(run_id: str) -> str:
    """The address that opens a saved run (relative to the dashboard's root)."""
    return f"/?run={run_id}"
