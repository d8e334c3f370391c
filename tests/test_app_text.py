"""User text in the dashboard: labels, case and file names and ids are shown as typed, never read
as markdown (the run library is shared: a label is written by one user and shown to another); a
ticked saved run stays the run that was ticked; uploads and labels are refused by name."""

from __future__ import annotations

import io
import re
import zipfile

import pytest
from streamlit.testing.v1 import AppTest

from rvpp.outputs.bundle import case_zip_bytes
from rvpp.store import RunLibrary, StoreError
from tests.factories import click, open_app, shown

# A label that would draw a sign-in link, a remote image, an icon, coloured text, an autolink and LaTeX.
HOSTILE = ("x` [Session expired: sign in again](https://evil.example/login) ![](https://evil.example/p.png) `y "
           ":material/home: :red[alert] <https://evil.example> $x$ :smile:")
HOSTILE_FILE = "x](https://evil.example) ![](https://evil.example/p.png).zip"
EMOJI_NAME = re.compile(r":(?!material/|streamlit:)[\w+-][\w_+-]*:")


pytestmark = pytest.mark.usefixtures("run_library")  # every test saves into a store of its own


def tick(at: AppTest, *rows: int) -> AppTest:
    """Tick rows of the Saved runs table, as the browser reports them."""
    table = at.dataframe[0]
    at.session_state[table.key] = {"selection": {"rows": list(rows), "columns": [], "cells": []}}
    at.run()
    assert not at.exception, at.exception
    return at


def assert_inert(text: str, *words: str) -> None:
    """``text`` (a markdown body) draws no link, image, icon, directive, emoji, code or LaTeX, and still
    shows ``words``."""
    syntax = re.sub(r"\\.", "", text)  # what markdown reads as syntax: escaped characters taken out
    for mark in ("](", "![", "`", "<http", ":red[", "$x$"):
        assert mark not in syntax, f"{mark!r} read as markdown in {text!r}"
    assert ":material/" not in text and not EMOJI_NAME.search(text), text  # Streamlit reads these before markdown
    for word in words:
        assert word in shown(text), (word, text)


def bodies(elements, word: str = "Session expired") -> list[str]:
    found = [e.value for e in elements if word in shown(e.value)]
    assert found, f"{word!r} not shown"
    return found


# ----------------------------------------------------------------------------- markdown


def test_a_hostile_label_and_case_name_show_as_text_where_a_saved_run_is_opened(run_library, paper_case):
    library = RunLibrary(run_library)
    saved = library.save(HOSTILE, paper_case.replace(name=HOSTILE), None, settings={"csp": True})
    at = open_app(run=saved.id)
    for toast in bodies(at.toast):
        assert_inert(toast, "Opened the saved run", "Session expired")
    for line in bodies(at.sidebar.markdown, "x` [Session"):
        assert_inert(line)
    for line in bodies(at.caption):  # Results says which saved run it shows (a link's toast is never drawn)
        assert_inert(line.removeprefix(":material/bookmark: "), "opened from the library", "saved without a plan")

    at.switch_page("pages/home.py").run()
    assert not at.exception, at.exception
    for line in bodies(at.markdown):
        assert_inert(line, "loaded from", "Session expired: sign in again")

    at.switch_page("pages/runs.py").run()
    tick(at, 0)
    for header in bodies(at.header):
        assert_inert(header, "sign in again")
    at.text_input(key=f"runs_label_{saved.id}").input(HOSTILE + " renamed").run()
    click(at, "runs_rename")
    for notice in bodies(at.success):
        assert_inert(notice, "Renamed to", "renamed")


def test_a_renaming_refused_names_the_label_as_text(run_library, paper_case):
    library = RunLibrary(run_library)
    library.save(HOSTILE, paper_case, None)
    other = library.save("other", paper_case, None)
    at = tick(open_app("runs"), 0)
    at.text_input(key=f"runs_label_{other.id}").input(HOSTILE).run()
    click(at, "runs_rename")
    for error in bodies(at.error):
        assert_inert(error, "is already used")
    assert [r.label for r in library.list()] == ["other", HOSTILE]


def test_a_hostile_run_link_is_refused_short_and_as_text():
    ident = ("x ](https://evil.example/login) [Your session expired - sign in again](https://evil.example/login) "
             "![](https://evil.example/p.png) ") + "a" * 10_000
    at = open_app(run=ident)
    (error,) = [e.value for e in at.error]
    assert "The linked run cannot be opened" in error and "no saved run has the id" in shown(error)
    assert_inert(error, "x ](https://evil.example/login) [Your s…")
    assert len(error) < 500  # the id is cut short, not echoed in full


def test_a_label_saved_on_results_shows_as_text(run_library, paper_solve):
    result = paper_solve()
    seed = RunLibrary(run_library).save("seed", result.case, result, settings={"csp": True})
    at = open_app(run=seed.id)  # its plan shows on Results without a solve
    (opened,) = [c.value for c in at.caption if "opened from the library" in c.value]
    assert "The saved run **seed**" in opened and "shown without a solve" in opened
    (notice,) = [s.value for s in at.success if "library" in s.value]
    assert "This plan is the saved run **seed**" in notice and f"(/?run={seed.id})" in notice
    at.text_input(key="results_run_label").input(HOSTILE).run()
    click(at, "results_save")
    for notice in bodies(at.success):
        own = re.compile(r"\[open it by link\]\(/\?run=[0-9a-f]{32}\)")  # the page's own link, the only one
        assert len(own.findall(notice)) == 1
        assert_inert(own.sub("", notice), "Saved as", "sign in again")
    assert [r.label for r in RunLibrary(run_library).list()][0] == HOSTILE


def test_an_uploaded_case_and_file_name_show_as_text_on_home(paper_case):
    at = open_app()
    at.file_uploader(key="home_upload").set_value(
        [(HOSTILE_FILE, case_zip_bytes(paper_case.replace(name=HOSTILE)), "application/zip")]).run()
    click(at, "home_load_upload")
    assert not at.error and at.session_state["case"].name == HOSTILE
    (line,) = [m.value for m in at.markdown if "loaded from" in shown(m.value)]
    assert_inert(line, "x` [Session expired", "loaded from upload", "evil.example")


def test_a_backtest_label_on_the_home_source_line_shows_as_text(paper_case):
    at = open_app()
    at.session_state["case_source"] = f'backtest "{HOSTILE}": 2025-05-20, balanced'  # as the Backtest page sets it
    at.switch_page("pages/home.py").run()
    assert not at.exception, at.exception
    (line,) = [m.value for m in at.markdown if "loaded from" in shown(m.value)]
    assert_inert(line, "backtest", "Session expired", "2025-05-20, balanced")


# ----------------------------------------------------------------------------- Saved runs selection


def test_a_ticked_run_stays_the_run_ticked_when_another_session_saves_one(run_library, paper_case):
    library = RunLibrary(run_library)
    alpha = library.save("alpha", paper_case, None)
    beta = library.save("beta", paper_case, None)
    at = tick(open_app("runs"), 1)  # newest first: beta, alpha
    assert [h.value for h in at.header] == ["alpha"]
    library.save("gamma", paper_case, None)  # another session: the rows move down by one
    at.run()
    assert not at.exception, at.exception
    assert "beta" not in [h.value for h in at.header]
    for button in [b for b in at.button if b.key == "runs_delete"]:
        button.click().run()  # whatever the page still offers acts on alpha alone
    assert {r.id for r in library.list()} >= {beta.id}
    assert {r.label for r in library.list()} >= {"beta", "gamma"}

    at = tick(open_app("runs"), 2)  # the list as it is now: gamma, beta, alpha
    assert [h.value for h in at.header] == ["alpha"]
    click(at, "runs_delete")
    assert [r.label for r in library.list()] == ["gamma", "beta"]
    assert alpha.id not in {r.id for r in library.list()}


# ----------------------------------------------------------------------------- uploads and labels


def case_files(case) -> tuple[bytes, bytes]:
    """The case.yaml and history.csv of a case's download zip."""
    with zipfile.ZipFile(io.BytesIO(case_zip_bytes(case))) as archive:
        names = archive.namelist()
        return tuple(archive.read(next(n for n in names if n.endswith(end))) for end in ("case.yaml", "history.csv"))


def test_two_uploaded_files_with_one_name_are_refused_by_name(paper_case):
    yaml_text, history = case_files(paper_case)
    at = open_app()
    at.file_uploader(key="home_upload").set_value([("case.yaml", yaml_text, "text/yaml"),
                                                   ("history.csv", history, "text/csv"),
                                                   ("history.csv", history + b"\n", "text/csv")]).run()
    click(at, "home_load_upload")
    errors = "\n".join(e.value for e in at.error)
    assert "two uploaded files are both named history.csv; upload one" in shown(errors)
    assert at.session_state["case"] == paper_case
    at.file_uploader(key="home_upload").set_value(
        [("case.zip", case_zip_bytes(paper_case), "application/zip"),
         ("case.zip", case_zip_bytes(paper_case.replace(name="other")), "application/zip")]).run()
    click(at, "home_load_upload")
    assert "two uploaded files are both named case.zip; upload one" in shown("\n".join(e.value for e in at.error))
    assert at.session_state["case"] == paper_case


@pytest.mark.parametrize(("label", "found"), [
    ("a\x00b", "control characters (found U+0000)"),
    ("esc\x1b[31mred", "control characters (found U+001B)"),
    ("line\nbreak", "control characters (found U+000A)"),
    ("c1\x85", "control characters (found U+0085)"),
    ("rtl\u202eevil", "bidirectional override characters (found U+202E)"),
    ("\u2066isolate\u2069", "bidirectional override characters (found U+2066)"),
    ("\u200b\u200b", "the label is empty"),
    (" \ufeff\u200c \u200d ", "the label is empty"),
])
def test_labels_with_control_or_invisible_characters_are_refused_by_name(run_library, paper_case, label, found):
    library = RunLibrary(run_library)
    with pytest.raises(StoreError, match=re.escape(found)):
        library.save(label, paper_case)
    kept = library.save("kept", paper_case)
    with pytest.raises(StoreError, match=re.escape(found)):
        library.rename(kept.id, label)
    assert [r.label for r in library.list()] == ["kept"]


def test_labels_keep_joiners_and_right_to_left_letters(run_library, paper_case):
    library = RunLibrary(run_library)
    assert library.save("👩\u200d🔬 مرحبا  run", paper_case).label == "👩\u200d🔬 مرحبا run"


def test_a_missing_run_is_named_by_the_start_of_its_id(run_library):
    with pytest.raises(StoreError, match="no saved run has the id") as refused:
        RunLibrary(run_library).load("x" * 10_000)
    assert len(str(refused.value)) < 200


def test_the_recommendation_note_shows_a_case_name_as_typed():
    from dashboard.backtests import recommendation_note
    from rvpp.store import StoredRecommendation

    rec = StoredRecommendation(1, "b" * 64, "2025-06-01T00:00:00+00:00", "x [sign in](https://evil.example)", 0.25,
                               "mean", ("2025-04-01", "2025-04-30"), ("2025-05-01", "2025-05-31"), "holds")
    note = recommendation_note(rec)
    assert "](" not in note and "sign in" in note and "evil" in note
