"""Portfolio: every unit's parameters in editable tables, and each unit's forecast band."""

import streamlit as st

from dashboard import fields, solving, state, widgets
from rvpp import CaseError
from rvpp.service import (KINDS, UNIT_KINDS, UnitKind, bands_figure, curve_figure, follow_capacity, table_message,
                          thin_clock_ticks, workbook)

state.through_app("pages/portfolio.py")

BAND_COLUMNS = 2
SCALE = "scale_with_capacity"   # table column: the unit's forecast band follows its capacity
FIXED = "portfolio_fixed_scale"  # session key: names of units whose band does not follow


def set_csp(on_key: str) -> None:
    state.set_csp_on(st.session_state[on_key])


def fixed() -> set[str]:
    """Units whose forecast band keeps its scale when their capacity changes."""
    return st.session_state.setdefault(FIXED, set())


def unit_table(kind: str):
    table = workbook.unit_table(state.case(), kind)
    if KINDS[kind].role is None:  # no forecast band to scale
        return table
    scale_at = table.columns.get_loc(workbook.SERIES_FIELDS[kind].replace("series", "series_scale"))
    table.insert(scale_at + 1, SCALE, [name not in fixed() for name in table["name"]])
    return table


def with_unit_table(kind: str, table):
    """The edited table as a case; capacities that changed scale their forecast band unless unticked.

    The unticked units are remembered only once the case model accepts the edit: a refused
    edit leaves them as they were. An empty cell is named by its column.
    """
    current = state.case()
    unticked = set(fixed())
    if SCALE in table:
        follows = table[SCALE].fillna(True).astype(bool)
        listed = {u.name for u in getattr(current, kind)} | set(table["name"].dropna())
        unticked = (fixed() - listed) | {name for name, on in zip(table["name"], follows) if not on}
    try:
        edited = workbook.with_unit_table(current, kind, table.drop(columns=[SCALE], errors="ignore"))
    except CaseError as err:
        raise CaseError([table_message(problem) for problem in err.problems]) from None
    edited = follow_capacity(current, edited, fixed=unticked)
    st.session_state[FIXED] = unticked
    return edited


st.title("Portfolio")
st.markdown("Edit any cell, add a row at the bottom of a table or select rows and delete them. Every edit is "
            "checked by the case model: a value that breaks a rule is refused with the reason under its table "
            "and the last valid case is kept. Wide tables scroll sideways; the name column stays in view. "
            "Changing a capacity scales the unit's forecast band too while **Scale band with capacity** is ticked.")

case = state.case()
if case.csp:
    st.toggle("Include the CSP plant(s) in the plan", value=state.csp_on(), key="portfolio_csp_on",
              on_change=set_csp, args=("portfolio_csp_on",),
              help="Off: the plan is made without any CSP, as in the paper's Table 11. The CSP's parameters "
                   "are kept and come back when you switch it on again.")

for kind in UNIT_KINDS:
    st.header(widgets.KIND_TITLES[kind])
    if kind == UnitKind.CSP and not state.csp_on():
        st.info("Switched off: the plan is made without the CSP plants. Their parameters are kept below.",
                icon=":material/power_off:")
    widgets.table_editor(
        f"portfolio_{kind}",
        build=lambda kind=kind: unit_table(kind),
        apply=lambda table, kind=kind: with_unit_table(kind, table),
        column_config={**fields.column_config(state.case(), kind), SCALE: st.column_config.CheckboxColumn(
            "Scale band with capacity", default=True, width="small",
            help="Ticked: changing the capacity scales the unit's forecast band and history profile by the same "
                 "ratio (Series scale follows). Unticked: the band stays as the history gives it.")},
        num_rows="dynamic", hide_index=True,
    )

case = state.case()
if case.csp:
    st.header("Power-block conversion curve")
    st.caption("Electrical output = thermal input × efficiency at each breakpoint, linear in between "
               "(paper Figure 5). Inputs must increase and the output must not fall.")
    name = st.segmented_control("CSP plant", [c.name for c in case.csp], key="portfolio_curve_csp",
                                default=case.csp[0].name, required=True) \
        if len(case.csp) > 1 else case.csp[0].name
    left, right = st.columns([3, 4])  # the table's two columns and row markers whole at 1280 px (327 px)
    with left:
        widgets.table_editor(
            f"portfolio_curve_{name}",
            build=lambda: workbook.breakpoint_table(state.case(), name),
            apply=lambda table: workbook.with_breakpoints(state.case(), name, table),
            column_config={"input_mw_th": st.column_config.NumberColumn("Thermal input [MW_th]"),
                           "efficiency": st.column_config.NumberColumn("Efficiency [-]")},
            num_rows="dynamic", hide_index=True,
        )
    with right:
        unit = next(c for c in state.case().csp if c.name == name)
        st.plotly_chart(curve_figure(unit.power_block.breakpoints, unit.p_max_mw), key="portfolio_curve_chart")

st.header("Forecast bands of the delivery day")
run = state.run_case()
q = run.uncertainty
st.caption(f"Per clock hour over the {q.window_days} days before {run.delivery_date:%d %b %Y}: the "
           f"{q.q_lo * 100:g}th percentile, the median and the {q.q_hi * 100:g}th percentile of each unit's "
           "history. Production is planned on the upper bound and may fall to the lower one; consumption is "
           "planned on the lower bound and may rise to the upper one. Sources on forecast-based bands (see "
           "Uncertainty) take their day-ahead forecast plus percentiles of its past errors instead.")
if run.provenance_summary():
    st.caption(run.provenance_summary())
problem = solving.prepare(run)
if problem is not None:
    kinds = [k for k in UNIT_KINDS if getattr(run, k) and KINDS[k].role is not None]  # a band: an uncertain series
    for tab, kind in zip(st.tabs([widgets.KIND_TITLES[k] for k in kinds]), kinds):
        with tab:
            columns = st.columns(BAND_COLUMNS)
            for i, unit in enumerate(getattr(run, kind)):
                with columns[i % BAND_COLUMNS]:
                    figure = thin_clock_ticks(bands_figure(problem, unit.name), widgets.NARROW_TICK_HOURS)
                    st.plotly_chart(figure, key=f"portfolio_band_{unit.name}")
