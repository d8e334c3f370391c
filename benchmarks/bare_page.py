"""A bare Streamlit page for ``benchmarks/dashboard.py``: a title and one small SVG chart, put in
place as Home puts its first chart (``dashboard.svg.draw``'s markdown image), and nothing else.
How soon its chart shows is what Streamlit itself costs on this machine, under any page of ours.

Run by the benchmark as ``python -m streamlit run benchmarks/bare_page.py``.
"""

import base64

import streamlit as st

CHART = ('<svg class="rvpp-chart" role="img" width="480" height="240" viewBox="0 0 480 240" '
         'xmlns="http://www.w3.org/2000/svg"><title>A bare chart</title>'
         '<rect x="40" y="20" width="400" height="180" fill="#8fb3e0"/></svg>')

st.set_page_config(page_title="bare page", layout="wide")
st.title("A bare Streamlit page")
st.markdown(f"![A bare chart](data:image/svg+xml;base64,{base64.b64encode(CHART.encode()).decode()})")
