"""The command line and its exports, as a user runs them."""

from __future__ import annotations

import json
import shutil
import signal
import subprocess
import sys

import highspy
import openpyxl
import pandas as pd
import pytest

from rvpp import load_case, with_options
from rvpp.settle.audit import audit_export
from rvpp.cli import main
from rvpp.outputs.export import PLAN_FILES

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
    assert book.sheetnames == ["summary", "market", "units", "csp", "dispatch", "flexibility"]
    # No battery, hydro or biomass unit: the dispatch file and sheet still name their columns.
    header = ["t", "start", "clock", "unit", "kind", "p_mw", "r_up_mw", "r_dn_mw", "charge_mw", "discharge_mw",
              "energy_mwh", "charging", "r_ch_up_mw", "r_ch_dn_mw", "r_dis_up_mw", "r_dis_dn_mw", "sigma_up",
              "sigma_dn", "energy_floor_mwh", "energy_ceiling_mwh", "online", "startup", "shutdown"]
    assert (out / "dispatch.csv").read_text().splitlines() == [",".join(header)]
    assert [list(row) for row in book["dispatch"].iter_rows(values_only=True)] == [header]
    assert audit_export(load_case(PAPER), out) == []
    # Another reader of the MPS file (HiGHS's own parser, not rvpp's compiler) finds the same optimum.
    highs = highspy.Highs()
    highs.setOptionValue("output_flag", False)
    highs.setOptionValue("mip_rel_gap", 1e-6)
    assert highs.readModel(str(out / "model.mps")) == highspy.HighsStatus.kOk
    highs.run()
    assert highs.getModelStatus() == highspy.HighsModelStatus.kOptimal
    assert highs.getInfo().objective_function_value == pytest.approx(summary["objective_eur"], rel=2e-4)
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


def test_earliest_ties_are_exported_and_audited(tmp_path, capsys):
    # 6 April, balanced: CSP1's field deviates by 300 MW_th at 11-13 h and 16-17 h and Γ = 4.
    code, err = run(capsys, "solve", "--date", "2025-04-06", "--strategy", "balanced", "--out", str(tmp_path / "c"))
    assert code == 0, err
    assert "tied deviations, the model chose: CSP1: 4 of the 5 periods tied at a deviation of 300 MW_th" in err
    out = tmp_path / "e"
    code, err = run(capsys, "solve", "--date", "2025-04-06", "--strategy", "balanced", "--ties", "earliest",
                    "--out", str(out))
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "optimal" and summary["budget_ties"] == "earliest"
    assert "tied deviations" not in err
    csp = pd.read_csv(out / "csp.csv")
    assert list(csp.loc[csp["chi"] == 1, "t"]) == [11, 12, 13, 16]
    assert audit_export(load_case(PAPER), out) == []
    csp.loc[csp["t"] == 16, ["chi", "sf_bound_mw"]] = [0, csp.loc[csp["t"] == 16, "sf_nominal_mw"].item()]
    csp.loc[csp["t"] == 17, ["chi", "sf_bound_mw"]] = [1, 0.0]
    csp.to_csv(out / "csp.csv", index=False)
    assert "budget.earliest_ties" in {v.check for v in audit_export(load_case(PAPER), out)}


def test_a_plan_without_a_csp_writes_the_csp_file_and_sheet_with_their_header(tmp_path, capsys):
    out = tmp_path / "plan"
    code, err = run(capsys, "solve", "--no-csp", "--quiet", "--out", str(out))
    assert code == 0, err
    assert json.loads((out / "summary.json").read_text())["csp"] == []
    # the public columns of docs/exports.md, in their order, and no row
    header = ["t", "start", "clock", *CONTRACT["csp"][1:], "shutdown", "ts_r_ch_up_mw", "ts_r_ch_dn_mw",
              "ts_r_dis_up_mw", "ts_r_dis_dn_mw", "ts_energy_floor_mwh", "ts_energy_ceiling_mwh"]
    assert (out / "csp.csv").read_text().splitlines() == [",".join(header)]
    book = openpyxl.load_workbook(out / "plan.xlsx", read_only=True)
    assert [list(row) for row in book["csp"].iter_rows(values_only=True)] == [header]
    assert audit_export(load_case(PAPER), out) == []  # the summary names no CSP: the audit leaves it out


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
    (["--date", "18/03/2025"], "--date: '18/03/2025' is not a day of the calendar; give YYYY-MM-DD"),
    (["--case", "does/not/exist"], "no case.yaml found"),
    (["--hpa-flat", "-5"], "--hpa-flat: '-5' is not allowed; give a number in [0, 1e+06] [EUR/MWh_th]"),
    (["--ties", "earliest", "--budget-mode", "planner_chosen"],
     "budgets.ties=earliest needs budgets.mode=paper and solver.budget_encoding=top_gamma (here planner_chosen"),
])
def test_bad_input_ends_with_a_message_not_a_traceback(tmp_path, capsys, args, message):
    code, err = run(capsys, "solve", *args, "--quiet", "--out", str(tmp_path / "o"))
    assert code == 1
    assert message in err and "Traceback" not in err


def test_unwritable_output_is_reported(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    code, err = run(capsys, "solve", "--quiet", "--out", str(blocker / "sub"))
    assert code == 1 and err.startswith("error:") and "Traceback" not in err
    code, err = run(capsys, "solve", "--quiet", "--out", str(blocker))
    assert code == 1
    assert err == f"error: cannot write: {blocker} (it is a file, not a folder)\n"  # said before solving
    assert blocker.read_text() == "x" and [p.name for p in tmp_path.iterdir()] == ["file"]
    code, err = run(capsys, "solve", "--quiet", "--out", "/")
    assert code == 1 and err == "error: cannot write: / (the root folder cannot take the exports; give a folder inside it)\n"


def test_the_current_folder_takes_the_exports(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "notes.txt").write_text("mine")
    code, err = run(capsys, "solve", "--case", str(PAPER), "--quiet", "--out", ".")
    assert code == 0, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["csp.csv", "dispatch.csv", "flexibility.csv", "market.csv",
                                                          "notes.txt", "plan.xlsx", "summary.json", "units.csv"]
    assert (tmp_path / "notes.txt").read_text() == "mine"
    assert json.loads((tmp_path / "summary.json").read_text())["status"] == "optimal"


def test_data_build_regenerates_the_committed_history(tmp_path, capsys):
    out = tmp_path / "history.csv"
    code, err = run(capsys, "data", "build", "--out", str(out))
    assert code == 0, err
    assert out.read_text() == (PAPER / "history.csv").read_text()
    assert "9504 hours" in err


# ----------------------------------------------------------------------------- a corpus of bad input


YAML = (PAPER / "case.yaml").read_text(encoding="utf-8")


def _case(tmp_path, case_yaml: str | bytes | None = None, history: bytes | None = None) -> str:
    """A copy of the paper case with its case.yaml or history replaced."""
    folder = tmp_path / "case"
    shutil.copytree(PAPER, folder)
    if case_yaml is not None:
        (folder / "case.yaml").write_bytes(case_yaml.encode() if isinstance(case_yaml, str) else case_yaml)
    if history is not None:
        (folder / "history.csv").write_bytes(history)
    return str(folder)


# (arguments, words the message must hold): every one ends with exit code 1 and "error: ...".
# A "{case}" argument is replaced by a case folder built from the entry's case.yaml / history.
SOLVE = [
    (["--time-limit", "0"], "--time-limit: '0' is not allowed; give a number in (0, 1e+06] [s]"),
    (["--time-limit", "inf"], "--time-limit: 'inf' is not allowed; give a number in (0, 1e+06] [s]"),
    (["--time-limit", "nan"], "--time-limit: 'nan' is not allowed"),
    (["--time-limit", "ten"], "--time-limit: 'ten' is not a number; give a number in (0, 1e+06] [s]"),
    (["--gap", "-1"], "--gap: '-1' is not allowed; give a number in [0, 1)"),
    (["--gap", "nan"], "--gap: 'nan' is not allowed; give a number in [0, 1)"),
    (["--gap", "1"], "--gap: '1' is not allowed; give a number in [0, 1)"),
    (["--threads", "-3"], "--threads: '-3' is not allowed; give a whole number in [0, 1024]"),
    (["--threads", "1.5"], "--threads: '1.5' is not allowed; give a whole number in [0, 1024]"),
    (["--threads", "99999"], "--threads: '99999' is not allowed; give a whole number in [0, 1024]"),
    (["--dt", "2"], "--dt: '2' is not allowed; give one of 1, 0.5, 0.25 [h]"),
    (["--dt", "quarter"], "--dt: 'quarter' is not allowed; give one of 1, 0.5, 0.25 [h]"),
    (["--hpa-flat", "-10"], "--hpa-flat: '-10' is not allowed; give a number in [0, 1e+06] [EUR/MWh_th]"),
    (["--hpa-flat", "nan"], "--hpa-flat: 'nan' is not allowed; give a number in [0, 1e+06] [EUR/MWh_th]"),
    (["--hpa-flat", "1e308"], "--hpa-flat: '1e308' is not allowed; give a number in [0, 1e+06] [EUR/MWh_th]"),
    (["--hpa-flat", "inf"], "--hpa-flat: 'inf' is not allowed"),
    (["--markets", ""], "--markets: markets='' names no market; give a comma-separated subset of DAM,SRM,HPA"),
    (["--markets", ","], "--markets: markets=',' names no market"),
    (["--markets", "DAM,IDM"], "--markets: markets: unknown market 'IDM'; choose from DAM, SRM, HPA"),
    (["--strategy", "cautious"], "--strategy: invalid choice: 'cautious'"),
    (["--gamma", "WF1=3", "--gamma", "WF1=4"], "--gamma gives 'WF1' twice (WF1=3 and WF1=4); keep one"),
    (["--gamma", "=3"], "--gamma '=3' must look like SOURCE=N"),
    (["--gamma", "WF1=-2"], "--gamma 'WF1=-2': N=-2 must be >= 0"),
    (["--date", "2025-02-30"], "--date: '2025-02-30' is not a day of the calendar; give YYYY-MM-DD, e.g. 2025-03-18"),
    (["--date", ""], "--date: '' is not a day of the calendar"),
    (["--date", "9999-12-31"], "--date: 9999-12-31 is not allowed; give a day from 1900-01-01 to 2199-12-31"),
    (["--date", "2025-05-05T00:00"], "--date: '2025-05-05T00:00' is not a day of the calendar"),
    (["--date", "20250505"], "--date: '20250505' is not a day of the calendar"),
    (["--case", ""], "--case: is empty; give a file or folder"),
    (["--out", ""], "--out: is empty; give a file or folder"),
    (["--frobnicate"], "unrecognized arguments: --frobnicate"),
]
CASE_FILES = [
    ("units section missing", YAML[:YAML.index("units:")], None,
     "units: section is required; list the units of the case under wind, pv, csp, ed, td"),
    ("a key written twice", YAML.replace("  kappa: 0.3\n", "  kappa: 0.3\n  kappa: 0.4\n"), None,
     'key "kappa" is written twice in one mapping'),
    ("latin-1", YAML.replace("name: paper", "name: año").encode("latin-1"), None,
     "case.yaml: not UTF-8 text"),
    ("utf-16", YAML.encode("utf-16"), None, "case.yaml: is UTF-16 text, not UTF-8 text"),
    ("a zip as history", None, b"PK\x03\x04" + bytes(100), "history.csv: is a zip archive"),
    ("history outside the folder", YAML.replace("history: history.csv", "history: /etc/hostname"), None,
     'case.yaml: history "/etc/hostname" is an absolute path'),
    ("a negative tariff hour", YAML.replace("[70, 70, 70, 70, 70, 70, 85,", "[70, 70, 70, 70, 70, 70, -85,"), None,
     "markets: hpa_tariff_eur_per_mwh hour 06:00 = -85 must be >= 0"),
    ("a budget on a source that does not exist", YAML.replace("overrides: {}", "overrides: {WF9: 3}"), None,
     "budgets.overrides: unknown source 'WF9'"),
    ("not YAML", "name: [unclosed\n", None, "case.yaml: not valid YAML at line 2"),
]


def _one_error(err: str) -> list[str]:
    lines = err.strip().splitlines()
    assert lines and lines[0].startswith("error: "), err
    assert all(line.startswith("  - ") for line in lines[1:]), err
    assert "Traceback" not in err
    return lines


@pytest.mark.parametrize("args, words", SOLVE, ids=[" ".join(a) for a, _ in SOLVE])
def test_a_bad_option_is_one_named_error_and_writes_nothing(tmp_path, capsys, args, words):
    out = tmp_path / "o"
    code, err = run(capsys, "solve", "--out", str(out), "--quiet", *args)
    assert code == 1
    assert words in _one_error(err)[0]
    assert not out.exists()


@pytest.mark.parametrize("label, case_yaml, history, words", CASE_FILES, ids=[c[0] for c in CASE_FILES])
def test_a_bad_case_file_is_one_named_error_and_writes_nothing(tmp_path, capsys, label, case_yaml, history, words):
    out = tmp_path / "o"
    code, err = run(capsys, "solve", "--case", _case(tmp_path, case_yaml, history), "--out", str(out), "--quiet")
    assert code == 1
    assert words in "\n".join(_one_error(err))
    assert not out.exists()


STUDY = [
    (["--strategies", ""], "--strategies: is empty; give a comma-separated subset of deterministic,optimistic"),
    (["--strategies", ","], "--strategies: ',': item 1 is empty"),
    (["--strategies", "balanced,,optimistic"], "item 2 is empty"),
    (["--strategies", "cautious"], "--strategies: unknown 'cautious'; choose from deterministic, optimistic"),
    (["--gammas", ""], "--gammas: is empty; give whole numbers >= 0 such as 0,6,12"),
    (["--gammas", "0,-6"], "--gammas: '-6' is not allowed; give a whole number >= 0"),
    (["--gammas", "1.5"], "--gammas: '1.5' is not allowed; give a whole number >= 0"),
    (["--sources", ","], "--sources: ',': item 1 is empty"),
    (["--market-sets", ""], "--market-sets: is empty"),
    (["--market-sets", "SRM"], "--market-sets: markets='SRM' must include DAM"),
    (["--hpa-prices", "nan"], "--hpa-prices: 'nan' is not allowed; give a number in [0, 1e+06] [EUR/MWh_th]"),
    (["--hpa-prices", "60,1e308"], "--hpa-prices: '1e308' is not allowed; give a number in [0, 1e+06] [EUR/MWh_th]"),
    (["--scenarios", "0"], "--scenarios: '0' is not allowed; give a whole number >= 1"),
    (["--scenarios", "5,1e9"], "scenario_counts: N=1e+09 must be at most 100"),
    (["--gammas", "0,1e308"], "Γ grid: 1e+308 is outside 0..24"),
    (["--test-days", "0"], "--test-days: '0' is not allowed; give a whole number >= 1"),
    (["--test-days", "nan"], "--test-days: 'nan' is not allowed"),
    (["--seed", "-1"], "--seed: '-1' is not allowed; give a whole number >= 0"),
    (["--seed", "1.5"], "--seed: '1.5' is not allowed"),
    (["--sp-time-limit", "0"], "--sp-time-limit: '0' is not allowed; give a number in (0, 1e+06] [s]"),
    (["--sp-time-limit", "1e308"], "--sp-time-limit: '1e308' is not allowed; give a number in (0, 1e+06] [s]"),
    (["--time-limit", "-1"], "--time-limit: '-1' is not allowed; give a number in (0, 1e+06] [s]"),
    (["--time-limit", "1e7"], "--time-limit: '1e7' is not allowed; give a number in (0, 1e+06] [s]"),
    (["--m-def", "-1"], "--m-def: '-1' is not allowed; give a number in [0, 1e+06]"),
    (["--m-def", "1e308"], "--m-def: '1e308' is not allowed; give a number in [0, 1e+06]"),
    (["--m-sur", "nan"], "--m-sur: 'nan' is not allowed; give a number in [0, 1e+06]"),
    (["--m-sr", "inf"], "--m-sr: 'inf' is not allowed; give a number in [0, 1e+06]"),
    (["--c-heat", "-5"], "--c-heat: '-5' is not allowed; give a number in [0, 1e+06] [EUR/MWh_th]"),
    (["--workers", "0"], "--workers: '0' is not allowed; give a whole number in [1, 1024]"),
    (["--workers", "1e9"], "--workers: '1e9' is not allowed; give a whole number in [1, 1024]"),
    (["--scheduler", "foo"], "--scheduler: 'foo' is neither processes, serial, local nor a scheduler address"),
    (["--dt", "0.3"], "--dt: '0.3' is not allowed; give one of 1, 0.5, 0.25 [h]"),
]


@pytest.mark.parametrize("args, words", STUDY, ids=[" ".join(a) for a, _ in STUDY])
def test_a_bad_study_option_is_one_named_error_and_writes_nothing(tmp_path, capsys, args, words):
    out = tmp_path / "o"
    code, err = run(capsys, "study", "sensitivity", "--out", str(out), "--quiet", *args)
    assert code == 1
    assert words in _one_error(err)[0]
    assert not out.exists()


@pytest.mark.parametrize("args, words", [
    ([], "usage: python -m rvpp"),
    (["solve", "--help"], "usage: python -m rvpp solve"),
    (["data", "build", "--seed", "-1"], "--seed: '-1' is not allowed; give a whole number >= 0"),
    (["study"], "the following arguments are required: name"),
])
def test_usage_and_help(capsys, args, words):
    code = main(args)
    captured = capsys.readouterr()
    assert code == (0 if "--help" in args else 1)
    assert words in captured.out + captured.err and "Traceback" not in captured.err


def test_the_command_line_runs_as_a_program_with_exit_code_1(tmp_path):
    """The same as a user's shell sees it: exit status, one line, no traceback."""
    done = subprocess.run([sys.executable, "-m", "rvpp", "solve", "--gap", "nan", "--out", str(tmp_path / "o")],
                          capture_output=True, text=True, cwd=PAPER.parents[2], timeout=120)
    assert done.returncode == 1
    assert done.stderr == ("error: --gap: 'nan' is not allowed; give a number in [0, 1) "
                           "(see python -m rvpp solve --help)\n")


# ----------------------------------------------------------------------------- outputs: nothing stale, nothing half-written


def test_an_infeasible_run_leaves_only_its_summary_and_your_own_files(tmp_path, capsys):
    out = tmp_path / "plan"
    assert run(capsys, "solve", "--quiet", "--out", str(out))[0] == 0
    assert sorted(p.name for p in out.iterdir()) == sorted(PLAN_FILES)
    (out / "notes.txt").write_text("my notes")
    (out / "model.mps").write_text("not rvpp's plan")
    code, err = run(capsys, "solve", "--no-csp", "--markets", "DAM,SRM", "--quiet", "--out", str(out))
    assert code == 1 and _one_error(err)[0].startswith("error: infeasible: ")
    assert sorted(p.name for p in out.iterdir()) == ["model.mps", "notes.txt", "summary.json"]
    assert json.loads((out / "summary.json").read_text())["status"] == "infeasible"
    assert (out / "notes.txt").read_text() == "my notes"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plan"]  # no temporary folder left beside it


def test_a_failure_while_writing_leaves_the_earlier_plan_as_it_was(tmp_path, paper_solve, monkeypatch):
    from rvpp.outputs import export

    out = tmp_path / "plan"
    export.write_plan(paper_solve(), out)
    before = {p.name: p.read_bytes() for p in out.iterdir()}

    def broken(result, target):
        raise OSError(28, "No space left on device", str(target))

    monkeypatch.setattr(export, "write_workbook", broken)
    with pytest.raises(OSError):
        export.write_plan(paper_solve(strategy="pessimistic"), out)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plan"]


def test_a_failed_mps_write_leaves_the_earlier_file_as_it_was(tmp_path, monkeypatch):
    from pyomo.core.base.block import BlockData

    from rvpp.solving.plan import write_mps

    target = tmp_path / "model.mps"
    target.write_text("earlier model\n")

    def broken(model, filename, **options):
        with open(filename, "w") as half:
            half.write("NAME half")
        raise OSError(28, "No space left on device", filename)

    monkeypatch.setattr(BlockData, "write", broken)
    with pytest.raises(OSError):
        write_mps(load_case(PAPER), target)
    assert target.read_text() == "earlier model\n"
    assert [p.name for p in tmp_path.iterdir()] == ["model.mps"]


def test_a_new_output_folder_appears_complete(tmp_path, paper_solve):
    from rvpp.outputs.export import write_plan

    written = write_plan(paper_solve(), tmp_path / "deep" / "plan")
    assert [p.name for p in written] == [*(f"{t}.csv" for t in ("market", "units", "csp", "dispatch", "flexibility")),
                                         "plan.xlsx", "summary.json"]
    assert sorted(p.name for p in (tmp_path / "deep").iterdir()) == ["plan"]


OMIE_DAY = str(PAPER.parent.parent.parent / "tests" / "data" / "omie" / "marginalpdbc_20180325.1")
NOT_OURS = b"root:x:0:0:root:/root:/bin/bash\n"  # a file rvpp did not write, e.g. /etc/passwd


@pytest.mark.parametrize("args, option, kind", [
    (["data", "build"], "--out", "a history CSV, whose first line starts with 'timestamp,'"),
    (["solve", "--quiet", "--out", "{tmp}/plan"], "--write-mps", "an MPS file, whose first line starts with '*'"),
    (["data", "import", OMIE_DAY], "--out", "a table rvpp wrote, whose first line starts with 'time_utc,time_local'"),
], ids=["data build", "solve --write-mps", "data import"])
def test_an_output_path_naming_a_file_rvpp_did_not_write_leaves_it_untouched(tmp_path, capsys, args, option, kind):
    victim = tmp_path / "passwd"
    victim.write_bytes(NOT_OURS)
    code, err = run(capsys, *(a.format(tmp=tmp_path) for a in args), option, str(victim))
    assert code == 1
    assert _one_error(err)[0].startswith(f"error: cannot write: {victim} (it exists and is not {kind}")
    assert "root:x" not in err
    assert victim.read_bytes() == NOT_OURS
    assert [p.name for p in tmp_path.iterdir()] == ["passwd"]  # nothing else written either
    code, err = run(capsys, *(a.format(tmp=tmp_path) for a in args), option, str(tmp_path))
    assert code == 1 and _one_error(err)[0] == f"error: cannot write: {tmp_path} (it is a folder, not a file)"


def test_an_imported_table_replaces_the_one_written_before(tmp_path, capsys):
    table = tmp_path / "prices.csv"
    for _ in range(2):
        code, err = run(capsys, "data", "import", OMIE_DAY, "--out", str(table))
        assert code == 0, err
    frame = pd.read_csv(table)
    assert list(frame.columns) == ["time_utc", "time_local", "price_da"] and len(frame) == 23  # 25 March 2018: DST
    assert [p.name for p in tmp_path.iterdir()] == ["prices.csv"]  # no temporary left


@pytest.mark.slow
def test_ctrl_c_during_a_solve_writes_the_best_plan_found_so_far(tmp_path):
    """6 April, 15 minutes, balanced: HiGHS has plans within a second, the optimum after 15-30 s."""
    out = tmp_path / "plan"
    process = subprocess.Popen([sys.executable, "-m", "rvpp", "solve", "--date", "2025-04-06", "--strategy",
                                "balanced", "--dt", "0.25", "--out", str(out)],
                               stderr=subprocess.PIPE, text=True)
    said = []
    for line in process.stderr:
        said.append(line)
        if "solving with HiGHS" in line:
            process.send_signal(signal.SIGINT)
            break
    said += process.stderr.readlines()
    assert process.wait(120) == 0, "".join(said)
    assert any("stopping at the best plan found so far" in line for line in said)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "stopped" and summary["mip_gap"] > 1e-4
    assert any(line.startswith("status stopped;") for line in said)
    case = with_options(load_case(PAPER), date="2025-04-06", strategy="balanced", dt_h=0.25)
    assert audit_export(case, out) == []  # the plan written is feasible


def test_a_second_ctrl_c_gives_up_and_the_command_says_so(monkeypatch, capsys):
    import rvpp.cli.solve as cli
    from rvpp.cli.options import INTERRUPTED

    stop = cli.SearchStop(lambda _m: None)
    before = signal.getsignal(signal.SIGINT)
    with pytest.raises(KeyboardInterrupt), stop.on_ctrl_c():
        signal.raise_signal(signal.SIGINT)
        assert stop.requested
        signal.raise_signal(signal.SIGINT)
    assert signal.getsignal(signal.SIGINT) is before  # the handler before is back

    def interrupted(_args):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "_run_solve", interrupted)
    assert main(["solve"]) == INTERRUPTED == 130
    assert capsys.readouterr().err == "error: interrupted; nothing more was written\n"


def test_a_long_search_reports_itself_every_few_seconds():
    from rvpp.cli.solve import SEARCH_REPORT_S, SearchStop
    from rvpp.solving.outcome import Search

    said = []
    stop = SearchStop(said.append)
    assert stop(Search(1.0, None, None, None, 0)) is False and said == []
    stop(Search(SEARCH_REPORT_S, None, -80000.0, None, 0))
    stop(Search(SEARCH_REPORT_S + 1, -84010.4, -83403.2, 0.0072, 12))  # within the interval: not said
    stop.requested = True
    assert stop(Search(2 * SEARCH_REPORT_S, -84010.4, -83403.2, 0.0072, 1234)) is True
    assert said == ["search 5 s: no plan yet",
                    "search 10 s: best plan so far, profit -84,010 EUR, gap 0.72% (1234 nodes); Ctrl-C keeps it"]


def test_the_library_names_a_value_of_the_wrong_type(tmp_path):
    from rvpp import load_case as load, solve as solve_case, write_plan

    case = load(PAPER)
    refused = [(lambda: solve_case(None), "rvpp.solve: case must be a Case (from rvpp.load_case), not NoneType"),
               (lambda: solve_case({}), "rvpp.solve: case must be a Case (from rvpp.load_case), not dict"),
               (lambda: write_plan(case, tmp_path / "o"), "rvpp.write_plan: result must be a Result"),
               (lambda: load(None), "rvpp.load_case: path must be a str or PathLike"),
               (lambda: with_options(None), "rvpp.with_options: case must be a Case"),
               (lambda: with_options(case, csp="no"), "rvpp.with_options: csp must be a bool"),
               (lambda: with_options(case, gammas=[1]), "rvpp.with_options: gammas must be a Mapping")]
    for call, message in refused:
        with pytest.raises(TypeError) as error:
            call()
        assert str(error.value).startswith(message)
    assert not (tmp_path / "o").exists()


def test_the_help_and_a_bad_option_load_no_solver_stack():
    """Building the command line (``--help``, a refused option) imports neither Pyomo nor HiGHS
    nor the studies and backtest engine: their options come from light settings modules."""
    code = "\n".join([
        "import sys", "from rvpp.cli import main",
        "assert main(['solve', '--gap', 'x']) == 1",
        "assert main(['study', 'nonsense']) == 1",
        "print(sorted(m for m in ('pyomo', 'highspy', 'rvpp.backtest.engine', 'rvpp.studies.run', 'rvpp.settle.recourse')"
        " if m in sys.modules))"])
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.split() == ["[]"]


def test_the_study_names_the_command_line_offers_are_the_studies():
    from rvpp.studies import STUDIES
    from rvpp.studies.settings import STUDY_NAMES

    assert tuple(STUDIES) == STUDY_NAMES
    assert {"case1", "backtest", "out-of-sample"} <= set(STUDY_NAMES)


def test_a_profit_of_zero_and_a_loss_under_half_a_cent_are_printed_without_a_minus():
    from types import SimpleNamespace

    from rvpp.cli.solve import _describe, _describe_parts

    result = SimpleNamespace(status="optimal", objective_eur=0.0, cost_keur=-0.0, mip_gap=0.0, build_s=0.1,
                             solve_s=0.2, parts={"revenue_dam_eur": 1234.5, "cost_opex_eur": -0.004},
                             protection_eur={"price_da": 1234.5})
    assert _describe(result) == ("status optimal; profit 0 EUR (cost 0.0 kEUR); MIP gap 0.00e+00; "
                                 "build 0.10 s, solve 0.20 s")
    assert _describe_parts(result) == (
        "  parts [EUR]: DAM revenue 1,234.50; SR revenue 0.00; HPA cost 0.00; operating cost 0.00; "
        "price protection DAM 1,234.50, SR up 0.00, SR down 0.00; profit 0.00")
    result.objective_eur, result.cost_keur = -1_234.56, 1.23456
    assert "profit -1,235 EUR (cost 1.2 kEUR)" in _describe(result)
