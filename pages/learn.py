"""Learn: robust bidding explained with live charts of the current case."""

import numpy as np
import streamlit as st

from dashboard import solving, state, sweeps, widgets
from rvpp.service import (SOURCE_TITLES, SourceKind, bands_figure, deviating_periods, exposure_figure, power_unit,
                          price_exposures, protection_exact, thin_clock_ticks, top_gamma_deviation)

state.through_app("pages/learn.py")

CONTROL_PX, SLIDER_PX = 220, 260  # a demo's choice and its Γ slider, side by side when the window allows

st.title("Robust bidding explained")
st.markdown(
    "Tomorrow's prices, wind, sun and demand are not known when the bids are sent. Planning on the forecast "
    "alone is cheap until the day goes wrong; planning for everything going wrong at once is ruinous. "
    "Robust optimisation (Bertsimas & Sim, 2004) sits in between: for each uncertain source you choose a "
    "**budget Γ**, the number of periods in which it may take its bad value, and the plan must stay feasible "
    "and is valued as if an adversary spent every budget in the worst way. This page uses the current case.")

run = state.run_case()
problem = solving.prepare(run)
if problem is None:
    st.stop()
nt = problem.nt
units = [u.name for _, u in run.units() if problem.sources[u.name].deviation.max() > 0]

st.header("1 · What a budget means")
st.markdown(
    f"Each source has a band from the history: production is planned on its upper bound and may fall to the "
    f"lower one; consumption the other way round. With budget Γ the source is assumed to take its bad bound "
    f"in Γ of the {nt} periods. In the paper's method these are the Γ periods where the band is **widest** "
    "(the largest deviation in MW). Move Γ and watch the periods move.")


@st.fragment
def budget_demo() -> None:
    controls = st.container(horizontal=True)  # a row that wraps in a narrow window; the chart below, full width
    source = controls.selectbox("Source", units, key="learn_source", width=CONTROL_PX)
    src = problem.sources[source]
    gamma = controls.slider(f"Γ [periods of {problem.dt_h * 60:g} min]", 0, nt, value=min(src.gamma, nt),
                            key="learn_gamma", width=SLIDER_PX)
    y = top_gamma_deviation(src.deviation, gamma)
    energy = power_unit(src.unit_kind).replace("MW", "MWh")
    controls.metric("Energy at risk in the bound", f"{float(y.sum() * problem.dt_h):,.1f} {energy}", width="content",
                    help="Σ deviation × period length over the Γ chosen periods: how much the plan must cover.")
    nominal, adverse = ("upper", "lower") if src.kind is SourceKind.PRODUCTION else ("lower", "upper")
    st.caption(f"Γ = 0 plans on the {nominal} bound everywhere; Γ = {nt} on the {adverse} bound everywhere.")
    st.plotly_chart(thin_clock_ticks(bands_figure(problem, source, (y > 0).astype(float)), widgets.NARROW_TICK_HOURS),
                    key="learn_band")


budget_demo()

st.header("2 · Price protection: the adversary picks the worst periods")
st.markdown(
    "Prices enter the profit, not the constraints. For a fixed plan, each period has a possible loss: the "
    "energy sold times how far the price may fall (or bought times how far it may rise), and each reserve "
    "band times how far its price may fall. With budget Γ the adversary takes the **Γ periods of largest "
    "loss**; their sum is the protection charged in the objective. The model finds it exactly, through the "
    "dual variables φ and ζ of Bertsimas and Sim's reformulation, while it chooses the plan.")
state.mark_requested(run)
plan = solving.solve(run, "Solving the current case for the examples")
if plan is None or not plan.has_plan:
    st.warning("The current case has no plan, so the price examples are not available.")
    st.stop()


@st.fragment
def protection_demo() -> None:
    controls = st.container(horizontal=True)
    price = controls.selectbox("Price", list(SOURCE_TITLES), format_func=SOURCE_TITLES.get, key="learn_price",
                               width=CONTROL_PX)
    gamma = controls.slider(f"Γ of this price [periods of {problem.dt_h * 60:g} min]", 0, nt,
                            value=problem.sources[price].gamma, key="learn_price_gamma", width=SLIDER_PX)
    exposure = price_exposures(plan.problem, plan.market)[price]
    protection = protection_exact(exposure, gamma)
    controls.metric("Protection [kEUR]", widgets.keur(protection), width="content",
                    help=f"Sum of the Γ largest losses. Exact: {widgets.eur(protection)}.")
    st.caption(f"This plan was made with Γ = {plan.problem.sources[price].gamma} for this price; the model charged "
               f"{widgets.keur(plan.protection_eur[price])} kEUR for it, of "
               f"{widgets.keur(sum(plan.protection_eur.values()))} kEUR for every price (the Protection card on "
               "Results). Here the plan stays fixed and only the adversary's budget moves; a new solve would also "
               "change the plan.")
    st.plotly_chart(thin_clock_ticks(exposure_figure(plan, price, gamma), widgets.NARROW_TICK_HOURS),
                    key="learn_exposure")


protection_demo()

st.header("3 · Constraint budgets: paper mode and planner-chosen periods")
st.markdown(
    "For units the model uses binaries χ (one per period) with Σχ = Γ. The published implementation adds two "
    "bounds that force χ onto the largest deviations (**paper mode**, the default). As printed in the paper "
    "they are missing, and then the optimiser itself picks the Γ periods — naturally those where a "
    "deviation hurts least (**planner-chosen**). Both solve the same day; compare where χ lands and what "
    "the plan is worth.")
# Planner-chosen hours have no ties to break: that variant takes the default rule.
variants = {"paper": run.replace(budgets={"mode": "paper"}),
            "planner_chosen": run.replace(budgets={"mode": "planner_chosen", "ties": "choose"})}
if all(state.is_requested(c) for c in variants.values()) or st.button(
        "Solve both variants", key="learn_modes", icon=":material/play_arrow:"):
    for case in variants.values():
        state.mark_requested(case)
    solved = solving.solve_all(list(variants.values()), "Solving both variants")
    if solved is None:  # refused (the reason is shown) or cancelled
        st.stop()
    paper, chosen = solved
    if paper.has_plan and chosen.has_plan:
        cards = st.container(horizontal=True)
        source = cards.selectbox("Source", units, key="learn_mode_source", width=CONTROL_PX)
        cards.metric("Net cost, paper mode [kEUR]", widgets.keur(-paper.objective_eur), border=True, width="content",
                     help=f"Positive: the plant pays. Exact: {widgets.eur(-paper.objective_eur)}.")
        difference = paper.objective_eur - chosen.objective_eur  # the planner-chosen plan's extra cost
        cards.metric("Net cost, planner-chosen [kEUR]", widgets.keur(-chosen.objective_eur), border=True,
                     width="content", delta=f"{widgets.keur(difference)} kEUR vs paper mode", delta_color="off",
                     delta_arrow="off",
                     help="Never above paper mode: the planner picks the periods that suit it, so it is protected "
                          f"against less, not better. Exact: {widgets.eur(-chosen.objective_eur)}.")
        charts = st.container(horizontal=True)  # side by side, or one below the other in a narrow window
        for label, result in (("paper mode", paper), ("planner-chosen", chosen)):
            figure = bands_figure(result.problem, source, deviating_periods(result, source))
            figure.update_layout(title_text=f"{source}, {label}")
            thin_clock_ticks(figure, widgets.NARROW_TICK_HOURS)
            charts.plotly_chart(figure, key=f"learn_mode_{label}")

st.header("4 · The price of robustness")
st.markdown(
    f"Give every source the same budget Γ and solve for every Γ from 0 to {nt}: the cost rises with Γ because "
    "the plan buys more, sells less and offers less reserve to stay feasible when more periods go wrong. The "
    "dashed line is the part of the cost that is price protection. Move Γ to see the plan behind each point.")
sweeps.gamma_slider(run, nt, round(float(np.mean([s.gamma for s in problem.sources.values()]))), page="learn",
                    charts=("trades",), curve=True)

st.header("5 · What paper mode does not protect against")
st.markdown(
    "- **Not the worst day for your profit.** Units deviate in their largest-deviation periods, which need not "
    "be the periods where a shortfall costs most; the adversary of the constraints is not searching your "
    "profit. A stress test that searches those hours gives a lower (worse) profit.\n"
    "- **Not beyond the band.** Bands are percentiles of recent history (by default the 20th and 80th of 30 "
    "days): one day in five is outside them by construction, and a regime change is not in the history.\n"
    "- **Not joint patterns.** Each source spends its own budget; the model does not know that a cloudy day "
    "lowers all PV plants and the CSP together and raises prices at the same time.\n"
    "- **Not the real-time settlement.** The plan is valued at the bands; what it earns on the day depends on "
    "the realised prices and on imbalance penalties, which an out-of-sample test measures.\n"
    "- **Γ is a dial, not a probability.** Bertsimas & Sim give probability bounds for independent, "
    "symmetric deviations; market data are neither, so read Γ as how many bad periods you plan for.")
