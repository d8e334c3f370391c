"""Start the dashboard as ``make run`` does: ``python -m dashboard [streamlit options]``.

Streamlit's own ``streamlit run app.py``, with one difference: while the server starts and the
first visitor's browser loads Streamlit's code (1-2 s), a background thread imports what Home's
first run needs (pandas, NumPy, PyArrow, the case model, the dashboard's modules) and reads the
shipped case into the sessions' shared cache. Without it, the first visitor after a server
start waits for these imports and that read after the page has loaded (docs/dashboard.md,
"Home's first chart").

Streamlit is imported before the thread starts (its plotting setup looks into ``sys.modules``
for pandas and must not find one half imported), and every script run waits for the thread
before it imports anything (:func:`wait`), so no module is ever imported from two threads.
``streamlit run app.py`` still works; it only skips this head start.
"""

from __future__ import annotations

import importlib
import sys
import threading
from pathlib import Path

APP = Path(__file__).resolve().parent.parent / "app.py"
# What Home's first run imports, in app.py's order (NumPy and pandas first: the longest).
FIRST_PAGE = ("numpy", "pandas", "pyarrow", "dashboard.browser", "dashboard.solving", "dashboard.state",
              "dashboard.widgets", "dashboard.svg", "rvpp.data.case_yaml", "rvpp.data.variants")
WAIT_S = 60.0  # a script run waits at most this long for the head start

_warming: threading.Thread | None = None


def _warm() -> None:
    """Import :data:`FIRST_PAGE`; a module that fails here fails again, with its message, where
    the page imports it."""
    for name in FIRST_PAGE:
        try:
            importlib.import_module(name)
        except Exception:  # noqa: BLE001 - the page's own import reports it
            return
    try:
        importlib.import_module("dashboard.state").read_default_case()
    except Exception:  # noqa: BLE001 - the first session's own load reports it
        return


def wait() -> None:
    """Wait for the head start's imports, if this server was started by :func:`main`."""
    if _warming is not None:
        _warming.join(WAIT_S)


def main(argv: list[str]) -> None:
    """``streamlit run app.py`` with ``argv`` as its options, the head start running beside it."""
    global _warming
    from streamlit.web import cli  # first, and in this thread: see the module's notes

    _warming = threading.Thread(target=_warm, name="rvpp-first-page-imports", daemon=True)
    _warming.start()
    sys.argv = ["streamlit", "run", str(APP), *argv]
    cli.main()
