"""Code the browser loads ahead of need, while it has nothing else to do.

Streamlit's page code comes in pieces: the code of a kind of element (a metric card, a
text field, a table, a Plotly chart) is fetched and compiled the first time a page shows
one. Home's first chart is drawn without Plotly (:mod:`dashboard.svg`), so a session's
first plan is usually the first thing it shows with Plotly charts, cards, the run label's
text field and the flexibility table, and their code would be loaded while the plan's
charts wait for it (Plotly's alone is 4.7 MB, 2.5-3.5 s of compiling and running on a
two-core machine). Every page therefore asks the browser, once, to import those pieces
when it is idle after the page's first chart is drawn (or after :data:`WAIT_MS`, on a
page without charts), so that a session's first plan finds them ready.

The pieces are files of the installed Streamlit (``static/js/<Element>.<hash>.js``),
found by name once per server process; a name that matches no file, or several, is
skipped, and the page then loads that code when first needed as before.
"""

from __future__ import annotations

import json
import re
from functools import cache
from pathlib import Path

import streamlit as st

from .svg import CHART_CLASS, IMAGE_PREFIX

ELEMENTS = ("PlotlyChart", "Metric", "TextInput", "DataFrame")  # what a plan shows that earlier pages may not have
WAIT_MS = 5000  # a page without a chart starts loading after this long [ms]
POLL_MS = 250   # how often a page looks for its first drawn chart [ms]
SCRIPT_DIR = Path(st.__file__).parent / "static" / "static" / "js"

_LOADER = """<script>
(() => {
  if (window.__rvppPreloaded) return;
  window.__rvppPreloaded = true;
  const index = document.querySelector('script[type="module"][src*="/static/js/index."]');
  if (!index) return;
  const files = FILES;
  const started = Date.now();
  const load = () => files.forEach(file => import(new URL(file, index.src).href).catch(() => {}));
  const idle = () => window.requestIdleCallback ? requestIdleCallback(load, {timeout: 2000}) : setTimeout(load, 0);
  const wait = () => {
    const drawn = document.querySelector('[data-testid="stPlotlyChart"] .main-svg, svg.CHART_CLASS, img[src^="IMAGE_PREFIX"]');
    if (drawn || Date.now() - started > WAIT_MS) idle(); else setTimeout(wait, POLL_MS);
  };
  wait();
})();
</script>"""


def chunk(element: str) -> str | None:
    """The file of Streamlit's code for ``element`` (``Metric.MSVuxtnf.js``), or ``None``
    when no single file has that name."""
    pattern = re.compile(rf"{re.escape(element)}\.[\w-]+\.js")
    found = [path.name for path in SCRIPT_DIR.glob(f"{element}.*.js") if pattern.fullmatch(path.name)]
    return found[0] if len(found) == 1 else None


@cache
def loader() -> str | None:
    """The script that loads the :data:`ELEMENTS`' code once per browser tab, or ``None``
    when none of their files is found (built once: every page's every run puts it in)."""
    files = [name for name in map(chunk, ELEMENTS) if name]
    if not files:
        return None
    return (_LOADER.replace("FILES", json.dumps(files)).replace("WAIT_MS", str(WAIT_MS))
            .replace("POLL_MS", str(POLL_MS)).replace("CHART_CLASS", CHART_CLASS).replace("IMAGE_PREFIX", IMAGE_PREFIX))


def preload() -> None:
    """Put the loader at the end of the sidebar (no height; it runs once per tab)."""
    script = loader()
    if script:
        st.sidebar.html(script, unsafe_allow_javascript=True)
