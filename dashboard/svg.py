"""Charts drawn on the server as SVG, for the first screen, which must not wait for a chart library.

Streamlit draws a Plotly chart with Plotly's whole bundle (4.7 MB), which the browser fetches
when the first chart arrives and then compiles and runs for 2.5-3.5 s on a two-core machine
before the chart appears. An SVG built here arrives drawn (:func:`draw`). It has what every
chart of the project has: a title, axis titles with units and the clock of each period's
start on x. It is one image to assistive technology (``role="img"``), named by its title and
described in words (``<desc>``); each period carries its values in a tooltip (``<title>``),
as Plotly's hover does. The data take their colour from rvpp's palette; text and axes take the
page's text colour, so the chart follows the light and the dark theme.

The chart reaches the page in two steps. First as a markdown image of the SVG, drawn with
the page's first text: markdown's code is part of every page, where any other element that
could carry an SVG is fetched on first use and then shown no sooner than 0.3 s after the
page's last element that waited for its code (React's pace for revealing such elements).
The page then puts the same SVG in place of the image (:func:`inline_charts`), which brings
the tooltips and the theme's own text colour; only images whose SVG carries this server's
:data:`NONCE` are replaced, so no image from user text could ever become markup.
"""

from __future__ import annotations

import base64
import math
import re
import secrets
from collections.abc import Sequence
from html import escape, unescape

import numpy as np
import streamlit as st

from rvpp import Problem
from rvpp.service import SERIES_COLORS, SOURCE_TITLES

from .widgets import literal

WIDTH, HEIGHT = 480, 280  # the drawing's own units; it is scaled to its column's width
LEFT, RIGHT, TOP, BOTTOM = 62, 14, 56, 46  # plot margins in those units
FONT = 13
TITLE_FONT = 16
Y_TICKS = 5  # about this many labelled values on the y axis
CLOCK_HOURS = 3  # a clock label every this many hours
CLOCK_TITLE = "Delivery day, period start (local time)"
PRICE_UNIT = "EUR/MWh"
MINUS = "\u2212"
CHART_CLASS = "rvpp-chart"  # what the benchmark and the browser tests look for
NONCE = secrets.token_hex(16)  # marks this server's charts for :func:`inline_charts`
TEXT_COLORS = {"light": "#31333F", "dark": "#FAFAFA"}  # Streamlit's text colour per theme, for the image
IMAGE_PREFIX = "data:image/svg+xml;base64,"
ROOT = f'<svg class="{CHART_CLASS}" '

_INLINE = """<script>
(() => {
  if (window.__rvppCharts) return;
  window.__rvppCharts = true;
  const images = 'img[src^="IMAGE_PREFIX"]';
  const root = 'ROOT' + 'data-rvpp="NONCE"';
  const shown = new Map();  // inline SVG -> the image it stands for
  const decode = (src) => new TextDecoder().decode(
    Uint8Array.from(atob(src.slice(src.indexOf(',') + 1)), (c) => c.charCodeAt(0)));
  const inline = () => {
    shown.forEach((img, svg) => {
      if (!img.isConnected || svg.dataset.src !== img.src) { svg.remove(); shown.delete(svg); img.hidden = false; }
    });
    document.querySelectorAll('[data-testid="stMarkdownContainer"] ' + images).forEach((img) => {
      if (img.hidden) return;
      let markup;
      try { markup = decode(img.src); } catch (e) { return; }
      if (!markup.startsWith(root)) return;
      img.insertAdjacentHTML('afterend', markup);
      const svg = img.nextElementSibling;
      svg.dataset.src = img.src;
      svg.style.removeProperty('color');
      svg.style.removeProperty('font-family');
      shown.set(svg, img);
      img.hidden = true;
    });
  };
  new MutationObserver(inline).observe(document.body, {subtree: true, childList: true,
                                                       attributes: true, attributeFilter: ['src']});
  inline();
})();
</script>"""


def draw(svg: str) -> None:
    """Show an SVG of this module in the page: at once as an image, then in place (see above)."""
    st.markdown(image_markdown(svg, getattr(st.context.theme, "type", None)))


def image_markdown(svg: str, theme: str | None) -> str:
    """``svg`` as a markdown image marked with :data:`NONCE`, in the text colour of ``theme``
    (``"light"``, ``"dark"``; ``None``: not known, light) and a sans-serif font (an image cannot
    use the page's fonts); its alternative text is the chart's title."""
    head, rest = svg.split(">", 1)
    head = head.replace(ROOT, f'{ROOT}data-rvpp="{NONCE}" ', 1).replace(
        'style="', f'style="color:{TEXT_COLORS.get(theme, TEXT_COLORS["light"])};font-family:sans-serif;', 1)
    found = re.search(r"<title[^>]*>([^<]*)</title>", rest)
    alt = literal(unescape(found.group(1)) if found else "chart", limit=None)
    return f"![{alt}]({IMAGE_PREFIX}{base64.b64encode((head + '>' + rest).encode()).decode()})"


def inline_charts() -> None:
    """Put the script that shows :func:`draw`'s images in place as SVG at the end of the sidebar
    (no height; it runs once per tab and keeps watching the page)."""
    script = (_INLINE.replace("IMAGE_PREFIX", IMAGE_PREFIX).replace("ROOT", ROOT.replace("<", "\\u003c"))
              .replace("NONCE", NONCE))  # no "<" in a script's text: Streamlit's sanitizer drops such a script
    st.sidebar.html(script, unsafe_allow_javascript=True)


def price_band_svg(problem: Problem, chart_id: str) -> str:
    """The day-ahead price band of the prepared day as an SVG: lower and upper bound as a
    shaded band, the median dashed (the band the model uses, MODEL_SPEC §6). ``chart_id``
    names the chart's title and description (unique on the page)."""
    bands = problem.bands
    lo, mid, hi = (bands[("price_da", stat)].to_numpy(float) for stat in ("lo", "mid", "hi"))
    q = problem.case.uncertainty
    low, high = f"{q.q_lo * 100:g}th", f"{q.q_hi * 100:g}th"
    if q.band_method("price_da") == "climatology":
        title = f"{SOURCE_TITLES['price_da']}: forecast band"
        band_name, mid_name = f"{low} to {high} percentile", "Median"
    else:
        title = f"{SOURCE_TITLES['price_da']}: forecast-error band"
        band_name, mid_name = f"Forecast + {low} to {high} percentile error", "Forecast + median error"
    day = f"{problem.day:%a %d %b %Y}"
    lowest, highest = int(np.argmin(mid)), int(np.argmax(mid))
    labels = list(problem.labels)
    description = (f"Day-ahead price on {day}, {len(labels)} periods of {problem.dt_h * 60:g} minutes. "
                   f"{mid_name}: from {number(mid[lowest])} {PRICE_UNIT} at {labels[lowest]} to "
                   f"{number(mid[highest])} {PRICE_UNIT} at {labels[highest]}. {band_name}: from "
                   f"{number(lo.min())} to {number(hi.max())} {PRICE_UNIT} over the day.")
    tips = [f"{label}: {mid_name.lower()} {number(m)} {PRICE_UNIT}; {low} percentile {number(a)}, "
            f"{high} percentile {number(b)} {PRICE_UNIT}" for label, a, m, b in zip(labels, lo, mid, hi)]
    return band_svg(labels, lo, mid, hi, chart_id=chart_id, title=title, description=description,
                    y_title=f"Price [{PRICE_UNIT}]", names=(band_name, mid_name), tips=tips, color=SERIES_COLORS[0])


def band_svg(labels: Sequence[str], lo: np.ndarray, mid: np.ndarray, hi: np.ndarray, *, chart_id: str, title: str,
             description: str, y_title: str, names: tuple[str, str], tips: Sequence[str], color: str) -> str:
    """A band from ``lo`` to ``hi`` with ``mid`` dashed, one point per clock label, as SVG text."""
    n = len(labels)
    if not n or not all(len(series) == n for series in (lo, mid, hi, tips)):
        raise ValueError(f"a band needs one value of each series per label ({n} labels)")
    if not np.all(np.isfinite(np.concatenate([lo, mid, hi]))):
        raise ValueError("a band's values must be finite numbers")
    ticks = nice_ticks(float(min(lo.min(), mid.min())), float(max(hi.max(), mid.max())))
    bottom, top = float(ticks[0]), float(ticks[-1])
    plot_w, plot_h = WIDTH - LEFT - RIGHT, HEIGHT - TOP - BOTTOM
    step = plot_w / n

    def x(i: int) -> float:
        return LEFT + (i + 0.5) * step

    def y(value: float) -> float:
        return TOP + (top - value) / (top - bottom) * plot_h

    def points(series) -> str:
        return " ".join(f"{x(i):.1f},{y(v):.1f}" for i, v in enumerate(series))

    title_id, desc_id = f"{chart_id}-title", f"{chart_id}-desc"
    parts = [f'<svg class="{CHART_CLASS}" role="img" aria-labelledby="{title_id}" aria-describedby="{desc_id}" '
             f'viewBox="0 0 {WIDTH} {HEIGHT}" width="100%" style="max-width:{WIDTH * 1.25:g}px;height:auto" '
             f'font-size="{FONT}" fill="currentColor" xmlns="http://www.w3.org/2000/svg">',
             f'<title id="{title_id}">{escape(title)}</title>', f'<desc id="{desc_id}">{escape(description)}</desc>',
             f'<text x="{LEFT}" y="{TITLE_FONT + 4}" font-size="{TITLE_FONT}" font-weight="600">{escape(title)}</text>']
    # Legend under the title: the band as a swatch, the median as a dashed stroke.
    legend_y = TITLE_FONT + 26
    parts += [f'<rect x="{LEFT}" y="{legend_y - 9}" width="22" height="10" fill="{color}" fill-opacity="0.22" '
              f'stroke="{color}" stroke-width="1"/>',
              f'<text x="{LEFT + 28}" y="{legend_y}">{escape(names[0])}</text>']
    second = LEFT + 44 + 7 * len(names[0])
    parts += [f'<line x1="{second:.0f}" y1="{legend_y - 4}" x2="{second + 22:.0f}" y2="{legend_y - 4}" '
              f'stroke="{color}" stroke-width="3" stroke-dasharray="6 3"/>',
              f'<text x="{second + 28:.0f}" y="{legend_y}">{escape(names[1])}</text>']
    # y axis: grid lines and their values; zero stronger where the band crosses it.
    parts.append('<g class="y-ticks" text-anchor="end">')
    for value in ticks:
        strong = value == 0 and bottom < 0 < top
        parts.append(f'<line x1="{LEFT}" x2="{WIDTH - RIGHT}" y1="{y(value):.1f}" y2="{y(value):.1f}" '
                     f'stroke="currentColor" stroke-opacity="{0.5 if strong else 0.15}"/>'
                     f'<text x="{LEFT - 6}" y="{y(value) + 4:.1f}">'
                     f'{tick_label(value, ticks)}</text>')
    parts.append("</g>")
    parts.append(f'<text transform="translate(16 {TOP + plot_h / 2:.1f}) rotate(-90)" text-anchor="middle">'
                 f'{escape(y_title)}</text>')
    # x axis: a clock label every CLOCK_HOURS hours, at the period that starts on that hour.
    parts.append(f'<g class="x-ticks" text-anchor="middle"><line x1="{LEFT}" x2="{WIDTH - RIGHT}" '
                 f'y1="{TOP + plot_h}" y2="{TOP + plot_h}" stroke="currentColor" stroke-opacity="0.5"/>')
    for i, label in enumerate(labels):
        if label.endswith(":00") and int(label[:2]) % CLOCK_HOURS == 0:
            parts.append(f'<line x1="{x(i):.1f}" x2="{x(i):.1f}" y1="{TOP + plot_h}" y2="{TOP + plot_h + 4}" '
                         f'stroke="currentColor" stroke-opacity="0.5"/>'
                         f'<text x="{x(i):.1f}" y="{TOP + plot_h + 17}">{escape(label)}</text>')
    parts.append("</g>")
    parts.append(f'<text x="{LEFT + plot_w / 2:.1f}" y="{HEIGHT - 6}" text-anchor="middle">'
                 f'{escape(CLOCK_TITLE)}</text>')
    # The data: the band, its two edges, the median.
    outline = " ".join(f"{x(i):.1f},{y(v):.1f}" for i, v in [*enumerate(hi), *reversed(list(enumerate(lo)))])
    parts += [f'<polygon class="band" points="{outline}" fill="{color}" fill-opacity="0.22" stroke="none"/>',
              f'<polyline class="upper" points="{points(hi)}" fill="none" stroke="{color}" stroke-width="1"/>',
              f'<polyline class="lower" points="{points(lo)}" fill="none" stroke="{color}" stroke-width="1"/>',
              f'<polyline class="median" points="{points(mid)}" fill="none" stroke="{color}" stroke-width="3" '
              f'stroke-dasharray="6 3"/>']
    # Tooltips: a transparent column per period, holding that period's values.
    parts.append('<g class="tips" fill="currentColor" fill-opacity="0">')
    parts += [f'<rect x="{LEFT + i * step:.1f}" y="{TOP}" width="{step:.1f}" height="{plot_h}">'
              f'<title>{escape(tip)}</title></rect>' for i, tip in enumerate(tips)]
    parts.append("</g></svg>")
    return "".join(parts)


def nice_ticks(low: float, high: float, count: int = Y_TICKS) -> np.ndarray:
    """Round values from at or below ``low`` to at or above ``high``, about ``count`` steps
    of 1, 2, 2.5 or 5 times a power of ten."""
    if high - low <= 0:
        half = max(abs(high), 1.0) / 2
        low, high = low - half, high + half
    raw = (high - low) / count
    power = 10.0 ** math.floor(math.log10(raw))
    step = next(m * power for m in (1, 2, 2.5, 5, 10) if m * power >= raw)
    first, last = math.floor(low / step), math.ceil(high / step)
    return np.array([k * step for k in range(first, last + 1)])


def tick_label(value: float, ticks: np.ndarray) -> str:
    """``value`` with as many decimals as the ticks' step needs and a true minus sign."""
    step = float(ticks[1] - ticks[0]) if len(ticks) > 1 else 1.0
    decimals = 0
    while decimals < 6 and abs(round(step, decimals) - step) > 1e-9 * max(1.0, abs(step)):
        decimals += 1
    text = f"{abs(value):,.{decimals}f}"
    return MINUS + text if value < 0 and float(text.replace(",", "")) != 0 else text


def number(value: float) -> str:
    """A price as the tooltips and the description give it: two decimals, a true minus sign."""
    text = f"{abs(value):,.2f}"
    return MINUS + text if value < 0 and text != "0.00" else text
