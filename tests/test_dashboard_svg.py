"""Home's first chart, drawn on the server as SVG (``dashboard.svg``).

What the chart draws is read back through its own y axis, as a viewer reads it: each grid
line's position and the value written beside it give the scale, and the lines' points are
turned back into prices and compared with the prepared day's band.
"""

from __future__ import annotations

import base64
import re
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import rvpp
from dashboard import svg
from tests.factories import open_app

SVG = "{http://www.w3.org/2000/svg}"
PIXEL_EUR = 0.1  # [EUR/MWh] points are written to 0.1 of the drawing's units: about 0.04 EUR/MWh


def read(text: str) -> ET.Element:
    return ET.fromstring(text)


def value(label: str) -> float:
    return float(label.replace("\u2212", "-").replace(",", ""))


def scale(chart: ET.Element):
    """The y axis as drawn: value = a + b·y, from the grid lines and the values beside them."""
    group = chart.find(f"{SVG}g[@class='y-ticks']")
    lines, labels = group.findall(f"{SVG}line"), group.findall(f"{SVG}text")
    assert len(lines) == len(labels) >= 3
    ys = [float(line.get("y1")) for line in lines]
    values = [value(label.text) for label in labels]
    slope, intercept = np.polyfit(ys, values, 1)
    np.testing.assert_allclose(intercept + slope * np.array(ys), values, atol=PIXEL_EUR)  # evenly spaced, straight
    assert slope < 0  # up is more
    return lambda y: intercept + slope * y


def points(chart: ET.Element, name: str) -> tuple[np.ndarray, np.ndarray]:
    line = chart.find(f"{SVG}polyline[@class='{name}']")
    xy = np.array([[float(v) for v in pair.split(",")] for pair in line.get("points").split()])
    return xy[:, 0], xy[:, 1]


def drawn(chart: ET.Element, name: str) -> np.ndarray:
    return scale(chart)(points(chart, name)[1])


def texts(chart: ET.Element) -> list[str]:
    return ["".join(t.itertext()) for t in chart.iter(f"{SVG}text")]


@pytest.fixture(scope="module")
def problem(paper_case):
    return rvpp.prepare(paper_case)


@pytest.fixture(scope="module")
def band(problem):
    return {stat: problem.bands[("price_da", stat)].to_numpy(float) for stat in ("lo", "mid", "hi")}


def test_the_price_band_is_drawn_at_the_prepared_days_prices(problem, band):
    chart = read(svg.price_band_svg(problem, "band"))
    for name, stat in (("lower", "lo"), ("median", "mid"), ("upper", "hi")):
        np.testing.assert_allclose(drawn(chart, name), band[stat], atol=PIXEL_EUR, err_msg=name)
    # One point per period, evenly spaced left to right; each clock label under its period's point.
    x, _ = points(chart, "median")
    assert len(x) == problem.nt == 24
    np.testing.assert_allclose(np.diff(x), np.diff(x)[0], atol=0.11)
    labels = list(problem.labels)
    clock = chart.find(f"{SVG}g[@class='x-ticks']").findall(f"{SVG}text")
    assert [t.text for t in clock] == ["00:00", "03:00", "06:00", "09:00", "12:00", "15:00", "18:00", "21:00"]
    for label in clock:
        assert float(label.get("x")) == pytest.approx(x[labels.index(label.text)], abs=0.11)


def test_the_chart_is_one_named_and_described_image_with_units_on_its_axes(problem, band):
    chart = read(svg.price_band_svg(problem, "band"))
    assert chart.get("role") == "img"
    title = chart.find(f"{SVG}title[@id='{chart.get('aria-labelledby')}']")
    desc = chart.find(f"{SVG}desc[@id='{chart.get('aria-describedby')}']")
    assert title.text == "Day-ahead price: forecast band"
    mid, labels = band["mid"], list(problem.labels)
    low, high = int(np.argmin(mid)), int(np.argmax(mid))
    assert f"from {mid[low]:,.2f} EUR/MWh at {labels[low]} to {mid[high]:,.2f} EUR/MWh at {labels[high]}" in desc.text
    assert f"from {band['lo'].min():,.2f} to {band['hi'].max():,.2f} EUR/MWh" in desc.text
    assert {"Day-ahead price: forecast band", "Price [EUR/MWh]", "Delivery day, period start (local time)",
            "20th to 80th percentile", "Median"} <= set(texts(chart))
    # Each period's values in a tooltip, as hovering a Plotly chart gives them.
    tips = [t.text for t in chart.find(f"{SVG}g[@class='tips']").iter(f"{SVG}title")]
    assert len(tips) == 24
    for t, tip in enumerate(tips):
        assert tip == (f"{labels[t]}: median {mid[t]:,.2f} EUR/MWh; 20th percentile {band['lo'][t]:,.2f}, "
                       f"80th percentile {band['hi'][t]:,.2f} EUR/MWh")


def test_a_band_below_zero_has_its_axis_below_zero_with_a_minus_sign():
    labels = [f"{h:02d}:00" for h in range(24)]
    lo = np.linspace(-37.5, 12.0, 24)
    mid, hi = lo + 8.25, lo + 20.0
    chart = read(svg.band_svg(labels, lo, mid, hi, chart_id="negative", title="t", description="d", y_title="y",
                              names=("band", "middle"), tips=labels, color="#2E86DE"))
    shown = [t.text for t in chart.find(f"{SVG}g[@class='y-ticks']").findall(f"{SVG}text")]
    assert shown[0].startswith("\u2212") and value(shown[0]) <= -37.5 and value(shown[-1]) >= 32.0
    assert "0" in shown and not any(label.startswith("-") for label in shown)
    for name, series in (("lower", lo), ("median", mid), ("upper", hi)):
        np.testing.assert_allclose(drawn(chart, name), series, atol=PIXEL_EUR, err_msg=name)


def test_a_flat_band_still_has_an_axis_around_it():
    labels = [f"{h:02d}:00" for h in range(24)]
    flat = np.full(24, 50.0)
    chart = read(svg.band_svg(labels, flat, flat, flat, chart_id="flat", title="t", description="d", y_title="y",
                              names=("band", "middle"), tips=labels, color="#2E86DE"))
    np.testing.assert_allclose(drawn(chart, "median"), flat, atol=PIXEL_EUR)


def test_text_is_drawn_as_text_and_bad_series_are_refused():
    labels = ["00:00", "01:00"]
    one = np.array([1.0, 2.0])
    chart = svg.band_svg(labels, one, one, one, chart_id="x", title='<script>alert("x")</script> & co',
                         description="a < b", y_title="y", names=("band", "middle"), tips=["<b>", "&"],
                         color="#2E86DE")
    root = read(chart)
    assert root.find(f"{SVG}title").text == '<script>alert("x")</script> & co'
    assert not [e for e in root.iter() if e.tag.endswith("script") or e.tag.endswith("}b")]
    with pytest.raises(ValueError, match="one value of each series per label"):
        svg.band_svg(labels, one, one, one[:1], chart_id="x", title="t", description="d", y_title="y",
                     names=("a", "b"), tips=labels, color="#000")
    with pytest.raises(ValueError, match="finite"):
        svg.band_svg(labels, one, np.array([1.0, np.nan]), one, chart_id="x", title="t", description="d",
                     y_title="y", names=("a", "b"), tips=labels, color="#000")


IMAGE = re.compile(r"!\[(?P<alt>(?:[^\]\\]|\\.)*)\]\(data:image/svg\+xml;base64,(?P<data>[A-Za-z0-9+/=]+)\)")


def test_homes_first_chart_is_the_svg_price_band_and_no_plotly_chart(problem, band):
    """Before a solve, Home draws its chart as SVG: no chart library to load. It arrives as a
    markdown image of the SVG, named by the chart's title, in the light theme's text colour and
    marked with this server's token, which the page's script needs to put the SVG in place."""
    at = open_app()
    assert not at.get("plotly_chart")
    images = [found for md in at.markdown if (found := IMAGE.fullmatch(md.value))]
    assert len(images) == 1
    assert images[0]["alt"] == "Day\\-ahead price\\: forecast band"  # escaped for markdown, shown as the title
    chart = read(base64.b64decode(images[0]["data"]).decode())
    assert chart.get("class") == "rvpp-chart" and chart.get("data-rvpp") == svg.NONCE
    assert "color:#31333F;" in chart.get("style")  # an image cannot take the page's colour
    np.testing.assert_allclose(drawn(chart, "median"), band["mid"], atol=PIXEL_EUR)
    scripts = [h.proto for h in at.get("html") if "__rvppCharts" in h.proto.body]
    assert len(scripts) == 1 and scripts[0].unsafe_allow_javascript
    body = scripts[0].body.removeprefix("<script>").removesuffix("</script>")
    assert "<" not in body  # Streamlit's sanitizer drops a script whose text holds one
    assert f'data-rvpp="{svg.NONCE}"' in body


def test_the_image_takes_the_dark_themes_text_colour_and_escapes_its_title():
    markup = ('<svg class="rvpp-chart" role="img" style="max-width:600px" '
              'xmlns="http://www.w3.org/2000/svg"><title>[x](y) &amp; *z*</title></svg>')
    found = IMAGE.fullmatch(svg.image_markdown(markup, "dark"))
    assert found["alt"] == "\\[x\\]\\(y\\) \\& \\*z\\*"  # drawn as typed, not as a link or emphasis
    chart = read(base64.b64decode(found["data"]).decode())
    assert chart.get("style") == "color:#FAFAFA;font-family:sans-serif;max-width:600px"
    assert chart.get("data-rvpp") == svg.NONCE
