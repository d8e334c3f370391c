"""A battery added on the Portfolio page is checked like any unit, solved, and drawn on Results."""

from __future__ import annotations

import json

from tests.factories import click, open_app


def test_a_battery_added_on_the_portfolio_page_is_validated_and_its_state_of_charge_drawn():
    at = open_app("portfolio")
    row = {"name": "BAT1", "e_min_mwh": 50.0, "e_max_mwh": 40.0, "p_ch_max_mw": 10.0, "p_dis_max_mw": 10.0,
           "ramp_mw_per_min": 10.0}
    at.session_state["portfolio_battery_0"] = {"edited_rows": {}, "added_rows": [row], "deleted_rows": []}
    at.run()
    assert not at.exception
    assert "BAT1: E min [MWh] = 50 must be < E max [MWh] = 40" in "\n".join(e.value for e in at.error)
    assert at.session_state["case"].battery == ()
    at.session_state["portfolio_battery_0"] = {"edited_rows": {}, "added_rows": [{**row, "e_min_mwh": 4.0}],
                                             "deleted_rows": []}
    at.run()
    assert not at.exception and not at.error
    assert [b.name for b in at.session_state["case"].battery] == ["BAT1"]
    at.switch_page("pages/results.py").run()
    click(at, "results_solve")
    titles = {json.loads(chart.proto.spec)["layout"]["title"]["text"] for chart in at.get("plotly_chart")}
    assert any(title.startswith("BAT1: state of charge") for title in titles), titles
