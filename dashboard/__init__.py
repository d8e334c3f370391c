"""Streamlit support for the rvpp dashboard: shared session state, cached solves in
worker processes and the widgets the pages share. Pages import from here and from
``rvpp``; the ``rvpp`` library never imports Streamlit."""
