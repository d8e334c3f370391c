"""Style rules for four texts Streamlit draws below the 4.5:1 contrast of WCAG 2 AA, and for tables in a
caption (Home's case at a glance) in a narrow column.

In the dark theme, the selected option of a segmented control (3.6:1), the selected tab and the value
over a slider's thumb (3.9:1) are in the primary colour on a dark background: a lighter primary colour
in the theme would fix them and break the white text of every primary button, so only these texts are
drawn lighter. In both
themes, the label of a control that cannot be changed (the day-ahead market's switch) is the text colour
at 40 % (2.8:1 light, 3.8:1 dark): it is drawn at 62 % instead, still lighter than an enabled label. A
disabled button's label (Home's "Load the uploaded case" before a file is chosen) had the same 40 % and is
drawn at the same 62 %.

Streamlit's theme for Plotly charts draws their axis titles, tick labels, the texts beside bars and in
annotations and legend texts without a colour of their own in its grey #808495: 3.7:1 on the light background
(4.9:1 on the dark one). In the light theme that grey is drawn as the text colour at 62 % (6.2:1); a colour the
figure sets itself is left alone.

``light-dark()`` picks the colour of the scheme Streamlit draws in (the theme follows the viewer's
preference, ``.streamlit/config.toml``); the light theme's own colours come from its settings.

Every button, link, tab, expander header, switch and checkbox reached by the keyboard is outlined in the primary colour (6.5:1 light, #FF7B72
7.2:1 dark), 2 px clear of its edge: Streamlit marks it with a ring of the primary colour at 50 %, 2.5:1 on the
light background, below the 3:1 WCAG 2 asks of a focus indicator, and marks a switch or a checkbox not at all.
A page's link in the sidebar, reached by the
keyboard, is outlined in the primary colour too, inside its box: Streamlit marks it
only with the faint grey it gives a link under the mouse (15 % grey over the sidebar), fainter than the mark of
the page shown, so a keyboard user could not tell where the focus was.

In a window at most NARROW_PX wide, a row of columns holding a table in a caption (Home's case at a
glance) puts its columns one below the other: the table cannot break its unit names (ED_residential) nor its
capacities (1,100 MWh_th), and beside Home's question, at 1024 px, it ran 54 px past the window's edge, its
last column cut off.
"""

from __future__ import annotations

from functools import cache

import streamlit as st

LIGHT_RED = "#FF7B72"  # dark theme: 6.6:1 on a selected option's background (#291a1a), 7.2:1 on the page's
DISABLED_SHARE = 62    # [%] of the text colour in a disabled control's label: 6.2:1 light, 7.5:1 dark
PLOTLY_GREY = "rgb(128, 132, 149)"  # Streamlit's chart text (#808495), as the browser writes it in a text's style
NARROW_PX = 1199       # [px] in a window at most this wide, Home's case goes below its question

_RULES = """<style>
[data-testid="stButtonGroup"] button[data-selected="true"] p, [data-testid="stTab"][aria-selected="true"] p,
[data-testid="stSliderThumbValue"] p { color: light-dark(PRIMARY, LIGHT_RED); }
.stApp label[data-disabled="true"] { color: light-dark(color-mix(in srgb, LIGHT_TEXT SHARE%, transparent),
                                                color-mix(in srgb, DARK_TEXT SHARE%, transparent)); }
.stApp label[data-disabled="true"] p { color: inherit; }
.stApp button:disabled { color: light-dark(color-mix(in srgb, LIGHT_TEXT SHARE%, transparent),
                                        color-mix(in srgb, DARK_TEXT SHARE%, transparent)); }
.js-plotly-plot .main-svg text[style*="fill: PLOTLY_GREY"] {
  fill: light-dark(color-mix(in srgb, LIGHT_TEXT SHARE%, transparent), PLOTLY_GREY) !important; }
body .stApp :where(button, a, summary, [role="tab"]):focus-visible,
body .stApp :where(label:has(input:is([type="checkbox"], [type="radio"]):focus-visible)) {
  outline: 2px solid light-dark(PRIMARY, LIGHT_RED); outline-offset: 2px; box-shadow: none; }
[data-testid="stSidebarNav"] a:focus-visible { outline: 2px solid light-dark(PRIMARY, LIGHT_RED); outline-offset: -2px; }
@media (max-width: NARROW_PXpx) {
  [data-testid="stHorizontalBlock"]:has([data-testid="stCaptionContainer"] table) { flex-wrap: wrap; }
  [data-testid="stHorizontalBlock"]:has([data-testid="stCaptionContainer"] table) > [data-testid="stColumn"] {
    min-width: 100%; }
}
</style>"""


@cache
def rules() -> str:
    """The style element, with the theme's colours (built once per server process)."""
    return (_RULES.replace("LIGHT_RED", LIGHT_RED).replace("PLOTLY_GREY", PLOTLY_GREY)
            .replace("PRIMARY", st.get_option("theme.light.primaryColor"))
            .replace("LIGHT_TEXT", st.get_option("theme.light.textColor"))
            .replace("DARK_TEXT", st.get_option("theme.dark.textColor")).replace("SHARE", str(DISABLED_SHARE))
            .replace("NARROW_PX", str(NARROW_PX)))


def contrast() -> None:
    """Put the rules at the foot of the sidebar. With an empty element beside them: Streamlit sends a style
    alone to the container of toasts, where it took the place of the toast a run opened from a link shows."""
    st.sidebar.html(rules() + "<span></span>")
