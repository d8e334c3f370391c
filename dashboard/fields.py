"""Column settings of the unit tables: readable labels with units and a line of help per
field (paper Tables 3-6, MODEL_SPEC §8-§9), from :data:`rvpp.data.edits.FIELDS`."""

from __future__ import annotations

import streamlit as st

from rvpp import Case
from rvpp.service import PRICE_COLUMNS, SERIES_FIELDS, field_words, label, new_unit_row, unit_columns

TEXT_FIELDS = {"name"}
BOOL_FIELDS = {"initially_on", "initial_online", "enabled", "profile_window", "energy_net_of_up_band",
               "output_capped"}


def column_config(case: Case, kind: str) -> dict:
    """``st.data_editor`` column settings for the unit table of ``kind``; new rows start
    from the template unit with a free name. A unit's series are chosen among the history's
    columns other than the prices."""
    defaults = new_unit_row(case, kind)
    series_options = [c for c in case.history.columns if c not in PRICE_COLUMNS]
    config = {}
    for column in unit_columns(kind):
        field = column.split(".")[-1]
        name, help_text = label(column), field_words(column)[2]
        default = defaults.get(column)
        if column == SERIES_FIELDS[kind] and column in defaults:  # a kind with a series
            config[column] = st.column_config.SelectboxColumn(name, help=help_text, options=series_options,
                                                              default=default, required=True)
        elif field == "forecast_series":
            config[column] = st.column_config.SelectboxColumn(name, help=help_text, options=series_options)
        elif field in TEXT_FIELDS:
            config[column] = st.column_config.TextColumn(name, help=help_text, default=default, required=True,
                                                         pinned=True)
        elif field in BOOL_FIELDS:
            config[column] = st.column_config.CheckboxColumn(name, help=help_text, default=bool(default))
        else:
            config[column] = st.column_config.NumberColumn(name, help=help_text, default=default)
    return config
