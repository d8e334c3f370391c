"""Building blocks every page draws with: KPI cards, refusals with the case model's
messages, table editors that go through the case model, case summaries and downloads."""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from typing import Any

import pandas as pd
import streamlit as st

from rvpp import Case, CaseError, Result, RvppError
from rvpp import service
from rvpp.service import EXCERPT_CHARS, KINDS, LABEL_LENGTH, Outcome, UnitKind, amount, excerpt, plain_message

from . import library, state

KIND_TITLES = {kind: info.group for kind, info in KINDS.items()}
KPI_CARD_PX = 193  # a card's width: "Reserve revenue [kEUR]" whole, four to a row in the 820 px of 1280 px
NARROW_TICK_HOURS = 2  # a clock label every other hour on a chart that may be narrow (450 px on a laptop at 150 %)
BIDS_HEIGHT_PX = 300  # about eight periods at a time; the table scrolls
NET = "Net cost [kEUR]"
# The one money convention of every page, chart, table and export label, said once.
MONEY = ("Money is in kEUR, as **cost: positive when the plant pays**, negative when it earns; "
         "the net cost is the costs and the price protection minus the revenues. A revenue is what the plant "
         "earns.")
PERCENT = 100.0
KILO = 1000.0
# Column formats by the unit a header ends with; money and energy with thousands separators.
KEUR_FORMAT = "%,.1f"  # an amount in kEUR: one decimal, thousands separators
UNIT_FORMATS = {"[kEUR]": KEUR_FORMAT, "[kEUR/day]": KEUR_FORMAT, "[%]": "%.1f", "[s]": "%.2f",
                "[MWh]": "%,.1f", "[h]": "%.2f", "[MW]": "%,.0f"}
LABEL_CHARS = LABEL_LENGTH  # a saved run's label is shown whole (the library keeps none longer)
# Markdown's special characters, each shown as typed once backslash-escaped: links and images, emphasis,
# code, headings, lists, tables, raw HTML and autolinks (<), LaTeX ($), entities (&) and Streamlit's own
# ":" syntax (emoji names, ":color[...]" directives, ":material/...:" icons, whose ":material/" Streamlit
# reads before markdown undoes the escapes: hence "/" too).
MARKDOWN_SPECIAL = re.compile(r"[\\`*_\[\]()#+\-.!|<>~$:/&]")
ADDED = re.compile(r" added \(")  # a unit added, in the words of rvpp.data.edits: "BAT1 added (20 MW)"


def eur(value: float | None) -> str:
    """``−124,035 EUR``: whole euros with a true minus sign (none on an amount that rounds to 0)."""
    return "–" if value is None else f"{amount(value, 0)} EUR".replace("-", "−")


def keur(value_eur: float | None) -> str:
    """``−124.0``: an amount in kEUR with one decimal, as in the paper's tables; an amount that rounds
    to 0.0 shows no sign (``−0.0`` read as a loss)."""
    return "–" if value_eur is None else tenths(value_eur / KILO)


def tenths(value: float) -> str:
    """``−11.3``: a number already in its unit (kEUR, %) with one decimal, thousands separators and a true
    minus, for text tables (:func:`keur` converts from EUR)."""
    return amount(value, 1).replace("-", "−")


def in_keur(frame: pd.DataFrame) -> pd.DataFrame:
    """A copy of ``frame`` to show: every money column ``*_eur`` [EUR] becomes ``*_keur`` [kEUR]
    (prices ``*_eur_per_mwh`` and other columns as they are)."""
    money = [c for c in frame.columns if str(c).endswith("_eur")]
    shown = frame.copy()
    shown[money] = shown[money] / KILO
    return shown.rename(columns={c: c.removesuffix("_eur") + "_keur" for c in money})


def literal(value: Any, limit: int | None = EXCERPT_CHARS) -> str:
    """User text (a label, a case or file name, an id, a message quoting them) as markdown that shows it
    as typed and draws nothing else: on one line, cut to ``limit`` characters (``None``: uncut) with
    control characters as ``?`` (:func:`~rvpp.data.files.excerpt`), every special character escaped."""
    text = " ".join(str(value).split())
    text = excerpt(text, len(text) if limit is None else limit)
    return MARKDOWN_SPECIAL.sub(lambda found: "\\" + found.group(), text)


def kpis(result: Result) -> dict[str, tuple[str, str]]:
    """Headline numbers of a plan: label → (shown value, explanation with the exact value).

    One card carries the objective, with its sign in words; the others are its parts.
    """
    parts = result.parts
    protection = sum(result.protection_eur.values()) if result.protection_eur else None
    net_cost = None if result.objective_eur is None else -result.objective_eur
    money = {
        NET: (net_cost, "What the day costs the plant: costs and robust protection minus revenues (the paper's "
                        "cost, minus the objective). Positive: the plant pays; negative: it earns."),
        "DAM revenue [kEUR]": (parts.get("revenue_dam_eur"), "Day-ahead sales minus purchases at median prices."),
        "Reserve revenue [kEUR]": (parts.get("revenue_sr_eur"), "Up and down secondary-reserve bands at their "
                                                         "upper-percentile prices."),
        "HPA cost [kEUR]": (parts.get("cost_hpa_eur"), "Heat bought through the heat purchase agreement."),
        "Operating cost [kEUR]": (parts.get("cost_opex_eur"), "O&M of wind, PV and CSP output."),
        "Protection [kEUR]": (protection, "Robust protection: worst-case loss from price deviations in the Γ "
                                          "worst periods of each price (DAM, SR up, SR down), charged in the "
                                          "objective."),
    }
    shown = {label: (keur(v), f"{text} Exact: {eur(v)}.")
             for label, (v, text) in money.items()}
    gap = "–" if result.mip_gap is None else f"{result.mip_gap * PERCENT:.3f}"
    total_s = result.build_s + result.solve_s + result.extract_s
    shown["MIP gap [%]"] = (gap, "Relative distance between the plan and the solver's bound.")
    shown["Solve time [s]"] = (f"{total_s:.2f}", f"Build {result.build_s:.2f} s, HiGHS {result.solve_s:.2f} s, "
                                               f"tables {result.extract_s:.2f} s.")
    return shown


def kpi_cards(result: Result, only: tuple[str, ...] | None = None) -> None:
    """KPI cards; money in kEUR with the exact amount in each card's help; the net
    cost's card says in words whether the plant pays or earns."""
    values = kpis(result)
    cards = st.container(horizontal=True)  # four to a row at 1280 px, fewer in a narrower window: each label whole
    for name in only or values:
        value, help_text = values[name]
        sign = {}
        if name == NET and result.objective_eur is not None:
            sign = dict(delta="the plant pays" if result.objective_eur <= 0 else "the plant earns",
                        delta_color="off", delta_arrow="off")
        cards.metric(name, value, help=help_text, border=True, width=KPI_CARD_PX, **sign)
    if result.has_plan:
        st.caption(":material/info: " + service.explanation(service.economics(result)) + " Hover a card's question mark for the "
                   "exact amount in EUR.")


# Said by every CSV download: an Excel set to a decimal comma splits or misreads such a file
CSV_NOTE = (". Commas separate its values and a point marks decimals, which an Excel set to a decimal comma "
            "(as in Spain) misreads: there, use an Excel download")

BID_COLUMNS = {  # market.csv column -> (header, format, help); short headers: the table fits 1280 px
    "clock": ("Period", None, "Start of the period, local time of the delivery day"),
    "p_da_mw": ("DAM [MW]", "%.1f", "Day-ahead energy bid: positive sells, negative buys"),
    "r_sr_up_mw": ("Up [MW]", "%.1f", "Upward secondary-reserve band offered"),
    "r_sr_dn_mw": ("Down [MW]", "%.1f", "Downward secondary-reserve band offered"),
    "h_hpa_mw": ("HPA [MW_th]", "%.1f", "Heat bought through the heat purchase agreement"),
    "price_da_mid": ("DAM [EUR/MWh]", "%.2f", "Forecast day-ahead price (middle of its band)"),
    "price_sr_up_hi": ("Up [EUR/MW]", "%.2f", "Forecast up-reserve price, per MW and hour of band"),
    "price_sr_dn_hi": ("Down [EUR/MW]", "%.2f", "Forecast down-reserve price, per MW and hour of band"),
    "tariff_hpa": ("HPA [EUR/MWh_th]", "%.2f", "Heat purchase agreement tariff"),
}


# The CSV has room the table has not: the DAM sign and the reserve prices' hour, in plain ASCII for Excel
CSV_HEADERS = {"DAM [MW]": "DAM [MW] (+ sell / - buy)", "Up [EUR/MW]": "Up [EUR/MW per h]",
               "Down [EUR/MW]": "Down [EUR/MW per h]"}


def bids_table(result: Result) -> pd.DataFrame:
    """The bids of a plan as an operator submits them: one row per period, the quantities [MW]
    and the forecast prices they are bid against, under readable headers."""
    market = result.market[list(BID_COLUMNS)]
    return market.rename(columns={column: header for column, (header, _, _) in BID_COLUMNS.items()})


def bids_csv(table: pd.DataFrame) -> str:
    """The bids table as CSV text, under :data:`CSV_HEADERS`."""
    return table.rename(columns=CSV_HEADERS).to_csv(index=False, float_format="%.3f")


def bids(result: Result, key: str) -> None:
    """The bids table with its own download (the table as shown)."""
    table = bids_table(result)
    st.caption("Quantities: DAM energy (+ sell, − buy), up and down reserve bands, heat bought through the HPA; "
               "then the forecast prices they are bid against.")
    config = {header: (st.column_config.NumberColumn(header, format=fmt, help=help_text) if fmt else
                       st.column_config.TextColumn(header, help=help_text))
              for header, fmt, help_text in BID_COLUMNS.values()}
    st.dataframe(table, hide_index=True, column_config=config, width="stretch", height=BIDS_HEIGHT_PX,
                 key=f"{key}_bids_table")
    st.download_button("Bids as shown (CSV)", bids_csv(table),
                       file_name=f"{result.case.name}_{result.day:%Y%m%d}_{result.case.budgets.strategy}_bids_table.csv",
                       mime="text/csv", on_click="ignore", key=f"{key}_bids_table_csv", icon=":material/download:",
                       help="This table as a CSV file; its headers also say the DAM sign and that reserve "
                            "prices are per MW and hour" + CSV_NOTE + " (the full plan's, on Results)")


def number_formats(frame: pd.DataFrame) -> dict:
    """Column settings that round each number column by the unit in its name."""
    config = {}
    for column in frame.columns:
        unit = next((u for u in UNIT_FORMATS if str(column).endswith(u)), None)
        if unit:
            config[column] = st.column_config.NumberColumn(format=UNIT_FORMATS[unit])
    return config


def status_line(result: Result) -> None:
    """Say how the solve ended; infeasible or failed solves explain why."""
    if result.status is Outcome.OPTIMAL:
        st.success(f"Optimal plan for {result.day:%A %d %B %Y} ({result.case.budgets.strategy} strategy, "
                   f"{result.case.markets.label}).", icon=":material/check_circle:")
    elif result.status is Outcome.STOPPED and result.has_plan:
        st.warning(f"Stopped early, as asked, after {result.solve_s:.1f} s of search: the plan below is the best "
                   f"found so far, feasible and within {result.mip_gap:.2%} of the optimum. Press **Solve** to "
                   "search on to the optimum.", icon=":material/done_all:")
    elif result.has_plan:
        st.warning(f"The solver stopped at its time limit of {result.case.solver.time_limit_s:g} s; the plan below "
                   f"is feasible but may not be optimal (gap {result.mip_gap:.2%}).", icon=":material/timer:")
    else:  # the message in words, not the solver's status code ("No plan: no_solution.")
        message = result.message or f"no plan ({result.status})"
        if result.status is Outcome.NO_SOLUTION:
            message += (f" (the limit is {result.case.solver.time_limit_s:g} s per solve, the case's "
                        "`solver.time_limit_s` in case.yaml or the case workbook)")
        st.error(f"**No plan.** {message[0].upper()}{message[1:]}.".replace("..", "."), icon=":material/error:")


def unproven(result: Result) -> str:
    """Why a plan is not proven optimal, in a few words: stopped early or at its time limit, and its gap."""
    why = "stopped early, as asked" if result.status is Outcome.STOPPED else "stopped at its time limit"
    return f"{why}, within {result.mip_gap:.2%} of the optimum"


def problems(messages: list[str], title: str = "Edit refused", note: str = "The last valid case is kept.") -> None:
    """Show the case model's messages, one per line, where the edit was made."""
    lines = "\n".join(f"- {plain_message(m)}" for m in messages)
    st.error(f"**{title}.** {note}\n\n{lines}", icon=":material/block:")


def refusal(err: RvppError, title: str, note: str) -> None:
    """Show why the library refused: the case model's problems, or the error's message."""
    problems(err.problems if isinstance(err, CaseError) else [str(err)], title, note)


def table_editor(key: str, build: Callable[[], pd.DataFrame], apply: Callable[[pd.DataFrame], Case],
                 **editor: Any) -> None:
    """An editable table whose every edit goes through the case model.

    ``build`` lays the current case out as a table; ``apply`` reads an edited table
    back into a case (raising :class:`~rvpp.errors.CaseError` when a value breaks a
    rule). A valid edit becomes the current case at once; an invalid one is refused
    with the model's message, in the form's words, under the table, and the last valid
    case is kept. When the case holds other values than the table shows after an edit
    (e.g. a forecast scale that followed a capacity), the table is drawn again from it.
    """
    # A new row's defaults follow the case (its free name: BAT2 once BAT1 is in). Streamlit gives an
    # editor whose settings changed a new identity and drops its edits, so it starts afresh from the case
    # (an edit that added or deleted rows draws it again at once, below).
    settings, drawn_with = repr(editor.get("column_config")), st.session_state.get(f"{key}_settings")
    if drawn_with is not None and drawn_with != settings:
        reset_editor(key)
    st.session_state[f"{key}_settings"] = settings
    generation = st.session_state.setdefault(f"{key}_generation", 0)
    widget, base = f"{key}_{generation}", f"{key}_base"
    if widget not in st.session_state or base not in st.session_state:
        st.session_state[base] = build()
    numbers = typed_numbers(st.session_state[base], editor.get("column_config") or {})
    editor["column_config"] = {**(editor.get("column_config") or {}), **{
        column: text_column(config) for column, config in numbers.items()}}
    edited = st.data_editor(as_text(st.session_state[base], numbers), key=widget, **editor)
    read, refused = read_numbers(edited, numbers, st.session_state[base])
    try:
        new = apply(read)
    except CaseError as err:
        refused = refused + err.problems  # every problem of the edit at once, the cells typed first
    if refused:
        problems(refused)
        st.button("Discard these edits", key=f"{key}_discard", on_click=reset_editor, args=(key,),
                  icon=":material/undo:")
        return
    if new != state.case():
        st.session_state[f"{key}_accepted"] = changes(state.case(), new)
        state.set_case(new)
        rows_moved = len(edited) != len(st.session_state[base])  # a new row's defaults move on with them
        if rows_moved or not _same_cells(as_text(build(), numbers), edited):
            reset_editor(key)
            st.rerun()
    if accepted := st.session_state.pop(f"{key}_accepted", None):
        st.success("**Edit accepted**: " + "; ".join(literal(c, limit=None) for c in accepted)
                   + ". The current case now holds it; solve again on Results to see its plan.",
                   icon=":material/check:")


def typed_numbers(table: pd.DataFrame, config: dict) -> dict[str, dict]:
    """The editable number columns of ``table`` with their settings (a label of its own where
    ``config`` gives none).

    The table editor shows them as text cells: a number cell of the browser's grid drops the
    letters typed into it without a word, so "abc" would arrive as an empty cell. As text it
    reaches :func:`read_numbers`, which names it by column and row.
    """
    numbers = {}
    for column in table.columns:
        setting = config.get(column) or {}
        if (setting.get("type_config") or {}).get("type") not in (None, "number") or setting.get("disabled"):
            continue
        if pd.api.types.is_numeric_dtype(table[column]) and not pd.api.types.is_bool_dtype(table[column]):
            numbers[column] = {**setting, "label": setting.get("label") or str(column)}
    return numbers


def text_column(setting: dict) -> dict:
    """A number column's settings as a right-aligned text column."""
    return st.column_config.TextColumn(setting["label"], help=setting.get("help"), width=setting.get("width"),
                                       pinned=setting.get("pinned"), required=setting.get("required"),
                                       alignment="right", default=number_text(setting.get("default")))


def number_text(value: Any) -> str | None:
    """A cell's number as typed (``50``, ``0.95``, ``1e-05``); an empty cell as ``None``."""
    if value is None or pd.isna(value):
        return None
    value = float(value)
    return str(int(value)) if value.is_integer() and abs(value) < 1e15 else f"{value:.12g}"


def as_text(table: pd.DataFrame, numbers: dict[str, dict]) -> pd.DataFrame:
    """``table`` with its ``numbers`` columns as text cells."""
    shown = table.copy()
    for column in numbers:
        shown[column] = pd.Series([number_text(v) for v in table[column]], index=table.index, dtype=object)
    return shown


def read_numbers(table: pd.DataFrame, numbers: dict[str, dict], before: pd.DataFrame) -> tuple[pd.DataFrame, list[str]]:
    """The edited ``table`` with its ``numbers`` columns read back as numbers, and the cells that are
    not numbers in the table's words (``WF1: P max [MW] "abc" is not a number``). Such a cell keeps
    its value in ``before`` (the table as drawn; empty in a new row), so the rest of the edit can be
    checked with it and every problem be told at once."""
    read, wrong = table.copy(), []
    names = next((table[c] for c in ("name", "source", "hour") if c in table), None)
    if "name" in table:  # typed by the user, like the cells: quoted as markdown that shows it as typed
        names = names.map(lambda name: literal(name) if isinstance(name, str) else name)
    for column, setting in numbers.items():
        values = []
        for position, (index, cell) in enumerate(table[column].items()):
            text = "" if cell is None or (not isinstance(cell, str) and pd.isna(cell)) else str(cell).strip()
            try:
                value = float(text) if text else float("nan")
            except ValueError:
                value = None
            if value is None or (text and not math.isfinite(value)):
                row = names[index] if names is not None and isinstance(names[index], str) else f"row {position + 1}"
                hint = " (write decimals with a point: 1.5)" if re.fullmatch(r"[+-]?\d+,\d+", text) else ""
                # The typed text as markdown that shows it as typed: the refusal is drawn as markdown.
                wrong.append(f'{row}: {setting["label"]} "{literal(text)}" is not a number{hint}')
                value = float(before.at[index, column]) if index in before.index else float("nan")
            values.append(value)
        read[column] = pd.Series(values, index=table.index, dtype=float)
    return read, wrong


def changes(before: Case, after: Case) -> list[str]:
    """What changed from ``before`` to ``after`` in the words of the forms, each with its old
    value when it can be paired (``WF1 80 MW (was 50 MW)``)."""
    switches = [f"{what} {b} (was {a})" for what, a, b in (
        ("strategy", before.budgets.label, after.budgets.label), ("markets", before.markets.label, after.markets.label))
        if a != b]
    new, old = service.describe_edits(before, after), service.describe_edits(after, before)
    if len(new) != len(old):
        return switches + new or ["the case"]
    return switches + [n if o == n or _added_or_removed(n, o) else f"{n} (was {_was(o, n)})"
                       for n, o in zip(new, old)] or ["the case"]


def _added_or_removed(new: str, old: str) -> bool:
    """Whether a pair of edit words tells a unit added or removed (``BAT1 added (20 MW)`` against
    ``BAT1 removed``, or a unit renamed: ``B1 added (20 MW)`` against ``BAT1 added (20 MW)``): it says so
    itself and has no old value."""
    return any(words.endswith(" removed") or ADDED.search(words) for words in (new, old))


def _was(old: str, new: str) -> str:
    """``old`` without the words it shares with the start of ``new`` (``WF1 50 MW`` -> ``50 MW``)."""
    shared = 0
    for a, b in zip(old.split(), new.split()):
        if a != b:
            break
        shared += 1
    return " ".join(old.split()[shared:]) or old


def _same_cells(left: pd.DataFrame, right: pd.DataFrame) -> bool:
    """Whether two tables hold the same values cell by cell (empty cells equal)."""
    if list(left.columns) != list(right.columns) or len(left) != len(right):
        return False
    plain = [frame.astype(object).where(frame.notna(), None).to_numpy().tolist() for frame in (left, right)]
    return plain[0] == plain[1]


def reset_editor(key: str) -> None:
    """Start the table ``key`` afresh from the current case (its pending edits are dropped)."""
    st.session_state[f"{key}_generation"] = st.session_state.get(f"{key}_generation", 0) + 1
    st.session_state.pop(f"{key}_base", None)


def case_summary(case: Case) -> None:
    """The case at a glance: units per kind with installed capacity, as a markdown table in the
    caption's smaller type (drawn with the page's text; ``st.table`` would have the browser
    load 0.75 MB of table code)."""
    rows = ["| Kind | Units | Names | Installed |", "|:--|--:|:--|:--|"]
    for kind, title in KIND_TITLES.items():
        units = getattr(case, kind)
        if not units:
            continue
        if kind == UnitKind.TD:
            capacity = f"{sum(u.h_max_mw_th for u in units):,.0f} MW_th"
        elif kind == UnitKind.CSP:
            storage = sum(u.storage.e_max_mwh_th for u in units)
            capacity = f"{sum(u.p_max_mw for u in units):,.0f} MW, TS {storage:,.0f} MWh_th"
        else:
            capacity = f"{sum(u.p_max_mw for u in units):,.0f} MW"
        off = kind == UnitKind.CSP and not state.csp_on()
        cells = (title + (" (switched off)" if off else ""), len(units), ", ".join(u.name for u in units), capacity)
        rows.append("| " + " | ".join(literal(cell, limit=None) for cell in cells) + " |")
    st.caption("\n".join(rows))


def sidebar(case: Case) -> None:
    """Where am I: the case, its day and what was edited, on every page (drawn after the
    page ran, so it shows the page's own edits)."""
    st.caption("Current case")
    st.markdown(f"**{literal(case.name)}** · {case.delivery_date:%d %b %Y}  \n{state.default_label()}")
    run = state.run_case()
    if not state.is_requested(run):
        return
    from . import solving  # solving imports this module

    key = state.case_key(run)
    result = solving.solver().result(key)
    if result is not None and result.has_plan:
        st.caption(":material/check: solved — see Results")
    elif result is not None:  # infeasible, or no plan within the time limit: not "solved"
        st.caption(":material/error: no plan — see Results for why")
    elif solving.solver().running(key):
        st.caption(":material/hourglass_top: solving…")


def lost_case_note() -> None:
    """Say that the tab's own case is gone when a new session began where it was (the server restarted or
    the tab was reloaded): the page would otherwise show the shipped case as if nothing had happened."""
    if state.lost_case():
        st.warning("This tab's case (loaded, opened or edited here) is gone: the server was restarted or the "
                   "tab reloaded, and a tab keeps its case only while its session lasts. This is the shipped "
                   f"case {state.DEFAULT_CASE.name} again. Saved runs are kept: open one on **Saved runs**, or "
                   "load a case you downloaded on **Home**.", icon=":material/restart_alt:")


def open_linked_run(page) -> None:
    """Open the saved run a link names (``?run=ID``) once per session, then show its plan."""
    run_id = st.query_params.get("run")
    if not run_id or st.session_state.get(state.OPENED_RUN) == run_id:
        return
    st.session_state[state.OPENED_RUN] = run_id
    try:
        saved = library.load(run_id)
    except RvppError as err:  # the id is the link's own text
        messages = err.problems if isinstance(err, CaseError) else [literal(err, limit=None)]
        problems(messages, "The linked run cannot be opened", note="The current case is unchanged.")
        return
    open_run(saved)
    if page.url_path != "results":
        st.switch_page("pages/results.py", query_params={"run": run_id})


def open_run(saved) -> None:
    """Make a saved run the session's current case, its plan shown without a solve."""
    from . import solving  # solving imports this module

    state.open_saved(saved)
    if saved.result is not None:
        solving.solver().remember(saved.result)
    # Results says which saved run it shows: a toast sent before a page switch (a link) is never drawn
    how = "opened" if saved.result is not None else "opened without a plan"
    st.session_state[state.SAVED_RUN] = (saved.info.id, saved.info.label, state.case_key(state.run_case()), how)
    st.toast(f"Opened the saved run \"{literal(saved.info.label, LABEL_CHARS)}\".", icon=":material/bookmark:")


def plan_downloads(result: Result, case: Case, key: str) -> None:
    """Bids CSV, full plan workbook and the case as edited (zip and workbook)."""
    stem = f"{case.name}_{result.day:%Y%m%d}_{case.budgets.strategy}"
    row = st.container(horizontal=True)  # the buttons wrap in a narrow window, each label whole
    row.download_button("Bids (CSV)", result.market.to_csv(index=False, float_format="%.6f"),
                        file_name=f"{stem}_bids.csv", mime="text/csv", on_click="ignore", key=f"{key}_bids",
                        icon=":material/download:", help="market.csv: one row per period with the DAM, SR "
                                                        "and HPA bids and the price bands" + CSV_NOTE)
    row.download_button("Full plan (Excel)", lambda: service.plan_workbook_bytes(result), file_name=f"{stem}_plan.xlsx",
                        mime="application/vnd.openxmlformats-officedocument.spreadsheetml.sheet",
                        on_click="ignore", key=f"{key}_plan", icon=":material/download:",
                        help="summary, market, units, csp and flexibility sheets")
    case_downloads(case, key, (row, row))


def case_downloads(case: Case, key: str, columns=None) -> None:
    """The case as edited: a zip (case.yaml + history.csv) and an Excel case workbook."""
    first, second = columns or st.columns(2)
    first.download_button("Case as edited (zip)", lambda: service.case_zip_bytes(case), file_name=f"{case.name}.zip",
                          mime="application/zip", on_click="ignore", key=f"{key}_case_zip",
                          icon=":material/folder_zip:", help="case.yaml and history.csv; load it again on Home")
    second.download_button("Case as edited (Excel)", lambda: service.case_workbook_bytes(case),
                           file_name=f"{case.name}_case.xlsx",
                           mime="application/vnd.openxmlformats-officedocument.spreadsheetml.sheet",
                           on_click="ignore", key=f"{key}_case_xlsx", icon=":material/table:",
                           help="settings, units, curves and history as sheets; load it again on Home")

