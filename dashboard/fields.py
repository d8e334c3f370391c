"""Column settings of the unit tables: readable labels with units and a line of help per
field (paper Tables 3-6, MODEL_SPEC §8-§9)."""

from __future__ import annotations

import streamlit as st

from rvpp import Case
from rvpp.outputs.workbook import SERIES_FIELDS, new_unit_row, unit_columns

# field -> (label with unit, help)
FIELDS = {
    "name": ("Name", "Unique name of the unit"),
    "p_max_mw": ("P max [MW]", "Installed (nameplate) power"),
    "p_min_mw": ("P min [MW]", "Minimum power"),
    "om_eur_per_mwh": ("O&M [EUR/MWh]", "Operating cost per MWh produced"),
    "ramp_up_mw_per_min": ("Ramp up [MW/min]", "Reserve ramp; × 15 min caps the up reserve"),
    "ramp_dn_mw_per_min": ("Ramp down [MW/min]", "Reserve ramp; × 15 min caps the down reserve"),
    "ramp_mw_per_min": ("Ramp [MW/min]", "Reserve ramp; × 15 min caps each reserve band"),
    "reserve_share": ("Reserve share [-]", "Largest reserve band as a fraction of P max (0-1)"),
    "series": ("History series", "History column that gives the unit's forecast band"),
    "series_scale": ("Series scale [-]", "Factor applied to the history series"),
    "forecast_series": ("Forecast series", "History column of the unit's day-ahead forecast, for forecast-error "
                                           "bands (see Uncertainty); empty: none"),
    "heat_efficiency": ("Heat efficiency [-]", "Fraction of solar-field heat delivered to thermal demands"),
    "p_max_mw_th": ("SF max [MW_th]", "Solar-field thermal capacity"),
    "e_min_mwh_th": ("TS E min [MWh_th]", "Minimum stored energy"),
    "e_max_mwh_th": ("TS E max [MWh_th]", "Maximum stored energy"),
    "p_ch_max_mw_th": ("TS charge max [MW_th]", "Largest charging power"),
    "p_ch_min_mw_th": ("TS charge min [MW_th]", "Smallest charging power while charging"),
    "p_dis_max_mw_th": ("TS discharge max [MW_th]", "Largest discharging power"),
    "p_dis_min_mw_th": ("TS discharge min [MW_th]", "Smallest discharging power while discharging"),
    "eta_ch": ("TS η charge [-]", "Charging efficiency (0-1]"),
    "eta_dis": ("TS η discharge [-]", "Discharging efficiency (0-1]"),
    "e_init_mwh_th": ("TS E start [MWh_th]", "Energy at the start of the day; empty: cyclic day"),
    "p_in_max_mw_th": ("PB input max [MW_th]", "Largest power-block thermal input"),
    "p_in_min_mw_th": ("PB input min [MW_th]", "Smallest thermal input while the turbine runs"),
    "p_el_max_mw": ("Turbine max [MW]", "Turbine nameplate, caps the output in every scenario"),
    "min_up_h": ("Min up [h]", "Minimum up time once started"),
    "min_down_h": ("Min down [h]", "Minimum down time once stopped"),
    "startup_fraction": ("Start-up heat [-]", "Thermal use at start-up as a fraction of PB input max"),
    "startup_duration_h": ("Start-up time [h]", "Duration of the start-up heat use"),
    "initially_on": ("On at midnight", "Turbine online at the start of the day"),
    "e_min_mwh": ("E min [MWh]", "Minimum energy over the day"),
    "p_init_mw": ("P start [MW]", "Consumption before the day starts (informative)"),
    "flex_up": ("Flex up [-]", "Up reserve (consumption decrease) as a fraction of consumption"),
    "flex_dn": ("Flex down [-]", "Down reserve (consumption increase) as a fraction of consumption"),
    "h_min_mw_th": ("H min [MW_th]", "Minimum heat"),
    "h_max_mw_th": ("H max [MW_th]", "Maximum heat"),
    "q_min_mwh_th": ("Q min [MWh_th]", "Minimum heat over the day"),
    "h_init_mw_th": ("H start [MW_th]", "Heat before the day starts (informative)"),
}
TEXT_FIELDS = {"name"}
BOOL_FIELDS = {"initially_on"}


def column_config(case: Case, kind: str) -> dict:
    """``st.data_editor`` column settings for the unit table of ``kind``; new rows start
    from the template unit with a free name."""
    defaults = new_unit_row(case, kind)
    series_options = list(case.history.columns)
    config = {}
    for column in unit_columns(kind):
        field = column.split(".")[-1]
        label, help_text = FIELDS[field]
        default = defaults.get(column)
        if column == SERIES_FIELDS[kind]:
            config[column] = st.column_config.SelectboxColumn(label, help=help_text, options=series_options,
                                                              default=default, required=True)
        elif field == "forecast_series":
            config[column] = st.column_config.SelectboxColumn(label, help=help_text, options=series_options)
        elif field in TEXT_FIELDS:
            config[column] = st.column_config.TextColumn(label, help=help_text, default=default, required=True)
        elif field in BOOL_FIELDS:
            config[column] = st.column_config.CheckboxColumn(label, help=help_text, default=bool(default))
        else:
            config[column] = st.column_config.NumberColumn(label, help=help_text, default=default)
    return config
