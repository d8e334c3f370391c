"""The Γ slider of Learn and Compare: the day swept once over every Γ, then any plan at once.

One Γ for every source, from 0 to the number of periods in whole hours
(:func:`dashboard.solving.sweep_grid`). The first time, the slider
offers to sweep the case (:func:`dashboard.solving.sweep`: one model re-solved for each
Γ in a solver process, with progress and Cancel); once the sweep is warm (for this
session or any other, until the case changes), moving the slider only picks the plan
already solved for that Γ and draws its key numbers and its figures, which are built
once per plan (:mod:`dashboard.figures`). Nothing is solved on a move.
"""

from __future__ import annotations

import streamlit as st

from rvpp import Case

from . import solving, state, widgets
from .figures import sweep_curve, titled_figure

KPIS = (widgets.NET, "DAM revenue [kEUR]", "Reserve revenue [kEUR]", "HPA cost [kEUR]", "Protection [kEUR]")
TITLES = {"trades": "Bids at Γ = {gamma}: day-ahead energy and reserve bands",
          "economics": "The day's economics at Γ = {gamma}"}


@st.fragment
def gamma_slider(run: Case, nt: int, default: int, page: str, charts: tuple[str, ...], curve: bool = False) -> None:
    """A slider of one Γ for every source of ``run`` (a day of ``nt`` periods) that draws the
    plan of the chosen Γ: its key numbers and its figures ``charts`` (names of
    :func:`dashboard.figures.plan_figures`), beside the cost curve when ``curve``.

    A fragment: moving the slider reruns only this part of the page.
    """
    grid = solving.sweep_grid(nt, run.dt_h)
    key = solving.sweep_key(run, grid)
    slider_key = f"{page}_sweep_gamma_{nt}"
    if slider_key not in st.session_state:
        st.session_state[slider_key] = min(grid, key=lambda g: abs(g - default))
    label = "Γ of every source [periods]"
    points = solving.swept(run, grid)
    if points is None:
        if not state.is_requested_key(key):
            # Words, not a disabled slider: Streamlit draws a disabled control's label too faint to read. The
            # button goes below them, in a row of its own: beside them its expected time was cut off.
            st.markdown(f"**{label}**: a slider from 0 to {nt} appears here once the plans are computed; "
                        "then every Γ shows at once.")
            st.button(f"Compute the plans for every Γ ({len(grid)} solves{_expected(run, grid)})",
                      key=f"{page}_sweep", icon=":material/play_arrow:", on_click=state.mark_requested_key,
                      args=(key,), help="One model of the day re-solved for each Γ in the background; the plans "
                                        "are kept for this case on this server.")
            _ties_note(run, grid)
            return
        points = solving.sweep(run, grid, f"Solving the plans for Γ = 0 to {nt}")
        if points is None:  # refused (the reason is shown) or cancelled
            return
    gamma = st.select_slider(label, grid, key=slider_key,
                             help="The plan for this Γ was solved with the others: moving the slider solves nothing.")
    result = points[grid.index(gamma)]
    if not result.has_plan:
        st.warning(f"No feasible plan for Γ = {gamma}: the demands cannot be met when that many periods go wrong.",
                   icon=":material/warning:")
        return
    widgets.kpi_cards(result, only=KPIS)
    figures = [titled_figure(result, name, TITLES[name].format(gamma=gamma)) for name in charts]
    if curve:
        figures.insert(0, sweep_curve(key, gamma, grid, points))
    row = st.container(horizontal=True)  # side by side, or one below the other in a narrow window
    for i, figure in enumerate(figures):
        row.plotly_chart(figure, key=f"{page}_sweep_chart_{i}")


def _ties_note(run: Case, grid: list[int]) -> None:
    """Name the Γ of the sweep at which the solver must choose among tied deviations, if any."""
    tied = solving.tied_gammas(run, grid)
    if not tied:
        return
    sources = sorted({phrase.split(":")[0] for phrases in tied.values() for phrase in phrases})
    at = ", ".join(f"{g:g}" for g in tied)
    st.caption(f"At Γ = {at} this day has deviations tied at the Γ boundary ({', '.join(sources)}): the model "
               "chooses which of them count, the exact rule, which makes each of these plans several times slower "
               f"to solve (the sweep can take minutes at 15-minute periods). {solving.EARLIEST_HINT}")


def _expected(run: Case, grid: list[int]) -> str:
    """`` · about N s`` for the button, measured by this server (:meth:`dashboard.solving.Solver.expected_s`),
    or nothing."""
    expected = solving.solver().expected_s(run, grid)
    return f" · about {expected[0]:.0f} s" if expected and expected[0] >= 1 else ""
