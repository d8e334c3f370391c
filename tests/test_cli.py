"""The command line and its exports, as a user runs them."""

from __future__ import annotations

import json

import openpyxl
import pandas as pd
import pytest

from rvpp import load_case
from rvpp.settle.audit import audit_export
from rvpp.cli import main

from tests.factories import PAPER

CONTRACT = {
    "market": ["t", "start", "p_da_mw", "r_sr_up_mw", "r_sr_dn_mw", "h_hpa_mw", "price_da_mid", "price_da_pos",
               "price_da_neg", "price_sr_up_hi", "price_sr_up_neg", "price_sr_dn_hi", "price_sr_dn_neg",
               "tariff_hpa"],
    "units": ["t", "unit", "kind", "p_mw", "r_up_mw", "r_dn_mw", "nominal_mw", "deviation_mw", "bound_mw", "chi"],
    "csp": ["t", "unit", "p_sf_mw", "sf_nominal_mw", "sf_deviation_mw", "sf_bound_mw", "chi", "p_pb_mw",
            "e_none_mw", "e_up_mw", "e_dn_mw", "ts_charge_mw", "ts_discharge_mw", "ts_energy_mwh", "ts_r_up_mw",
            "ts_r_dn_mw", "charging", "online", "startup", "heat_to_td_mw", "sigma_up", "sigma_dn"],
    "flexibility": ["kind", "r_up_mwh", "r_dn_mwh", "capacity_mw", "r_up_h", "r_dn_h"],
}
SUMMARY_KEYS = {"objective_eur", "cost_keur", "status", "mip_gap", "build_s", "solve_s", "strategy", "budgets",
                "markets", "dt_h", "periods", "revenue_dam_eur", "revenue_sr_eur", "cost_hpa_eur", "cost_opex_eur",
                "protection_eur"}


def run(capsys, *args):
    code = main(list(args))
    captured = capsys.readouterr()
    return code, captured.err


def test_solve_writes_every_export_with_the_public_columns(tmp_path, capsys):
    out = tmp_path / "plan"
    code, err = run(capsys, "solve", "--strategy", "optimistic", "--gamma", "WF1=8", "--gamma", "price_da=2",
                    "--out", str(out), "--write-mps", str(out / "model.mps"))
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text())
    assert SUMMARY_KEYS <= set(summary)
    assert summary["status"] == "optimal" and summary["strategy"] == "optimistic"
    assert summary["budgets"]["WF1"] == 8 and summary["budgets"]["price_da"] == 2 and summary["budgets"]["PV1"] == 2
    assert set(summary["protection_eur"]) == {"da", "sr_up", "sr_dn"}
    assert summary["cost_keur"] == pytest.approx(-summary["objective_eur"] / 1000)
    for name, columns in CONTRACT.items():
        table = pd.read_csv(out / f"{name}.csv")
        assert columns == [c for c in table.columns if c in columns], name
    units = pd.read_csv(out / "units.csv")
    assert len(units) == 24 * 11 and set(units["kind"]) == {"wind", "pv", "csp", "ed", "td"}
    book = openpyxl.load_workbook(out / "plan.xlsx", read_only=True)
    assert book.sheetnames == ["summary", "market", "units", "csp", "flexibility"]
    assert (out / "model.mps").read_text().startswith("*")
    assert audit_export(load_case(PAPER), out) == []
    assert "status optimal" in err


def test_quarter_hours_without_srm_on_a_short_day(tmp_path, capsys):
    out = tmp_path / "q"
    code, err = run(capsys, "solve", "--dt", "0.25", "--date", "2025-03-30", "--markets", "DAM,HPA",
                    "--hpa-flat", "60", "--out", str(out))
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["periods"] == 92 and summary["markets"] == "DAM+HPA" and summary["dt_h"] == 0.25
    market = pd.read_csv(out / "market.csv")
    assert (market["tariff_hpa"] == 60).all() and (market[["r_sr_up_mw", "r_sr_dn_mw"]] == 0).all().all()
    assert audit_export(load_case(PAPER), out) == []


def test_no_csp_and_no_hpa_names_the_missing_heat_source(tmp_path, capsys):
    code, err = run(capsys, "solve", "--no-csp", "--markets", "DAM,SRM", "--out", str(tmp_path / "x"))
    assert code == 1
    assert "no heat source" in err
    summary = json.loads((tmp_path / "x" / "summary.json").read_text())
    assert summary["status"] == "infeasible" and "no heat source" in summary["message"]


@pytest.mark.parametrize("args, message", [
    (["--gamma", "WF1"], "must look like SOURCE=N"),
    (["--gamma", "WF1=two"], "must be a whole number"),
    (["--gamma", "NOPE=3"], "unknown source 'NOPE'"),
    (["--gamma", "PV1=25"], "exceeds the 24 periods"),
    (["--markets", "SRM"], "must include DAM"),
    (["--date", "2031-01-01"], "is not covered"),
    (["--date", "18/03/2025"], "delivery_date='18/03/2025' must be a date"),
    (["--case", "does/not/exist"], "no case.yaml found"),
    (["--hpa-flat", "-5"], "must be >= 0"),
])
def test_bad_input_ends_with_a_message_not_a_traceback(tmp_path, capsys, args, message):
    code, err = run(capsys, "solve", *args, "--quiet", "--out", str(tmp_path / "o"))
    assert code == 2
    assert message in err and "Traceback" not in err


def test_unwritable_output_is_reported(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    code, err = run(capsys, "solve", "--quiet", "--out", str(blocker / "sub"))
    assert code == 2 and err.startswith("error:") and "Traceback" not in err


def test_data_build_regenerates_the_committed_history(tmp_path, capsys):
    out = tmp_path / "history.csv"
    code, err = run(capsys, "data", "build", "--out", str(out))
    assert code == 0, err
    assert out.read_text() == (PAPER / "history.csv").read_text()
    assert "9504 hours" in err
