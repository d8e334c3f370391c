"""Session state shared by every page.

``app.py`` calls :func:`init` once per run; pages read and change the shared state only
through the functions here. Page-local widget keys are prefixed with the page name
(``portfolio_``, ``markets_``, ...). Each browser tab is its own session, so two tabs
never share or clobber each other's case. Saved runs live in the store
(:mod:`dashboard.library`), shared by every session.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
from typing import TYPE_CHECKING

import streamlit as st

import rvpp
from rvpp import Case, CaseError
from rvpp.service import CasePathError, excerpt, parse_case, run_label

if TYPE_CHECKING:  # the run store loads when a run is opened, not with the first page
    from rvpp.service import SavedRun

ROOT = Path(__file__).resolve().parent.parent
DEFAULT_CASE = ROOT / "data" / "cases" / "paper"
CASES_DIR = ROOT / "data" / "cases"
MAX_CACHED_FOLDERS = 16
SERVER_FOLDERS = "RVPP_ALLOW_SERVER_FOLDERS"  # "1": the Home page may load any case folder on the server

CASE = "case"              # the current, valid case (every edit goes through the case model)
ORIGIN = "case_origin"     # the case as loaded: what "reset" and the tariff preset go back to
SOURCE = "case_source"     # where the case came from, for display
CSP_ON = "csp_on"          # False: solve without the CSP plants (paper Table 11)
REQUESTED = "requested"    # keys of the run cases this session asked to solve (done or under way)
OPENED_RUN = "opened_run"  # id of the saved run this session opened from a link (?run=ID)
SAVED_RUN = "results_saved"  # (id, label, case key, how) of the run last saved or opened
DEEP_LINK = "deep_link"    # the page asked for before app.py had set the session up, and its query parameters
LOST = "lost_case"         # True: this session began in a tab whose own case the server no longer holds
OWN_CASE = "own_case"      # query parameter, "1": the tab's case is not the shipped case as a session opens it
DEFAULT_SOURCE = f"the shipped case {DEFAULT_CASE.name}"
APP = "app.py"


@st.cache_resource(show_spinner=False, max_entries=MAX_CACHED_FOLDERS)
def _load_cached(folder: str, stamp: tuple) -> Case:
    return rvpp.load_case(folder)


def _load(folder: str) -> Case:
    """Parse a case folder once per version of its files; sessions share the immutable case."""
    path = Path(folder)
    stamp = tuple(sorted((p.name, _modified_ns(p)) for p in path.iterdir())) if path.is_dir() else ()
    return _load_cached(folder, stamp)


def read_default_case() -> None:
    """Read the shipped case into the cache sessions share (``dashboard.serve``'s head start: the first
    session after a server start then finds it read)."""
    _load(str(DEFAULT_CASE))


def _modified_ns(path: Path) -> int | None:
    """When the file at ``path`` last changed [ns since the epoch]; ``None`` for an entry that cannot be
    followed, such as a link to nothing (an editor's lock file: Emacs' ``.#case.yaml``): the case does
    not read it, or reports it by name if it does."""
    try:
        return path.stat().st_mtime_ns
    except OSError:
        return None


def init() -> None:
    """Set every shared key once per session (the default case on first load). A session that begins in a tab
    whose address says it held a case of its own (:func:`mark_own_case`) remembers that it was lost."""
    if CASE not in st.session_state:
        load(_load(str(DEFAULT_CASE)), source=DEFAULT_SOURCE)
        _, linked = st.session_state.get(DEEP_LINK) or (None, {})
        st.session_state[LOST] = {**linked, **st.query_params.to_dict()}.get(OWN_CASE) == "1"


def own_case() -> bool:
    """Whether the tab's case is anything but the shipped case as a new session opens it: loaded, opened,
    edited or run without its CSP. It lives in the session only, so a server restart loses it."""
    return case() is not origin() or source() != DEFAULT_SOURCE or csp_on() != bool(case().csp)


def mark_own_case() -> None:
    """Say in the tab's address whether its case is its own, so that a session starting there (the server
    restarted, the tab reloaded) can say that case is gone instead of showing the shipped case silently."""
    if own_case():
        st.query_params[OWN_CASE] = "1"
        st.session_state[LOST] = False
    elif OWN_CASE in st.query_params:
        del st.query_params[OWN_CASE]


def lost_case() -> bool:
    """Whether this session began in a tab whose own case is gone, and still shows the shipped case."""
    return st.session_state.get(LOST, False) and not own_case()


def through_app(page: str) -> None:
    """Run ``page`` only inside app.py's navigation.

    Until some session has opened the app, Streamlit serves a link straight to a page
    (a bookmark, or a tab reconnecting after a restart) in its pages-folder mode,
    which runs the page file alone, without the session set up. Such a visit goes
    through the app, which sets the session up and comes back to ``page``.
    """
    if CASE in st.session_state:
        return
    st.session_state[DEEP_LINK] = (page, st.query_params.to_dict())
    st.switch_page(APP)


def resume_deep_link() -> None:
    """Called by app.py once its navigation is set: go to the page first asked for."""
    page, linked = st.session_state.pop(DEEP_LINK, None) or (None, {})
    if page:
        st.switch_page(page, query_params=linked)


def load(case: Case, source: str) -> None:
    """Make ``case`` the current and original case; forget what belonged to the old one."""
    st.session_state[CASE] = case
    st.session_state[ORIGIN] = case
    st.session_state[SOURCE] = source
    st.session_state[CSP_ON] = bool(case.csp)
    st.session_state[REQUESTED] = set()
    st.session_state[LOST] = False
    for key in [k for k in st.session_state if k.startswith(("portfolio_", "markets_", "uncertainty_"))]:
        del st.session_state[key]


def server_folders_allowed() -> bool:
    """Whether the server was started with ``RVPP_ALLOW_SERVER_FOLDERS=1`` (off by default:
    anyone who can open the dashboard could otherwise read case folders on the server)."""
    return os.environ.get(SERVER_FOLDERS, "").strip() == "1"


def load_folder(folder: str | Path) -> Case:
    """Load a case folder on the server and make it the current case.

    Refused with :class:`rvpp.errors.CasePathError` unless :func:`server_folders_allowed`.
    """
    if not server_folders_allowed():
        raise CasePathError(
            "loading a case folder from the server's disk is turned off; upload the case instead (the server's "
            f"operator can turn folders on by starting it with {SERVER_FOLDERS}=1)")
    try:
        case = _load(str(Path(folder).resolve()))
    except ValueError:
        if "\x00" not in str(folder):
            raise
        # the system's path functions refuse a NUL character ("embedded null byte")
        raise CasePathError(f"case folder {excerpt(folder)!r}: a path cannot hold a NUL character") from None
    except OSError as err:  # a name too long, a folder that may not be listed
        raise CasePathError(f"case folder {excerpt(folder)!r} cannot be read: {err.strerror or err}") from None
    load(case, source=str(folder))
    return case


def load_shipped(name: str) -> Case:
    """Load a case shipped with the project (one of :func:`known_case_folders`)."""
    if name not in known_case_folders():
        raise rvpp.CaseError(f"no shipped case {name!r}; the shipped cases are {', '.join(known_case_folders())}")
    case = _load(str(CASES_DIR / Path(name).name))
    load(case, source=f"the shipped case {name}")
    return case


def case() -> Case:
    """The current case as edited (every unit, whether switched on or not)."""
    return st.session_state[CASE]


def origin() -> Case:
    return st.session_state[ORIGIN]


def source() -> str:
    return st.session_state[SOURCE]


def set_case(new: Case) -> None:
    """Replace the current case with an edited, valid one."""
    st.session_state[CASE] = new


def csp_on() -> bool:
    return st.session_state[CSP_ON]


def set_csp_on(on: bool) -> None:
    st.session_state[CSP_ON] = on


def run_case() -> Case:
    """The case that gets solved: the current case with the run switches applied."""
    current = case()
    return current if csp_on() or not current.csp else rvpp.with_options(current, csp=False)


def case_key(case: Case) -> str:
    """A stable digest of everything a solve depends on (settings, units, history)."""
    text = json.dumps(case.to_data(), sort_keys=True, default=str)
    return hashlib.sha256(f"{text}|{case.history.fingerprint}".encode()).hexdigest()


def mark_requested(case: Case) -> None:
    """Remember that this session asked for ``case``: its pages then show the plan (from the
    cache, or by waiting for the solve under way) without another click."""
    mark_requested_key(case_key(case))


def is_requested(case: Case) -> bool:
    return is_requested_key(case_key(case))


def mark_requested_key(key: str) -> None:
    """Remember that this session asked for the work of ``key`` (a case's or a sweep's digest)."""
    st.session_state[REQUESTED].add(key)


def is_requested_key(key: str) -> bool:
    return key in st.session_state[REQUESTED]


def default_label(edited: Case | None = None) -> str:
    """The label a run of the current case (or of ``edited``, a variant of it) is saved under
    unless the user types another: strategy, market set and what was edited since the
    case was loaded."""
    return run_label(origin(), edited or case(), csp_on())


def open_saved(saved: SavedRun) -> None:
    """Make a saved run's case the current case, with its run switches and the case it was
    edited from (so its label's edits stay described)."""
    load(saved.case, source=f'saved run "{saved.info.label}"')
    try:
        st.session_state[ORIGIN] = parse_case(saved.settings["origin"], saved.case.history)
    except (KeyError, TypeError, CaseError):
        pass  # saved without its origin: edits are counted from the run's own case
    set_csp_on(saved.settings.get("csp", True) is not False and bool(saved.case.csp))
    if saved.result is not None:
        mark_requested(run_case())


def known_case_folders() -> list[str]:
    """Case folders shipped with the project (``data/cases/*``)."""
    return sorted(f"data/cases/{p.parent.name}" for p in CASES_DIR.glob("*/case.yaml"))
