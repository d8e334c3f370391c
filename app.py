"""rvpp dashboard: ``streamlit run app.py`` (or ``make run``).

Sets the shared session state once, then hands over to the page the user chose; the
sidebar's summary of the current case is drawn again after the page ran, so it shows the
case with the page's edits. New pages are one ``st.Page`` line in :func:`main`.

Every process the dashboard starts imports this file first (``multiprocessing`` runs
the parent's main script in each new process), so it imports nothing at the top and the
``__main__`` guard keeps the app from running there: importing Streamlit in each solver
process cost 0.7-0.9 s before its solve could start.
"""


def main() -> None:
    import streamlit as st  # here, not above: every solver process imports this file

    from dashboard import serve

    serve.wait()  # `python -m dashboard` imports the first page's modules while the server starts
    from dashboard import browser, solving, state, style, svg, widgets

    st.set_page_config(page_title="rvpp · robust VPP bidding", page_icon=":material/solar_power:",
                       layout="wide")
    state.init()
    solving.solver()
    pages = {
        "Plan": [
            st.Page("pages/home.py", title="Home", icon=":material/home:", default=True),
            st.Page("pages/portfolio.py", title="Portfolio", icon=":material/factory:"),
            st.Page("pages/markets.py", title="Markets & tariffs", icon=":material/euro:"),
            st.Page("pages/uncertainty.py", title="Uncertainty", icon=":material/ssid_chart:"),
            st.Page("pages/results.py", title="Results", icon=":material/insights:"),
        ],
        "Analyse": [
            st.Page("pages/compare.py", title="Compare strategies", icon=":material/compare_arrows:"),
            st.Page("pages/runs.py", title="Saved runs", icon=":material/bookmarks:"),
        ],
        "Studies": [
            st.Page("pages/sensitivity.py", title="Sensitivity to Γ", icon=":material/tune:"),
            st.Page("pages/market_sets.py", title="Market sets & HPA prices", icon=":material/storefront:"),
            st.Page("pages/out_of_sample.py", title="Out-of-sample vs stochastic", icon=":material/fact_check:"),
            st.Page("pages/backtest.py", title="Backtest", icon=":material/history:"),
        ],
        "Learn": [
            st.Page("pages/learn.py", title="Robust bidding explained", icon=":material/school:"),
        ],
    }
    page = st.navigation(pages)
    state.resume_deep_link()
    widgets.open_linked_run(page)
    widgets.lost_case_note()
    state.mark_own_case()
    summary = st.sidebar.empty()
    with summary.container():  # stays if the page stops early (st.stop() ends the run)
        widgets.sidebar(state.case())
    svg.inline_charts()
    browser.preload()
    style.contrast()
    page.run()
    with summary.container():  # drawn again after the page: the case as the page's edits left it
        widgets.sidebar(state.case())
    state.mark_own_case()
    solving.start_fork_server()  # once the page is sent (a solve started earlier starts it itself)


if __name__ == "__main__":
    main()
