"""Saved runs: the run library of the store, shared by everyone using this server.

Select runs in the table to open, rename, export, delete or compare them. A run opened
here (or by its link) becomes the current case, with its plan shown on Results without
a new solve.
"""

import hashlib

import pandas as pd
import streamlit as st

from dashboard import library, state, widgets
from rvpp import RvppError
from rvpp.service import STORE_ERRORS

state.through_app("pages/runs.py")

COMPARE_MAX = 4
TABLE_KEY = "runs_table"  # the table's widget key, followed by the digest of the runs it lists
COLUMNS = {  # every column in view without scrolling sideways at 1280 px: the strategy and the markets are in the
    # default label and in the caption of a ticked run
    "label": st.column_config.TextColumn("Label", width=280, pinned=True),
    "net_cost_keur": st.column_config.NumberColumn("Net cost [kEUR]", format="%,.1f",
                                                   help="Positive: the plant pays; negative: it earns"),
    "status": st.column_config.TextColumn("Status"),
    "day": st.column_config.TextColumn("Delivery day"),
    "case": st.column_config.TextColumn("Case"),
    "saved": st.column_config.TextColumn("Saved (UTC)"),
    "link": st.column_config.LinkColumn("Link", display_text="open", width="small",
                                        help="Opens the run in a new tab; copy it to share the run"),
}


def rename(run_id: str, key: str) -> None:
    try:
        info = library.library().rename(run_id, st.session_state[key])
    except RvppError as err:
        st.session_state["runs_problem"] = str(err)
        return
    st.session_state["runs_problem"] = None
    st.session_state["runs_notice"] = f'Renamed to "{widgets.literal(info.label, widgets.LABEL_CHARS)}".'


def delete(run_ids: list[str]) -> None:
    try:
        for run_id in run_ids:
            library.library().delete(run_id)
            library.forget(run_id)
    except RvppError as err:
        st.session_state["runs_problem"] = str(err)
        return
    st.session_state["runs_problem"] = None
    st.session_state["runs_notice"] = f"Deleted {len(run_ids)} run{'s' if len(run_ids) > 1 else ''}."


def open_one(run_id: str) -> None:
    try:
        widgets.open_run(library.load(run_id))
    except RvppError as err:
        st.session_state["runs_problem"] = str(err)
        return
    st.session_state["runs_open"] = True


def compare(run_ids: list[str]) -> None:
    st.session_state["compare_runs"] = list(run_ids)
    st.session_state["compare_mode"] = "Saved runs"


def table_key(runs) -> str:
    """The table's key for this list of runs. A tick is a row number: when the list changed (a run saved or
    deleted, in this session or another), the table starts again without ticks rather than move them onto
    other runs."""
    listed = hashlib.sha256(" ".join(r.id for r in runs).encode()).hexdigest()[:16]
    return f"{TABLE_KEY}_{listed}"


def saved(run) -> str:
    """When ``run`` was saved, to the minute, in UTC (the store's time)."""
    return run.created_at[:16].replace("T", " ")


def where() -> str:
    url = library.library().engine.url
    if url.get_backend_name() == "sqlite":
        return "a SQLite file in the data folder (`RVPP_DATA_DIR`, by default `rvpp-data/` where the server runs)"
    return f"the {url.get_backend_name()} database at `{url.render_as_string(hide_password=True)}` (`RVPP_STORE_URL`)"


st.title("Saved runs")
if st.session_state.pop("runs_open", False):
    st.switch_page("pages/results.py")
try:
    runs = library.runs()
except (RvppError, *STORE_ERRORS) as err:
    widgets.problems([f"the run library cannot be read: {err}"], "Saved runs unavailable", note="Nothing was changed.")
    st.stop()
st.markdown(f"Every run saved on **Results** or **Compare strategies**, with its case as edited, its settings and "
            f"its plan. They are kept in {where()}, so they survive a reload, a restart of the server and a crash, "
            "and everyone using this server sees them.")
if st.session_state.get("runs_problem"):
    widgets.problems([widgets.literal(st.session_state["runs_problem"], limit=None)], "Not done",
                     note="The library is unchanged.")
if notice := st.session_state.pop("runs_notice", None):
    st.success(notice, icon=":material/check:")
if not runs:
    st.info("No saved runs yet. Solve on **Results** and press **Save run**.", icon=":material/bookmark_border:")
    st.stop()

table = pd.DataFrame({
    "label": [r.label for r in runs],
    "saved": [saved(r) for r in runs],
    "case": [r.case_name for r in runs],
    "day": [r.delivery_date for r in runs],
    "status": [r.status for r in runs],
    "net_cost_keur": [None if r.objective_eur is None else -r.objective_eur / 1000.0 for r in runs],
    "link": [library.link(r.id) for r in runs],
})
st.caption(f"{len(runs)} saved run{'s' if len(runs) > 1 else ''}, newest first. Tick the boxes at the left of the "
           f"rows to act on them; tick two, three or {COMPARE_MAX} to compare them.")
selection = st.dataframe(table[list(COLUMNS)], hide_index=True, column_config=COLUMNS, key=table_key(runs),
                         on_select="rerun",
                         selection_mode="multi-row", height=min(38 + 35 * len(runs), 560))
chosen = [runs[i] for i in selection.selection.rows if i < len(runs)]
if not chosen:
    st.stop()

ids = [r.id for r in chosen]
if len(chosen) == 1:
    run = chosen[0]
    st.header(widgets.literal(run.label, widgets.LABEL_CHARS))
    st.caption(widgets.literal(f"{run.strategy} strategy · {run.markets} · case {run.case_name} · delivery day "
                               f"{run.delivery_date} · saved {saved(run)} UTC", limit=None))
    first, second, third = st.columns(3, vertical_alignment="bottom")
    first.button("Open as the current case", key="runs_open_button", type="primary", on_click=open_one,
                 args=(run.id,), icon=":material/open_in_browser:",
                 help="Its case becomes the current case; its plan shows on Results without a new solve.")
    second.download_button("Export (zip)", lambda: library.library().export_zip(run.id),
                           file_name=f"{run.case_name}_{run.delivery_date}_{run.strategy}.zip", mime="application/zip",
                           on_click="ignore", key="runs_export", icon=":material/folder_zip:",
                           help="The case folder (loads again on Home), the plan's CSV and Excel files and run.json")
    third.link_button("Open in a new tab", library.link(run.id), icon=":material/link:")
    left, right = st.columns([4, 1], vertical_alignment="bottom")
    left.text_input("New label", value=run.label, key=f"runs_label_{run.id}", max_chars=190)
    right.button("Rename", key="runs_rename", on_click=rename, args=(run.id, f"runs_label_{run.id}"),
                 icon=":material/edit:")
else:
    if len(chosen) <= COMPARE_MAX and st.button(f"Compare these {len(chosen)} runs", key="runs_compare",
                                                type="primary", on_click=compare, args=(ids,),
                                                icon=":material/compare_arrows:"):
        st.switch_page("pages/compare.py")
    if len(chosen) > COMPARE_MAX:
        st.caption(f"Compare takes two, three or {COMPARE_MAX} runs; {len(chosen)} are ticked.")
with st.popover(f"Delete {len(chosen)} run{'s' if len(chosen) > 1 else ''}…", icon=":material/delete:"):
    st.markdown("Deleted runs cannot be brought back. Export them first to keep a copy.")
    st.button("Delete for good", key="runs_delete", on_click=delete, args=(ids,), type="primary")
