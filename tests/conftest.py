"""Shared fixtures: the paper case and cached solves of it, and a data folder of a test's own."""

from __future__ import annotations

import functools

import pytest

from rvpp import load_case, solve, with_options
from tests.factories import PAPER, cyclic_storage


def _scan_component_packages_once() -> None:
    """Every AppTest scans the metadata of every installed package for Streamlit components
    (0.6-1.3 s each on this machine, for about a hundred AppTests); the packages do not change
    during a test session, so the scan's answer is kept after the first."""
    try:
        from streamlit.components.v2 import manifest_scanner
    except ImportError:  # a Streamlit without such components has no scan to keep
        return
    manifest_scanner.scan_component_manifests = functools.cache(manifest_scanner.scan_component_manifests)


_scan_component_packages_once()


@pytest.fixture(scope="session")
def paper_case():
    return load_case(PAPER)


def cached_solves(case):
    """Solve ``case`` with options, once per distinct set of options."""
    cache = {}

    def run(**options):
        key = repr(sorted(options.items()))
        if key not in cache:
            cache[key] = solve(with_options(case, **options))
        return cache[key]

    return run


@pytest.fixture(scope="session")
def paper_solve(paper_case):
    """Solve the paper case with options, once per distinct set of options."""
    return cached_solves(paper_case)


@pytest.fixture(scope="session")
def cyclic_solve(paper_case):
    """The same with a cyclic storage day (:func:`tests.factories.cyclic_storage`)."""
    return cached_solves(cyclic_storage(paper_case))


@pytest.fixture
def data_dir(tmp_path, monkeypatch):
    """A data folder of this test's own (the store, the run library and a launched backtest read the
    environment at each call); the folder itself is made by the first write."""
    monkeypatch.delenv("RVPP_STORE_URL", raising=False)
    folder = tmp_path / "rvpp-data"
    monkeypatch.setenv("RVPP_DATA_DIR", str(folder))
    return folder


@pytest.fixture
def run_library(data_dir):
    """The URL of the run library in this test's own data folder (:func:`data_dir`)."""
    return f"sqlite:///{data_dir / 'rvpp.sqlite3'}"
