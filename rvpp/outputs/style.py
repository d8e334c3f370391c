"""One visual language for every figure and page: colours, line dashes and markers.

The dashboard's pages, :mod:`rvpp.outputs.plots` and :mod:`rvpp.studies.figures` take
their colours from here, so a strategy, a market or a unit kind looks the same wherever
it is drawn. The palette is Okabe & Ito's (2008) colour-blind safe set, its blue
lightened to read on dark backgrounds too. Colour is never the only carrier of meaning:
each strategy also has its own dash pattern and marker symbol, and every trace has a
legend entry.
"""

from __future__ import annotations

from ..data.kinds import KINDS

BLUE, SKY, GREEN, YELLOW = "#2E86DE", "#56B4E9", "#009E73", "#F0E442"
ORANGE, VERMILION, PURPLE, GREY = "#E69F00", "#D55E00", "#CC79A7", "#8C8C8C"
SERIES_COLORS = (BLUE, VERMILION, GREEN, ORANGE, PURPLE, SKY, GREY, YELLOW)
DASHES = ("solid", "dash", "dot", "dashdot", "longdash", "longdashdot")
MARKERS = ("circle", "triangle-up", "square", "diamond", "x", "star", "pentagon", "hexagon")

GRID_COLOR = "rgba(128, 128, 128, 0.28)"
CHI_SHADE = "rgba(213, 94, 0, 0.14)"
TRANSPARENT = "rgba(0, 0, 0, 0)"
FIGURE_HEIGHT = 420
# Space [px] around a figure's plot area, as wide as what the dashboard's charts draw there:
# title and legend above, the tilted clock-hour labels and the axis title below, tick labels
# of up to five characters and the axis title on the left. Plotly widens a margin that is too
# narrow (automargin) by drawing the whole figure again, which doubles the browser's work.
FIGURE_MARGIN = {"t": 100, "b": 84, "l": 80, "r": 30}

# Every unit kind has a colour: those named here, grey for any other (biomass, a kind added later).
_NAMED_COLORS = {"wind": SKY, "pv": ORANGE, "csp": VERMILION, "ed": PURPLE, "td": GREEN, "battery": YELLOW,
                 "hydro": BLUE}
KIND_COLORS = {**{kind: _NAMED_COLORS.get(kind, GREY) for kind in KINDS}, "hpa": GREY}
KIND_LABELS = {kind: info.label for kind, info in KINDS.items()}
KIND_GROUP_LABELS = {kind: info.group for kind, info in KINDS.items()}

# Markets: day-ahead energy, up and down secondary reserve, heat purchase agreement.
MARKET_COLORS = {"dam": BLUE, "sr_up": GREEN, "sr_dn": ORANGE, "hpa": GREY}

STRATEGY_COLORS = {"deterministic": GREY, "optimistic": GREEN, "balanced": BLUE, "pessimistic": VERMILION}
STRATEGY_DASHES = {"deterministic": "dot", "optimistic": "dash", "balanced": "solid", "pessimistic": "dashdot"}
STRATEGY_MARKERS = {"deterministic": "circle", "optimistic": "triangle-up", "balanced": "square",
                    "pessimistic": "diamond"}

# The day's economics: what comes in, what goes out, and the net result.
GAIN_COLOR, LOSS_COLOR, NET_COLOR = GREEN, VERMILION, BLUE


def strategy_of(label: str) -> str | None:
    """The strategy a run label starts with (``"balanced · DAM+SRM+HPA"`` → ``"balanced"``)."""
    first = label.strip().split(" ", 1)[0].lower() if label.strip() else ""
    return first if first in STRATEGY_COLORS else None


def run_style(label: str, index: int) -> dict[str, str]:
    """Colour, dash and marker of the ``index``-th of several runs drawn together.

    A run named after a strategy takes that strategy's colour; every run gets a dash
    pattern and a marker of its own position, so two runs of one strategy still differ
    without relying on colour.
    """
    strategy = strategy_of(label)
    if label in STRATEGY_COLORS:
        return {"color": STRATEGY_COLORS[label], "dash": STRATEGY_DASHES[label], "symbol": STRATEGY_MARKERS[label]}
    color = STRATEGY_COLORS[strategy] if strategy else SERIES_COLORS[index % len(SERIES_COLORS)]
    return {"color": color, "dash": DASHES[index % len(DASHES)], "symbol": MARKERS[index % len(MARKERS)]}


def rgba(color: str, alpha: float) -> str:
    """``#RRGGBB`` with an opacity, as Plotly's ``rgba(...)``."""
    r, g, b = (int(color[k:k + 2], 16) for k in (1, 3, 5))
    return f"rgba({r}, {g}, {b}, {alpha})"
