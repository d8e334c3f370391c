"""What a backtest's ``--out`` may replace, and the recommend periods named as the user gave them.

An export replaces its folder as a whole, so it may only replace an earlier export or an empty
folder: a folder of your own or a file of that name is refused by name, before any backtest runs,
and left exactly as it was.
"""

from __future__ import annotations

import datetime as dt
import importlib
import json
import os
from pathlib import Path

import pytest

from rvpp.backtest import BacktestSettings, run_backtest, variants_of
from rvpp.backtest.export import export
from rvpp.cli import main
from rvpp.store import BacktestStore

DAY = dt.date(2025, 5, 2)
THESIS = "Chapter 1. Four years of work.\n"
NOT_AN_EXPORT = "the folder exists and is not a backtest export; choose a new folder or remove it"


@pytest.fixture(scope="module")
def stored(paper_case, tmp_path_factory):
    """A one-day backtest of the deterministic plan: (store URL, backtest id)."""
    url = f"sqlite:///{tmp_path_factory.mktemp('store') / 'store.sqlite3'}"
    settings = BacktestSettings(DAY, DAY, variants_of(["deterministic"], [], perfect=False))
    return url, run_backtest(paper_case, settings, BacktestStore(url))


@pytest.fixture
def mydocs(tmp_path) -> Path:
    """A folder of the user's own, holding their thesis."""
    folder = tmp_path / "mydocs"
    folder.mkdir()
    (folder / "thesis.txt").write_text(THESIS)
    return folder


@pytest.fixture
def no_backtest(monkeypatch):
    """Fail the test if a backtest starts: a refused --out must be refused before any long work."""
    def started(*_args, **_kwargs):
        raise AssertionError("the backtest started although --out was going to be refused")

    # the modules, not the package's functions of the same names
    monkeypatch.setattr(importlib.import_module("rvpp.backtest.engine"), "run_backtest", started)
    monkeypatch.setattr(importlib.import_module("rvpp.backtest.recommend"), "recommend", started)


def run(capsys, *args):
    code = main(["backtest", *args])
    return code, capsys.readouterr().err


def siblings(folder: Path) -> list[str]:
    """Everything beside ``folder`` (a staging or set-aside folder left behind would show here)."""
    return sorted(p.name for p in folder.parent.iterdir())


def test_export_refuses_a_folder_of_the_users_own_and_leaves_it_untouched(stored, mydocs, capsys):
    url, ident = stored
    code, err = run(capsys, "export", ident, "--out", str(mydocs), "--store", url)
    assert code == 1
    assert f"error: --out {mydocs}: {NOT_AN_EXPORT}" in err and "Traceback" not in err
    assert sorted(p.name for p in mydocs.iterdir()) == ["thesis.txt"]
    assert (mydocs / "thesis.txt").read_text() == THESIS
    assert siblings(mydocs) == ["mydocs"]


def test_export_refuses_a_file_of_that_name_and_leaves_it_untouched(stored, tmp_path, capsys):
    url, ident = stored
    notes = tmp_path / "notes.txt"
    notes.write_text("my notes\n")
    code, err = run(capsys, "export", ident, "--out", str(notes), "--store", url)
    assert code == 1
    assert f"error: --out {notes}: a file of that name exists" in err and "Traceback" not in err
    assert notes.is_file() and notes.read_text() == "my notes\n"
    assert siblings(notes) == ["notes.txt"]


def test_export_refuses_a_link_to_nothing(stored, tmp_path, capsys):
    url, ident = stored
    link = tmp_path / "out"
    link.symlink_to(tmp_path / "nowhere" / "export")
    code, err = run(capsys, "export", ident, "--out", str(link), "--store", url)
    assert code == 1
    assert f"error: --out {link}: " in err and "is not a folder" in err
    assert link.is_symlink() and not (tmp_path / "nowhere").exists()


def test_export_replaces_an_empty_folder_and_then_its_own_earlier_export(stored, tmp_path, capsys):
    url, ident = stored
    out = tmp_path / "out"
    out.mkdir()
    assert run(capsys, "export", ident, "--out", str(out), "--store", url)[0] == 0
    first = json.loads((out / "manifest.json").read_text())
    assert first["backtest_id"] == ident
    (out / "records.csv").write_text("an older export's records\n")
    code, err = run(capsys, "export", ident, "--out", str(out), "--store", url)
    assert code == 0, err
    assert (out / "records.csv").read_text() != "an older export's records\n"
    assert sorted(p.name for p in out.iterdir()) == sorted([*first["files"], "manifest.json"])
    assert siblings(out) == ["out"]


def test_an_earlier_export_holding_a_file_of_the_users_own_is_refused(stored, tmp_path, capsys):
    url, ident = stored
    out = tmp_path / "out"
    export(BacktestStore(url), ident, out)
    (out / "thesis.txt").write_text(THESIS)
    code, err = run(capsys, "export", ident, "--out", str(out), "--store", url)
    assert code == 1
    assert f"error: --out {out}: " in err and '"thesis.txt"' in err and "Traceback" not in err
    assert (out / "thesis.txt").read_text() == THESIS and (out / "manifest.json").is_file()
    assert siblings(out) == ["out"]


def test_a_manifest_of_another_kind_does_not_make_a_folder_an_export(stored, mydocs, capsys):
    url, ident = stored
    (mydocs / "manifest.json").write_text(json.dumps({"name": "my web app", "files": ["thesis.txt"]}))
    code, err = run(capsys, "export", ident, "--out", str(mydocs), "--store", url)
    assert code == 1 and NOT_AN_EXPORT in err
    assert sorted(p.name for p in mydocs.iterdir()) == ["manifest.json", "thesis.txt"]
    assert (mydocs / "thesis.txt").read_text() == THESIS


def test_export_as_a_library_call_refuses_the_same_folders(stored, mydocs, tmp_path):
    url, ident = stored
    with pytest.raises(FileExistsError, match="is not a backtest export") as refused:
        export(BacktestStore(url), ident, mydocs)
    assert refused.value.filename == str(mydocs)
    notes = tmp_path / "notes.txt"
    notes.write_text("my notes\n")
    with pytest.raises(FileExistsError, match="a file of that name exists"):
        export(BacktestStore(url), ident, notes)
    assert (mydocs / "thesis.txt").read_text() == THESIS and notes.read_text() == "my notes\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mydocs", "notes.txt"]


@pytest.mark.parametrize("where", [".", "/"])
def test_out_dot_or_root_is_refused_by_name_not_with_a_traceback(stored, mydocs, monkeypatch, capsys, where):
    url, ident = stored
    monkeypatch.chdir(mydocs)
    code, err = run(capsys, "export", ident, "--out", where, "--store", url)
    assert code == 1
    assert f"error: --out {where}: {NOT_AN_EXPORT}" in err and "Traceback" not in err
    assert sorted(os.listdir(mydocs)) == ["thesis.txt"] and (mydocs / "thesis.txt").read_text() == THESIS
    assert siblings(mydocs) == ["mydocs"]


def test_out_dot_replaces_the_current_folder_when_it_is_an_earlier_export(stored, tmp_path, monkeypatch, capsys):
    url, ident = stored
    out = tmp_path / "out"
    export(BacktestStore(url), ident, out)
    (out / "records.csv").write_text("an older export's records\n")
    monkeypatch.chdir(out)
    code, err = run(capsys, "export", ident, "--out", ".", "--store", url)
    monkeypatch.chdir(tmp_path)  # the folder the process stood in was swapped out
    assert code == 0, err
    assert (out / "records.csv").read_text() != "an older export's records\n"
    assert json.loads((out / "manifest.json").read_text())["backtest_id"] == ident
    assert siblings(out) == ["out"]


def test_a_backtest_refuses_its_out_before_it_runs(mydocs, tmp_path, no_backtest, capsys):
    url = f"sqlite:///{tmp_path / 'fresh.sqlite3'}"
    code, err = run(capsys, "--from", DAY.isoformat(), "--to", DAY.isoformat(), "--strategies", "deterministic",
                    "--no-perfect", "--scheduler", "serial", "--quiet", "--store", url, "--out", str(mydocs))
    assert code == 1
    assert f"error: --out {mydocs}: {NOT_AN_EXPORT}" in err and "Traceback" not in err
    assert (mydocs / "thesis.txt").read_text() == THESIS and sorted(os.listdir(mydocs)) == ["thesis.txt"]


def test_recommend_refuses_its_out_before_it_runs(tmp_path, no_backtest, capsys):
    notes = tmp_path / "notes.txt"
    notes.write_text("my notes\n")
    code, err = run(capsys, "recommend", "--train", "2025-05-02:2025-05-03", "--test", "2025-05-04:2025-05-04",
                    "--scheduler", "serial", "--quiet", "--store", f"sqlite:///{tmp_path / 'fresh.sqlite3'}",
                    "--out", str(notes))
    assert code == 1
    assert f"error: --out {notes}: a file of that name exists" in err and "Traceback" not in err
    assert notes.read_text() == "my notes\n"
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


@pytest.mark.parametrize("train, test, words", [
    ("2025-05-01:2025-05-02", "2025-04-01:2025-04-02", "--test must start after --train ends (2025-05-02)"),
    ("2025-05-01:2025-05-02", "2025-05-04:2030-04-02", "--test 2030-04-02: the day is settled against its own"),
    ("2024-12-05:2024-12-06", "2024-12-07:2024-12-08", "--train 2024-12-05: the first day needs the 30 days"),
])
def test_recommend_names_train_and_test_not_from_and_to(tmp_path, capsys, train, test, words):
    code, err = run(capsys, "recommend", "--train", train, "--test", test, "--scheduler", "serial", "--quiet",
                    "--store", f"sqlite:///{tmp_path / 'fresh.sqlite3'}")
    assert code == 1
    assert words in err and "Traceback" not in err
    assert "--to" not in err and "--from" not in err


def test_a_backtest_without_a_recorded_day_is_refused_by_name(paper_case, tmp_path, capsys):
    """Stopped before its first day: nothing to export, said so (it was a KeyError in the monthly sums)."""
    url = f"sqlite:///{tmp_path / 'store.sqlite3'}"
    settings = BacktestSettings(DAY, DAY, variants_of(["deterministic"], [], perfect=False))
    ident = BacktestStore(url).open(paper_case, settings.stored(), keys_total=1)
    code, err = run(capsys, "export", ident, "--out", str(tmp_path / "out"), "--store", url)
    assert code == 1
    assert err == f"error: backtest {ident} has no day recorded yet: nothing to export (see backtest list)\n"
    assert not (tmp_path / "out").exists()


def test_commands_that_read_a_store_refuse_a_path_that_holds_none(tmp_path, capsys):
    """A mistyped --store of backtest list or export is said so, not answered from a new, empty store."""
    url = f"sqlite:///{tmp_path / 'typo' / 'store.sqlite3'}"
    for args in (["list", "--store", url], ["export", "b" * 64, "--store", url, "--out", str(tmp_path / "out")]):
        code, err = run(capsys, *args)
        assert code == 1
        assert err == (f"error: store URL {url!r}: no store there ({tmp_path / 'typo' / 'store.sqlite3'} does not "
                       "exist); check the path (a store is made by the first saved run or backtest)\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == []
