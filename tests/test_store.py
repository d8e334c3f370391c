"""The store: saved runs and backtest records, on SQLite and on a real PostgreSQL server."""

from __future__ import annotations

import datetime as dt
import os
import signal
import subprocess
import sys
import zipfile
from io import BytesIO

import pandas as pd
import pytest
import sqlalchemy as sa

from rvpp import audit_result
from rvpp.store import BacktestStore, RecordKey, RunLibrary, StoreError, connect, pending
from rvpp.store.engine import metadata
from tests.factories import ROOT
from tests.stores import postgres_missing, postgres_server

TABLES = ("market", "units", "csp", "flexibility")


@pytest.fixture(scope="module")
def postgres_url():
    reason = postgres_missing()
    if reason:
        pytest.skip(reason)
    with postgres_server() as url:
        yield url


@pytest.fixture(params=["sqlite", "postgresql"])
def url(request, tmp_path):
    if request.param == "sqlite":
        yield f"sqlite:///{tmp_path / 'store.sqlite3'}"
        return
    server = request.getfixturevalue("postgres_url")
    yield server
    metadata.drop_all(connect(server))


@pytest.fixture
def balanced(paper_solve):
    result = paper_solve(strategy="balanced")
    assert result.status == "optimal"
    return result


def test_a_saved_run_reopens_equal_to_what_was_saved(url, balanced):
    library = RunLibrary(url)
    info = library.save("balanced · DAM+SRM+HPA", balanced.case, balanced, settings={"csp_on": True})
    saved = library.load(info.id)
    assert saved.info == info and saved.settings == {"csp_on": True}
    assert saved.case == balanced.case and saved.case.history.fingerprint == balanced.case.history.fingerprint
    result = saved.result
    assert result.status == "optimal" and result.objective_eur == balanced.objective_eur
    assert result.parts == balanced.parts and result.protection_eur == balanced.protection_eur
    for name in TABLES:
        pd.testing.assert_frame_equal(getattr(result, name), getattr(balanced, name))
    assert audit_result(result) == []
    assert library.info(info.id).objective_eur == balanced.objective_eur


def test_a_run_solved_without_the_csp_keeps_the_csp_parameters(url, paper_case, paper_solve):
    without = paper_solve(csp=False)
    assert without.status == "optimal" and not without.case.csp
    library = RunLibrary(url)
    with pytest.raises(StoreError, match="solved for another case"):
        library.save("no CSP", paper_case, without)
    info = library.save("no CSP", paper_case, without, settings={"csp": False})
    saved = library.load(info.id)
    assert saved.case == paper_case and saved.case.csp  # the parameters are kept
    assert saved.result.case == without.case and not saved.result.case.csp
    assert saved.result.objective_eur == without.objective_eur
    assert audit_result(saved.result) == []


def test_labels_stay_unique_and_renames_refuse_a_taken_label(url, balanced):
    library = RunLibrary(url)
    first = library.save("WF1 80 MW", balanced.case, balanced)
    second = library.save("  WF1   80 MW ", balanced.case, balanced)
    third = library.save("WF1 80 MW", balanced.case, balanced)
    assert [first.label, second.label, third.label] == ["WF1 80 MW", "WF1 80 MW (2)", "WF1 80 MW (3)"]
    with pytest.raises(StoreError, match='"WF1 80 MW" is already used'):
        library.rename(third.id, "WF1 80 MW")
    assert library.rename(third.id, "WF1 80 MW, pessimistic").label == "WF1 80 MW, pessimistic"
    assert library.rename(first.id, "WF1 80 MW").label == "WF1 80 MW"  # its own label is not a conflict
    with pytest.raises(StoreError, match="label is empty"):
        library.rename(first.id, "   ")
    assert sorted(r.label for r in library.list()) == ["WF1 80 MW", "WF1 80 MW (2)", "WF1 80 MW, pessimistic"]


def test_labels_with_wildcard_characters_are_matched_literally(url, balanced):
    library = RunLibrary(url)
    library.save("100%_solar", balanced.case, balanced)
    assert library.save("100%", balanced.case, balanced).label == "100%"


def test_runs_share_one_copy_of_a_history_and_deleted_runs_are_gone(url, balanced):
    library = RunLibrary(url)
    a = library.save("a", balanced.case, balanced)
    b = library.save("b", balanced.case, None)
    with library.engine.connect() as connection:
        kinds = connection.execute(sa.text("SELECT kind, count(*) FROM blobs GROUP BY kind ORDER BY kind")).all()
    assert [tuple(k) for k in kinds] == [("history.parquet", 1), ("tables.zip", 1)]
    assert library.load(b.id).result is None and library.info(b.id).status == "not solved"
    library.delete(a.id)
    assert [r.id for r in library.list()] == [b.id]
    with pytest.raises(StoreError, match="no saved run has the id"):
        library.load(a.id)
    with pytest.raises(StoreError, match="no saved run has the id"):
        library.delete(a.id)

    def kinds() -> list[tuple]:
        with library.engine.connect() as connection:
            return [tuple(k) for k in connection.execute(
                sa.text("SELECT kind, count(*) FROM blobs GROUP BY kind ORDER BY kind")).all()]

    # a's plan tables went with it; the history b shares stays, and goes with b.
    assert kinds() == [("history.parquet", 1)]
    assert library.load(b.id).case.history.fingerprint == balanced.case.history.fingerprint
    library.delete(b.id)
    assert kinds() == []


def test_an_exported_run_holds_its_case_folder_and_plan_files(url, balanced, tmp_path):
    from rvpp.outputs.bundle import read_case_files

    library = RunLibrary(url)
    info = library.save("exported", balanced.case, balanced)
    data = library.export_zip(info.id)
    with zipfile.ZipFile(BytesIO(data)) as archive:
        names = set(archive.namelist())
    assert {"case/case.yaml", "case/history.csv", "plan/summary.json", "plan/market.csv", "plan/plan.xlsx",
            "run.json"} <= names
    case_only = BytesIO()
    with zipfile.ZipFile(BytesIO(data)) as archive, zipfile.ZipFile(case_only, "w") as out:
        for name in ("case/case.yaml", "case/history.csv"):
            out.writestr(name, archive.read(name))
    assert read_case_files({"case.zip": case_only.getvalue()}) == balanced.case


def test_backtest_records_resume_where_they_stopped(url, paper_case):
    store = BacktestStore(url)
    settings = {"from": "2025-05-01", "to": "2025-05-03", "strategies": ["balanced", "pessimistic"]}
    keys = [RecordKey(day, s, "preset") for day in ("2025-05-01", "2025-05-02", "2025-05-03")
            for s in ("balanced", "pessimistic")]
    ident = store.open(paper_case, settings, keys_total=len(keys), label="May")
    for key in keys[:3]:
        store.record(ident, key, {"day": key.day, "strategy": key.strategy, "status": "optimal",
                                  "net_cost_eur": 100.0 + len(key.day), "penalty_eur": 1.5})
    again = BacktestStore(url).open(paper_case, settings, keys_total=len(keys))
    assert again == ident
    assert pending(keys, store.done(ident)) == keys[3:]
    other = store.open(paper_case, {**settings, "to": "2025-05-04"}, keys_total=8)
    assert other != ident and store.done(other) == set()
    table = store.records(ident)
    assert list(table["strategy"]) == ["balanced", "pessimistic", "balanced"]
    assert table["net_cost_eur"].tolist() == [110.0] * 3
    [info] = [b for b in store.list() if b.id == ident]
    assert (info.keys_done, info.keys_total, info.label) == (3, 6, "May")
    store.record(ident, keys[0], {"status": "optimal", "net_cost_eur": 7.0})
    assert len(store.records(ident)) == 3 and store.records(ident)["net_cost_eur"].iloc[0] == 7.0


def test_sqlite_store_runs_in_wal_mode(tmp_path):
    engine = connect(f"sqlite:///{tmp_path / 'x' / 'store.sqlite3'}")
    with engine.connect() as connection:
        assert connection.exec_driver_sql("PRAGMA journal_mode").scalar() == "wal"
        assert connection.exec_driver_sql("PRAGMA synchronous").scalar() == 1  # NORMAL


def test_a_bad_store_url_is_a_named_error():
    with pytest.raises(StoreError, match="is not a database URL"):
        connect("not a url at all")
    with pytest.raises(StoreError, match="'mysql://x': the store is kept in SQLite or PostgreSQL, not 'mysql'"):
        connect("mysql://x")
    with pytest.raises(StoreError, match=r"postgresql\+nodriver://u@h/x: its database driver is not available"):
        connect("postgresql+nodriver://u@h/x")


@pytest.mark.parametrize("url", ["postgresql:/user:s3cret@db.example/rvpp",      # one slash short
                                 "postgresql+psycopg://u:s3cret@h:5432x/db",     # a port that is not a number
                                 "postgresql://user:top@s3cret@127.0.0.1:1/db"])  # an "@" in the password
def test_a_mistyped_store_url_never_shows_its_password(url):
    with pytest.raises(StoreError) as refused:
        connect(url)
    assert "s3cret" not in str(refused.value) and "***" in str(refused.value)
    assert "percent-encoded" in str(refused.value)


def test_a_store_in_memory_is_refused_since_it_keeps_nothing():
    for url in ("sqlite://", "sqlite:///:memory:"):
        with pytest.raises(StoreError, match="names no file: a store in memory keeps nothing"):
            connect(url)


def test_a_data_folder_that_cannot_be_made_is_named(monkeypatch, tmp_path):
    monkeypatch.delenv("RVPP_STORE_URL", raising=False)
    (tmp_path / "afile").write_text("mine")
    monkeypatch.setenv("RVPP_DATA_DIR", str(tmp_path / "afile"))
    with pytest.raises(StoreError, match=r"\(from RVPP_DATA_DIR\): its folder cannot be made \(File exists\)"):
        RunLibrary()
    assert (tmp_path / "afile").read_text() == "mine"


def test_a_data_folder_whose_name_looks_like_a_url_query_holds_the_store(monkeypatch, tmp_path):
    monkeypatch.delenv("RVPP_STORE_URL", raising=False)
    folder = tmp_path / "data?v=1 #2 %41"
    monkeypatch.setenv("RVPP_DATA_DIR", str(folder))
    RunLibrary()
    assert [p.name for p in folder.iterdir() if p.suffix == ".sqlite3"] == ["rvpp.sqlite3"]


def test_opening_a_new_store_that_another_process_is_creating_tries_once_more(monkeypatch, tmp_path):
    from rvpp.store import engine as module

    calls = []
    create_all = module.metadata.create_all

    def raced(bind):
        calls.append(1)
        if len(calls) == 1:  # what the second of two processes sees: a table made meanwhile
            raise sa.exc.OperationalError("CREATE TABLE blobs", {}, Exception("table blobs already exists"))
        return create_all(bind)

    monkeypatch.setattr(module.metadata, "create_all", raced)
    connect(f"sqlite:///{tmp_path / 'store.sqlite3'}")
    assert len(calls) == 2


def test_a_database_of_another_program_is_refused_and_left_as_it_was(tmp_path):
    import sqlite3

    path = tmp_path / "theirs.sqlite3"
    with sqlite3.connect(path) as theirs:
        theirs.execute("CREATE TABLE runs (id TEXT, name TEXT, started TEXT)")
    with pytest.raises(StoreError, match="is not an rvpp store: its table 'runs' has no column"):
        RunLibrary(f"sqlite:///{path}")
    with sqlite3.connect(path) as theirs:
        assert theirs.execute("SELECT name FROM sqlite_master WHERE type = 'table'").fetchall() == [("runs",)]


def test_a_refusal_of_the_database_is_a_store_error_naming_the_store(tmp_path, balanced):
    import sqlite3

    library = RunLibrary(f"sqlite:///{tmp_path / 'store.sqlite3'}")
    info = library.save("a", balanced.case, balanced)
    with sqlite3.connect(tmp_path / "store.sqlite3") as other:  # e.g. another program at work on the file
        other.execute("DROP TABLE runs")
    for call in (library.list, lambda: library.load(info.id)):
        with pytest.raises(StoreError, match=r"the store at sqlite:///.*store.sqlite3 refused the operation "
                                             r"\(no such table: runs\)"):
            call()


def test_a_damaged_saved_run_is_named_not_a_traceback(tmp_path, balanced):
    url = f"sqlite:///{tmp_path / 'store.sqlite3'}"
    library = RunLibrary(url)
    bad_table, bad_result = library.save("t", balanced.case, balanced), library.save("r", balanced.case, None)
    with library.engine.begin() as connection:  # a byte of the plan tables flipped; a result cut short
        digest = connection.execute(sa.text("SELECT tables_digest FROM runs WHERE id = :i"),
                                    {"i": bad_table.id}).scalar()
        data = bytearray(connection.execute(sa.text("SELECT data FROM blobs WHERE digest = :d"), {"d": digest}).scalar())
        data[len(data) // 2] ^= 0xFF
        connection.execute(sa.text("UPDATE blobs SET data = :b WHERE digest = :d"), {"b": bytes(data), "d": digest})
    second = RunLibrary(url)
    with second.engine.begin() as connection:
        connection.execute(sa.text("""UPDATE runs SET result = '{"status": "weird"}' WHERE id = :i"""),
                           {"i": bad_result.id})
    with pytest.raises(StoreError, match=r"a stored table \(\w+\) is damaged: its content no longer matches"):
        second.load(bad_table.id)
    with pytest.raises(StoreError, match=r"the saved run '\w+' is damaged and cannot be opened \(\w+Error"):
        second.load(bad_result.id)


def test_the_default_store_lives_in_the_data_folder_from_the_environment(monkeypatch, tmp_path):
    from rvpp.store import default_url

    monkeypatch.delenv("RVPP_STORE_URL", raising=False)
    monkeypatch.setenv("RVPP_DATA_DIR", str(tmp_path / "mine"))
    assert default_url() == f"sqlite:///{tmp_path / 'mine' / 'rvpp.sqlite3'}"
    monkeypatch.setenv("RVPP_STORE_URL", "postgresql+psycopg://team@db/rvpp")
    assert default_url() == "postgresql+psycopg://team@db/rvpp"


SAVER = """
import sys, time
import rvpp
from rvpp.store import RunLibrary
import rvpp.store.runs as runs

library = RunLibrary(sys.argv[1])
case = rvpp.with_options(rvpp.load_case(sys.argv[2]), strategy="deterministic")
result = rvpp.solve(case)
for i in range(5):
    library.save(f"variant {i}", case, result)
real_put = runs.put_blob

def slow_put(connection, kind, data):
    digest = real_put(connection, kind, data)
    if kind == "tables.zip":
        print("inside the save", flush=True)
        time.sleep(120)
    return digest

runs.put_blob = slow_put
library.save("never finished", case, result)
"""


@pytest.mark.slow
def test_a_save_killed_halfway_loses_nothing_that_was_saved(url, tmp_path):
    process = subprocess.Popen([sys.executable, "-c", SAVER, url, str(ROOT / "data" / "cases" / "paper")],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT,
                               env={**os.environ, "PYTHONPATH": str(ROOT)})
    try:
        line = process.stdout.readline()
        assert line.strip() == "inside the save", process.stderr.read()
        process.send_signal(signal.SIGKILL)
        process.wait(timeout=30)
    finally:
        if process.poll() is None:
            process.kill()
    library = RunLibrary(url)
    runs = library.list()
    assert sorted(r.label for r in runs) == [f"variant {i}" for i in range(5)]
    objectives = {library.load(r.id).result.objective_eur for r in runs}
    assert len(objectives) == 1 and None not in objectives
    assert library.save("after the crash", library.load(runs[0].id).case).label == "after the crash"
    if url.startswith("sqlite"):
        with library.engine.connect() as connection:
            assert connection.exec_driver_sql("PRAGMA integrity_check").scalar() == "ok"


def test_a_backtest_reopens_with_its_case_and_keeps_its_progress(url, paper_case):
    store = BacktestStore(url)
    settings = {"from": "2025-05-01", "to": "2025-05-02"}
    ident = store.open(paper_case, settings, keys_total=4)
    case, stored = store.load(ident)
    assert case == paper_case and case.history.fingerprint == paper_case.history.fingerprint and stored == settings
    key = RecordKey("2025-05-01", "balanced", "preset")
    store.record(ident, key, {"status": "optimal", "net_cost_eur": 1.5, "end_state": {"CSP1": {"e_mwh_th": 110.0}}})
    assert store.record_map(ident) == {key: {"status": "optimal", "net_cost_eur": 1.5,
                                             "end_state": {"CSP1": {"e_mwh_th": 110.0}}}}
    assert store.progress(ident) is None
    started = dt.datetime.now(dt.timezone.utc).isoformat()  # this process runs it, started before
    store.set_progress(ident, "running", 1, 4, None, started_at=started)
    store.set_progress(ident, "running", 2, 4, 30.0)
    progress = store.progress(ident)
    assert (progress.state, progress.done, progress.total, progress.eta_s, progress.pid) == ("running", 2, 4, 30.0,
                                                                                          os.getpid())
    assert progress.started_at == started
    store.set_progress(ident, "finished", 4, 4, 0.0)
    assert store.progress(ident).state == "finished"
    with pytest.raises(StoreError, match="no backtest has the id"):
        store.load("nope")
    store.delete(ident)
    assert store.progress(ident) is None
    with store.engine.connect() as connection:  # its history went with it
        assert connection.execute(sa.text("SELECT count(*) FROM blobs")).scalar() == 0


def test_the_latest_remembered_recommendation_is_read_back_and_goes_with_its_backtest(url, paper_case):
    store = BacktestStore(url)
    assert store.recommendation() is None
    ident = store.open(paper_case, {"from": "2025-05-01", "to": "2025-05-09"}, keys_total=9)
    periods = (dt.date(2025, 5, 1), dt.date(2025, 5, 6)), (dt.date(2025, 5, 7), dt.date(2025, 5, 9))
    first = store.remember_recommendation(ident, 0.125, "mean", *periods, "no preset does better.")
    latest = store.remember_recommendation(ident, 0.25, "cvar95", *periods, "it LOSES to balanced.")
    assert first.id != latest.id
    again = BacktestStore(url).recommendation()  # another connection, as after a restart
    assert again == latest
    assert (again.fraction, again.criterion, again.case_name, again.backtest_id) == (0.25, "cvar95", paper_case.name,
                                                                                    ident)
    assert (again.train, again.test) == (("2025-05-01", "2025-05-06"), ("2025-05-07", "2025-05-09"))
    with pytest.raises(StoreError, match="no backtest has the id"):
        store.remember_recommendation("nope", 0.5, "mean", *periods, "")
    store.delete(ident)
    assert store.recommendation() is None


def test_a_running_backtest_whose_process_is_gone_reads_stopped(tmp_path, paper_case):
    store = BacktestStore(f"sqlite:///{tmp_path / 'store.sqlite3'}")
    ident = store.open(paper_case, {"x": 1}, keys_total=2)
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    store.set_progress(ident, "running", 1, 2, 5.0, started_at="2025-01-01T00:00:00+00:00")
    with store.engine.begin() as connection:
        connection.execute(sa.text("UPDATE backtest_progress SET pid = :pid"), {"pid": gone.pid})
    progress = store.progress(ident)
    assert progress.state == "stopped" and progress.eta_s is None and "resume" in progress.message


def test_a_running_row_whose_process_number_was_given_again_reads_stopped(tmp_path, paper_case):
    """After a restart the row's process number may belong to a later process: not the backtest's,
    and never to be stopped in its name."""
    from rvpp.backtest import launch

    store = BacktestStore(f"sqlite:///{tmp_path / 'store.sqlite3'}")
    ident = store.open(paper_case, {"x": 1}, keys_total=2)
    store.set_progress(ident, "running", 1, 2, 5.0,
                       started_at=(dt.datetime.now(dt.timezone.utc) - dt.timedelta(minutes=5)).isoformat())
    later = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"], start_new_session=True)
    try:
        with store.engine.begin() as connection:
            connection.execute(sa.text("UPDATE backtest_progress SET pid = :pid"), {"pid": later.pid})
        assert store.progress(ident).state == "stopped"
        assert launch.stop(ident, store) is False
        assert later.poll() is None  # not signalled
    finally:
        later.kill()
        later.wait()
